// Sleeping (engine/src/dynamics/islands.cpp): a settled pile falls asleep and stops, a touch or a write
// wakes it, a world without sleep is unchanged bit for bit, sleep is thread-count invariant in
// the deterministic scheme, and bad sleep settings are refused.
#include <gtest/gtest.h>

#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "quadrant/error.h"
#include "quadrant/world.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

using namespace test;  // the small-world builders of test_helpers.h

// A pyramid of boxes (side 1 m, `base` boxes in the bottom row) on a static ground whose top is
// at y = 0. Returns the boxes.
std::vector<BodyId> AddPyramid(World& world, int base) {
  AddGround(world, 40, Real(0.5), {0, Real(-0.5)});
  std::vector<BodyId> boxes;
  for (int row = 0; row < base; ++row) {
    const int count = base - row;
    for (int k = 0; k < count; ++k) {
      const Real x = Real(k) - Real(count - 1) * Real(0.5);
      boxes.push_back(AddBox(world, {x, Real(0.5) + Real(row)}));
    }
  }
  return boxes;
}

WorldDef SleepDef() {
  WorldDef def;
  def.effects.sleep = true;
  return def;
}

int AwakeCount(const World& world, const std::vector<BodyId>& ids) {
  int awake = 0;
  for (BodyId id : ids) awake += world.IsAwake(id) ? 1 : 0;
  return awake;
}

// Steps until every body in `ids` sleeps; returns the steps taken, or -1 after `maxSteps`.
int StepUntilAsleep(World& world, const std::vector<BodyId>& ids, int maxSteps) {
  for (int s = 1; s <= maxSteps; ++s) {
    world.Step(kDt);
    if (AwakeCount(world, ids) == 0) return s;
  }
  return -1;
}

TEST(SleepTest, SettledPyramidFallsAsleepAndStops) {
  World world(SleepDef());
  const std::vector<BodyId> boxes = AddPyramid(world, 8);
  EXPECT_EQ(AwakeCount(world, boxes), int(boxes.size()));
  const int steps = StepUntilAsleep(world, boxes, 5 * 60);
  ASSERT_GT(steps, 0) << "the pyramid did not fall asleep within 5 s";
  EXPECT_GE(steps, 30) << "asleep before timeToSleep (0.5 s) could pass";
  for (BodyId id : boxes) {
    EXPECT_EQ(world.GetLinearVelocity(id).x, 0);
    EXPECT_EQ(world.GetLinearVelocity(id).y, 0);
    EXPECT_EQ(world.GetAngularVelocity(id), 0);
  }
  std::vector<Vec2> before;
  for (BodyId id : boxes) before.push_back(world.GetPosition(id));
  const uint64_t hash = world.StateHash();
  StepN(world, 120);
  EXPECT_EQ(world.StateHash(), hash) << "a sleeping pile moved";
  for (size_t k = 0; k < boxes.size(); ++k) {
    EXPECT_EQ(world.GetPosition(boxes[k]).x, before[k].x);
    EXPECT_EQ(world.GetPosition(boxes[k]).y, before[k].y);
  }
  // Sleeping pairs are not even searched: no candidate pairs, no contacts.
  EXPECT_EQ(world.GetCounters().candidatePairs, 0);
  EXPECT_EQ(world.GetCounters().contacts, 0);
  // Still standing: the top box is near its built height (row 7 at y = 7.5).
  EXPECT_GT(world.GetPosition(boxes.back()).y, Real(7.3));
}

