// Tests for the World (engine/src/world/world.cpp and the stages it drives): collisions, resting
// contact, determinism, ids, read-outs and effects.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "quadrant/world.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

using namespace test;  // the small-world builders of test_helpers.h

std::string SolverName(const ::testing::TestParamInfo<SolverType>& info) {
  return info.param == SolverType::kThesis ? "Thesis" : "Pgs";
}

class SolverTest : public ::testing::TestWithParam<SolverType> {};

// ------------------------------------------------------------------ collisions

TEST_P(SolverTest, HeadOnEqualCirclesExchangeVelocities) {
  WorldDef def = NoGravityDef(GetParam());
  def.restitutionThreshold = 0;
  World world(def);
  // Equal circles (r 0.5, density 1), 1 m gap; A at 3 m/s, B at rest. Elastic (e = 1) and
  // frictionless: A must stop and B leave at 3 m/s.
  BodyId a = AddCircle(world, {-2, 0}, Real(0.5), {3, 0}, 1, 0, 1);
  BodyId b = AddCircle(world, {0, 0}, Real(0.5), {0, 0}, 1, 0, 1);
  StepN(world, 60);  // contact after ~1/3 s
  Vec2 va = world.GetLinearVelocity(a);
  Vec2 vb = world.GetLinearVelocity(b);
  // 1 % of the 3 m/s approach speed.
  EXPECT_NEAR(va.x, 0.0, 0.03);
  EXPECT_NEAR(vb.x, 3.0, 0.03);
  EXPECT_NEAR(va.y, 0.0, 1e-6);  // head-on: nothing can create a y component
  EXPECT_NEAR(vb.y, 0.0, 1e-6);
  // Separated again, B ahead of A.
  EXPECT_GT(world.GetPosition(b).x - world.GetPosition(a).x, 1.0);
}

TEST_P(SolverTest, ObliqueCollisionConservesMomentum) {
  WorldDef def = NoGravityDef(GetParam());
  World world(def);
  // Unequal masses (0.785 kg and 4.02 kg), off-centre hit with friction 0.6 and e = 0.5.
  BodyId a = AddCircle(world, {-2, Real(0.4)}, Real(0.5), {4, 0}, 1, Real(0.6), Real(0.5));
  BodyId b = AddCircle(world, {0, 0}, Real(0.8), {-1, Real(0.5)}, 2, Real(0.6), Real(0.5));
  const double ma = world.GetMass(a), mb = world.GetMass(b);
  ASSERT_GT(mb, 4 * ma);
  auto momentum = [&] {
    Vec2 va = world.GetLinearVelocity(a), vb = world.GetLinearVelocity(b);
    return std::pair<double, double>{ma * va.x + mb * vb.x, ma * va.y + mb * vb.y};
  };
  auto p0 = momentum();
  Vec2 vb0 = world.GetLinearVelocity(b);
  StepN(world, 60);
  auto p1 = momentum();
  // The collision happened (B's velocity changed by much more than any rounding).
  Vec2 vb1 = world.GetLinearVelocity(b);
  ASSERT_GT(Length(vb1 - vb0), 0.5);
  // Impulses are applied equal and opposite; float32 rounding of ~10 velocity updates on
  // O(10) kg m/s values is ~1e-6 relative, so 1e-4 is a wide margin.
  double mag = std::hypot(p0.first, p0.second);
  EXPECT_NEAR(p1.first, p0.first, 1e-4 * mag);
  EXPECT_NEAR(p1.second, p0.second, 1e-4 * mag);
}

TEST_P(SolverTest, RestingBoxDoesNotFallThroughGround) {
  WorldDef def;
  def.solver = GetParam();
  World world(def);
  AddGround(world);  // top face at y = 0.5
  BodyId box = AddBox(world, {0, 1}, Real(0.5), Real(0.5), 10);  // resting exactly on it
  for (int i = 0; i < 300; ++i) {
    world.Step(kDt);
    ASSERT_GT(world.GetPosition(box).y, 0.98) << "step " << i;  // 2 cm: 4x linearSlop
  }
  EXPECT_NEAR(world.GetPosition(box).y, 1.0, 0.01);
}

TEST_P(SolverTest, BoxDroppedOnGroundComesToRest) {
  WorldDef def;
  def.solver = GetParam();
  World world(def);
  AddGround(world);  // top at 0.5
  // Box of half-width 0.5, density 1, its bottom 2 m above the ground.
  BodyId box = AddBox(world, {0, Real(3.0)}, Real(0.5), Real(0.5), 1);
  StepN(world, 120);  // 2 s: lands after ~0.63 s
  Vec2 p = world.GetPosition(box);
  // Resting centre = ground top + half-height = 1.0; Box2D-style solvers settle within
  // about linearSlop (5 mm) of contact, so 1 cm.
  EXPECT_NEAR(p.y, 1.0, 0.01);
  EXPECT_NEAR(p.x, 0.0, 0.01);  // a straight drop stays put
  EXPECT_LT(0.5 - (p.y - 0.5), 0.01);  // geometric penetration below 1 cm
  EXPECT_GT(DeepestPenetration(world, box), -0.01);
  // At rest: below 5 cm/s (the free-fall speed at landing is 6.3 m/s).
  EXPECT_LT(Length(world.GetLinearVelocity(box)), 0.05);
  EXPECT_NEAR(world.GetAngle(box), 0.0, 0.01);
}

