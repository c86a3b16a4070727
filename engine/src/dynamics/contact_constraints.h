// The contact constraints shared by the iterative solvers (pgs, soft_step) as a component each
// holds (ContactConstraints): preparation, warm starting, restitution as pairwise collisions,
// early-bounce correction, the position pass and storing impulses for the next step; and the
// row kernels both solvers' loops call (relative velocity, applying an impulse, the friction
// row, the 2x2 block problem). The passes that go colour by colour take the solver's
// constraint graph (constraint_graph.h), which orders the constraints: constraint k is the
// k-th in colour order.
#pragma once

#include <algorithm>
#include <atomic>
#include <type_traits>
#include <utility>
#include <vector>

#include "dynamics/box2d_position.h"
#include "dynamics/constraint_graph.h"
#include "dynamics/contact_ends.h"
#include "dynamics/integrate.h"
#include "dynamics/restitution_policy.h"
#include "dynamics/solver.h"
#include "parallel/stage_clock.h"

namespace quadrant {


struct PointConstraint {
  Vec2 rA, rB;
  Real normalMass, tangentMass;
  Real normalImpulse, tangentImpulse;
  Real separation;        // at collision time
  Real bounceShift;       // early-bounce correction (m) applied after integration, 0 if none
  Real collisionImpulse;  // normal impulse of this step's collisions (pgs), not warm-started
  Real restitutionBias;   // RestitutionPolicy::kBox2d: the row's target velocity (m/s), else 0
};

struct ContactConstraint {
  int contact;  // index in ctx.contacts (constraints are stored in colour order)
  int a, b;
  Vec2 normal;
  Real friction, restitution;
  Real invMassA, invIA, invMassB, invIB;
  int pointCount;
  PointConstraint points[2];
  // Two-point manifolds: the off-diagonal of the 2x2 effective-mass matrix and whether it is
  // well enough conditioned for the block solver (pgs).
  Real k12;
  bool block;
};

// The 2x2 linear complementarity problem of a two-point manifold's normal rows: impulses
// x >= 0 with velocities w = K x + b >= 0 and x_i w_i = 0, found by trying the four cases in
// turn (both points active, the first alone, the second alone, neither), as Box2D 2.4's block
// solver does. Returns false when no case fits (a numerical corner).
[[gnu::always_inline]] inline bool SolveLcp2(Real k11, Real k12, Real k22, Real b0, Real b1, Real& x0, Real& x1) {
  const Real det = k11 * k22 - k12 * k12;
  x0 = -(k22 * b0 - k12 * b1) / det;
  x1 = -(k11 * b1 - k12 * b0) / det;
  if (x0 >= 0 && x1 >= 0) return true;
  x0 = -b0 / k11;
  x1 = 0;
  if (x0 >= 0 && k12 * x0 + b1 >= 0) return true;
  x0 = 0;
  x1 = -b1 / k22;
  if (x1 >= 0 && k12 * x1 + b0 >= 0) return true;
  x0 = 0;
  x1 = 0;
  return b0 >= 0 && b1 >= 0;
}

// The relative velocity of a point's two bodies (b's minus a's), for body velocities or
// soft_step's solver states (anything with v and w).
template <bool kRotation, class State>
[[gnu::always_inline]] inline Vec2 RelativeVelocity(const State& va, const State& vb, const PointConstraint& pc) {
  Vec2 dv = vb.v - va.v;
  if constexpr (kRotation) dv += Cross(vb.w, pc.rB) - Cross(va.w, pc.rA);
  return dv;
}

// Impulse P at a point: -P on a's velocity, +P on b's, in this order of operations (the rows'
// loops keep both bodies' velocities in locals and write them back once).
template <bool kRotation, class State>
[[gnu::always_inline]] inline void ApplyPointImpulse(const ContactConstraint& cc, const PointConstraint& pc, Vec2 P,
                                                     State& va, State& vb) {
  va.v -= cc.invMassA * P;
  vb.v += cc.invMassB * P;
  if constexpr (kRotation) {
    va.w -= cc.invIA * Cross(pc.rA, P);
    vb.w += cc.invIB * Cross(pc.rB, P);
  }
}

// Static and kinematic bodies (inverse mass 0) are never written: other threads may be
// reading them for constraints of the same colour.
template <bool kRotation>
inline void ApplyImpulse(Bodies& bodies, const ContactConstraint& cc, const PointConstraint& pc, Vec2 P) {
  if (cc.invMassA > 0) {
    BodyVelocity& va = bodies.vel[cc.a];
    va.v -= cc.invMassA * P;
    if constexpr (kRotation) va.w -= cc.invIA * Cross(pc.rA, P);
  }
  if (cc.invMassB > 0) {
    BodyVelocity& vb = bodies.vel[cc.b];
    vb.v += cc.invMassB * P;
    if constexpr (kRotation) vb.w += cc.invIB * Cross(pc.rB, P);
  }
}

// One point's friction row: the accumulated tangent impulse `impulse` moves toward stopping
// the sliding, within mu times `load` (pgs: the normal impulse plus this step's collision
// impulse, Coulomb over the whole impact; soft_step's Box2D restitution: plus its bounce
// impulse); the change is applied to va and vb and the new impulse returned.
template <bool kRotation, class State>
[[gnu::always_inline]] inline Real SolveFrictionRow(const ContactConstraint& cc, const PointConstraint& pc, Vec2 t,
                                                    Real impulse, Real load, State& va, State& vb) {
  const Real vt = Dot(RelativeVelocity<kRotation>(va, vb, pc), t);
  const Real maxFriction = cc.friction * load;
  const Real newImpulse = std::clamp(impulse - pc.tangentMass * vt, -maxFriction, maxFriction);
  ApplyPointImpulse<kRotation>(cc, pc, (newImpulse - impulse) * t, va, vb);
  return newImpulse;
}

// The effects' dispatch of both solvers: fn(rotation, friction) with each as a
// std::bool_constant, so a world with an effect off runs a path without its rows or terms.
template <class Fn>
void DispatchEffects(const Effects& fx, Fn&& fn) {
  if (fx.rotation) {
    fx.friction ? fn(std::true_type{}, std::true_type{}) : fn(std::true_type{}, std::false_type{});
  } else {
    fx.friction ? fn(std::false_type{}, std::true_type{}) : fn(std::false_type{}, std::false_type{});
  }
}

class ContactConstraints {
 public:
  // One constraint per coloured contact (call after ConstraintGraph::Color).
  void Resize(int count) { list_.resize(count); }
  int Size() const { return static_cast<int>(list_.size()); }
  ContactConstraint& operator[](int k) { return list_[k]; }
  const ContactConstraint& operator[](int k) const { return list_[k]; }

