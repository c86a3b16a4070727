// Soft step: sub-stepping with soft contacts and relaxation (Box2D 3's family; Catto,
// "Solver2D", 2024). Per step the contacts are found once; then, for each of N sub-steps of
// h = dt/N: gravity, warm start, one soft solve (contacts act as stiff damped springs:
// penetration is pushed out at a bounded speed instead of by an impulse that adds velocity),
// position integration, and one relax solve (the same rows with no bias, removing the push-out
// velocity). Restitution comes first, as pairwise collisions before the sub-steps (shared with
// pgs: ApplyCollisions in contact_solver.h); the early-bounce shifts follow the last sub-step.
//
// Why: many small steps converge where many iterations of one big step do not (Macklin et al.
// 2019, "Small steps in physics simulation"), which is what stacks and large mass ratios need.
// The separation of each point is re-evaluated every sub-step from how far its bodies moved.
//
// Why restitution comes first: applied after the sub-steps from the pre-step approach speed
// (Box2D 3's way) it gained energy here (elastic polygon stress +63 % kinetic energy; the
// 3000-step soak ended with 56 bodies out of the box).
//
// Deep overlap: a contact point is soft only down to contactPushMaxDepth (0.01 m) of
// penetration. A deeper point is a rigid row (full mass: it holds whatever load it carries, as
// pgs's rows do) whose push-out bias is the one a soft point has at that depth; the rest of the
// overlap is moved out after the sub-steps by pgs's position pass (SolvePositions), which changes
// positions, not velocities. Pushed out entirely by velocity, a row of overlapping bodies added
// up the push speeds of its contacts, which the relax pass cannot take back (overlap_recovery
// 10.8 m/s, confined 15.6 m/s; 2 allowed; now 1.32 and 1.54). A soft deep point with only its
// bias capped would cap the load it holds too: at 4 sub-steps the 100 kg box of mass_ratio_100
// fell through the pyramid. docs/soft_step.md gives the figures of every variant measured.
//
// Heavy loads sag: a soft contact is a spring of stiffness m_eff (2 pi contactHertz)^2 and sags
// by load / stiffness whatever the sub-step (1000 N on a 1 kg box's corner at 30 Hz: 0.071 m).
// The Quadrant adapter turns a scene's larger solver budget into more sub-steps with the
// stiffness scaled along (quadrant_adapter.cpp says why).
#include <cmath>
#include <numbers>

#include "contact_solver.h"

namespace quadrant {
namespace {

using Clock = SolverClock;

// Soft constraint coefficients for a spring of `hertz` and damping ratio `zeta` over step h:
// the bias velocity is biasRate * C, and massScale / impulseScale soften the impulse.
struct Softness {
  Real biasRate = 0;
  Real massScale = 1;
  Real impulseScale = 0;
};

Softness MakeSoftness(Real hertz, Real zeta, Real h) {
  if (hertz <= 0) return {};
  const Real omega = 2 * std::numbers::pi_v<Real> * hertz;
  const Real a1 = 2 * zeta + h * omega;
  const Real a2 = h * omega * a1;
  const Real a3 = Real(1) / (Real(1) + a2);
  return {omega / a1, a2 * a3, a3};
}

class SoftStepSolver final : public ContactSolverBase {
 public:
  const char* Name() const override { return "soft_step"; }

