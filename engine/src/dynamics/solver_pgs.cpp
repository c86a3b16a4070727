// Projected Gauss-Seidel over contact impulses (sequential impulses, Box2D 2.4's family).
//
// Per step: gravity, prepare constraints, warm start, restitution as pairwise collisions,
// N velocity iterations (friction then normal, accumulated impulses clamped), position
// integration, then a
// position pass (non-linear Gauss-Seidel on the linearised separation, with slop and a
// Baumgarte factor) that removes penetration without adding velocity.
//
// Contacts are speculative: a point that is still apart by s may close at most s this step
// (the normal row targets vn >= -s/dt), so fast bodies stop at the surface instead of passing
// through it. A speculative point that will close its gap this step collides now (and is moved
// back by the distance it bounced early, after integration): a bounce then does not depend on
// the step at which the gap closed, which keeps restitution-1 scenes from losing energy.
// Collisions are applied pair by pair before the iterations (ApplyCollisions in
// contact_constraints.h says why: Newton's cradle).
//
// The kernels are templates on the effects (rotation, friction): a world with an effect off
// runs a path without its rows or terms instead of multiplying them by zero.
//
// Colouring (constraint_graph.h), and preparation, warm starting, the collisions, the position
// pass and the row kernels (contact_constraints.h) are shared with soft_step: components each
// solver holds.
#include "dynamics/constraint_graph.h"
#include "dynamics/contact_constraints.h"

namespace quadrant {
namespace {

using Clock = StageClock;

class PgsSolver final : public Solver {
 public:
  const char* Name() const override { return "pgs"; }

  void Step(StepContext& ctx) override {
    DispatchEffects(ctx.def->effects,
                    [&](auto rotation, auto friction) { Run<decltype(rotation)::value, decltype(friction)::value>(ctx); });
  }

 private:
  template <bool kRotation, bool kFriction>
  void Run(StepContext& ctx) {
    const WorldDef& def = *ctx.def;
    Bodies& bodies = *ctx.bodies;
    StageRunner& run = *ctx.run;
    const Real dt = ctx.dt;

    auto t0 = Clock::now();
    IntegrateVelocities(bodies, def, dt, run);
    auto t1 = Clock::now();

    graph_.Color(run, ctx);
    constraints_.Resize(graph_.Count());
    const int m = constraints_.Size();
    run.For(Stage::kSolve, m, run.MinHeavyItems(),
            [&](int b, int e, int) { constraints_.Prepare<kRotation>(ctx, graph_, b, e); });
    if (def.effects.warmStarting) {
      graph_.ForEachColor(run, [&](int b, int e) { constraints_.WarmStart<kRotation>(bodies, b, e); });
    }
    const Real invDt = Real(1) / dt;
    const bool collisions = def.effects.restitution && def.restitution == RestitutionPolicy::kCollisions;
    if (collisions) constraints_.ApplyCollisionPasses<kRotation>(run, graph_, bodies, def, invDt, Vec2{});
    // Every iteration's colours in one region (ForEachColor): the same order of passes.
    graph_.ForEachColor(run, [&](int b, int e) { SolveVelocities<kRotation, kFriction>(bodies, invDt, b, e); },
                 def.velocityIterations);
    const Real maxSpeed2 = def.maxLinearSpeed * def.maxLinearSpeed;
    run.For(Stage::kSolve, m, run.MinHeavyItems(), [&](int b, int e, int) {
      constraints_.StoreImpulsesWithinSpeedLimit(ctx.contacts, bodies, maxSpeed2, b, e);
    });
    auto t2 = Clock::now();

    const bool correct = def.positionIterations > 0 && m > 0;
    if (correct) constraints_.SnapshotPositions(run, bodies);
    const bool box2dPositions = correct && def.box2dPositionSolve;
    if (box2dPositions) run.Serial(Stage::kSolve, [&] { constraints_.SnapshotBox2dGeometry(ctx); });
    IntegratePositions(bodies, def, dt, run);
    if (collisions && m > 0) {
      graph_.ForEachColor(run, [&](int b, int e) { constraints_.ApplyBounceShifts(bodies, b, e); });
    }
    auto t3 = Clock::now();
    if (box2dPositions) {
      run.Serial(Stage::kSolve, [&] { constraints_.CorrectPositionsBox2d<kRotation>(bodies, def, def.positionIterations); });
    } else if (correct) {
      constraints_.CorrectPositions<kRotation>(run, graph_, bodies, def, def.linearSlop, def.positionIterations);
    }
    auto t4 = Clock::now();
    ctx.profile->integrate += Ms(t0, t1) + Ms(t2, t3);
    ctx.profile->solve += Ms(t1, t2) + Ms(t3, t4);
  }