  // kBlock: also the 2x2 block data (k12, block), which pgs's normal rows and the restitution
  // passes read; soft_step without restitution reads neither (base-100 pyramid: 237 -> 199
  // instructions a contact without them).
  template <bool kRotation, bool kBlock = true>
  void Prepare(const StepContext& ctx, const ConstraintGraph& graph, int begin, int end) {
    for (int k = begin; k < end; ++k) PrepareContact<kRotation, kBlock>(ctx, graph.ContactOf(k), list_[k]);
  }

  // One contact's constraint (Prepare's body; soft_step prepares into a local one where it keeps
  // no constraint list).
  template <bool kRotation, bool kBlock>
  [[gnu::always_inline]] static void PrepareContact(const StepContext& ctx, int contactIndex, ContactConstraint& cc) {
    const Bodies& bodies = *ctx.bodies;
    {
      const Contact& contact = ctx.contacts[contactIndex];
      cc.contact = contactIndex;
      const Real skin = CopyContactEnds(contact, bodies, *ctx.def, kRotation, cc);
      cc.restitution = contact.restitution;
      const Vec2 n = cc.normal;
      const Vec2 t = RightPerp(n);
      for (int k = 0; k < cc.pointCount; ++k) {
        const ManifoldPoint& mp = contact.manifold.points[k];
        PointConstraint& pc = cc.points[k];
        pc.rA = mp.anchorA;
        pc.rB = mp.anchorB;
        Real kn = cc.invMassA + cc.invMassB;
        Real kt = kn;
        if constexpr (kRotation) {
          const Real rnA = Cross(pc.rA, n), rnB = Cross(pc.rB, n);
          const Real rtA = Cross(pc.rA, t), rtB = Cross(pc.rB, t);
          kn += cc.invIA * rnA * rnA + cc.invIB * rnB * rnB;
          kt += cc.invIA * rtA * rtA + cc.invIB * rtB * rtB;
        }
        pc.normalMass = kn > 0 ? Real(1) / kn : Real(0);
        pc.tangentMass = kt > 0 ? Real(1) / kt : Real(0);
        pc.normalImpulse = mp.normalImpulse;
        pc.tangentImpulse = mp.tangentImpulse;
        pc.collisionImpulse = 0;
        pc.separation = mp.separation - skin;
        pc.bounceShift = 0;
        pc.restitutionBias = 0;
        if (ctx.def->restitution == RestitutionPolicy::kBox2d && ctx.def->effects.restitution) {
          const BodyVelocity& va = bodies.vel[cc.a];
          const BodyVelocity& vb = bodies.vel[cc.b];
          const Real vn = Dot(RelativeVelocity<kRotation>(va, vb, pc), n);
          pc.restitutionBias = Box2dRestitutionBias(cc.restitution, ctx.def->restitutionThreshold, vn, pc.separation);
        }
      }
      cc.k12 = 0;
      cc.block = false;
      if (kBlock && cc.pointCount == 2) {
        const PointConstraint& p0 = cc.points[0];
        const PointConstraint& p1 = cc.points[1];
        Real k12 = cc.invMassA + cc.invMassB;
        if constexpr (kRotation) {
          k12 += cc.invIA * Cross(p0.rA, n) * Cross(p1.rA, n) + cc.invIB * Cross(p0.rB, n) * Cross(p1.rB, n);
        }
        const Real k11 = p0.normalMass > 0 ? Real(1) / p0.normalMass : Real(0);
        const Real k22 = p1.normalMass > 0 ? Real(1) / p1.normalMass : Real(0);
        // Two nearly coincident points make the matrix singular: solve those one at a time.
        constexpr Real kMaxCondition = 1000;
        cc.k12 = k12;
        cc.block = k11 > 0 && k11 * k11 < kMaxCondition * (k11 * k22 - k12 * k12);
      }
    }
  }