  void Step(StepContext& ctx) override {
    const Effects& fx = ctx.def->effects;
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
    StageRunner& run = *ctx.run;
    const int n = def.softSubSteps;
    const Real h = ctx.dt / Real(n);
    const Real invH = Real(1) / h;
    // Stiffer than the sub-step can resolve is unstable: at most a quarter of its rate.
    const Real hertz = std::min(def.contactHertz, Real(0.25) * invH);
    const Softness soft = MakeSoftness(hertz, def.contactDampingRatio, h);
    // Contacts with a static body hold twice as stiff: nothing on the other side gives way.
    const Softness staticSoft = MakeSoftness(2 * hertz, def.contactDampingRatio, h);

    double integrateMs = 0;
    auto t0 = Clock::now();
    Color(run, ctx);
    const int m = static_cast<int>(constraints_.size());
    run.For(Stage::kSolve, m, run.MinHeavyItems(), [&](int b, int e, int) { Prepare<kRotation>(ctx, b, e); });
    SnapshotPositions(run, bodies);
    if (def.effects.restitution) {
      const Vec2 stepGravity = def.effects.gravity ? ctx.dt * def.gravity : Vec2{};
      ApplyCollisionPasses<kRotation>(run, bodies, def, Real(1) / ctx.dt, stepGravity);
    }
    // The sub-steps run on the compact solver state (velocity and motion since the step began,
    // 32 bytes a body), not on the body arrays: a row reads two states and nothing else.
    auto ti = Clock::now();
    LoadStates(run, bodies);
    integrateMs += Ms(ti, Clock::now());
    for (int sub = 0; sub < n; ++sub) {
      ti = Clock::now();
      IntegrateStateVelocities(run, bodies, def, h);
      integrateMs += Ms(ti, Clock::now());
      if (def.effects.warmStarting) ForEachColor(run, [&](int b, int e) { WarmStartStates<kRotation>(b, e); });
      ForEachColor(run, [&](int b, int e) { Solve<kRotation, kFriction, true>(def, soft, staticSoft, invH, b, e); });
      ti = Clock::now();
      // The rotation guard is per world step: per sub-step it allowed n times the turn (188 rad/s
      // instead of 47 at 4 sub-steps), and spinning triangles of the soak left the box.
      IntegrateStatePositions(run, bodies, def, h, ctx.dt);
      integrateMs += Ms(ti, Clock::now());
      ForEachColor(run, [&](int b, int e) { Solve<kRotation, kFriction, false>(def, soft, staticSoft, invH, b, e); });
    }
    ti = Clock::now();
    StoreStates(run, bodies, def);
    integrateMs += Ms(ti, Clock::now());
    if (def.effects.restitution && m > 0) ForEachColor(run, [&](int b, int e) { ApplyBounceShifts(bodies, b, e); });
    // Overlap deeper than the soft contacts push out (contactPushMaxDepth) is moved out here, by pgs's
    // position pass: positions change, velocities do not, so deep overlap cannot fling bodies.
    if (m > 0) CorrectPositions<kRotation>(run, bodies, def, def.contactPushMaxDepth, def.positionIterations);
    run.For(Stage::kSolve, m, run.MinHeavyItems(), [&](int b, int e, int) { StoreImpulses(ctx.contacts, b, e); });
    const double total = Ms(t0, Clock::now());
    ctx.profile->integrate += integrateMs;
    ctx.profile->solve += total - integrateMs;
  }