TEST_P(SolverTest, CircleDroppedOnGroundComesToRest) {
  WorldDef def;
  def.solver = GetParam();
  World world(def);
  AddGround(world);
  BodyId ball = AddCircle(world, {Real(0.3), Real(3.0)}, Real(0.5));
  StepN(world, 120);
  Vec2 p = world.GetPosition(ball);
  EXPECT_NEAR(p.y, 1.0, 0.01);  // same reasoning as the box
  EXPECT_GT(DeepestPenetration(world, ball), -0.01);
  EXPECT_LT(Length(world.GetLinearVelocity(ball)), 0.05);
}

INSTANTIATE_TEST_SUITE_P(BothSolvers, SolverTest, ::testing::Values(SolverType::kThesis, SolverType::kPgs),
                         SolverName);

// ------------------------------------------------------------------ contact quality (pgs)

TEST(WorldContactTest, SpeculativeContactIsCreatedBeforeTouching) {
  // world.h: "speculativeDistance: contacts are created this far before touching". A circle
  // and a box 1 cm above the ground (default speculative distance 2 cm), no gravity.
  World world(NoGravityDef());
  AddGround(world);  // top at 0.5
  BodyId ball = AddCircle(world, {-3, Real(1.01)}, Real(0.5));
  BodyId box = AddBox(world, {3, Real(1.01)}, Real(0.5), Real(0.5));
  world.Step(kDt);
  EXPECT_EQ(world.GetCounters().candidatePairs, 2);
  EXPECT_EQ(world.GetCounters().contacts, 2);
  EXPECT_EQ(world.GetCounters().touchingContacts, 0);
  EXPECT_EQ(world.GetCounters().contactPoints, 3);
  for (const ContactInfo& c : world.GetContacts()) {
    for (int i = 0; i < c.pointCount; ++i) EXPECT_NEAR(c.separations[i], 0.01, 1e-4);
  }
  // Nothing pushes: both stay where they are.
  EXPECT_NEAR(world.GetPosition(ball).y, 1.01, 1e-6);
  EXPECT_NEAR(world.GetPosition(box).y, 1.01, 1e-6);
}

TEST(WorldContactTest, SpeculativeContactStopsApproachAtTheSurface) {
  // A circle 2.5 cm above the ground approaching at 0.9 m/s (1.5 cm per step), no gravity,
  // e = 0. Step 1: gap 2.5 cm > 2 cm, no contact, gap becomes 1 cm. Step 2: a speculative
  // contact at 1 cm lets it close exactly that gap. It must never penetrate (1e-4 m covers
  // float rounding of O(1) coordinates).
  World world(NoGravityDef());
  AddGround(world);
  BodyId ball = AddCircle(world, {0, Real(1.025)}, Real(0.5), {0, Real(-0.9)});
  for (int i = 0; i < 10; ++i) {
    world.Step(kDt);
    EXPECT_GE(world.GetPosition(ball).y, 1.0 - 1e-4) << "step " << i;
  }
  EXPECT_NEAR(world.GetLinearVelocity(ball).y, 0.0, 1e-3);
}

TEST(WorldContactTest, ElasticBallReturnsToItsDropHeight) {
  // e = 1 on both shapes, no friction, threshold 0: a ball whose bottom starts 2 m above the
  // ground must come back up to where it started. The impact happens at an arbitrary point
  // inside a step, so the discrete bounce may be off by up to one step of travel at the
  // impact speed: sqrt(2 g h) dt = 6.32 / 60 = 0.105 m. (Energy lost or gained beyond that on
  // one bounce is an error of the contact handling, not of the time discretisation.)
  WorldDef def;
  def.restitutionThreshold = 0;
  World world(def);
  BodyDef g;
  g.shape = ShapeDef::Box(20, Real(0.5));
  g.shape.restitution = 1;
  g.shape.friction = 0;
  world.CreateBody(g);
  BodyId ball = AddCircle(world, {0, 3}, Real(0.5), {}, 1, 0, 1);
  Real apex = 0;
  bool bounced = false;
  for (int i = 0; i < 120; ++i) {
    world.Step(kDt);
    Real vy = world.GetLinearVelocity(ball).y;
    if (vy > 0) bounced = true;
    if (bounced) apex = std::max(apex, world.GetPosition(ball).y);
    if (bounced && vy < 0) break;  // past the first apex
  }
  ASSERT_TRUE(bounced);
  EXPECT_NEAR(apex, 3.0, 0.105);
}