  template <bool kRotation>
  void WarmStart(Bodies& bodies, int begin, int end) {
    for (int k = begin; k < end; ++k) {
      const ContactConstraint& cc = list_[k];
      const Vec2 t = RightPerp(cc.normal);
      for (int k = 0; k < cc.pointCount; ++k) {
        const PointConstraint& pc = cc.points[k];
        ApplyImpulse<kRotation>(bodies, cc, pc, pc.normalImpulse * cc.normal + pc.tangentImpulse * t);
      }
    }
  }

  // Restitution as pairwise collisions, before the velocity iterations (pgs). Each contact
  // whose points approach faster than the threshold, and fast enough to close their gap this
  // step, receives the impulse of a collision of its two bodies alone: the approach speed vn
  // becomes -e vn (both points of a two-point manifold at once, through the 2x2 problem). A
  // pass runs colour by colour, so a collision that sets a body moving is seen by the next
  // contact of that body in the same pass, and passes repeat until none collides (at most
  // restitutionIterations).
  //
  // Why not the simultaneous model (solve every contact inelastically, then add e times each
  // point's pre-solve approach, as Box2D does and soft_step still does): in a row of touching
  // balls only the first pair approaches, so the row leaves as a block (Newton's cradle: the
  // last of five balls left at 0.41 m/s instead of 1). Sequential collisions carry the impulse
  // down the row as a real cradle does, and each collision of an elastic pair keeps its kinetic
  // energy exactly. An isolated collision gets the same impulse as before, (1 + e) times the
  // inelastic one.
  //
  // The impulse is kept apart from the solve's accumulated impulse: the velocity iterations
  // only keep points from approaching (which a bounced point no longer does), friction is
  // bounded by mu times the sum of both (Coulomb over the whole impact), and the collision is
  // not warm-started into the next step. Returns whether any point collided.
  //
  // stepGravity is the velocity the step's gravity has yet to add to a dynamic body (zero for
  // pgs, which applies it before the collisions; g dt for soft_step, which applies it over its
  // sub-steps after them). A collision must see the approach speed at impact, gravity included,
  // and leave the pair parting at e times it once that gravity is in: without it a ball's
  // rebound lost (1 + e) g dt (soft_step: -25 % rebound height at e = 0.25).
  template <bool kRotation>
  bool ApplyCollisions(Bodies& bodies, Real threshold, Real invDt, Vec2 stepGravity, int begin, int end) {
    bool any = false;
    for (int c = begin; c < end; ++c) {
      ContactConstraint& cc = list_[c];
      if (cc.restitution == 0) continue;
      const Real e = cc.restitution;
      const Vec2 n = cc.normal;
      BodyVelocity va = bodies.vel[cc.a];
      BodyVelocity vb = bodies.vel[cc.b];
      // Gravity changes the normal velocity only between a body it moves and one it does not.
      const Real gravityA = cc.invMassA > 0 ? Real(1) : Real(0), gravityB = cc.invMassB > 0 ? Real(1) : Real(0);
      const Real pendingVn = (gravityB - gravityA) * Dot(stepGravity, n);
      auto approach = [&](const PointConstraint& pc, Real& vn) {
        vn = Dot(RelativeVelocity<kRotation>(va, vb, pc), n) + pendingVn;
        const Real gap = pc.separation > 0 ? pc.separation * invDt : Real(0);
        return vn < -threshold && vn + gap < 0;
      };
      auto apply = [&](PointConstraint& pc, Real x) {
        ApplyPointImpulse<kRotation>(cc, pc, x * n, va, vb);
        pc.collisionImpulse += x;
        if (pc.separation > 0) pc.bounceShift = std::max(pc.bounceShift, (Real(1) + e) * pc.separation);
      };
      Real vn0 = 0, vn1 = 0;
      const bool hit0 = approach(cc.points[0], vn0);
      const bool hit1 = cc.pointCount == 2 && approach(cc.points[1], vn1);
      if (!hit0 && !hit1) continue;
      if (hit0 && hit1 && cc.block) {
        PointConstraint& p0 = cc.points[0];
        PointConstraint& p1 = cc.points[1];
        Real x0, x1;
        const Real k11 = Real(1) / p0.normalMass, k22 = Real(1) / p1.normalMass;
        if (!SolveLcp2(k11, cc.k12, k22, (Real(1) + e) * vn0, (Real(1) + e) * vn1, x0, x1)) continue;
        apply(p0, x0);
        apply(p1, x1);
      } else {
        // One point, or two badly conditioned ones: one after the other.
        for (int k = 0; k < cc.pointCount; ++k) {
          PointConstraint& pc = cc.points[k];
          Real vn;
          if (!approach(pc, vn)) continue;
          apply(pc, -(Real(1) + e) * vn * pc.normalMass);
        }
      }
      any = true;
      if (cc.invMassA > 0) bodies.vel[cc.a] = va;
      if (cc.invMassB > 0) bodies.vel[cc.b] = vb;
    }
    return any;
  }

