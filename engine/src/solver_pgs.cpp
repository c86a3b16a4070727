// Projected Gauss-Seidel over contact impulses (sequential impulses, Box2D 2.4's family).
//
// Per step: gravity, prepare constraints, warm start, N velocity iterations (friction then
// normal, accumulated impulses clamped), a restitution pass, position integration, then a
// position pass (non-linear Gauss-Seidel on the linearised separation, with slop and a
// Baumgarte factor) that removes penetration without adding velocity.
//
// Contacts are speculative: a point that is still apart by s may close at most s this step
// (the normal row targets vn >= -s/dt), so fast bodies stop at the surface instead of passing
// through it. Restitution is applied after the iterations from the approach speed measured
// before them (as Box2D 3 does): a bounce then does not depend on the step at which the gap
// closed, which keeps restitution-1 scenes from losing energy on speculative contacts.
//
// The kernels are templates on the effects (rotation, friction): a world with an effect off
// runs a path without its rows or terms instead of multiplying them by zero.
#include <algorithm>
#include <chrono>
#include <vector>

#include "integrate.h"
#include "solver.h"

namespace quadrant {
namespace {

using Clock = std::chrono::steady_clock;
double Ms(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }

struct PointConstraint {
  Vec2 rA, rB;
  Real normalMass, tangentMass;
  Real normalImpulse, tangentImpulse;
  Real separation;        // at collision time
  Real relativeVelocity;  // normal approach speed before the solve
  Real bounceShift;       // early-bounce correction (m) applied after integration, 0 if none
};

struct ContactConstraint {
  int a, b;
  Vec2 normal;
  Real friction, restitution;
  Real invMassA, invIA, invMassB, invIB;
  int pointCount;
  PointConstraint points[2];
};

class PgsSolver final : public Solver {
 public:
  const char* Name() const override { return "pgs"; }

  void Step(StepContext& ctx) override {
    const WorldDef& def = *ctx.def;
    const Effects& fx = def.effects;
    if (fx.rotation) {
      fx.friction ? Run<true, true>(ctx) : Run<true, false>(ctx);
    } else {
      fx.friction ? Run<false, true>(ctx) : Run<false, false>(ctx);
    }
  }

 private:
  template <bool kRotation, bool kFriction>
  void Run(StepContext& ctx) {
    const WorldDef& def = *ctx.def;
    Bodies& bodies = *ctx.bodies;
    const Real dt = ctx.dt;

    auto t0 = Clock::now();
    IntegrateVelocities(bodies, def, dt);
    auto t1 = Clock::now();

    Prepare<kRotation>(ctx);
    if (def.effects.warmStarting) WarmStart<kRotation>(bodies);
    const Real invDt = Real(1) / dt;
    for (int it = 0; it < def.velocityIterations; ++it) SolveVelocities<kRotation, kFriction>(bodies, invDt);
    hasBounceShift_ = false;
    if (def.effects.restitution) {
      for (int it = 0; it < def.restitutionIterations; ++it) ApplyRestitution<kRotation>(bodies, def.restitutionThreshold);
    }
    StoreImpulses(ctx.contacts);
    auto t2 = Clock::now();

    const bool correct = def.positionIterations > 0 && !constraints_.empty();
    if (correct) Snapshot(bodies);
    IntegratePositions(bodies, def, dt);
    if (hasBounceShift_) ApplyBounceShifts(bodies);
    auto t3 = Clock::now();
    if (correct) {
      for (int it = 0; it < def.positionIterations; ++it) SolvePositions<kRotation>(bodies, def);
      // Only bodies that can move: re-deriving a static body's origin would change its bits.
      for (const ContactConstraint& cc : constraints_) {
        if (cc.invMassA > 0) SyncTransform(bodies, cc.a);
        if (cc.invMassB > 0) SyncTransform(bodies, cc.b);
      }
    }
    auto t4 = Clock::now();
    ctx.profile->integrate += Ms(t0, t1) + Ms(t2, t3);
    ctx.profile->solve += Ms(t1, t2) + Ms(t3, t4);
  }