TEST(WorldContactTest, ElasticBouncesDoNotGainEnergy) {
  // Same ball, eight bounces. Each impact's phase inside its step may cost or add up to one
  // step of travel (0.105 m, see above), but e = 1 must never create energy bounce after
  // bounce: no apex may exceed the start height by more than that one-step allowance.
  WorldDef def;
  def.restitutionThreshold = 0;
  World world(def);
  BodyDef g;
  g.shape = ShapeDef::Box(20, Real(0.5));
  g.shape.restitution = 1;
  g.shape.friction = 0;
  world.CreateBody(g);
  BodyId ball = AddCircle(world, {0, 3}, Real(0.5), {}, 1, 0, 1);
  std::vector<Real> apexes;
  Real apex = 0, prevVy = 0;
  for (int i = 0; i < 60 * 20 && apexes.size() < 8; ++i) {
    world.Step(kDt);
    const Real vy = world.GetLinearVelocity(ball).y;
    if (vy > 0) apex = std::max(apex, world.GetPosition(ball).y);
    if (prevVy > 0 && vy <= 0) {
      apexes.push_back(apex);
      apex = 0;
    }
    prevVy = vy;
  }
  ASSERT_EQ(apexes.size(), 8u);
  for (size_t k = 0; k < apexes.size(); ++k) EXPECT_LE(apexes[k], 3.0 + 0.105) << "bounce " << k + 1;
}

// Newton's cradle as a free row: k balls strike a row of touching equal balls, elastic and
// frictionless. A chain of binary collisions sends exactly k balls off at the strike speed and
// leaves the rest at rest; the simultaneous-contact model would move the whole row instead
// (the last of five balls at 0.41 m/s). `dir` flips the row so the contacts come in the other
// order.
struct CradleResult {
  std::vector<Real> vx;
};
CradleResult RunCradle(int balls, int strikers, Real dir, int steps) {
  WorldDef def = NoGravityDef();
  def.restitutionThreshold = 0;
  def.effects.friction = false;
  World world(def);
  std::vector<BodyId> ids;
  for (int k = 0; k < balls; ++k) {
    const Vec2 v = k < strikers ? Vec2{dir, 0} : Vec2{0, 0};
    ids.push_back(AddCircle(world, {dir * Real(k), 0}, Real(0.5), v, 1, 0, 1));
  }
  StepN(world, steps);
  CradleResult r;
  for (BodyId id : ids) r.vx.push_back(world.GetLinearVelocity(id).x);
  return r;
}

TEST(WorldContactTest, NewtonsCradleSendsOffOneBallForOne) {
  for (Real dir : {Real(1), Real(-1)}) {
    // Ball 0 strikes (at the row's near end, moving into it); ball 4 is the far end.
    const CradleResult r = RunCradle(5, 1, dir, 1);
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(r.vx[k], 0.0, 1e-5) << "ball " << k << " dir " << dir;
    EXPECT_NEAR(r.vx[4], dir, 1e-5) << "dir " << dir;
  }
}

TEST(WorldContactTest, NewtonsCradleSendsOffTwoBallsForTwo) {
  // Two balls strike three: after the chain of collisions the two far balls leave at the strike
  // speed and the three near ones stay. A single step may not finish the chain (the second
  // striker's collisions follow the first's), so run a few.
  const CradleResult r = RunCradle(5, 2, 1, 10);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(r.vx[k], 0.0, 1e-4) << "ball " << k;
  EXPECT_NEAR(r.vx[3], 1.0, 1e-4);
  EXPECT_NEAR(r.vx[4], 1.0, 1e-4);
}

TEST(WorldContactTest, BoxLandingFlatBouncesWithoutSpin) {
  // Both corners of a flat face hit at once and are solved together (the 2x2 problem), so
  // the bounce is e times the approach and no spin appears; one corner after the other would
  // tilt the box.
  WorldDef def;
  World world(def);
  BodyDef g;
  g.shape = ShapeDef::Box(20, Real(0.5));
  g.shape.restitution = Real(0.5);
  world.CreateBody(g);
  BodyId box = AddBox(world, {0, Real(1.0)}, Real(0.5), Real(0.5), 1, 0, {0, -3});
  world.Step(kDt);
  const Real approach = 3 + 10 * kDt;
  EXPECT_NEAR(world.GetLinearVelocity(box).y, 0.5 * approach, 1e-4);
  EXPECT_NEAR(world.GetAngularVelocity(box), 0.0, 1e-5);
}

