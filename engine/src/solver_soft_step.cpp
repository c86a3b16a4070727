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
    for (int sub = 0; sub < n; ++sub) {
      auto ti = Clock::now();
      IntegrateVelocities(bodies, def, h, run);
      integrateMs += Ms(ti, Clock::now());
      if (def.effects.warmStarting) ForEachColor(run, [&](int b, int e) { WarmStart<kRotation>(bodies, b, e); });
      ForEachColor(run, [&](int b, int e) { Solve<kRotation, kFriction, true>(bodies, def, soft, staticSoft, invH, b, e); });
      ti = Clock::now();
      // The rotation guard is per world step: per sub-step it allowed n times the turn (188 rad/s
      // instead of 47 at 4 sub-steps), and spinning triangles of the soak left the box.
      IntegratePositions(bodies, def, h, ctx.dt, run);
      integrateMs += Ms(ti, Clock::now());
      ForEachColor(run, [&](int b, int e) { Solve<kRotation, kFriction, false>(bodies, def, soft, staticSoft, invH, b, e); });
    }
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
  void Solve(Bodies& bodies, const WorldDef& def, const Softness& soft, const Softness& staticSoft, Real invH,
             int begin, int end) {
    for (int c = begin; c < end; ++c) {
      ContactConstraint& cc = constraints_[c];
      const Vec2 n = cc.normal;
      BodyVelocity va = bodies.vel[cc.a];
      BodyVelocity vb = bodies.vel[cc.b];
      const Softness& s = (cc.invMassA == 0 || cc.invMassB == 0) ? staticSoft : soft;
      auto apply = [&](const PointConstraint& pc, Vec2 P) {
        va.v -= cc.invMassA * P;
        vb.v += cc.invMassB * P;
        if constexpr (kRotation) {
          va.w -= cc.invIA * Cross(pc.rA, P);
          vb.w += cc.invIB * Cross(pc.rB, P);
        }
      };
      for (int k = 0; k < cc.pointCount; ++k) {
        PointConstraint& pc = cc.points[k];
        Vec2 rA, rB;
        const Real sep = CurrentSeparation<kRotation>(bodies, cc, pc, rA, rB);
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
        const Real vn = Dot(RelativeVelocity<kRotation>(va, vb, pc), n);
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
          const Real vt = Dot(RelativeVelocity<kRotation>(va, vb, pc), t);
          // Coulomb over the whole impact, as pgs: the step's collision impulse (ApplyCollisions)
          // counts. Bounded by the sub-steps' normal impulse alone, a bouncing hit got almost no
          // friction: the random campaign's p90 difference to Box2D was 49 %, now 9.5 %
          // (2000 hits, seed 17; README "validation").
          const Real maxFriction = cc.friction * (pc.normalImpulse + pc.collisionImpulse);
          const Real newImpulse = std::clamp(pc.tangentImpulse - pc.tangentMass * vt, -maxFriction, maxFriction);
          const Real lambda = newImpulse - pc.tangentImpulse;
          pc.tangentImpulse = newImpulse;
          apply(pc, lambda * t);
        }
      }
      if (cc.invMassA > 0) bodies.vel[cc.a] = va;
      if (cc.invMassB > 0) bodies.vel[cc.b] = vb;
    }
  }
};

}  // namespace

std::unique_ptr<Solver> MakeSoftStepSolver() { return std::make_unique<SoftStepSolver>(); }

}  // namespace quadrant
