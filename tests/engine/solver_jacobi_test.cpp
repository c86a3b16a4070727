// The Jacobi solver (SolverType::kJacobi, engine/src/dynamics/jacobi_solve.h) in the single-process World:
// the solver of the distributed world, whose result must not depend on how work is split.
#include <gtest/gtest.h>

#include <cmath>

#include "quadrant/error.h"
#include "quadrant/world.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

using namespace test;

// A ball dropped on the ground comes to rest on it (the Baumgarte bias and speculative rows hold
// it), not sinking by more than the slop.
TEST(SolverJacobi, BallRestsOnGround) {
  WorldDef def;
  def.solver = SolverType::kJacobi;
  World world(def);
  AddGround(world);
  const BodyId ball = AddCircle(world, {0, 3});
  StepN(world, 180);
  EXPECT_NEAR(world.GetPosition(ball).y, 1.0, 0.01);
  EXPECT_NEAR(world.GetLinearVelocity(ball).y, 0.0, 0.01);
}

// A head-on elastic collision of equal circles exchanges their velocities (a two-body contact has
// split factor 1, so the Jacobi row is exactly the sequential one) and keeps momentum.
TEST(SolverJacobi, ElasticHeadOnExchangesVelocities) {
  World world(NoGravityDef(SolverType::kJacobi));
  const BodyId a = AddCircle(world, {-2, 0}, Real(0.5), {3, 0}, 1, 0, 1);
  const BodyId b = AddCircle(world, {2, 0}, Real(0.5), {-1, 0}, 1, 0, 1);
  StepN(world, 120);
  EXPECT_NEAR(world.GetLinearVelocity(a).x, -1.0, 1e-4);
  EXPECT_NEAR(world.GetLinearVelocity(b).x, 3.0, 1e-4);
}

// The solve is serial and in contact order: the state is the same bits for any thread count.
TEST(SolverJacobi, SameStateForAnyThreadCount) {
  uint64_t hashes[2] = {0, 0};
  for (int t = 0; t < 2; ++t) {
    WorldDef def;
    def.solver = SolverType::kJacobi;
    def.threadCount = t == 0 ? 1 : 4;
    def.minParallelItems = 16;  // make the broad and narrow phases split even this small scene
    World world(def);
    AddGround(world);
    for (int i = 0; i < 200; ++i) AddCircle(world, {Real(i % 20) - 10, Real(1 + i / 20)}, Real(0.45));
    StepN(world, 60);
    if (t == 1) {
      EXPECT_TRUE(ParallelSectionRan(world.GetProfile()));
    }
    hashes[t] = world.StateHash();
  }
  EXPECT_EQ(hashes[0], hashes[1]);
}

// Penetration is pushed out by split impulses (jacobi_solve.h), which move the bodies and leave
// their velocities alone (issue #26). Two circles at rest overlapping by 0.1 m, no gravity: a
// Baumgarte bias in the velocity rows sent them apart at about 1.1 m/s each (0.2 x 0.095 m over a
// step, shared), energy from the overlap; with the split impulses they stay at rest while the
// overlap shrinks.
TEST(SolverJacobi, OverlapIsPushedOutWithoutVelocity) {
  World world(NoGravityDef(SolverType::kJacobi));
  const BodyId a = AddCircle(world, {0, 0});
  const BodyId b = AddCircle(world, {Real(0.9), 0});
  StepN(world, 30);
  EXPECT_EQ(world.GetLinearVelocity(a).x, 0);
  EXPECT_EQ(world.GetLinearVelocity(b).x, 0);
  const double gap = double(world.GetPosition(b).x - world.GetPosition(a).x) - 1;
  EXPECT_GT(gap, -0.01);  // 0.1 m at the start, linearSlop 0.005 allowed
  EXPECT_LT(gap, 0);      // pushed out to the slop, not beyond
}

TEST(SolverJacobi, RefusedWithQuadrantsScheme) {
  WorldDef def;
  def.solver = SolverType::kJacobi;
  def.scheme = ParallelScheme::kQuadrants;
  def.threadCount = 2;
  EXPECT_THROW(World{def}, Error);
}

}  // namespace
}  // namespace quadrant