TEST(WorldContactTest, SlidingBoxStopsAfterCoulombDistance) {
  // Box at 5 m/s on the ground, friction 0.6 on both (mixed sqrt(0.6*0.6) = 0.6): deceleration
  // mu g = 6 m/s^2, distance v^2 / (2 mu g) = 2.083 m after 5/6 s. Velocity-first Euler stops
  // v dt / 2 = 4 cm short; allow 5 cm.
  World world;
  AddGround(world, 50);
  BodyId box = AddBox(world, {0, 1}, Real(0.5), Real(0.5), 1, 0, {5, 0});
  StepN(world, 120);
  EXPECT_NEAR(world.GetPosition(box).x, 25.0 / 12.0, 0.05);
  EXPECT_NEAR(world.GetLinearVelocity(box).x, 0.0, 1e-3);
  EXPECT_NEAR(world.GetAngle(box), 0.0, 0.01);  // it slides, it does not tip
}

TEST(WorldContactTest, StaticBodyMovedBySetTransformIsCollidedWithThere) {
  World world;
  BodyId ground = AddGround(world, 5);
  world.SetTransform(ground, {100, 0}, 0);
  BodyId box = AddBox(world, {100, 2});
  StepN(world, 90);
  EXPECT_NEAR(world.GetPosition(box).y, 1.0, 0.01);
  // And nothing is left at the old place.
  BodyId other = AddCircle(world, {0, 2});
  StepN(world, 45);  // free fall for 0.75 s: 2.8 m
  EXPECT_LT(world.GetPosition(other).y, 0.0);
}

// ------------------------------------------------------------------ free motion

TEST(WorldTest, FreeFallFollowsGravity) {
  World world;  // g = (0, -10)
  BodyId ball = AddCircle(world, {0, 100}, Real(0.5));
  const int n = 60;
  StepN(world, n);
  const double t = n * double(kDt);
  // v = g t exactly for any Euler variant (60 float additions: ~1e-5 m/s rounding).
  EXPECT_NEAR(world.GetLinearVelocity(ball).y, -10 * t, 1e-4);
  // Position: continuous y0 - g t^2/2, up to the Euler error g dt t / 2 either way.
  const double cont = 100 - 5 * t * t;
  EXPECT_NEAR(world.GetPosition(ball).y, cont, 10 * double(kDt) * t / 2 + 1e-3);
}

TEST(WorldTest, PipelineRepeatsSplitTheStep) {
  World world;
  BodyId ball = AddCircle(world, {0, 100}, Real(0.5));
  world.StepRepeated(kDt, 4);
  EXPECT_NEAR(world.GetLinearVelocity(ball).y, -10 * double(kDt), 1e-5);
}

TEST(WorldTest, GravityDisabledKeepsVelocityConstant) {
  WorldDef def;
  def.effects.gravity = false;
  World world(def);
  BodyDef bd;
  bd.type = BodyType::kDynamic;
  bd.position = {1, 2};
  bd.linearVelocity = {Real(1.5), Real(-0.7)};
  bd.angularVelocity = Real(0.3);
  bd.shape = ShapeDef::Box(Real(0.5), Real(0.25));
  BodyId body = world.CreateBody(bd);
  StepN(world, 100);
  Vec2 v = world.GetLinearVelocity(body);
  // Nothing acts on a lone body: the velocity must be bit-for-bit what it was.
  EXPECT_EQ(v.x, Real(1.5));
  EXPECT_EQ(v.y, Real(-0.7));
  EXPECT_EQ(world.GetAngularVelocity(body), Real(0.3));
  // And it moved by v t (100 float additions of ~0.025 m: 1e-4 m).
  const double t = 100 * double(kDt);
  EXPECT_TRUE(VecNear(world.GetPosition(body), Vec2{Real(1 + 1.5 * t), Real(2 - 0.7 * t)}, 1e-3));
}

TEST(WorldTest, RotationDisabledKeepsAnglesExactlyConstant) {
  WorldDef def;
  def.effects.rotation = false;
  World world(def);
  AddGround(world);
  // A tilted box lands on a corner, a circle hits it with friction: all would spin.
  BodyId box = AddBox(world, {0, 2}, Real(0.5), Real(0.3), 1, Real(0.4));
  BodyId ball = AddCircle(world, {-3, 1}, Real(0.4), {6, 0});
  BodyId box2 = AddBox(world, {Real(0.2), Real(3.5)}, Real(0.4), Real(0.4), 2, Real(-0.7), {0, -2});
  const BodyId ids[] = {box, ball, box2};
  Rot r0[3];
  for (int i = 0; i < 3; ++i) r0[i] = world.GetRotation(ids[i]);
  for (int s = 0; s < 120; ++s) {
    world.Step(kDt);
    for (int i = 0; i < 3; ++i) {
      Rot r = world.GetRotation(ids[i]);
      ASSERT_EQ(r.c, r0[i].c) << "body " << i << " step " << s;
      ASSERT_EQ(r.s, r0[i].s) << "body " << i << " step " << s;
      ASSERT_EQ(world.GetAngularVelocity(ids[i]), 0) << "body " << i << " step " << s;
    }
  }
  // The box did land (it is not just floating).
  EXPECT_LT(world.GetPosition(box).y, 1.5);
}