  template <bool kRotation, bool kFriction>
  void SolveVelocities(Bodies& bodies, Real invDt, int begin, int end) {
    for (int c = begin; c < end; ++c) {
      ContactConstraint& cc = constraints_[c];
      const Vec2 n = cc.normal;
      BodyVelocity va = bodies.vel[cc.a];
      BodyVelocity vb = bodies.vel[cc.b];
      if constexpr (kFriction) {
        const Vec2 t = RightPerp(n);
        for (int k = 0; k < cc.pointCount; ++k) {
          PointConstraint& pc = cc.points[k];
          pc.tangentImpulse = SolveFrictionRow<kRotation>(cc, pc, t, pc.tangentImpulse,
                                                          pc.normalImpulse + pc.collisionImpulse, va, vb);
        }
      }
      if (cc.block) {
        SolveBlock<kRotation>(cc, va, vb, invDt);
      } else {
        for (int k = 0; k < cc.pointCount; ++k) {
          PointConstraint& pc = cc.points[k];
          const Real vn = Dot(RelativeVelocity<kRotation>(va, vb, pc), n);
          // Speculative: a gap s may close this step, no more (target vn >= -s/dt); or the
          // restitution bias of RestitutionPolicy::kBox2d (restitution_policy.h).
          const Real offset = NormalRowOffset(pc.separation, pc.restitutionBias, invDt);
          const Real newImpulse = std::max(pc.normalImpulse - pc.normalMass * (vn + offset), Real(0));
          const Real lambda = newImpulse - pc.normalImpulse;
          pc.normalImpulse = newImpulse;
          ApplyPointImpulse<kRotation>(cc, pc, lambda * n, va, vb);
        }
      }
      if (cc.invMassA > 0) bodies.vel[cc.a] = va;
      if (cc.invMassB > 0) bodies.vel[cc.b] = vb;
    }
  }

  // The two normal rows of a two-point manifold solved together, as a 2x2 linear
  // complementarity problem (Box2D 2.4's block solver): find impulses x >= 0 with velocities
  // w = K x + b >= 0 and x_i w_i = 0, by trying the four cases (both active, one, the other,
  // none). Solving the pair exactly instead of one row after the other removes the rocking
  // that lets a stack creep sideways.
  //
  // Always inlined: it is the inner loop of the velocity iterations, and GCC's own heuristics
  // stopped inlining it (and SolveLcp2 in it) when this file grew by a few shared helpers:
  // +4.6 % instructions on the base-20 pyramid (icount), all of it calls in this loop.
  template <bool kRotation>
  [[gnu::always_inline]] static void SolveBlock(ContactConstraint& cc, BodyVelocity& va, BodyVelocity& vb,
                                                Real invDt) {
    PointConstraint& p0 = cc.points[0];
    PointConstraint& p1 = cc.points[1];
    const Vec2 n = cc.normal;
    const Real k11 = Real(1) / p0.normalMass, k22 = Real(1) / p1.normalMass, k12 = cc.k12;
    const Real a0 = p0.normalImpulse, a1 = p1.normalImpulse;
    const Real gap0 = NormalRowOffset(p0.separation, p0.restitutionBias, invDt);
    const Real gap1 = NormalRowOffset(p1.separation, p1.restitutionBias, invDt);
    // b = current velocity (plus allowed gap closing) minus what the accumulated impulses did.
    const Real b0 = Dot(RelativeVelocity<kRotation>(va, vb, p0), n) + gap0 - (k11 * a0 + k12 * a1);
    const Real b1 = Dot(RelativeVelocity<kRotation>(va, vb, p1), n) + gap1 - (k12 * a0 + k22 * a1);
    Real x0, x1;
    if (!SolveLcp2(k11, k12, k22, b0, b1, x0, x1)) return;  // no case fits: keep the old impulses
    const Vec2 P0 = (x0 - a0) * n, P1 = (x1 - a1) * n;
    va.v -= cc.invMassA * (P0 + P1);
    vb.v += cc.invMassB * (P0 + P1);
    if constexpr (kRotation) {
      va.w -= cc.invIA * (Cross(p0.rA, P0) + Cross(p1.rA, P1));
      vb.w += cc.invIB * (Cross(p0.rB, P0) + Cross(p1.rB, P1));
    }
    p0.normalImpulse = x0;
    p1.normalImpulse = x1;
  }

  ConstraintGraph graph_;
  ContactConstraints constraints_;
};

}  // namespace

std::unique_ptr<Solver> MakePgsSolver() { return std::make_unique<PgsSolver>(); }

std::unique_ptr<Solver> MakeSolver(SolverType type) {
  switch (type) {
    case SolverType::kThesis: return MakeThesisSolver();
    case SolverType::kPgs: return MakePgsSolver();
    case SolverType::kSoftStep: return MakeSoftStepSolver();
    case SolverType::kJacobi: return MakeJacobiSolver();
  }
  return MakePgsSolver();
}

}  // namespace quadrant