  // A speculative point (still apart by s) that bounces reverses this step although the true
  // impact happens s/|vn| into it: integrated with the bounce velocity for the whole step, the
  // pair would end (1 + e) s farther apart than the exact motion puts it. Speed and energy are
  // right; the position is not, and it would raise every rebound (a ball dropped from 3 m came
  // back 10 cm higher). ApplyCollisions records that distance and this moves each pair back
  // together along the normal by it after integration, split by inverse mass (the linear part
  // only: enough for the bounce, and it cannot spin a body), which makes an isolated collision
  // exact in both. Only bodies that move are touched.
  //
  // BounceShift gives a constraint's shift as d: body A moves by invMassA d, body B by -invMassB d
  // (false when there is none). soft_step applies it to its solver states.
  static bool BounceShift(const ContactConstraint& cc, Vec2& d) {
    Real shift = 0;
    for (int k = 0; k < cc.pointCount; ++k) shift = std::max(shift, cc.points[k].bounceShift);
    const Real sum = cc.invMassA + cc.invMassB;
    if (shift == 0 || sum == 0) return false;
    d = (shift / sum) * cc.normal;
    return true;
  }

  void ApplyBounceShifts(Bodies& bodies, int begin, int end) {
    for (int c = begin; c < end; ++c) {
      const ContactConstraint& cc = list_[c];
      Vec2 d;
      if (!BounceShift(cc, d)) continue;
      if (cc.invMassA > 0) {
        bodies.center[cc.a] += cc.invMassA * d;
        SyncTransform(bodies, cc.a);
      }
      if (cc.invMassB > 0) {
        bodies.center[cc.b] -= cc.invMassB * d;
        SyncTransform(bodies, cc.b);
      }
    }
  }

