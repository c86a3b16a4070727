// Restitution in the iterative solvers (restitution_policy.h, contact_constraints.h ApplyCollisions,
// soft_step_restitution.cpp ApplyBox2dRestitution): the bounce and the friction that goes with it, for
// both policies on pgs and soft_step, on single hits without gravity whose answers are known.
#include <gtest/gtest.h>

#include <cstdint>
#include <utility>

#include "test_helpers.h"

namespace quadrant::test {
namespace {

struct Solver {
  SolverType solver;
  RestitutionPolicy policy;
  const char* name;
};
const Solver kSolvers[] = {
    {SolverType::kPgs, RestitutionPolicy::kCollisions, "pgs"},
    {SolverType::kPgs, RestitutionPolicy::kBox2d, "pgs+kBox2d"},
    {SolverType::kSoftStep, RestitutionPolicy::kCollisions, "soft_step"},
    {SolverType::kSoftStep, RestitutionPolicy::kBox2d, "soft_step+kBox2d"},
};

World MakeWorld(const Solver& s) {
  WorldDef def = NoGravityDef(s.solver);
  def.restitution = s.policy;
  return World(def);
}

BodyId AddStaticGround(World& world, Real friction, Real restitution) {
  BodyDef g;
  g.type = BodyType::kStatic;
  g.shape = ShapeDef::Box(20, Real(0.5));
  g.shape.friction = friction;
  g.shape.restitution = restitution;
  return world.CreateBody(g);
}

TEST(RestitutionPolicyTest, HeadOnBounceIsEtimesTheApproach) {
  // A frictionless ball at 3 m/s onto the ground, e = 0.5: it leaves at 1.5 m/s, without spin.
  for (const Solver& s : kSolvers) {
    World world = MakeWorld(s);
    AddStaticGround(world, 0, Real(0.5));
    const BodyId ball = AddCircle(world, {0, Real(0.9995)}, Real(0.5), {0, -3}, 1, 0, Real(0.5));
    StepN(world, 5);
    EXPECT_NEAR(world.GetLinearVelocity(ball).y, 1.5, 1e-4) << s.name;
    EXPECT_NEAR(world.GetLinearVelocity(ball).x, 0.0, 1e-5) << s.name;
  }
}

TEST(RestitutionPolicyTest, FlatLandingBoxBouncesWithoutSpin) {
  // Both corners of a face touch at once; the bounce is e times the approach and no spin appears.
  for (const Solver& s : kSolvers) {
    World world = MakeWorld(s);
    AddStaticGround(world, Real(0.6), Real(0.5));
    const BodyId box = AddBox(world, {0, Real(0.9995)}, Real(0.5), Real(0.5), 1, 0, {0, -3});
    StepN(world, 5);
    EXPECT_NEAR(world.GetLinearVelocity(box).y, 1.5, 1e-3) << s.name;
    EXPECT_NEAR(world.GetAngularVelocity(box), 0.0, 1e-3) << s.name;
  }
}

TEST(RestitutionPolicyTest, SlidingBounceGetsCoulombFrictionOverTheWholeImpact) {
  // A solid disc (friction 0.3, e = 0.5) at (4, -2) m/s onto the ground. The normal impulse is
  // (1 + e) m 2 = 3 m; sticking would take m vt / 3 = 1.33 m of tangential impulse (a disc's
  // tangential effective mass is m / 3), more than mu times the normal impulse, 0.9 m: it slides,
  // and leaves at vx = 4 - 0.9 = 3.1 m/s. soft_step bounded each sub-step's friction by the whole
  // collision impulse until it took a 1/n share per sub-step (solver_soft_step.cpp, collisionShare_):
  // it stuck (vx 2.67 m/s).
  for (const Solver& s : kSolvers) {
    World world = MakeWorld(s);
    AddStaticGround(world, Real(0.3), Real(0.5));
    const BodyId ball = AddCircle(world, {0, Real(0.9995)}, Real(0.5), {4, -2}, 1, Real(0.3), Real(0.5));
    StepN(world, 5);
    EXPECT_NEAR(world.GetLinearVelocity(ball).y, 1.0, 1e-3) << s.name;
    EXPECT_NEAR(world.GetLinearVelocity(ball).x, 3.1, 1e-3) << s.name;
  }
}

uint64_t BouncingPile(SolverType solver, RestitutionPolicy policy, int threads) {
  WorldDef def;
  def.solver = solver;
  def.restitution = policy;
  def.threadCount = threads;
  def.minParallelItems = 8;  // split every section that has 8 items: colours run on several threads
  World world(def);
  AddGround(world, 30);
  for (int i = 0; i < 60; ++i) {
    BodyDef b;
    b.type = BodyType::kDynamic;
    b.position = {Real(i % 12) * Real(1.1) - 6, Real(2) + Real(i / 12) * Real(1.2)};
    b.angle = Real(0.3) * Real(i);
    b.shape = i % 2 ? ShapeDef::MakeCircle(Real(0.4)) : ShapeDef::Box(Real(0.3), Real(0.45));
    b.shape.restitution = Real(0.5);
    b.shape.friction = Real(0.3);
    world.CreateBody(b);
  }
  StepN(world, 120);
  return world.StateHash();
}

TEST(RestitutionPolicyTest, Box2dRestitutionIsDeterministicAcrossThreadCounts) {
  // Bodies falling 1-6 m onto the ground and onto each other bounce above the 1 m/s threshold.
  for (SolverType solver : {SolverType::kPgs, SolverType::kSoftStep}) {
    const uint64_t one = BouncingPile(solver, RestitutionPolicy::kBox2d, 1);
    EXPECT_EQ(BouncingPile(solver, RestitutionPolicy::kBox2d, 3), one);
    EXPECT_NE(BouncingPile(solver, RestitutionPolicy::kCollisions, 1), one) << "the policy changes the bounces";
  }
}

TEST(RestitutionPolicyTest, ThesisRefusesBox2dRestitutionAndBadPassCounts) {
  WorldDef def = NoGravityDef(SolverType::kThesis);
  def.restitution = RestitutionPolicy::kBox2d;
  EXPECT_THROW(World{def}, Error);
  def.restitution = RestitutionPolicy::kCollisions;
  def.thesisPasses = 0;
  EXPECT_THROW(World{def}, Error);
  def.thesisPasses = 1001;
  EXPECT_THROW(World{def}, Error);
}

TEST(RestitutionPolicyTest, ThesisPointImpulsesAndPassesLandABoxFlat) {
  // e = 0, a box landing flat: the thesis's one impulse at the centroid of the two corners stops
  // the centre; an impulse at each corner in turn leaves the first corner approaching again after
  // the second one's impulse, and further passes settle that (thesisPasses).
  auto land = [](bool points, int passes) {
    WorldDef def = NoGravityDef(SolverType::kThesis);
    def.thesisPointImpulses = points;
    def.thesisPasses = passes;
    World world(def);
    AddStaticGround(world, 0, 0);
    const BodyId box = AddBox(world, {Real(0.1), Real(0.9995)}, Real(0.5), Real(0.5), 1, 0, {0, -3});
    world.Step(kDt);
    return std::pair<Real, Real>{world.GetLinearVelocity(box).y, world.GetAngularVelocity(box)};
  };
  const auto centroid = land(false, 1), points = land(true, 1), settled = land(true, 8);
  EXPECT_NEAR(centroid.first, 0.0, 1e-4);
  EXPECT_NEAR(centroid.second, 0.0, 1e-4);
  EXPECT_GT(std::abs(points.second), 0.1) << "one pass, corner after corner, leaves the box turning";
  EXPECT_NEAR(settled.first, 0.0, 1e-3);
  EXPECT_LT(std::abs(settled.second), 0.1 * std::abs(points.second));
}

}  // namespace
}  // namespace quadrant::test