TEST(SleepTest, ThrownBodyWakesThePile) {
  World world(SleepDef());
  const std::vector<BodyId> boxes = AddPyramid(world, 6);
  ASSERT_GT(StepUntilAsleep(world, boxes, 5 * 60), 0);
  const Vec2 hitBox = world.GetPosition(boxes[0]);  // bottom left
  // A ball 3 m to the left of the pile (not touching: creating it wakes nothing), at 10 m/s.
  const BodyId ball = AddCircle(world, {hitBox.x - Real(3.5), Real(0.5)}, Real(0.5), {10, 0}, 5);
  EXPECT_EQ(AwakeCount(world, boxes), 0) << "a body created apart from the pile woke it";
  EXPECT_TRUE(world.IsAwake(ball));
  int hitStep = -1;
  for (int s = 1; s <= 60 && hitStep < 0; ++s) {
    world.Step(kDt);
    if (AwakeCount(world, boxes) > 0) hitStep = s;
  }
  ASSERT_GT(hitStep, 0) << "the ball never woke the pile";
  // The whole island wakes, not only the box that was hit.
  EXPECT_EQ(AwakeCount(world, boxes), int(boxes.size()));
  StepN(world, 10);
  EXPECT_GT(world.GetPosition(boxes[0]).x - hitBox.x, Real(0.01)) << "the hit box did not move";
  EXPECT_LT(world.GetPosition(ball).x, world.GetPosition(boxes[0]).x) << "the ball passed through the pile";
}

TEST(SleepTest, WritesWakeASleepingBody) {
  World world(SleepDef());
  const std::vector<BodyId> boxes = AddPyramid(world, 3);
  ASSERT_GT(StepUntilAsleep(world, boxes, 5 * 60), 0);
  const BodyId top = boxes.back();
  const Vec2 p0 = world.GetPosition(top);
  world.SetLinearVelocity(top, {0, 3});
  EXPECT_TRUE(world.IsAwake(top));
  EXPECT_EQ(world.GetLinearVelocity(top).y, Real(3));
  EXPECT_EQ(AwakeCount(world, boxes), int(boxes.size())) << "its island stays asleep";
  world.Step(kDt);
  EXPECT_GT(world.GetPosition(top).y, p0.y + Real(0.03));


  ASSERT_GT(StepUntilAsleep(world, boxes, 10 * 60), 0);
  world.SetAwake(boxes[1], true);
  EXPECT_EQ(AwakeCount(world, boxes), int(boxes.size()));
  ASSERT_GT(StepUntilAsleep(world, boxes, 10 * 60), 0);
  const Vec2 p1 = world.GetPosition(top);
  world.SetTransform(top, {p1.x + 10, p1.y}, 0);  // lifted off: it falls, the rest wakes too
  EXPECT_TRUE(world.IsAwake(top));
  EXPECT_TRUE(world.IsAwake(boxes[0]));
  StepN(world, 10);
  EXPECT_LT(world.GetPosition(top).y, p1.y - Real(0.1));

  // Last, as it knocks the bottom-left box out of the pile (its own island from then on).
  ASSERT_GT(StepUntilAsleep(world, boxes, 10 * 60), 0);
  world.ApplyLinearImpulse(boxes[0], {-5, 0}, world.GetWorldCenter(boxes[0]));
  EXPECT_TRUE(world.IsAwake(boxes[0]));
  EXPECT_LT(world.GetLinearVelocity(boxes[0]).x, Real(-1)) << "the impulse acted on inverse mass 0";
}

TEST(SleepTest, SetAwakeAndBodyTypes) {
  World world(SleepDef());
  const BodyId ground = AddGround(world);
  BodyDef kin;
  kin.type = BodyType::kKinematic;
  kin.position = {0, 10};
  kin.shape = ShapeDef::MakeCircle(1);
  const BodyId kinematic = world.CreateBody(kin);
  const BodyId ball = AddCircle(world, {5, 20});
  EXPECT_FALSE(world.IsAwake(ground));  // static bodies are never simulated
  EXPECT_TRUE(world.IsAwake(kinematic));
  EXPECT_TRUE(world.IsAwake(ball));
  world.SetAwake(kinematic, false);  // no effect on kinematic bodies
  EXPECT_TRUE(world.IsAwake(kinematic));
  world.SetLinearVelocity(ball, {1, 0});
  world.SetAwake(ball, false);
  EXPECT_FALSE(world.IsAwake(ball));
  EXPECT_EQ(world.GetLinearVelocity(ball).x, 0);
  const Vec2 p = world.GetPosition(ball);
  StepN(world, 30);  // asleep in mid-air: not integrated, gravity does not act
  EXPECT_EQ(world.GetPosition(ball).y, p.y);
  world.SetAwake(ball, true);
  StepN(world, 30);
  EXPECT_LT(world.GetPosition(ball).y, p.y - Real(1));
}