  /// StoreImpulses for pgs, whose velocities the integrator then limits to maxLinearSpeed: a
  /// contact with a body over the limit keeps no impulse for the next step's warm start. Its
  /// impulse did not move the body as solved (the limit took the rest), and warm-starting it
  /// again grows it step after step where a body is squeezed between static and kinematic ones
  /// (random extreme worlds: 2 of 300 overflowed to infinity within 100 steps; none with this).
  void StoreImpulsesWithinSpeedLimit(std::span<Contact> contacts, const Bodies& bodies, Real maxSpeed2, int begin,
                                     int end) const {
    for (int c = begin; c < end; ++c) {
      const ContactConstraint& cc = list_[c];
      Manifold& m = contacts[cc.contact].manifold;
      const bool limited =
          LengthSquared(bodies.vel[cc.a].v) > maxSpeed2 || LengthSquared(bodies.vel[cc.b].v) > maxSpeed2;
      for (int k = 0; k < cc.pointCount; ++k) {
        m.points[k].normalImpulse = limited ? Real(0) : cc.points[k].normalImpulse;
        m.points[k].tangentImpulse = limited ? Real(0) : cc.points[k].tangentImpulse;
      }
    }
  }

  void StoreImpulses(std::span<Contact> contacts, int begin, int end) const {
    for (int c = begin; c < end; ++c) {
      const ContactConstraint& cc = list_[c];
      Manifold& m = contacts[cc.contact].manifold;
      for (int k = 0; k < cc.pointCount; ++k) {
        m.points[k].normalImpulse = cc.points[k].normalImpulse;
        m.points[k].tangentImpulse = cc.points[k].tangentImpulse;
      }
    }
  }

  // Where every body is before the step moves it: CurrentSeparation measures from here.
  void SnapshotPositions(StageRunner& run, const Bodies& bodies) {
    center0_.resize(bodies.Count());
    rot0_.resize(bodies.Count());
    run.For(Stage::kSolve, bodies.Count(), run.MinItems(), [&](int b, int e, int) {
      for (int i = b; i < e; ++i) {
        center0_[i] = bodies.center[i];
        rot0_[i] = bodies.xf[i].q;
      }
    });
  }

  // Re-derives the origins of the bodies a position correction moved (dynamic ones only:
  // re-deriving a static body's origin could change its bits).
  void SyncContactBodies(StageRunner& run, ConstraintGraph& graph, Bodies& bodies) {
    graph.ForEachColor(run, [&](int b, int e) {
      for (int k = b; k < e; ++k) {
        const ContactConstraint& cc = list_[k];
        if (cc.invMassA > 0) SyncTransform(bodies, cc.a);
        if (cc.invMassB > 0) SyncTransform(bodies, cc.b);
      }
    });
  }