TEST(WorldTest, KinematicBodyIgnoresGravityAndContacts) {
  World world;
  BodyDef kd;
  kd.type = BodyType::kKinematic;
  kd.position = {0, 0};
  kd.linearVelocity = {Real(0.5), 0};
  kd.shape = ShapeDef::Box(3, Real(0.5));
  BodyId platform = world.CreateBody(kd);
  BodyId box = AddBox(world, {0, Real(1.2)}, Real(0.5), Real(0.5), 5);
  StepN(world, 90);
  EXPECT_EQ(world.GetLinearVelocity(platform).x, Real(0.5));
  EXPECT_EQ(world.GetLinearVelocity(platform).y, 0);
  EXPECT_NEAR(world.GetPosition(platform).y, 0.0, 1e-6);
  // The box rests on it (carried by friction) rather than falling through.
  EXPECT_NEAR(world.GetPosition(box).y, 1.0, 0.01);
}

// ------------------------------------------------------------------ determinism

void BuildScene(World& world) {
  AddGround(world);
  AddBox(world, {0, 1}, Real(0.5), Real(0.5));
  AddBox(world, {Real(0.1), 2}, Real(0.5), Real(0.5), 1, Real(0.2));
  AddBox(world, {Real(-0.2), Real(3.2)}, Real(0.6), Real(0.3));
  AddCircle(world, {2, 2}, Real(0.4), {-1, 0});
  AddCircle(world, {-2, Real(2.5)}, Real(0.3), {2, 1});
}

TEST(WorldTest, StateHashEqualForIdenticalWorldsAndSensitive) {
  World w1, w2;
  BuildScene(w1);
  BuildScene(w2);
  EXPECT_EQ(w1.StateHash(), w2.StateHash());
  const uint64_t initial = w1.StateHash();
  StepN(w1, 100);
  StepN(w2, 100);
  EXPECT_EQ(w1.StateHash(), w2.StateHash());
  EXPECT_NE(w1.StateHash(), initial);  // things moved
  // A 1 mm/s nudge to one body changes the hash at once and the trajectories after.
  BodyId id = w2.GetBodyIds()[4];
  Vec2 v = w2.GetLinearVelocity(id);
  w2.SetLinearVelocity(id, {v.x + Real(1e-3), v.y});
  EXPECT_NE(w1.StateHash(), w2.StateHash());
  StepN(w1, 10);
  StepN(w2, 10);
  EXPECT_NE(w1.StateHash(), w2.StateHash());
}

/// A small random circle scene in a walled box: ~40 circles of 0.2..0.5 m with random
/// velocities, on a jittered grid so none overlap initially.
void BuildRandomCircles(World& world, uint32_t seed) {
  AddGround(world, 6, Real(0.5), {0, -0.5});
  AddGround(world, Real(0.5), 6, {-6.5, 5.5});
  AddGround(world, Real(0.5), 6, {6.5, 5.5});
  std::mt19937 rng(seed);
  auto uni = [&](double lo, double hi) { return lo + (hi - lo) * (double(rng()) / double(std::mt19937::max())); };
  for (int row = 0; row < 5; ++row) {
    for (int col = 0; col < 8; ++col) {
      Real r = Real(uni(0.2, 0.5));
      Vec2 p{Real(-5.25 + 1.5 * col + uni(-0.2, 0.2)), Real(1 + 1.2 * row + uni(-0.05, 0.05))};
      Vec2 v{Real(uni(-3, 3)), Real(uni(-3, 3))};
      AddCircle(world, p, r, v, Real(uni(0.5, 2)), Real(0.4), Real(uni(0, 0.5)));
    }
  }
}

TEST(WorldTest, BothBroadPhasesGiveTheSameTrajectory) {
  WorldDef dq;
  dq.broadPhase = BroadPhaseType::kQuadTree;
  WorldDef dg;
  dg.broadPhase = BroadPhaseType::kUniformGrid;
  World wq(dq), wg(dg);
  BuildRandomCircles(wq, 1234);
  BuildRandomCircles(wg, 1234);
  ASSERT_EQ(wq.StateHash(), wg.StateHash());
  int maxPairs = 0;
  for (int i = 0; i < 200; ++i) {
    wq.Step(kDt);
    wg.Step(kDt);
    ASSERT_EQ(wq.GetCounters().candidatePairs, wg.GetCounters().candidatePairs) << "step " << i;
    ASSERT_EQ(wq.GetCounters().contacts, wg.GetCounters().contacts) << "step " << i;
    maxPairs = std::max(maxPairs, wq.GetCounters().candidatePairs);
  }
  EXPECT_GT(maxPairs, 10);  // the scene really collides
  // Identical pair sets + deterministic contact order => bit-identical states.
  EXPECT_EQ(wq.StateHash(), wg.StateHash());
}

