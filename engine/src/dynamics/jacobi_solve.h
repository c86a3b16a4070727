// The Jacobi contact solve (SolverType::kJacobi): a velocity iteration whose arithmetic does not
// depend on how the bodies are split among threads or processes.
//
// Why: pgs and soft_step are Gauss-Seidel; each row reads the velocities every earlier row of the
// iteration wrote, in the order of the global greedy colouring (constraint_graph.h). A process
// holding part of the world sees other rows in another order, so their result cannot be made
// independent of the process count without replaying the global order (one exchange per colour
// per iteration). The thesis solver is one sequential pass with the same dependence.
//
// How it splits:
// - every contact's impulse comes from the velocities at the start of the iteration, so it
//   depends only on its two bodies; a body's change is the sum of its contacts' impulses, added
//   in contact-key order (the pair of body ids), the same numbers in the same order anywhere;
// - mass splitting (Tonge, English and Gamble 2012) against plain Jacobi's overshoot: a body
//   with n contacts is seen by each as one of n copies of mass m / n, whose velocities are then
//   averaged (the sum above); every impulse acts on both bodies, so momentum stays exact;
// - penetration is pushed out by split impulses: rows of their own on a second, pseudo velocity
//   per body (Catto's split impulse), solved in the same Jacobi iterations with a Baumgarte bias,
//   started from zero every step and never warm-started; the pseudo velocity moves the bodies
//   (after the real velocity has) and is then dropped. The real rows only keep points from
//   approaching. Why (issue #26): with the bias in the real rows, a body squeezed between
//   contacts (2000 circles at area fraction 0.85 in a closed box) cannot satisfy them all, so its
//   contacts' impulses grew, pushing against each other, step after step through the warm start;
//   once the pile moved they no longer cancelled, and the warm start threw bodies at up to 22 m/s
//   (it added 0.3-0.7 MJ of kinetic energy a second that the iterations took out again). Without the
//   bias in them the warm-started impulses stay bounded and the box comes to rest;
// - restitution as RestitutionPolicy::kBox2d's bias (pairwise collisions, pgs's default, are
//   sequential too), given also to speculative points that close within the step.
//
// Cost (one process, base-10 pyramid, 300 steps, apex drift): 0.191 m at 8 iterations, 0.032 at
// 16, 0.013 at 32, 0.006 at 64 (with the bias in the real rows 0.089 m at 8, the same from 16 on);
// pgs 0.013 m at 8. The World runs the phases back to back
// (solver_jacobi.cpp), the distributed world exchanges boundary bodies between them: same bits.
#pragma once

#include <algorithm>
#include <cstdlib>
#include <span>
#include <utility>
#include <vector>

#include "dynamics/contact_ends.h"
#include "dynamics/integrate.h"
#include "dynamics/restitution_policy.h"
#include "world/world_internal.h"