  // Separation of a point now, from how far its bodies have moved and turned since the
  // manifold was computed (linearised about the stored anchors). Also returns the turned
  // anchors, which the position and soft solvers use as lever arms.
  template <bool kRotation>
  Real CurrentSeparation(const Bodies& bodies, const ContactConstraint& cc, const PointConstraint& pc, Vec2& rA,
                         Vec2& rB) const {
    rA = pc.rA;
    rB = pc.rB;
    if constexpr (kRotation) {
      rA = Rotate(InvMul(rot0_[cc.a], bodies.xf[cc.a].q), pc.rA);
      rB = Rotate(InvMul(rot0_[cc.b], bodies.xf[cc.b].q), pc.rB);
    }
    const Vec2 d = (bodies.center[cc.b] - center0_[cc.b]) - (bodies.center[cc.a] - center0_[cc.a]) + (rB - pc.rB) -
                   (rA - pc.rA);
    return pc.separation + Dot(cc.normal, d);
  }

  // One non-linear Gauss-Seidel pass over positions: the separation is re-evaluated from how far
  // the bodies have moved and turned since the manifold was computed, and the penetration beyond
  // `allowed` is reduced by the Baumgarte fraction, at most maxLinearCorrection at a time. It
  // moves bodies without giving them velocity. pgs allows linearSlop; soft_step allows the depth
  // its soft contacts push out themselves (solver_soft_step.cpp says why).
  template <bool kRotation>
  bool SolvePositions(Bodies& bodies, const WorldDef& def, Real allowed, int begin, int end) {
    bool moved = false;
    for (int c = begin; c < end; ++c) {
      const ContactConstraint& cc = list_[c];
      const Vec2 n = cc.normal;
      for (int k = 0; k < cc.pointCount; ++k) {
        const PointConstraint& pc = cc.points[k];
        Vec2 rA, rB;
        const Real s = CurrentSeparation<kRotation>(bodies, cc, pc, rA, rB);
        const Real C = std::clamp(def.baumgarte * (s + allowed), -def.maxLinearCorrection, Real(0));
        if (C == 0) continue;
        Real K = cc.invMassA + cc.invMassB;
        if constexpr (kRotation) {
          const Real rnA = Cross(rA, n), rnB = Cross(rB, n);
          K += cc.invIA * rnA * rnA + cc.invIB * rnB * rnB;
        }
        if (K <= 0) continue;
        const Vec2 P = (-C / K) * n;
        moved = true;
        // Static and kinematic bodies (inverse mass 0) are left untouched bit for bit.
        if (cc.invMassA > 0) {
          bodies.center[cc.a] -= cc.invMassA * P;
          if constexpr (kRotation) bodies.xf[cc.a].q = IntegrateRot(bodies.xf[cc.a].q, -cc.invIA * Cross(rA, P));
        }
        if (cc.invMassB > 0) {
          bodies.center[cc.b] += cc.invMassB * P;
          if constexpr (kRotation) bodies.xf[cc.b].q = IntegrateRot(bodies.xf[cc.b].q, cc.invIB * Cross(rB, P));
        }
      }
    }
    return moved;
  }

  // The position pass of both solvers: up to `iterations` passes of SolvePositions, then the
  // moved bodies' origins re-derived. A pass that moves nothing leaves every later one nothing
  // to do (positions are all it reads), so the loop stops there, and with nothing moved the
  // origins are already right: a pile at rest within `allowed` (soft_step allows 0.01 m, so
  // nearly always) costs one pass instead of positionIterations passes and a sync. Results are
  // the same bits either way.
  template <bool kRotation>
  void CorrectPositions(StageRunner& run, ConstraintGraph& graph, Bodies& bodies, const WorldDef& def, Real allowed, int iterations) {
    bool anyMoved = false;
    for (int it = 0; it < iterations; ++it) {
      std::atomic<bool> moved{false};
      graph.ForEachColor(run, [&](int b, int e) {
        if (SolvePositions<kRotation>(bodies, def, allowed, b, e)) moved.store(true, std::memory_order_relaxed);
      });
      if (!moved.load(std::memory_order_relaxed)) break;  // read after the last colour's join
      anyMoved = true;
    }
    if (anyMoved) SyncContactBodies(run, graph, bodies);
  }