  // One pass over the rows: with kBias the soft solve (push-out toward zero separation at a
  // bounded speed), without it the relax pass (rigid rows, no bias). Speculative points (still
  // apart) may close their gap within the sub-step, no more, in both passes.
  //
  // Friction is solved in the relax pass only (as Box2D 3 does since it split its push stage):
  // during the soft solve the velocities still carry the push-out the relax pass removes and the
  // normal impulse its soft bias, so a friction row there resists a sliding that is not real
  // and is bounded by a load that is not real, and the warm start carries its impulse into the
  // next sub-step. With friction in both passes the 15-box stack's top crept 0.014 m in 9 s and
  // slowly toppled (worse at 8 and 16 sub-steps, with less numerical damping: 0.14-0.17 m); with
  // friction in the relax pass only it moves 0.0003 m.
  template <bool kRotation, bool kFriction, bool kBias>
  void Solve(const WorldDef& def, const Softness& soft, const Softness& staticSoft, Real invH, int begin, int end) {
    for (int c = begin; c < end; ++c) {
      ContactConstraint& cc = constraints_[c];
      const Vec2 n = cc.normal;
      SolverBody& sa = states_[cc.a];
      SolverBody& sb = states_[cc.b];
      Vec2 vA = sa.v, vB = sb.v;
      Real wA = sa.w, wB = sb.w;
      // Motion since the step began: the separation of a point is its prepared one plus the
      // normal part of how far its two anchors moved apart.
      const Vec2 dp = sb.dp - sa.dp;
      const Rot qA = sa.dq, qB = sb.dq;
      const Softness& s = (cc.invMassA == 0 || cc.invMassB == 0) ? staticSoft : soft;
      auto apply = [&](const PointConstraint& pc, Vec2 P) {
        vA -= cc.invMassA * P;
        vB += cc.invMassB * P;
        if constexpr (kRotation) {
          wA -= cc.invIA * Cross(pc.rA, P);
          wB += cc.invIB * Cross(pc.rB, P);
        }
      };
      auto relative = [&](const PointConstraint& pc) {
        Vec2 dv = vB - vA;
        if constexpr (kRotation) dv += Cross(wB, pc.rB) - Cross(wA, pc.rA);
        return dv;
      };
      for (int k = 0; k < cc.pointCount; ++k) {
        PointConstraint& pc = cc.points[k];
        Vec2 d = dp;
        if constexpr (kRotation) d += (Rotate(qB, pc.rB) - pc.rB) - (Rotate(qA, pc.rA) - pc.rA);
        const Real sep = pc.separation + Dot(n, d);
        Real bias = 0, massScale = 1, impulseScale = 0;
        if (sep > 0) {
          bias = sep * invH;
        } else if constexpr (kBias) {
          if (sep >= -def.contactPushMaxDepth) {
            bias = std::max(s.biasRate * sep, -def.contactPushMaxVelocity);
            massScale = s.massScale;
            impulseScale = s.impulseScale;
          } else {
            // Deeper than the cap: a rigid row (holds any load) pushing apart at the cap's rate;
            // the rest of the overlap is left to the position pass after the sub-steps.
            bias = std::max(-s.biasRate * def.contactPushMaxDepth, -def.contactPushMaxVelocity);
          }
        }
        const Real vn = Dot(relative(pc), n);
        const Real impulse = -pc.normalMass * massScale * (vn + bias) - impulseScale * pc.normalImpulse;
        const Real newImpulse = std::max(pc.normalImpulse + impulse, Real(0));
        const Real lambda = newImpulse - pc.normalImpulse;
        pc.normalImpulse = newImpulse;
        apply(pc, lambda * n);
      }
      if constexpr (kFriction && !kBias) {
        const Vec2 t = RightPerp(n);
        for (int k = 0; k < cc.pointCount; ++k) {
          PointConstraint& pc = cc.points[k];
          const Real vt = Dot(relative(pc), t);
          const Real maxFriction = cc.friction * pc.normalImpulse;
          const Real newImpulse = std::clamp(pc.tangentImpulse - pc.tangentMass * vt, -maxFriction, maxFriction);
          const Real lambda = newImpulse - pc.tangentImpulse;
          pc.tangentImpulse = newImpulse;
          apply(pc, lambda * t);
        }
      }
      // Static and kinematic bodies (inverse mass 0) are never written: other threads may be
      // reading them for constraints of the same colour.
      if (cc.invMassA > 0) {
        sa.v = vA;
        sa.w = wA;
      }
      if (cc.invMassB > 0) {
        sb.v = vB;
        sb.w = wB;
      }
    }
  }

  template <bool kRotation>
  void WarmStartStates(int begin, int end) {
    for (int c = begin; c < end; ++c) {
      const ContactConstraint& cc = constraints_[c];
      const Vec2 t = RightPerp(cc.normal);
      SolverBody& sa = states_[cc.a];
      SolverBody& sb = states_[cc.b];
      for (int k = 0; k < cc.pointCount; ++k) {
        const PointConstraint& pc = cc.points[k];
        const Vec2 P = pc.normalImpulse * cc.normal + pc.tangentImpulse * t;
        if (cc.invMassA > 0) {
          sa.v -= cc.invMassA * P;
          if constexpr (kRotation) sa.w -= cc.invIA * Cross(pc.rA, P);
        }
        if (cc.invMassB > 0) {
          sb.v += cc.invMassB * P;
          if constexpr (kRotation) sb.w += cc.invIB * Cross(pc.rB, P);
        }
      }
    }
  }