TEST(WorldTest, PipelineRepeatsEqualSmallerSteps) {
  // StepRepeated(dt, 2) runs the pipeline twice with dt/2: bit-identical to Step(dt/2) twice (dt/2 is
  // exact in binary floating point).
  World a, b;
  BuildScene(a);
  BuildScene(b);
  for (int i = 0; i < 60; ++i) {
    a.StepRepeated(kDt, 2);
    b.Step(kDt / 2);
    b.Step(kDt / 2);
  }
  EXPECT_EQ(a.StateHash(), b.StateHash());
}

// 43 bodies are far below the default grain (2048 items), so the grain is lowered to 4: every
// stage splits across the workers, and the test checks that parallel sections really ran (so
// that it cannot compare a serial step with a serial step).
TEST(WorldTest, ThreadCountDoesNotChangeTheResult) {
  WorldDef d1;
  d1.minParallelItems = 4;
  World w1(d1);
  BuildRandomCircles(w1, 99);
  StepN(w1, 120);
  EXPECT_FALSE(ParallelSectionRan(w1.GetProfile()));
  for (int threads : {2, 4}) {
    WorldDef dn = d1;
    dn.threadCount = threads;
    World wn(dn);
    BuildRandomCircles(wn, 99);
    int parallelSteps = 0;
    for (int i = 0; i < 120; ++i) {
      wn.Step(kDt);
      parallelSteps += ParallelSectionRan(wn.GetProfile()) ? 1 : 0;
    }
    // Every step splits here (measured: 120 of 120); one is enough to show it is not serial.
    EXPECT_GT(parallelSteps, 0) << threads << " threads";
    EXPECT_EQ(w1.StateHash(), wn.StateHash()) << threads << " threads";
  }
}

// A sparse scene (at most a sixteenth as many contacts as bodies) runs the soft step's rows beside
// the free bodies' pass (solver_soft_step.cpp, StageRunner::Beside): the rows' part on one thread,
// the free bodies in blocks on the others, at the same time. Bouncing circles (the restitution
// passes write the rows' bodies' velocities while the free pass runs), a kinematic body, boxes
// resting on the ground: the result must be the one-thread result, bit for bit.
TEST(WorldTest, RowsBesideFreeBodiesGiveTheOneThreadResult) {
  auto build = [](World& world) {
    AddGround(world, 40, Real(0.5), {0, -0.5});
    for (int k = 0; k < 4; ++k) AddBox(world, {Real(-30 + 3 * k), Real(0.5)});
    BodyDef kin;
    kin.type = BodyType::kKinematic;
    kin.position = {0, 3};
    kin.linearVelocity = {Real(0.5), 0};
    kin.angularVelocity = Real(0.3);
    kin.shape = ShapeDef::Box(2, Real(0.2));
    world.CreateBody(kin);
    std::mt19937 rng(5);
    auto uni = [&](double lo, double hi) { return lo + (hi - lo) * (double(rng()) / double(std::mt19937::max())); };
    for (int row = 0; row < 20; ++row) {
      for (int col = 0; col < 30; ++col) {
        AddCircle(world, {Real(-29 + 2 * col), Real(5 + 2 * row)}, Real(uni(0.1, 0.3)), {Real(uni(-3, 3)), Real(uni(-3, 3))}, 1,
                  Real(0.3), Real(0.8));
      }
    }
  };
  auto run = [&](int threads, int* besideSteps, int* parallelSteps) {
    WorldDef def;
    def.threadCount = threads;
    def.minParallelItems = 8;  // split every pass of these 606 bodies
    World world(def);
    build(world);
    for (int i = 0; i < 150; ++i) {
      world.Step(kDt);
      const Counters& c = world.GetCounters();
      *besideSteps += c.contacts > 0 && 16 * c.contacts <= c.bodies ? 1 : 0;
      *parallelSteps += ParallelSectionRan(world.GetProfile()) ? 1 : 0;
    }
    return world.StateHash();
  };
  int beside = 0, parallel = 0;
  const uint64_t one = run(1, &beside, &parallel);
  EXPECT_GT(beside, 0);  // steps with contacts, sparse enough to run the rows beside the free bodies
  for (int threads : {2, 3}) {
    beside = parallel = 0;
    EXPECT_EQ(run(threads, &beside, &parallel), one) << threads << " threads";
    EXPECT_GT(parallel, 0) << threads << " threads";
  }
}

TEST(WorldTest, MoveKeepsTheWorld) {
  World w1;
  BuildScene(w1);
  StepN(w1, 5);
  const uint64_t h = w1.StateHash();
  World w2(std::move(w1));
  EXPECT_EQ(w2.StateHash(), h);
  EXPECT_EQ(w2.GetBodyCount(), 6);
  World w3;
  w3 = std::move(w2);
  EXPECT_EQ(w3.StateHash(), h);
  EXPECT_NO_THROW(w3.Step(kDt));
}