  // WorldDef::box2dPositionSolve (box2d_position.h): each point's Box2D geometry, taken with the
  // bodies where the narrow phase saw them (before the positions are integrated).
  void SnapshotBox2dGeometry(const StepContext& ctx) {
    box2dGeometry_.resize(2 * list_.size());
    for (size_t k = 0; k < list_.size(); ++k) {
      const ContactConstraint& cc = list_[k];
      for (int j = 0; j < cc.pointCount; ++j) {
        box2dGeometry_[2 * k + j] = MakeBox2dPositionPoint(*ctx.bodies, ctx.contacts[cc.contact], j, cc.points[j].separation);
      }
    }
  }

  // The position pass as Box2D 2.4.1's (WorldDef::box2dPositionSolve): its geometry, in colour
  // order on one thread (the same bits at any thread count), up to `iterations` passes, stopping
  // after the first in which no point was deeper than 3 linearSlop. A validation setting.
  template <bool kRotation>
  void CorrectPositionsBox2d(Bodies& bodies, const WorldDef& def, int iterations) {
    bool anyMoved = false;
    for (int it = 0; it < iterations; ++it) {
      Real minSeparation = 0;
      for (size_t c = 0; c < list_.size(); ++c) {
        const ContactConstraint& cc = list_[c];
        for (int k = 0; k < cc.pointCount; ++k) {
          const Box2dPositionPoint& g = box2dGeometry_[2 * c + k];
          Real s;
          Vec2 n = cc.normal, rA, rB;
          if (g.kind == Box2dPositionPoint::kDefault) {
            s = CurrentSeparation<kRotation>(bodies, cc, cc.points[k], rA, rB);
          } else {
            const Rot turnA = kRotation ? InvMul(rot0_[cc.a], bodies.xf[cc.a].q) : Rot{};
            const Rot turnB = kRotation ? InvMul(rot0_[cc.b], bodies.xf[cc.b].q) : Rot{};
            Vec2 point;
            Box2dPositionNow(g, bodies.center[cc.a], turnA, bodies.center[cc.b], turnB, s, n, point);
            rA = point - bodies.center[cc.a];
            rB = point - bodies.center[cc.b];
          }
          minSeparation = std::min(minSeparation, s);
          anyMoved |= ApplyBox2dPositionCorrection<kRotation>(bodies, def, cc.a, cc.invMassA, cc.invIA, cc.b, cc.invMassB,
                                                              cc.invIB, s, n, rA, rB);
        }
      }
      if (minSeparation >= -3 * def.linearSlop) break;
    }
    if (!anyMoved) return;
    for (const ContactConstraint& cc : list_) {
      if (cc.invMassA > 0) SyncTransform(bodies, cc.a);
      if (cc.invMassB > 0) SyncTransform(bodies, cc.b);
    }
  }

  // Restitution: passes of ApplyCollisions, colour by colour, until one finds no collision (at
  // most restitutionIterations). stepGravity as ApplyCollisions says.
  template <bool kRotation>
  void ApplyCollisionPasses(StageRunner& run, ConstraintGraph& graph, Bodies& bodies, const WorldDef& def, Real invDt, Vec2 stepGravity) {
    for (int it = 0; it < def.restitutionIterations; ++it) {
      std::atomic<bool> collided{false};
      graph.ForEachColor(run, [&](int b, int e) {
        if (ApplyCollisions<kRotation>(bodies, def.restitutionThreshold, invDt, stepGravity, b, e)) {
          collided.store(true, std::memory_order_relaxed);
        }
      });
      if (!collided.load(std::memory_order_relaxed)) break;  // read after the last colour's join
    }
  }

 private:
  std::vector<ContactConstraint> list_;  // in colour order
  std::vector<Vec2> center0_;            // SnapshotPositions: where each body was before the step
  std::vector<Rot> rot0_;
  std::vector<Box2dPositionPoint> box2dGeometry_;  // SnapshotBox2dGeometry: 2 per constraint
};

}  // namespace quadrant