namespace quadrant {

class JacobiSolve {
 public:
  /// After gravity and damping (IntegrateVelocities, the caller's): the rows of `contacts` (in
  /// their order, which must be key order), each body's contact count, and the warm-start
  /// impulses added to the bodies. Afterwards the velocities and counts of bodies whose contacts
  /// are not all in `contacts` (a process's shadow bodies) are incomplete: the caller replaces
  /// them before Prepare.
  void Begin(Bodies& bodies, const WorldDef& def, Real dt, std::span<const Contact> contacts) {
    const int n = bodies.Count();
    counts_.assign(n, 0);
    pseudo_.assign(n, BodyVelocity{});
    const int m = static_cast<int>(contacts.size());
    rows_.resize(m);
    invDt_ = Real(1) / dt;
    const bool rotation = def.effects.rotation;
    const bool bias = def.effects.restitution;
    for (int c = 0; c < m; ++c) {
      const Contact& contact = contacts[c];
      Row& r = rows_[c];
      ++counts_[contact.a];
      ++counts_[contact.b];
      const Real skin = CopyContactEnds(contact, bodies, def, rotation, r);
      r.pushP = Vec2{0, 0};
      r.pushAngA = r.pushAngB = 0;
      for (int k = 0; k < r.pointCount; ++k) {
        const ManifoldPoint& mp = contact.manifold.points[k];
        Point& p = r.points[k];
        p.rA = mp.point - bodies.center[r.a];
        p.rB = mp.point - bodies.center[r.b];
        p.normalImpulse = def.effects.warmStarting ? mp.normalImpulse : Real(0);
        p.pushImpulse = 0;
        p.tangentImpulse = def.effects.warmStarting ? mp.tangentImpulse : Real(0);
        p.separation = mp.separation - skin;
        const Real vn = Dot(RelativeVelocity(bodies.vel[r.a], bodies.vel[r.b], p), r.normal);
        p.restitutionBias = bias ? RestitutionBias(contact.restitution, def.restitutionThreshold, vn, p.separation)
                                 : Real(0);
      }
    }
    if (def.effects.warmStarting) {
      for (Row& r : rows_) {
        const Vec2 t = RightPerp(r.normal);
        Vec2 P{};
        Real angA = 0, angB = 0;
        for (int k = 0; k < r.pointCount; ++k) {
          const Point& p = r.points[k];
          const Vec2 Pk = p.normalImpulse * r.normal + p.tangentImpulse * t;
          P += Pk;
          angA += Cross(p.rA, Pk);
          angB += Cross(p.rB, Pk);
        }
        r.P = P;
        r.angA = angA;
        r.angB = angB;
      }
      ApplyRows(bodies);
    }
  }

  /// Per body: how many contacts it has (valid for bodies whose contacts are all present).
  std::vector<int32_t>& Counts() { return counts_; }

  /// Per body: the pseudo velocity of the split impulses (exchanged with the velocities).
  std::vector<BodyVelocity>& Pseudo() { return pseudo_; }

  /// Effective masses of mass splitting, from the counts (complete for every body by now).
  void Prepare(const WorldDef& def) {
    for (Row& r : rows_) PrepareRow(r, def.effects.rotation);
  }

  /// One Jacobi iteration: every row from the velocities (and pseudo velocities) as they are
  /// now, then the bodies' changes added in row order.
  void Iterate(Bodies& bodies, const WorldDef& def) {
    for (Row& r : rows_) SolveOne(bodies, def, r);
    ApplyRows(bodies);
  }

  // The same in parts, for a caller that overlaps a part with communication (the distributed
  // world's boundary rows wait for their shadows' velocities): each row's arithmetic reads only
  // its two bodies and no velocity changes before ApplyRows, so any split and order of the rows
  // gives Prepare's and Iterate's bits.
  /// Prepare for the listed rows only.
  void PrepareRows(const WorldDef& def, std::span<const int32_t> rows) {
    for (int32_t c : rows) PrepareRow(rows_[size_t(c)], def.effects.rotation);
  }
  /// Iterate's rows for the listed rows only (no body changes yet).
  void SolveRows(const Bodies& bodies, const WorldDef& def, std::span<const int32_t> rows) {
    for (int32_t c : rows) SolveOne(bodies, def, rows_[size_t(c)]);
  }
  /// Iterate's second half: every row's change added to its bodies, in row (key) order. Static
  /// and kinematic bodies are never written.
  void ApplyRows(Bodies& bodies) {
    for (const Row& r : rows_) {
      if (r.invMassA > 0) {
        BodyVelocity& va = bodies.vel[r.a];
        va.v -= r.invMassA * r.P;
        va.w -= r.invIA * r.angA;
        BodyVelocity& pa = pseudo_[r.a];
        pa.v -= r.invMassA * r.pushP;
        pa.w -= r.invIA * r.pushAngA;
      }
      if (r.invMassB > 0) {
        BodyVelocity& vb = bodies.vel[r.b];
        vb.v += r.invMassB * r.P;
        vb.w += r.invIB * r.angB;
        BodyVelocity& pb = pseudo_[r.b];
        pb.v += r.invMassB * r.pushP;
        pb.w += r.invIB * r.pushAngB;
      }
    }
  }
  /// The bodies of row c (dense indices).
  std::pair<int32_t, int32_t> RowBodies(size_t c) const { return {rows_[c].a, rows_[c].b}; }
  size_t RowCount() const { return rows_.size(); }