// ------------------------------------------------------------------ ids

TEST(WorldTest, DestroyedAndNullIdsAreInvalidAndThrow) {
  World world;
  BodyId a = AddBox(world, {0, 5});
  BodyId b = AddCircle(world, {3, 5});
  EXPECT_TRUE(world.IsValid(a));
  EXPECT_FALSE(world.IsValid(BodyId{}));
  EXPECT_TRUE(BodyId{}.IsNull());
  EXPECT_FALSE(a.IsNull());
  world.DestroyBody(a);
  EXPECT_FALSE(world.IsValid(a));
  EXPECT_TRUE(world.IsValid(b));
  EXPECT_THROW(world.GetPosition(a), Error);
  EXPECT_THROW(world.GetLinearVelocity(a), Error);
  EXPECT_THROW(world.SetLinearVelocity(a, {1, 0}), Error);
  EXPECT_THROW(world.DestroyBody(a), Error);
  EXPECT_THROW(world.GetPosition(BodyId{}), Error);
  EXPECT_THROW(world.DestroyBody(BodyId{}), Error);
  // An id for a slot that never existed.
  EXPECT_FALSE(world.IsValid(BodyId{1000, 1}));
  EXPECT_THROW(world.GetPosition(BodyId{1000, 1}), Error);
  // The survivor is untouched.
  EXPECT_TRUE(VecNear(world.GetPosition(b), Vec2{3, 5}, 0));
  EXPECT_EQ(world.GetBodyCount(), 1);
}

TEST(WorldTest, NewIdsAfterDestroyAreDistinctFromStaleOnes) {
  World world;
  std::vector<BodyId> stale;
  BodyId keep = AddCircle(world, {-5, 0});
  for (int round = 0; round < 10; ++round) {
    BodyId id = AddBox(world, {0, Real(round)});
    for (BodyId s : stale) {
      EXPECT_FALSE(id == s) << "round " << round << " reused a stale id";
      EXPECT_FALSE(world.IsValid(s));
    }
    EXPECT_TRUE(world.IsValid(id));
    world.DestroyBody(id);
    stale.push_back(id);
  }
  BodyId fresh = AddBox(world, {1, 1});
  for (BodyId s : stale) EXPECT_FALSE(fresh == s);
  EXPECT_TRUE(VecNear(world.GetPosition(fresh), Vec2{1, 1}, 0));
  EXPECT_TRUE(world.IsValid(keep));
  EXPECT_EQ(world.GetBodyCount(), 2);
}

TEST(WorldTest, BodyIdsInCreationOrderAndSwapRemove) {
  World world;
  BodyId a = AddCircle(world, {0, 0});
  BodyId b = AddCircle(world, {2, 0});
  BodyId c = AddCircle(world, {4, 0});
  std::vector<BodyId> ids = world.GetBodyIds();
  ASSERT_EQ(ids.size(), 3u);
  EXPECT_TRUE(ids[0] == a && ids[1] == b && ids[2] == c);
  world.DestroyBody(a);
  ids = world.GetBodyIds();
  ASSERT_EQ(ids.size(), 2u);
  // Documented: the last body moves into the destroyed one's place.
  EXPECT_TRUE(ids[0] == c && ids[1] == b);
  // The moved body's id still reaches its own data.
  EXPECT_TRUE(VecNear(world.GetPosition(c), Vec2{4, 0}, 0));
  EXPECT_TRUE(VecNear(world.GetPosition(b), Vec2{2, 0}, 0));
}

TEST(WorldTest, DestroyWhileInContactThenStep) {
  World world;
  AddGround(world);
  BodyId a = AddBox(world, {0, 1});
  BodyId b = AddBox(world, {0, 2});
  BodyId c = AddBox(world, {0, 3});
  StepN(world, 30);
  world.DestroyBody(b);  // middle of a stack with cached contacts
  EXPECT_NO_THROW(StepN(world, 60));
  // c fell onto a and rests on it.
  EXPECT_NEAR(world.GetPosition(c).y, 2.0, 0.02);
  EXPECT_NEAR(world.GetPosition(a).y, 1.0, 0.02);
}

// ------------------------------------------------------------------ read-outs

TEST(WorldTest, ProfileAndCounters) {
  World world;
  AddGround(world);
  // Box and circle 5 mm into the ground's top face (y = 0.5): touching for sure.
  AddBox(world, {0, Real(0.995)});
  AddCircle(world, {3, Real(0.995)});
  AddCircle(world, {-3, 8});  // in the air
  world.Step(kDt);
  EXPECT_GT(world.GetProfile().total, 0);
  EXPECT_GE(world.GetProfile().total, world.GetProfile().solve);
  const Counters& c = world.GetCounters();
  EXPECT_EQ(c.bodies, 4);
  EXPECT_EQ(c.candidatePairs, 2);  // box-ground, circle-ground
  EXPECT_EQ(c.contacts, 2);
  EXPECT_EQ(c.touchingContacts, 2);
  EXPECT_EQ(c.contactPoints, 3);  // 2 for the box, 1 for the circle
  world.DestroyBody(world.GetBodyIds()[3]);
  world.Step(kDt);
  EXPECT_EQ(world.GetCounters().bodies, 3);
  EXPECT_EQ(world.GetBodyCount(), 3);
}