  template <bool kRotation>
  void Prepare(StepContext& ctx) {
    const Bodies& bodies = *ctx.bodies;
    constraints_.resize(ctx.contacts.size());
    for (size_t c = 0; c < ctx.contacts.size(); ++c) {
      const Contact& contact = ctx.contacts[c];
      ContactConstraint& cc = constraints_[c];
      cc.a = contact.a;
      cc.b = contact.b;
      cc.normal = contact.manifold.normal;
      cc.friction = contact.friction;
      cc.restitution = contact.restitution;
      cc.invMassA = bodies.inv[cc.a].invMass;
      cc.invMassB = bodies.inv[cc.b].invMass;
      cc.invIA = kRotation ? bodies.inv[cc.a].invInertia : Real(0);
      cc.invIB = kRotation ? bodies.inv[cc.b].invInertia : Real(0);
      cc.pointCount = contact.manifold.pointCount;
      const Vec2 n = cc.normal;
      const Vec2 t = RightPerp(n);
      const BodyVelocity va = bodies.vel[cc.a];
      const BodyVelocity vb = bodies.vel[cc.b];
      for (int k = 0; k < cc.pointCount; ++k) {
        const ManifoldPoint& mp = contact.manifold.points[k];
        PointConstraint& pc = cc.points[k];
        pc.rA = mp.point - bodies.center[cc.a];
        pc.rB = mp.point - bodies.center[cc.b];
        Real kn = cc.invMassA + cc.invMassB;
        Real kt = kn;
        Vec2 dv = vb.v - va.v;
        if constexpr (kRotation) {
          const Real rnA = Cross(pc.rA, n), rnB = Cross(pc.rB, n);
          const Real rtA = Cross(pc.rA, t), rtB = Cross(pc.rB, t);
          kn += cc.invIA * rnA * rnA + cc.invIB * rnB * rnB;
          kt += cc.invIA * rtA * rtA + cc.invIB * rtB * rtB;
          dv += Cross(vb.w, pc.rB) - Cross(va.w, pc.rA);
        }
        pc.normalMass = kn > 0 ? Real(1) / kn : Real(0);
        pc.tangentMass = kt > 0 ? Real(1) / kt : Real(0);
        pc.normalImpulse = mp.normalImpulse;
        pc.tangentImpulse = mp.tangentImpulse;
        pc.separation = mp.separation;
        pc.relativeVelocity = Dot(dv, n);
        pc.bounceShift = 0;
      }
    }
  }

  template <bool kRotation>
  static void ApplyImpulse(Bodies& bodies, const ContactConstraint& cc, const PointConstraint& pc, Vec2 P) {
    BodyVelocity& va = bodies.vel[cc.a];
    BodyVelocity& vb = bodies.vel[cc.b];
    va.v -= cc.invMassA * P;
    vb.v += cc.invMassB * P;
    if constexpr (kRotation) {
      va.w -= cc.invIA * Cross(pc.rA, P);
      vb.w += cc.invIB * Cross(pc.rB, P);
    }
  }

  template <bool kRotation>
  void WarmStart(Bodies& bodies) {
    for (const ContactConstraint& cc : constraints_) {
      const Vec2 t = RightPerp(cc.normal);
      for (int k = 0; k < cc.pointCount; ++k) {
        const PointConstraint& pc = cc.points[k];
        ApplyImpulse<kRotation>(bodies, cc, pc, pc.normalImpulse * cc.normal + pc.tangentImpulse * t);
      }
    }
  }

  template <bool kRotation>
  static Vec2 RelativeVelocity(const BodyVelocity& va, const BodyVelocity& vb, const PointConstraint& pc) {
    Vec2 dv = vb.v - va.v;
    if constexpr (kRotation) dv += Cross(vb.w, pc.rB) - Cross(va.w, pc.rA);
    return dv;
  }

  template <bool kRotation, bool kFriction>
  void SolveVelocities(Bodies& bodies, Real invDt) {
    for (ContactConstraint& cc : constraints_) {
      const Vec2 n = cc.normal;
      BodyVelocity va = bodies.vel[cc.a];
      BodyVelocity vb = bodies.vel[cc.b];
      auto apply = [&](const PointConstraint& pc, Vec2 P) {
        va.v -= cc.invMassA * P;
        vb.v += cc.invMassB * P;
        if constexpr (kRotation) {
          va.w -= cc.invIA * Cross(pc.rA, P);
          vb.w += cc.invIB * Cross(pc.rB, P);
        }
      };
      if constexpr (kFriction) {
        const Vec2 t = RightPerp(n);
        for (int k = 0; k < cc.pointCount; ++k) {
          PointConstraint& pc = cc.points[k];
          const Real vt = Dot(RelativeVelocity<kRotation>(va, vb, pc), t);
          const Real maxFriction = cc.friction * pc.normalImpulse;
          const Real newImpulse = std::clamp(pc.tangentImpulse - pc.tangentMass * vt, -maxFriction, maxFriction);
          const Real lambda = newImpulse - pc.tangentImpulse;
          pc.tangentImpulse = newImpulse;
          apply(pc, lambda * t);
        }
      }
      for (int k = 0; k < cc.pointCount; ++k) {
        PointConstraint& pc = cc.points[k];
        const Real vn = Dot(RelativeVelocity<kRotation>(va, vb, pc), n);
        // Speculative: a gap s may close this step, no more (target vn >= -s/dt).
        const Real gap = pc.separation > 0 ? pc.separation * invDt : Real(0);
        const Real newImpulse = std::max(pc.normalImpulse - pc.normalMass * (vn + gap), Real(0));
        const Real lambda = newImpulse - pc.normalImpulse;
        pc.normalImpulse = newImpulse;
        apply(pc, lambda * n);
      }
      bodies.vel[cc.a] = va;
      bodies.vel[cc.b] = vb;
    }
  }