// Sleep off: no body ever sleeps, and changing the (unused) sleep settings changes nothing.
TEST(SleepTest, SleepOffNeverSleepsAndKeepsResults) {
  WorldDef tuned;
  tuned.linearSleepTolerance = Real(10);
  tuned.angularSleepTolerance = Real(10);
  tuned.timeToSleep = Real(0.01);
  World plain{WorldDef{}};
  World other(tuned);
  const std::vector<BodyId> a = AddPyramid(plain, 6);
  const std::vector<BodyId> b = AddPyramid(other, 6);
  plain.SetAwake(a[0], false);  // no effect without sleep
  EXPECT_TRUE(plain.IsAwake(a[0]));
  for (int s = 0; s < 240; ++s) {
    plain.Step(kDt);
    other.Step(kDt);
    ASSERT_EQ(AwakeCount(plain, a), int(a.size())) << "step " << s;
    ASSERT_EQ(AwakeCount(other, b), int(b.size())) << "step " << s;
  }
  EXPECT_EQ(plain.StateHash(), other.StateHash());
  EXPECT_GT(plain.GetCounters().contacts, 0);  // still simulated: the pile's contacts exist
}

// Run under ThreadSanitizer in CI (the name matches DeterministicScheme).
TEST(DeterministicSchemeSleep, StateHashIsThreadCountInvariant) {
  auto run = [](int threads, int& maxAsleep) {
    WorldDef def = SleepDef();
    def.threadCount = threads;
    def.minParallelItems = 1;  // exercise the parallel sections on a small scene
    World world(def);
    const std::vector<BodyId> boxes = AddPyramid(world, 8);
    maxAsleep = 0;
    int parallelSteps = 0;
    for (int s = 0; s < 240; ++s) {
      world.Step(kDt);
      maxAsleep = std::max(maxAsleep, int(boxes.size()) - AwakeCount(world, boxes));
      parallelSteps += ParallelSectionRan(world.GetProfile()) ? 1 : 0;
    }
    if (threads > 1) {
      EXPECT_GT(parallelSteps, 0) << threads << " threads: no section ran in parallel";
    }
    AddCircle(world, {-8, Real(0.5)}, Real(0.5), {12, 0}, 5);  // wakes the pile
    StepN(world, 120);
    return world.StateHash();
  };
  int asleep1 = 0;
  const uint64_t h1 = run(1, asleep1);
  EXPECT_GT(asleep1, 0) << "nothing fell asleep: the test would not cover sleeping";
  for (int threads = 2; threads <= 4; ++threads) {
    int asleep = 0;
    EXPECT_EQ(run(threads, asleep), h1) << threads << " threads";
    EXPECT_EQ(asleep, asleep1) << threads << " threads";
  }
}