  /// The accumulated impulses back into the contacts (warm starting), then positions.
  void Finish(Bodies& bodies, const WorldDef& def, Real dt, std::span<Contact> contacts, StageRunner& run) {
    for (size_t c = 0; c < rows_.size(); ++c) {
      Manifold& m = contacts[c].manifold;
      for (int k = 0; k < rows_[c].pointCount; ++k) {
        m.points[k].normalImpulse = rows_[c].points[k].normalImpulse;
        m.points[k].tangentImpulse = rows_[c].points[k].tangentImpulse;
      }
    }
    IntegratePositions(bodies, def, dt, run);
    // The split impulses' push: positions only, the velocities keep none of it.
    const bool rotation = def.effects.rotation;
    for (int i = 0; i < bodies.Count(); ++i) {
      const BodyVelocity& p = pseudo_[i];
      if (p.v == Vec2{0, 0} && p.w == 0) continue;
      bodies.center[i] += dt * p.v;
      if (rotation && p.w != 0) bodies.xf[i].q = IntegrateRot(bodies.xf[i].q, dt * p.w);
      SyncTransform(bodies, i);
    }
  }

 private:
  struct Point {
    Vec2 rA, rB;
    Real normalMass = 0, tangentMass = 0;
    Real normalImpulse = 0, tangentImpulse = 0;
    Real separation = 0;
    Real restitutionBias = 0;
    Real pushImpulse = 0;  // split impulse on the pseudo velocities, this step's only
  };
  struct Row {
    int32_t a = 0, b = 0;
    Vec2 normal;
    Real friction = 0;
    Real invMassA = 0, invIA = 0, invMassB = 0, invIB = 0;
    Real splitMassA = 0, splitIA = 0, splitMassB = 0, splitIB = 0;
    int pointCount = 0;
    Point points[2];
    // This pass's impulse on B (A gets the opposite) and its moments about each centre; the
    // same for the split impulse.
    Vec2 P;
    Real angA = 0, angB = 0;
    Vec2 pushP;
    Real pushAngA = 0, pushAngB = 0;
  };

  // kBox2d's bias (-e vn above the threshold), also for a speculative point whose gap closes
  // within the step: the speculative row would otherwise stop it at the surface, and touching at
  // rest next step it would never bounce (circle stress lost nearly all its energy: 158 owner
  // changes in 2000 steps at 2 ranks instead of thousands). Such a point bounces up to (1 + e) s
  // early, which pgs corrects with its bounce shift and this solver does not.
  Real RestitutionBias(Real e, Real threshold, Real vn, Real separation) const {
    const Real gap = separation > 0 ? separation * invDt_ : Real(0);
    return e > 0 && vn < -threshold && vn + gap < 0 ? -e * vn : Real(0);
  }

  static Vec2 RelativeVelocity(const BodyVelocity& va, const BodyVelocity& vb, const Point& p) {
    return vb.v - va.v + Cross(vb.w, p.rB) - Cross(va.w, p.rA);
  }

  // Mass splitting's effective masses of one row, from its bodies' contact counts.
  void PrepareRow(Row& r, bool rotation) {
    const Real sA = Real(std::max(counts_[r.a], 1)), sB = Real(std::max(counts_[r.b], 1));
    r.splitMassA = sA * r.invMassA;
    r.splitMassB = sB * r.invMassB;
    r.splitIA = sA * r.invIA;
    r.splitIB = sB * r.invIB;
    const Vec2 n = r.normal, t = RightPerp(n);
    for (int k = 0; k < r.pointCount; ++k) {
      Point& p = r.points[k];
      Real kn = r.splitMassA + r.splitMassB, kt = kn;
      if (rotation) {
        const Real rnA = Cross(p.rA, n), rnB = Cross(p.rB, n), rtA = Cross(p.rA, t), rtB = Cross(p.rB, t);
        kn += r.splitIA * rnA * rnA + r.splitIB * rnB * rnB;
        kt += r.splitIA * rtA * rtA + r.splitIB * rtB * rtB;
      }
      p.normalMass = kn > 0 ? Real(1) / kn : Real(0);
      p.tangentMass = kt > 0 ? Real(1) / kt : Real(0);
    }
  }

