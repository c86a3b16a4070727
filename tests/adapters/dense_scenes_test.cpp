// The dense, solver-bound scenes (benchmarks/scenes/dense.cpp): builders keep their contracts,
// every engine runs them or says it cannot, and the tumbler's kinematic walls turn as a rigid
// square in every engine that runs it.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "adapter.h"
#include "quadrant/error.h"
#include "scenes.h"

namespace quadrant::scene {
namespace {

TEST(DenseScenes, ManyPyramidsLayout) {
  const Scene s = MakeManyPyramids(5500);  // 100 pyramids: 10 rows of 10, 10 shelves
  EXPECT_EQ(s.name, "many_pyramids");
  ASSERT_EQ(s.bodies.size(), 10u + 5500u);
  int shelves = 0;
  for (const BodyDesc& b : s.bodies) shelves += b.dynamic ? 0 : 1;
  EXPECT_EQ(shelves, 10);
  EXPECT_NO_THROW(ValidateScene(s));
  EXPECT_EQ(MakeManyPyramids(5540).bodies.size(), 10u + 5500u);  // rounds down to whole pyramids
  EXPECT_EQ(MakeManyPyramids(55).bodies.size(), 1u + 55u);
  EXPECT_THROW(MakeManyPyramids(54), Error);
  EXPECT_FALSE(s.effects.sleep);
  EXPECT_EQ(s.velocityIterations, 8);
}

TEST(DenseScenes, TumblerLayout) {
  const Scene s = MakeTumbler(2025);
  ASSERT_EQ(s.bodies.size(), 4u + 2025u);
  for (int k = 0; k < 4; ++k) {
    EXPECT_FALSE(s.bodies[k].dynamic);
    EXPECT_TRUE(s.bodies[k].kinematic);
  }
  EXPECT_TRUE(bool(s.driver));
  EXPECT_NO_THROW(ValidateScene(s));
  // Every box starts strictly inside the walls' inner faces (|x|, |y - 10| < 9.5).
  for (size_t i = 4; i < s.bodies.size(); ++i) {
    EXPECT_LT(std::abs(double(s.bodies[i].position.x)) + 0.125, 9.5);
    EXPECT_LT(std::abs(double(s.bodies[i].position.y) - 10) + 0.125, 9.5);
  }
  EXPECT_NO_THROW(MakeTumbler(46 * 46));
  EXPECT_THROW(MakeTumbler(46 * 46 + 1), Error);
  EXPECT_THROW(MakeTumbler(0), Error);
  // A body cannot be both dynamic and kinematic.
  Scene bad = s;
  bad.bodies[0].dynamic = true;
  EXPECT_THROW(ValidateScene(bad), Error);
}

TEST(DenseScenes, RegistryAndBenchDefaults) {
  for (const std::string& name : DefaultBenchScenes()) {
    const std::vector<int> counts = DefaultBenchCounts(name);
    ASSERT_FALSE(counts.empty()) << name;
    EXPECT_NO_THROW(ValidateScene(MakeScene(name, counts.front()))) << name;
  }
  EXPECT_TRUE(IsDenseScene("pyramid"));
  EXPECT_TRUE(IsDenseScene("many_pyramids"));
  EXPECT_TRUE(IsDenseScene("tumbler"));
  EXPECT_TRUE(IsDenseScene("junkyard"));
  EXPECT_TRUE(IsDenseScene("smash"));
  EXPECT_FALSE(IsDenseScene("circle_stress"));
  EXPECT_THROW(DefaultBenchCounts("newtons_cradle"), Error);
  EXPECT_EQ(MakeScene("tumbler", 2025).bodies.size(), 4u + 2025u);
  EXPECT_EQ(MakeScene("many_pyramids", 22000).bodies.size(), 20u + 22000u);  // Box2D 3's size
}

// After 2 s the walls are where a rigid rotation of 25 deg/s about (0, 10) puts them (the driver
// moves each along chords of its circle), and no box has left the square.
void ExpectTumbles(const std::string& engine) {
  SCOPED_TRACE(engine);
  const Scene s = MakeTumbler(400);
  auto adapter = MakeAdapter(engine);
  adapter->Load(s, 1);
  const int steps = 120;
  for (int i = 0; i < steps; ++i) adapter->Step();
  std::vector<BodyState> st;
  adapter->ReadBodies(st);
  const double a = 25.0 * std::numbers::pi / 180.0 * steps / 60.0;
  const double offsets[4][2] = {{10, 0}, {-10, 0}, {0, 10}, {0, -10}};
  for (int k = 0; k < 4; ++k) {
    const double x = std::cos(a) * offsets[k][0] - std::sin(a) * offsets[k][1];
    const double y = 10 + std::sin(a) * offsets[k][0] + std::cos(a) * offsets[k][1];
    EXPECT_NEAR(double(st[k].position.x), x, 1e-3) << "wall " << k;
    EXPECT_NEAR(double(st[k].position.y), y, 1e-3) << "wall " << k;
    EXPECT_NEAR(double(st[k].angle), a, 1e-3) << "wall " << k;
  }
  int outside = 0;
  for (size_t i = 4; i < st.size(); ++i) {
    if (std::hypot(double(st[i].position.x), double(st[i].position.y) - 10) > 10 * std::sqrt(2.0)) ++outside;
  }
  EXPECT_EQ(outside, 0);
  EXPECT_GT(adapter->ContactCount(), 400);  // a dense pile: more contacts than boxes
}

TEST(DenseScenes, TumblerTurnsInEveryEngineThatRunsIt) {
  ExpectTumbles("quadrant");
  ExpectTumbles("quadrant:pgs");
  ExpectTumbles("box2d");
  ExpectTumbles("chipmunk");
  // Bullet moves kinematic bodies by transform, not velocity: it says so instead of running.
  auto bullet = MakeAdapter("bullet");
  EXPECT_THROW(bullet->Load(MakeTumbler(16), 1), Unsupported);
}

// Box2D 3's junkyard (box2d3.cpp): the pusher follows x = 60 sin(0.2 t) (the driver's velocity
// reaches each step's target), the pentagons fall onto the ground and stay between the walls.
void ExpectJunkyard(const std::string& engine) {
  SCOPED_TRACE(engine);
  const Scene s = MakeJunkyard(400);
  ASSERT_NO_THROW(ValidateScene(s));
  auto adapter = MakeAdapter(engine);
  adapter->Load(s, 1);
  const int steps = 180;
  for (int i = 0; i < steps; ++i) adapter->Step();
  std::vector<BodyState> st;
  adapter->ReadBodies(st);
  EXPECT_NEAR(double(st[0].position.x), 60.0 * std::sin(0.2 * steps / 60.0), 1e-3);
  EXPECT_NEAR(double(st[0].position.y), 4.0, 1e-4);
  int outside = 0;
  for (size_t i = 262; i < st.size(); ++i) {
    const double x = st[i].position.x, y = st[i].position.y;
    if (!(std::abs(x) < 80 && y > 0.4 && y < 40)) ++outside;
  }
  EXPECT_EQ(outside, 0);
}

TEST(Box2d3Scenes, JunkyardPusherFollowsItsTargetInEveryEngineThatRunsIt) {
  EXPECT_EQ(MakeScene("junkyard", 8000).bodies.size(), 1u + 261u + 8000u);  // Box2D 3's size
  ExpectJunkyard("quadrant");
  ExpectJunkyard("box2d");
  ExpectJunkyard("chipmunk");
  auto bullet = MakeAdapter("bullet");
  EXPECT_THROW(bullet->Load(MakeJunkyard(200), 1), Unsupported);
}

// Box2D 3's joint_grid (box2d3.cpp): the grid hangs from its seven static bodies and sags; no
// circle touches another (the filter), and the top corners sink.
void ExpectJointGrid(const std::string& engine) {
  SCOPED_TRACE(engine);
  const Scene s = MakeJointGrid(393);  // N = 20
  ASSERT_NO_THROW(ValidateScene(s));
  ASSERT_EQ(s.bodies.size(), 400u);
  ASSERT_EQ(s.joints.size(), 2u * 20u * 19u);
  auto adapter = MakeAdapter(engine);
  adapter->Load(s, 1);
  for (int i = 0; i < 120; ++i) adapter->Step();
  EXPECT_EQ(adapter->ContactCount(), 0);
  std::vector<BodyState> st;
  adapter->ReadBodies(st);
  // Body k * 20 + i is column k, row i. The fixed ones stay; the bottom corners have swung down.
  EXPECT_EQ(st[10 * 20].position.y, Real(0));
  // The lattice of pinned squares shears slowly: after 2 s the top corners have sunk a few cm
  // to a few dm (Quadrant 0.08 and 0.06 m, Box2D 2.4.1 0.19 and 0.02 m), and the first column's
  // links keep their 1 m within 1 %. Chipmunk's pivots (8 iterations) give way: its links are
  // 0.89-1.0 m and the corners jump up by 0.7 and 1.4 m; it is held to 15 % and finite. Bullet's
  // 6-dof joints hold to Quadrant's bounds.
  const bool chipmunk = engine == "chipmunk";
  for (int c : {0, 19 * 20}) {
    EXPECT_TRUE(std::isfinite(double(st[size_t(c)].position.y)));
    if (!chipmunk) {
      EXPECT_LT(st[size_t(c)].position.y, Real(-0.01)) << c;
      EXPECT_GT(st[size_t(c)].position.y, Real(-2)) << c;
    }
  }
  for (int i = 1; i < 20; ++i) {
    EXPECT_NEAR(double(Length(st[size_t(i)].position - st[size_t(i - 1)].position)), 1.0, chipmunk ? 0.15 : 0.01) << i;
  }
}

TEST(Box2d3Scenes, JointGridHangsInEveryEngineThatLoadsJoints) {
  EXPECT_EQ(MakeScene("joint_grid", 9993).bodies.size(), 10000u);  // Box2D 3's 100 x 100
  EXPECT_EQ(MakeScene("joint_grid", 9993).joints.size(), 19800u);
  EXPECT_EQ(MakeScene("joint_grid", 9994).bodies.size(), 101u * 101u);
  EXPECT_TRUE(IsDenseScene("joint_grid"));
  ExpectJointGrid("quadrant");
  ExpectJointGrid("box2d");
  ExpectJointGrid("chipmunk");
  ExpectJointGrid("bullet");
  auto pgs = MakeAdapter("quadrant:pgs");
  EXPECT_THROW(pgs->Load(MakeJointGrid(393), 1), Unsupported);
}

// Bad joints in a scene: refused by ValidateScene (and so by every adapter's Load) with the joint named.
TEST(Box2d3Scenes, BadSceneJointsAreRefused) {
  Scene s = MakeJointGrid(57);
  auto expectRefused = [&](auto&& edit, const char* what) {
    Scene bad = s;
    edit(bad.joints[3]);
    try {
      ValidateScene(bad);
      ADD_FAILURE() << "accepted: " << what;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("scene joint 3"), std::string::npos) << e.what();
    }
    auto adapter = MakeAdapter("quadrant");
    EXPECT_THROW(adapter->Load(bad, 1), Error) << what;
  };
  expectRefused([](JointDesc& j) { j.bodyB = 64; }, "index out of range");
  expectRefused([](JointDesc& j) { j.bodyB = j.bodyA; }, "same body");
  expectRefused([](JointDesc& j) { j.anchor.x = std::nanf(""); }, "NaN anchor");
  expectRefused([](JointDesc& j) { j.lowerAngle = 1; j.upperAngle = 0; }, "inverted limit");
  expectRefused([](JointDesc& j) { j.maxMotorTorque = -1; }, "negative torque");
  expectRefused([](JointDesc& j) { j.kind = JointKind::kPrismatic; j.axis = {0, 0}; }, "zero axis");
  expectRefused([](JointDesc& j) { j.lowerTranslation = 1; j.upperTranslation = 0; }, "inverted translation limits");
  expectRefused([](JointDesc& j) { j.kind = JointKind::kDistance; j.length = Real(0.001); }, "too short a rod");
  expectRefused([](JointDesc& j) { j.minLength = 2; j.maxLength = 1; }, "minLength > maxLength");
  expectRefused([](JointDesc& j) { j.maxMotorForce = -1; }, "negative force");
  expectRefused([](JointDesc& j) { j.kind = static_cast<JointKind>(9); }, "unknown kind");
  expectRefused([](JointDesc& j) { j.anchorB.y = INFINITY; }, "infinite anchorB");
}

// Box2D 3's smash: the wall of boxes is created asleep; the ram wakes and scatters the boxes it
// reaches, while the far end of the wall still sleeps (velocity 0) when the ram has just hit.
void ExpectSmash(const std::string& engine) {
  SCOPED_TRACE(engine);
  const Scene s = MakeSmash(1600);  // 20 columns of 80
  ASSERT_NO_THROW(ValidateScene(s));
  auto adapter = MakeAdapter(engine);
  adapter->Load(s, 1);
  std::vector<BodyState> st;
  // The ram's front starts 45.8 m from the wall: it arrives after about 69 steps.
  for (int i = 0; i < 60; ++i) adapter->Step();
  adapter->ReadBodies(st);
  for (size_t i = 1; i < st.size(); ++i) ASSERT_EQ(Length(st[i].velocity), 0) << "box " << i << " moved before the hit";
  for (int i = 0; i < 30; ++i) adapter->Step();
  adapter->ReadBodies(st);
  int moving = 0;
  for (size_t i = 1; i < st.size(); ++i) moving += Length(st[i].velocity) > 1 ? 1 : 0;
  EXPECT_GT(moving, 80);  // at least the first column flies
  EXPECT_LT(double(st[0].velocity.x), 40.0);  // the ram has given momentum away
}

TEST(Box2d3Scenes, SmashWakesTheSleepingWallInEveryEngine) {
  EXPECT_EQ(MakeScene("smash", 9600).bodies.size(), 1u + 9600u);  // Box2D 3's size
  for (const char* engine : {"quadrant", "quadrant:pgs", "box2d", "chipmunk", "bullet"}) ExpectSmash(engine);
  // A body created asleep needs the sleep effect.
  Scene awake = MakeSmash(80);
  awake.effects.sleep = false;
  EXPECT_THROW(ValidateScene(awake), Error);
}

// Box2D 3's compounds: bodies of two triangles (compound bodies) fall between the walls onto the
// ground; none passes through a wall or the ground. withoutSegment: the scene less its catch-all
// segment 80 m down (for Bullet, which has no segment shape).
void ExpectCompounds(const std::string& engine, bool withoutSegment = false) {
  SCOPED_TRACE(engine);
  Scene s = MakeCompounds(200);  // 10 rows of 20
  if (withoutSegment) {
    std::erase_if(s.bodies, [](const BodyDesc& b) { return b.shape == ShapeKind::kSegment; });
  }
  ASSERT_NO_THROW(ValidateScene(s));
  auto adapter = MakeAdapter(engine);
  adapter->Load(s, 1);
  for (int i = 0; i < 240; ++i) adapter->Step();
  std::vector<BodyState> st;
  adapter->ReadBodies(st);
  int outside = 0, resting = 0;
  for (size_t i = s.bodies.size() - 200; i < st.size(); ++i) {
    const double x = st[i].position.x, y = st[i].position.y;
    if (!(std::abs(x) < 39.5 && y > 0.4 && y < 40)) ++outside;
    resting += y < 6 ? 1 : 0;
  }
  EXPECT_EQ(outside, 0);
  EXPECT_GT(resting, 20);  // the first rows have landed
}

TEST(Box2d3Scenes, CompoundsFallBetweenTheWallsInEveryEngineThatRunsThem) {
  const Scene big = MakeScene("compounds", 3000);  // Box2D 3's size
  ASSERT_EQ(big.bodies.size(), 282u + 3000u);
  EXPECT_EQ(big.bodies.back().extraShapes.size(), 1u);
  // Two triangles of area 1 each at density 1.
  EXPECT_NEAR(ComputeMassProperties(big.bodies.back()).mass, 2.0, 1e-6);
  for (const char* engine : {"quadrant", "quadrant:pgs", "box2d", "chipmunk"}) ExpectCompounds(engine);
  // Bullet loads the compound bodies but has no segment shape: it refuses the scene, saying so,
  // and runs it without the segment.
  try {
    MakeAdapter("bullet")->Load(MakeCompounds(200), 1);
    ADD_FAILURE() << "bullet loaded a segment";
  } catch (const Unsupported& e) {
    EXPECT_NE(std::string(e.what()).find("segment"), std::string::npos) << e.what();
  }
  ExpectCompounds("bullet", /*withoutSegment=*/true);
  // The quadrants scheme has no compound bodies.
  EXPECT_THROW(MakeAdapter("quadrant:pgs+quadrants")->Load(MakeCompounds(200), 2), Unsupported);
  EXPECT_THROW(MakeCompounds(19), Error);
}

// Box2D 3's washer: a kinematic drum of 40 polygons on one body turns at 25 deg/s; the boxes
// inside stay inside (within the fins' radius 14 of the drum's centre) and are carried round.
void ExpectWasher(const std::string& engine) {
  SCOPED_TRACE(engine);
  const Scene s = MakeWasher(400);  // 20 x 20
  ASSERT_NO_THROW(ValidateScene(s));
  auto adapter = MakeAdapter(engine);
  adapter->Load(s, 1);
  const int steps = 240;
  for (int i = 0; i < steps; ++i) adapter->Step();
  std::vector<BodyState> st;
  adapter->ReadBodies(st);
  EXPECT_NEAR(double(st[0].angle), 4.0 * 25 * std::numbers::pi / 180, 1e-3);
  int outside = 0;
  double meanX = 0;
  for (size_t i = 1; i < st.size(); ++i) {
    const Vec2 d = st[i].position - st[0].position;
    if (!(Length(d) < 16)) ++outside;
    meanX += d.x / double(st.size() - 1);
  }
  EXPECT_EQ(outside, 0);
  // Turning counter-clockwise, the drum's bottom moves towards +x: the boxes ride up on the right.
  EXPECT_GT(meanX, 0.5);
}

TEST(Box2d3Scenes, WasherDrumTurnsTheBoxesInEveryEngineThatRunsIt) {
  const Scene big = MakeScene("washer", 8100);  // Box2D 3's size
  ASSERT_EQ(big.bodies.size(), 1u + 8100u);
  EXPECT_EQ(big.bodies[0].extraShapes.size() + 1, 40u);  // the drum: 36 pieces and 4 fins
  EXPECT_EQ(MakeScene("washer", 8200).bodies.size(), 1u + 8100u);  // rounds down to a square
  for (const char* engine : {"quadrant", "box2d", "chipmunk"}) ExpectWasher(engine);
  EXPECT_THROW(MakeAdapter("bullet")->Load(MakeWasher(400), 1), Unsupported);  // the kinematic drum
  EXPECT_THROW(MakeWasher(3), Error);
}

}  // namespace
}  // namespace quadrant::scene