TEST(SleepTest, BadSleepSettingsAreRefused) {
  constexpr Real kNaN = std::numeric_limits<Real>::quiet_NaN();
  constexpr Real kInf = std::numeric_limits<Real>::infinity();
  auto refuse = [](const std::function<void(WorldDef&)>& edit, const std::string& message, const std::string& what) {
    WorldDef d;
    d.effects.sleep = true;
    edit(d);
    ExpectError([&] { World w(d); }, message, what);
  };
  refuse([](WorldDef& d) { d.linearSleepTolerance = -1; }, "WorldDef.linearSleepTolerance must be finite and >= 0", "linear -1");
  refuse([&](WorldDef& d) { d.linearSleepTolerance = kNaN; }, "WorldDef.linearSleepTolerance", "linear NaN");
  refuse([&](WorldDef& d) { d.angularSleepTolerance = kInf; }, "WorldDef.angularSleepTolerance must be finite and >= 0", "angular inf");
  refuse([](WorldDef& d) { d.angularSleepTolerance = Real(-0.1); }, "WorldDef.angularSleepTolerance", "angular -0.1");
  refuse([](WorldDef& d) { d.timeToSleep = 0; }, "WorldDef.timeToSleep must be finite and > 0", "time 0");
  refuse([&](WorldDef& d) { d.timeToSleep = kNaN; }, "WorldDef.timeToSleep", "time NaN");
  refuse([](WorldDef& d) { d.scheme = ParallelScheme::kQuadrants; }, "effects.sleep is not supported with ParallelScheme::kQuadrants", "quadrants");
  // Settings are validated with sleep off too (a bad value is a bug whether or not it is used).
  WorldDef off;
  off.timeToSleep = -1;
  ExpectError([&] { World w(off); }, "WorldDef.timeToSleep", "time -1, sleep off");
  // Sleep 0 tolerances are allowed (nothing is ever slow enough unless exactly at rest).
  WorldDef zero;
  zero.effects.sleep = true;
  zero.linearSleepTolerance = 0;
  zero.angularSleepTolerance = 0;
  EXPECT_NO_THROW(World w(zero));

  // Stale ids: IsAwake and SetAwake throw and change nothing.
  World world(SleepDef());
  const std::vector<BodyId> boxes = AddPyramid(world, 3);
  const BodyId gone = AddCircle(world, {10, 5});
  world.DestroyBody(gone);
  StepN(world, 5);
  const uint64_t hash = world.StateHash();
  ExpectError([&] { (void)world.IsAwake(gone); }, "stale or invalid BodyId", "IsAwake stale");
  ExpectError([&] { world.SetAwake(gone, false); }, "stale or invalid BodyId", "SetAwake stale");
  ExpectError([&] { world.SetAwake(BodyId{}, true); }, "stale or invalid BodyId", "SetAwake null");
  EXPECT_EQ(world.StateHash(), hash);
  EXPECT_EQ(AwakeCount(world, boxes), int(boxes.size()));
}

TEST(SleepTest, ABodyCreatedAsleepStaysPutUntilAnAwakeBodyTouchesIt) {
  // BodyDef::isAwake = false (Box2D 3's smash): no gravity acts on it while it sleeps; a box
  // thrown at it wakes it and moves it.
  World world(SleepDef());
  BodyDef def;
  def.type = BodyType::kDynamic;
  def.position = {0, 5};
  def.shape = ShapeDef::Box(Real(0.5), Real(0.5));
  def.isAwake = false;
  const BodyId asleep = world.CreateBody(def);
  EXPECT_FALSE(world.IsAwake(asleep));
  for (int i = 0; i < 30; ++i) world.Step(kDt);
  EXPECT_EQ(world.GetPosition(asleep).y, 5);
  EXPECT_FALSE(world.IsAwake(asleep));
  BodyDef thrown = def;
  thrown.isAwake = true;
  thrown.position = {-3, 5};
  thrown.linearVelocity = {10, 0};
  thrown.gravityScale = 0;
  world.CreateBody(thrown);
  for (int i = 0; i < 30; ++i) world.Step(kDt);
  EXPECT_TRUE(world.IsAwake(asleep));
  EXPECT_GT(world.GetPosition(asleep).x, 0.5);
}

TEST(SleepTest, ABodyCreatedAsleepNeedsSleepAndADynamicBody) {
  for (bool sleep : {false, true}) {
    WorldDef wd = SleepDef();
    wd.effects.sleep = sleep;
    World world(wd);
    BodyDef def;
    def.type = sleep ? BodyType::kStatic : BodyType::kDynamic;  // each refusal in turn
    def.shape = ShapeDef::Box(Real(0.5), Real(0.5));
    def.isAwake = false;
    EXPECT_THROW(world.CreateBody(def), Error);
    EXPECT_EQ(world.GetBodyCount(), 0);
  }
}

}  // namespace
}  // namespace quadrant