  void SolveOne(const Bodies& bodies, const WorldDef& def, Row& r) {
    SolveRow(r, bodies.vel[r.a], bodies.vel[r.b], def.effects.friction);
    SolvePushRow(r, pseudo_[r.a], pseudo_[r.b], def);
  }

  // Sequential impulses on the row's own copies of its two bodies (split masses), from the
  // velocities at the start of the iteration; records the row's impulse in r.P / angA / angB.
  void SolveRow(Row& r, BodyVelocity va, BodyVelocity vb, bool friction) const {
    const Vec2 n = r.normal, t = RightPerp(n);
    Vec2 P{};
    Real angA = 0, angB = 0;
    auto apply = [&](const Point& p, Vec2 Pk) {
      va.v -= r.splitMassA * Pk;
      vb.v += r.splitMassB * Pk;
      va.w -= r.splitIA * Cross(p.rA, Pk);
      vb.w += r.splitIB * Cross(p.rB, Pk);
      P += Pk;
      angA += Cross(p.rA, Pk);
      angB += Cross(p.rB, Pk);
    };
    if (friction) {
      for (int k = 0; k < r.pointCount; ++k) {
        Point& p = r.points[k];
        const Real vt = Dot(RelativeVelocity(va, vb, p), t);
        const Real maxFriction = r.friction * p.normalImpulse;
        const Real newImpulse = std::clamp(p.tangentImpulse - p.tangentMass * vt, -maxFriction, maxFriction);
        const Real lambda = newImpulse - p.tangentImpulse;
        p.tangentImpulse = newImpulse;
        apply(p, lambda * t);
      }
    }
    for (int k = 0; k < r.pointCount; ++k) {
      Point& p = r.points[k];
      const Real vn = Dot(RelativeVelocity(va, vb, p), n);
      // The bounce, or the gap a speculative point may close; a touching point only stops
      // approaching (its penetration is the split impulse's).
      const Real offset = NormalRowOffset(p.separation, p.restitutionBias, invDt_);
      const Real newImpulse = std::max(p.normalImpulse - p.normalMass * (vn + offset), Real(0));
      const Real lambda = newImpulse - p.normalImpulse;
      p.normalImpulse = newImpulse;
      apply(p, lambda * n);
    }
    r.P = P;
    r.angA = angA;
    r.angB = angB;
  }

  // The split impulse of the row's normal points on the pseudo velocities: a Baumgarte bias for
  // penetration beyond the slop, at most maxLinearCorrection per step; a point not that deep only
  // keeps the push from closing it.
  void SolvePushRow(Row& r, BodyVelocity va, BodyVelocity vb, const WorldDef& def) const {
    const Vec2 n = r.normal;
    Vec2 P{};
    Real angA = 0, angB = 0;
    for (int k = 0; k < r.pointCount; ++k) {
      Point& p = r.points[k];
      const Real C = std::clamp(def.baumgarte * (p.separation + def.linearSlop), -def.maxLinearCorrection, Real(0));
      const Real vn = Dot(RelativeVelocity(va, vb, p), n);
      const Real newImpulse = std::max(p.pushImpulse - p.normalMass * (vn + C * invDt_), Real(0));
      const Vec2 Pk = (newImpulse - p.pushImpulse) * n;
      p.pushImpulse = newImpulse;
      va.v -= r.splitMassA * Pk;
      vb.v += r.splitMassB * Pk;
      va.w -= r.splitIA * Cross(p.rA, Pk);
      vb.w += r.splitIB * Cross(p.rB, Pk);
      P += Pk;
      angA += Cross(p.rA, Pk);
      angB += Cross(p.rB, Pk);
    }
    r.pushP = P;
    r.pushAngA = angA;
    r.pushAngB = angB;
  }

  std::vector<Row> rows_;
  std::vector<int32_t> counts_;
  std::vector<BodyVelocity> pseudo_;  // per body: the split impulses' velocity this step
  Real invDt_ = 0;
};

}  // namespace quadrant