TEST(WorldTest, ContactsReadBackNormalFromAToB) {
  World world;
  AddGround(world);
  BodyId box = AddBox(world, {Real(0.5), Real(0.995)});
  world.Step(kDt);
  std::vector<ContactInfo> contacts = world.GetContacts();
  ASSERT_EQ(contacts.size(), 1u);
  const ContactInfo& ci = contacts[0];
  EXPECT_TRUE(ci.bodyA == box || ci.bodyB == box);
  EXPECT_NEAR(Length(ci.normal), 1.0, 1e-5);
  Vec2 ab = world.GetPosition(ci.bodyB) - world.GetPosition(ci.bodyA);
  EXPECT_GT(Dot(ci.normal, ab), 0);
  EXPECT_NEAR(std::abs(ci.normal.y), 1.0, 1e-4);
  ASSERT_EQ(ci.pointCount, 2);
  for (int i = 0; i < 2; ++i) {
    EXPECT_GT(ci.normalImpulses[i], 0);  // it is holding the box up
    EXPECT_NEAR(ci.points[i].y, 0.5, 0.01);
  }
}

TEST(WorldTest, MassPropertiesReadBack) {
  World world;
  BodyId box = AddBox(world, {0, 0}, Real(0.5), Real(0.25), 2);  // 1 x 0.5 m, 2 kg/m^2
  EXPECT_NEAR(world.GetMass(box), 1.0, 1e-5);
  EXPECT_NEAR(world.GetRotationalInertia(box), 1.0 * (1 + 0.25) / 12, 1e-6);
  EXPECT_EQ(world.GetType(box), BodyType::kDynamic);
  BodyDef cd;
  cd.type = BodyType::kDynamic;
  cd.position = {1, 1};
  cd.angle = Real(test::kPi / 2);
  cd.shape = ShapeDef::MakeCircle(Real(0.5), {1, 0});  // centre 1 m along local x
  BodyId c = world.CreateBody(cd);
  // World centre: origin + rotated local centre = (1, 1) + (0, 1).
  EXPECT_TRUE(VecNear(world.GetWorldCenter(c), Vec2{1, 2}, 1e-5));
  EXPECT_TRUE(VecNear(world.GetPosition(c), Vec2{1, 1}, 0));
  double m = test::kPi * 0.25;
  EXPECT_NEAR(world.GetMass(c), m, 1e-5);
  EXPECT_NEAR(world.GetRotationalInertia(c), m * 0.25 / 2, 1e-6);
  // AABB of the offset circle.
  AABB bb = world.GetAABB(c);
  EXPECT_NEAR(bb.lower.y, 1.5, 1e-4);
  EXPECT_NEAR(bb.upper.y, 2.5, 1e-4);
  EXPECT_EQ(world.GetShape(c).type, ShapeType::kCircle);
}

TEST(WorldTest, ImpulseAndSetters) {
  World world(NoGravityDef());
  BodyId box = AddBox(world, {0, 0}, Real(0.5), Real(0.5), 1);  // m = 1, I = 1/6
  world.ApplyLinearImpulse(box, {2, 0}, {0, 0});
  EXPECT_TRUE(VecNear(world.GetLinearVelocity(box), Vec2{2, 0}, 1e-5));
  EXPECT_NEAR(world.GetAngularVelocity(box), 0.0, 1e-6);
  // Off-centre: dw = cross(r, J) / I = (0.5 * 1) / (1/6) = 3 rad/s, dv = J / m.
  world.ApplyLinearImpulse(box, {0, 1}, {Real(0.5), 0});
  EXPECT_TRUE(VecNear(world.GetLinearVelocity(box), Vec2{2, 1}, 1e-5));
  EXPECT_NEAR(world.GetAngularVelocity(box), 3.0, 1e-4);
  world.SetTransform(box, {5, -1}, Real(0.25));
  EXPECT_TRUE(VecNear(world.GetPosition(box), Vec2{5, -1}, 0));
  EXPECT_NEAR(world.GetAngle(box), 0.25, 1e-6);
  EXPECT_TRUE(VecNear(world.GetWorldCenter(box), Vec2{5, -1}, 1e-6));
  world.SetAngularVelocity(box, Real(-1));
  EXPECT_EQ(world.GetAngularVelocity(box), Real(-1));
}

}  // namespace
}  // namespace quadrant