  // The solver state of every body: its velocity (after the restitution passes), no motion yet.
  void LoadStates(StageRunner& run, const Bodies& bodies) {
    states_.resize(bodies.Count());
    run.For(Stage::kIntegrate, bodies.Count(), run.MinItems(), [&](int b, int e, int) {
      for (int i = b; i < e; ++i) states_[i] = SolverBody{bodies.vel[i].v, bodies.vel[i].w, 0, Vec2{}, Rot{}};
    });
  }

  // Gravity and damping over a sub-step, as IntegrateVelocities does on the bodies: for bodies
  // with an inverse mass (dynamic and awake; a sleeping body has inverse mass 0).
  void IntegrateStateVelocities(StageRunner& run, const Bodies& bodies, const WorldDef& def, Real h) {
    const Effects& fx = def.effects;
    if (!fx.gravity && !fx.damping) return;
    const Vec2 dv = fx.gravity ? h * def.gravity : Vec2{};
    run.For(Stage::kIntegrate, bodies.Count(), run.MinItems(), [&](int b, int e, int) {
      for (int i = b; i < e; ++i) {
        if (bodies.inv[i].invMass == 0) continue;
        SolverBody& st = states_[i];
        st.v += dv;
        if (fx.damping) {
          st.v = (Real(1) / (Real(1) + h * bodies.linearDamping[i])) * st.v;
          st.w *= Real(1) / (Real(1) + h * bodies.angularDamping[i]);
        }
      }
    });
  }

  // Motion over a sub-step, with integrate.cpp's guards (speed limit; the turn limit per world
  // step stepDt). Every moving body (dynamic awake or kinematic) moves; static ones stay.
  void IntegrateStatePositions(StageRunner& run, const Bodies& bodies, const WorldDef& def, Real h, Real stepDt) {
    const Real maxSpeed2 = def.maxLinearSpeed * def.maxLinearSpeed;
    const Real maxAngularSpeed = def.maxRotation / stepDt;
    const bool rotation = def.effects.rotation, sleep = def.effects.sleep;
    run.For(Stage::kIntegrate, bodies.Count(), run.MinItems(), [&](int b, int e, int) {
      for (int i = b; i < e; ++i) {
        if (sleep ? bodies.awake[i] == 0 : bodies.type[i] == BodyType::kStatic) continue;
        SolverBody& st = states_[i];
        const Real speed2 = LengthSquared(st.v);
        if (speed2 > maxSpeed2) st.v = (def.maxLinearSpeed / std::sqrt(speed2)) * st.v;
        st.w = std::clamp(st.w, -maxAngularSpeed, maxAngularSpeed);
        st.dp += h * st.v;
        if (rotation && st.w != 0) st.dq = IntegrateRot(st.dq, h * st.w);
      }
    });
  }

  // Back to the bodies: velocity, centre (where the step began plus the motion) and rotation.
  void StoreStates(StageRunner& run, Bodies& bodies, const WorldDef& def) {
    const bool sleep = def.effects.sleep;
    run.For(Stage::kIntegrate, bodies.Count(), run.MinItems(), [&](int b, int e, int) {
      for (int i = b; i < e; ++i) {
        if (sleep ? bodies.awake[i] == 0 : bodies.type[i] == BodyType::kStatic) continue;
        const SolverBody& st = states_[i];
        bodies.vel[i] = BodyVelocity{st.v, st.w};
        bodies.center[i] = center0_[i] + st.dp;
        if (st.dq.s != 0 || st.dq.c != 1) {
          const Rot q = Mul(rot0_[i], st.dq);
          const Real inv = Real(1) / std::sqrt(q.c * q.c + q.s * q.s);
          bodies.xf[i].q = {q.c * inv, q.s * inv};
        }
        SyncTransform(bodies, i);
      }
    });
  }

  std::vector<SolverBody> states_;
};

}  // namespace

std::unique_ptr<Solver> MakeSoftStepSolver() { return std::make_unique<SoftStepSolver>(); }

}  // namespace quadrant