  // Restitution after the iterations, from the approach speed measured before them (as Box2D 3
  // does), so the bounce does not depend on which step the gap closed in.
  //
  // A speculative point (still apart by s) that bounces reverses this step although the true
  // impact happens s/|vn| into it: integrated with the bounce velocity for the whole step, the
  // pair would end (1 + e) s farther apart than the exact motion puts it. Speed and energy are
  // right; the position is not, and it would raise every rebound (a ball dropped from 3 m came
  // back 10 cm higher). The point records that distance and ApplyBounceShifts moves the pair
  // back by it after integration, which makes an isolated collision exact in both.
  template <bool kRotation>
  void ApplyRestitution(Bodies& bodies, Real threshold) {
    for (ContactConstraint& cc : constraints_) {
      if (cc.restitution == 0) continue;
      for (int k = 0; k < cc.pointCount; ++k) {
        PointConstraint& pc = cc.points[k];
        // Only points that approached fast enough and actually pushed bounce.
        if (pc.relativeVelocity > -threshold || pc.normalImpulse == 0) continue;
        const Real vn = Dot(RelativeVelocity<kRotation>(bodies.vel[cc.a], bodies.vel[cc.b], pc), cc.normal);
        const Real target = -cc.restitution * pc.relativeVelocity;
        const Real newImpulse = std::max(pc.normalImpulse - pc.normalMass * (vn - target), Real(0));
        const Real lambda = newImpulse - pc.normalImpulse;
        pc.normalImpulse = newImpulse;
        ApplyImpulse<kRotation>(bodies, cc, pc, lambda * cc.normal);
        if (pc.separation > 0) {
          pc.bounceShift = (Real(1) + cc.restitution) * pc.separation;
          hasBounceShift_ = true;
        }
      }
    }
  }

  // Moves each pair that bounced early back together along the normal by its recorded
  // distance, split by inverse mass (the linear part only: enough for the bounce, and it cannot
  // spin a body). Only bodies that move are touched.
  void ApplyBounceShifts(Bodies& bodies) {
    for (const ContactConstraint& cc : constraints_) {
      Real shift = 0;
      for (int k = 0; k < cc.pointCount; ++k) shift = std::max(shift, cc.points[k].bounceShift);
      const Real sum = cc.invMassA + cc.invMassB;
      if (shift == 0 || sum == 0) continue;
      const Vec2 d = (shift / sum) * cc.normal;
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

  void StoreImpulses(std::span<Contact> contacts) const {
    for (size_t c = 0; c < contacts.size(); ++c) {
      for (int k = 0; k < constraints_[c].pointCount; ++k) {
        contacts[c].manifold.points[k].normalImpulse = constraints_[c].points[k].normalImpulse;
        contacts[c].manifold.points[k].tangentImpulse = constraints_[c].points[k].tangentImpulse;
      }
    }
  }

  void Snapshot(const Bodies& bodies) {
    center0_ = bodies.center;
    rot0_.resize(bodies.xf.size());
    for (size_t i = 0; i < bodies.xf.size(); ++i) rot0_[i] = bodies.xf[i].q;
  }

  // One non-linear Gauss-Seidel pass: the separation is re-evaluated from how far the bodies
  // have moved and turned since the manifold was computed, and the position error beyond the
  // slop is reduced by the Baumgarte fraction, at most maxLinearCorrection at a time.
  template <bool kRotation>
  void SolvePositions(Bodies& bodies, const WorldDef& def) {
    for (const ContactConstraint& cc : constraints_) {
      const Vec2 n = cc.normal;
      for (int k = 0; k < cc.pointCount; ++k) {
        const PointConstraint& pc = cc.points[k];
        Vec2 rA = pc.rA, rB = pc.rB;
        if constexpr (kRotation) {
          rA = Rotate(InvMul(rot0_[cc.a], bodies.xf[cc.a].q), pc.rA);
          rB = Rotate(InvMul(rot0_[cc.b], bodies.xf[cc.b].q), pc.rB);
        }
        const Vec2 d = (bodies.center[cc.b] - center0_[cc.b]) - (bodies.center[cc.a] - center0_[cc.a]) +
                       (rB - pc.rB) - (rA - pc.rA);
        const Real s = pc.separation + Dot(n, d);
        const Real C = std::clamp(def.baumgarte * (s + def.linearSlop), -def.maxLinearCorrection, Real(0));
        if (C == 0) continue;
        Real K = cc.invMassA + cc.invMassB;
        if constexpr (kRotation) {
          const Real rnA = Cross(rA, n), rnB = Cross(rB, n);
          K += cc.invIA * rnA * rnA + cc.invIB * rnB * rnB;
        }
        if (K <= 0) continue;
        const Vec2 P = (-C / K) * n;
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
  }

  std::vector<ContactConstraint> constraints_;
  bool hasBounceShift_ = false;
  std::vector<Vec2> center0_;
  std::vector<Rot> rot0_;
};

}  // namespace

std::unique_ptr<Solver> MakePgsSolver() { return std::make_unique<PgsSolver>(); }

std::unique_ptr<Solver> MakeSolver(SolverType type) {
  switch (type) {
    case SolverType::kThesis: return MakeThesisSolver();
    case SolverType::kPgs: return MakePgsSolver();
  }
  return MakePgsSolver();
}

}  // namespace quadrant
