// A world the API accepts stays finite: random worlds at the extremes CreateBody allows (39 bodies
// over +-1000 m, sizes 5 mm to 5 km, densities 1e-6 to 1e6 kg/m^2, speeds to 50 m/s, spins to
// 100 rad/s, restitution and friction 0..1, a tenth kinematic), stepped 120 times on each broad
// phase and on 1 and 2 threads. Any non-finite position, angle or velocity fails.
//
// Two rules keep them finite, and these cases fail without them: soft_step does not warm-start a
// contact over its mass-ratio limit whose light body lost its support (soft_step_rows.cpp,
// LaneEnds::kCold; without it 66 of 300 worlds went non-finite), and pgs keeps no warm start for a
// contact with a body over the speed limit (ContactConstraints::StoreImpulsesWithinSpeedLimit;
// without it 2 of 300 overflowed, squeezed between static and kinematic bodies).
#include <cmath>
#include <random>
#include <string>

#include "test_helpers.h"

namespace quadrant::test {
namespace {

double LogUniform(std::mt19937_64& rng, double lo, double hi) {
  std::uniform_real_distribution<double> u(std::log(lo), std::log(hi));
  return std::exp(u(rng));
}

// Builds world `seed` into `world`; bodies CreateBody refuses are skipped (the fuzz of the
// refusals themselves is tests/adapters/fuzz_validation_test.cpp).
void BuildExtremeWorld(World& world, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < 39; ++i) {
    BodyDef b;
    b.type = i == 0 ? BodyType::kStatic : (u(rng) < 0.1 ? BodyType::kKinematic : BodyType::kDynamic);
    b.position = {Real((u(rng) * 2 - 1) * 1000), Real((u(rng) * 2 - 1) * 1000)};
    b.angle = Real(u(rng) * 6.28);
    b.linearVelocity = {Real((u(rng) * 2 - 1) * 50), Real((u(rng) * 2 - 1) * 50)};
    b.angularVelocity = Real((u(rng) * 2 - 1) * 100);
    const double size = LogUniform(rng, 0.005, 5000);
    if (u(rng) < 0.5) {
      b.shape = ShapeDef::MakeCircle(Real(size));
    } else {
      b.shape = ShapeDef::Box(Real(size), Real(LogUniform(rng, 0.005, 5000)));
    }
    b.shape.density = Real(LogUniform(rng, 1e-6, 1e6));
    b.shape.restitution = Real(u(rng));
    b.shape.friction = Real(u(rng));
    if (b.type == BodyType::kStatic) {
      b.linearVelocity = {};
      b.angularVelocity = 0;
    }
    try {
      world.CreateBody(b);
    } catch (const Error&) {
    }
  }
}

// The first step at which some body is not finite, or -1.
int FirstNonFiniteStep(World& world, int steps) {
  for (int s = 0; s < steps; ++s) {
    world.Step(kDt);
    for (BodyId id : world.GetBodyIds()) {
      const Vec2 p = world.GetPosition(id), v = world.GetLinearVelocity(id);
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(v.x) || !std::isfinite(v.y) ||
          !std::isfinite(world.GetAngle(id)) || !std::isfinite(world.GetAngularVelocity(id))) {
        return s;
      }
    }
  }
  return -1;
}

struct ExtremeCase {
  SolverType solver;
  BroadPhaseType broadPhase;
  int threads;
  std::string name;
};

class ExtremeWorlds : public ::testing::TestWithParam<ExtremeCase> {};

TEST_P(ExtremeWorlds, StayFinite) {
  const ExtremeCase& c = GetParam();
  constexpr int kWorlds = 60, kSteps = 120;
  int bad = 0;
  std::string first;
  for (int w = 0; w < kWorlds; ++w) {
    WorldDef def;
    def.solver = c.solver;
    def.broadPhase = c.broadPhase;
    def.threadCount = c.threads;
    def.minParallelItems = 4;  // 39 bodies: exercise the partition
    World world(def);
    BuildExtremeWorld(world, 1000 + uint64_t(w));
    const int step = FirstNonFiniteStep(world, kSteps);
    if (step >= 0 && bad++ == 0) first = "world " + std::to_string(w) + " at step " + std::to_string(step);
  }
  EXPECT_EQ(bad, 0) << bad << " of " << kWorlds << " worlds turned non-finite, first: " << first;
}

INSTANTIATE_TEST_SUITE_P(
    Solvers, ExtremeWorlds,
    ::testing::Values(ExtremeCase{SolverType::kSoftStep, BroadPhaseType::kUniformGrid, 1, "soft_step_grid_1"},
                      ExtremeCase{SolverType::kSoftStep, BroadPhaseType::kQuadTree, 1, "soft_step_quadtree_1"},
                      ExtremeCase{SolverType::kSoftStep, BroadPhaseType::kUniformGrid, 2, "soft_step_grid_2"},
                      ExtremeCase{SolverType::kPgs, BroadPhaseType::kQuadTree, 1, "pgs_quadtree_1"},
                      ExtremeCase{SolverType::kPgs, BroadPhaseType::kUniformGrid, 2, "pgs_grid_2"},
                      ExtremeCase{SolverType::kThesis, BroadPhaseType::kUniformGrid, 1, "thesis_grid_1"},
                      ExtremeCase{SolverType::kJacobi, BroadPhaseType::kQuadTree, 2, "jacobi_quadtree_2"}),
    [](const ::testing::TestParamInfo<ExtremeCase>& info) { return info.param.name; });

}  // namespace
}  // namespace quadrant::test
