// The Jacobi solver in the single-process World: jacobi_solve.h's phases back to back, on the
// calling thread (its result is the same for any thread count because it is serial; the
// distributed world splits the same phases among processes instead).
#include "dynamics/jacobi_solve.h"
#include "dynamics/solver.h"
#include "parallel/stage_clock.h"

namespace quadrant {
namespace {

using Clock = StageClock;

class JacobiSolver final : public Solver {
 public:
  const char* Name() const override { return "jacobi"; }

  void Step(StepContext& ctx) override {
    const WorldDef& def = *ctx.def;
    Bodies& bodies = *ctx.bodies;
    const auto t0 = Clock::now();
    IntegrateVelocities(bodies, def, ctx.dt, *ctx.run);
    const auto t1 = Clock::now();
    ctx.run->Serial(Stage::kSolve, [&] {
      solve_.Begin(bodies, def, ctx.dt, ctx.contacts);
      solve_.Prepare(def);
      for (int it = 0; it < def.velocityIterations; ++it) solve_.Iterate(bodies, def);
    });
    const auto t2 = Clock::now();
    solve_.Finish(bodies, def, ctx.dt, ctx.contacts, *ctx.run);
    ctx.profile->solve += Ms(t1, t2);
    ctx.profile->integrate += Ms(t0, t1) + Ms(t2, Clock::now());
  }

 private:
  JacobiSolve solve_;
};

}  // namespace

std::unique_ptr<Solver> MakeJacobiSolver() { return std::make_unique<JacobiSolver>(); }

}  // namespace quadrant
