// Filter::groupIndex (Box2D's group rule) and sensor shapes with their overlap events:
// behaviour, bad input, and that the state is the same for any thread count with both in use.
#include <gtest/gtest.h>

#include <utility>
#include <vector>

#include "quadrant/world.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

using namespace test;

BodyId AddCircleWith(World& world, Vec2 p, Filter filter, BodyType type = BodyType::kDynamic) {
  BodyDef def;
  def.type = type;
  def.position = p;
  def.shape = ShapeDef::MakeCircle(Real(0.5));
  def.filter = filter;
  return world.CreateBody(def);
}

TEST(FilterGroupTest, ShouldCollideFollowsBoxTwosRule) {
  const Filter plain{};
  const Filter none{1, 0, 0};  // collides with nothing by its bits
  EXPECT_TRUE(ShouldCollide(plain, plain));
  EXPECT_FALSE(ShouldCollide(plain, none));
  // The same positive group: always, whatever the bits.
  EXPECT_TRUE(ShouldCollide(Filter{1, 0, 3}, Filter{1, 0, 3}));
  // The same negative group: never, whatever the bits.
  EXPECT_FALSE(ShouldCollide(Filter{1, kAllCategories, -2}, Filter{1, kAllCategories, -2}));
  // Different groups (or one of them 0): the bits decide.
  EXPECT_TRUE(ShouldCollide(Filter{1, kAllCategories, -2}, Filter{1, kAllCategories, -3}));
  EXPECT_FALSE(ShouldCollide(Filter{1, 0, 3}, Filter{1, 0, 4}));
  EXPECT_TRUE(ShouldCollide(Filter{1, kAllCategories, -2}, Filter{1, kAllCategories, 0}));
  EXPECT_FALSE(ShouldCollide(Filter{1, 0, 0}, Filter{1, 0, 0}));  // group 0 is no group
}

TEST(FilterGroupTest, NegativeGroupsPassThroughPositiveGroupsCollide) {
  World world;
  AddGround(world);
  // Two balls above each other in the same negative group: the upper one falls through the lower
  // one and both rest on the ground side by side in the same place.
  const BodyId lowNeg = AddCircleWith(world, {-4, 1}, Filter{1, kAllCategories, -1});
  const BodyId highNeg = AddCircleWith(world, {-4, 3}, Filter{1, kAllCategories, -1});
  // Two balls whose bits exclude each other (and not the ground) but that share a positive group:
  // they stack.
  const BodyId lowPos = AddCircleWith(world, {4, 1}, Filter{2, kAllCategories & ~2u, 5});
  const BodyId highPos = AddCircleWith(world, {4, 3}, Filter{2, kAllCategories & ~2u, 5});
  // The same bits without the group: they pass through each other.
  const BodyId lowBits = AddCircleWith(world, {0, 1}, Filter{2, kAllCategories & ~2u, 0});
  const BodyId highBits = AddCircleWith(world, {0, 3}, Filter{2, kAllCategories & ~2u, 0});
  StepN(world, 120);
  EXPECT_NEAR(world.GetPosition(lowNeg).y, 1.0, 0.02);
  EXPECT_NEAR(world.GetPosition(highNeg).y, 1.0, 0.02);
  EXPECT_NEAR(world.GetPosition(lowPos).y, 1.0, 0.02);
  EXPECT_NEAR(world.GetPosition(highPos).y, 2.0, 0.05);  // on top of the other
  EXPECT_NEAR(world.GetPosition(lowBits).y, 1.0, 0.02);
  EXPECT_NEAR(world.GetPosition(highBits).y, 1.0, 0.02);
  EXPECT_EQ(world.GetFilter(highNeg).groupIndex, -1);
  // SetFilter with a group takes effect at the next step: leave the negative group and stack.
  world.SetTransform(highNeg, {-4, 3}, 0);
  world.SetLinearVelocity(highNeg, {0, 0});
  world.SetFilter(highNeg, Filter{1, kAllCategories, 0});
  StepN(world, 120);
  EXPECT_NEAR(world.GetPosition(highNeg).y, 2.0, 0.05);
}

TEST(FilterGroupTest, RefusedUnderTheQuadrantsScheme) {
  WorldDef def;
  def.scheme = ParallelScheme::kQuadrants;
  def.threadCount = 2;
  World world(def);
  const BodyId ball = AddCircle(world, {0, 2});
  BodyDef d;
  d.type = BodyType::kDynamic;
  d.shape = ShapeDef::MakeCircle(Real(0.5));
  d.filter.groupIndex = -1;
  const uint64_t hash = world.StateHash();
  ExpectError([&] { world.CreateBody(d); }, "non-default collision filter needs ParallelScheme::kDeterministic",
              "CreateBody");
  ExpectError([&] { world.SetFilter(ball, Filter{1, kAllCategories, 1}); }, "SetFilter: a non-default collision filter",
              "SetFilter");
  EXPECT_EQ(world.GetBodyCount(), 1);
  EXPECT_EQ(world.GetFilter(ball), Filter{});
  EXPECT_EQ(world.StateHash(), hash);
}

BodyId AddSensor(World& world, Vec2 p, ShapeDef shape, BodyType type = BodyType::kStatic, Filter filter = {}) {
  BodyDef def;
  def.type = type;
  def.position = p;
  def.shape = shape;
  def.shape.isSensor = true;
  def.filter = filter;
  return world.CreateBody(def);
}

struct SensorLog {
  std::vector<std::pair<int, SensorEvent>> begins, ends;  // (step, event)
  void Read(const World& world, int step) {
    for (const SensorEvent& e : world.GetSensorBeginEvents()) begins.push_back({step, e});
    for (const SensorEvent& e : world.GetSensorEndEvents()) ends.push_back({step, e});
  }
};

TEST(SensorTest, BallFallsThroughAStaticSensorUntouchedWithOneBeginAndOneEnd) {
  World world, plain;
  AddGround(world);
  AddGround(plain);
  const BodyId sensor = AddSensor(world, {0, 5}, ShapeDef::Box(1, 1));  // y in [4, 6]
  const BodyId ball = AddCircle(world, {0, 10});
  const BodyId plainBall = AddCircle(plain, {0, 10});
  SensorLog log;
  std::vector<Real> y{world.GetPosition(ball).y};  // y[s]: after s steps
  for (int s = 0; s < 150; ++s) {
    world.Step(kDt);
    plain.Step(kDt);
    log.Read(world, s);
    y.push_back(world.GetPosition(ball).y);
    // The sensor pushes nothing: the ball moves exactly as in a world without it.
    ASSERT_EQ(world.GetPosition(ball), plain.GetPosition(plainBall)) << s;
  }
  ASSERT_EQ(log.begins.size(), 1u);
  ASSERT_EQ(log.ends.size(), 1u);
  EXPECT_EQ(log.begins[0].second, (SensorEvent{sensor, ball}));
  EXPECT_EQ(log.ends[0].second, (SensorEvent{sensor, ball}));
  // Overlaps are seen where the step starts: the step of the begin started with the ball's
  // bottom (y - 0.5) at or below the top of the sensor (6), the step before above it.
  const int b = log.begins[0].first, e = log.ends[0].first;
  EXPECT_LE(y[size_t(b)] - 0.5, 6.0);
  EXPECT_GT(y[size_t(b - 1)] - 0.5, 6.0);
  // ... and the step of the end started with its top (y + 0.5) below the sensor's bottom (4).
  EXPECT_LT(y[size_t(e)] + 0.5, 4.0);
  EXPECT_GE(y[size_t(e - 1)] + 0.5, 4.0);
  EXPECT_NEAR(world.GetPosition(ball).y, 1.0, 0.02);  // then it rests on the ground
  EXPECT_EQ(world.GetCounters().contacts, 1);         // the ground's; the sensor has none
  EXPECT_TRUE(world.GetShape(sensor).isSensor);
}

TEST(SensorTest, DynamicAndKinematicSensorsAndTheRules) {
  WorldDef def;
  def.gravity = {0, 0};
  World world(def);
  const BodyId ground = AddGround(world);  // y in [-0.5, 0.5]
  // A dynamic sensor moving down through the ground senses it (a static visitor) and passes.
  const BodyId diver = AddSensor(world, {-5, Real(1.6)}, ShapeDef::MakeCircle(Real(0.5)), BodyType::kDynamic);
  world.SetLinearVelocity(diver, {0, -3});
  // A kinematic sensor sweeping over a dynamic box senses it; a static box it does not sense (no
  // pair: neither is dynamic).
  BodyDef k;
  k.type = BodyType::kKinematic;
  k.position = {4, Real(2.5)};
  k.linearVelocity = {0, -3};
  k.shape = ShapeDef::Box(Real(0.5), Real(0.5));
  k.shape.isSensor = true;
  const BodyId sweeper = world.CreateBody(k);
  const BodyId box = AddBox(world, {4, 1});
  BodyDef st;
  st.position = {4, Real(-0.2)};
  st.shape = ShapeDef::Box(Real(0.2), Real(0.2));
  world.CreateBody(st);  // overlaps the ground: a static pair, never found
  // A second sensor where the diver passes: sensors do not sense each other.
  AddSensor(world, {-5, 1}, ShapeDef::Box(1, Real(0.2)));
  // A sensor that its filter keeps from the box it overlaps.
  AddSensor(world, {4, 1}, ShapeDef::Box(1, 1), BodyType::kStatic, Filter{1, kAllCategories, -7});
  world.SetFilter(box, Filter{1, kAllCategories, -7});
  SensorLog log;
  for (int s = 0; s < 60; ++s) {
    world.Step(kDt);
    log.Read(world, s);
  }
  // In the order they happened (each pass takes under a second).
  std::vector<SensorEvent> begins, ends;
  for (const auto& [step, e] : log.begins) begins.push_back(e);
  for (const auto& [step, e] : log.ends) ends.push_back(e);
  const std::vector<SensorEvent> want{{sweeper, box}, {diver, ground}};
  EXPECT_EQ(begins, want);
  EXPECT_EQ(ends, want);
  EXPECT_LT(world.GetPosition(diver).y, -1);
  EXPECT_NEAR(world.GetPosition(box).y, 1.0, 1e-3);  // neither sensor pushed it
  EXPECT_NEAR(world.GetLinearVelocity(box).y, 0.0, 1e-3);
}

TEST(SensorTest, DestroyingEitherEndsTheOverlapAndTheEventsThenClear) {
  World world;
  const BodyId sensor = AddSensor(world, {0, 0}, ShapeDef::Box(5, 5));
  const BodyId a = AddCircle(world, {-1, 0});
  const BodyId b = AddCircle(world, {1, 0});
  world.Step(kDt);
  const std::vector<SensorEvent> both{{sensor, a}, {sensor, b}};
  EXPECT_EQ(std::vector<SensorEvent>(world.GetSensorBeginEvents().begin(), world.GetSensorBeginEvents().end()), both);
  world.DestroyBody(a);
  world.Step(kDt);
  ASSERT_EQ(world.GetSensorEndEvents().size(), 1u);
  EXPECT_EQ(world.GetSensorEndEvents()[0], (SensorEvent{sensor, a}));
  EXPECT_FALSE(world.IsValid(world.GetSensorEndEvents()[0].visitor));
  EXPECT_TRUE(world.GetSensorBeginEvents().empty());
  world.DestroyBody(sensor);  // the last sensor: its overlaps end all the same
  world.Step(kDt);
  ASSERT_EQ(world.GetSensorEndEvents().size(), 1u);
  EXPECT_EQ(world.GetSensorEndEvents()[0], (SensorEvent{sensor, b}));
  world.Step(kDt);
  EXPECT_TRUE(world.GetSensorEndEvents().empty());
  EXPECT_TRUE(world.GetSensorBeginEvents().empty());
}

TEST(SensorTest, FallingAsleepInsideIsNotAnEnd) {
  WorldDef def;
  def.effects.sleep = true;
  World world(def);
  AddGround(world);
  const BodyId sensor = AddSensor(world, {0, 1}, ShapeDef::Box(2, 1));
  const BodyId box = AddBox(world, {0, 2});
  SensorLog log;
  bool slept = false;
  for (int s = 0; s < 240; ++s) {
    world.Step(kDt);
    log.Read(world, s);
    slept = slept || !world.IsAwake(box);
  }
  ASSERT_TRUE(slept);
  ASSERT_EQ(log.begins.size(), 1u);
  EXPECT_EQ(log.begins[0].second, (SensorEvent{sensor, box}));
  EXPECT_TRUE(log.ends.empty());
  world.SetAwake(box, true);
  for (int s = 0; s < 5; ++s) {
    world.Step(kDt);
    log.Read(world, s);
  }
  EXPECT_EQ(log.begins.size(), 1u);
  EXPECT_TRUE(log.ends.empty());
}

TEST(SensorTest, RefusedUnderTheQuadrantsScheme) {
  WorldDef def;
  def.scheme = ParallelScheme::kQuadrants;
  def.threadCount = 2;
  World world(def);
  AddCircle(world, {0, 2});
  BodyDef d;
  d.shape = ShapeDef::Box(1, 1);
  d.shape.isSensor = true;
  const uint64_t hash = world.StateHash();
  ExpectError([&] { world.CreateBody(d); }, "CreateBody: a sensor shape needs ParallelScheme::kDeterministic",
              "CreateBody");
  EXPECT_EQ(world.GetBodyCount(), 1);
  EXPECT_EQ(world.StateHash(), hash);
  EXPECT_TRUE(world.GetSensorBeginEvents().empty());
}

// Balls poured into a box past static sensor strips, with dynamic sensor balls among them, group
// filters (a negative group that never collides, a positive one whose bits exclude each other):
// the state and every sensor event must be the same for 1, 2, 3 and 4 threads, with the grain
// lowered so the parallel sections run.
TEST(SensorTest, SameStateAndEventsForAnyThreadCountWithSensorsAndGroups) {
  auto run = [](int threads, bool reusePairs, std::vector<SensorEvent>* log, uint64_t* hash) {
    WorldDef def;
    def.threadCount = threads;
    def.minParallelItems = 8;
    def.reusePairs = reusePairs;
    World world(def);
    AddGround(world, 10, Real(0.5), {0, 0});
    AddGround(world, Real(0.5), 20, {-10, 20});
    AddGround(world, Real(0.5), 20, {10, 20});
    for (int k = 0; k < 4; ++k) AddSensor(world, {0, Real(2 + 3 * k)}, ShapeDef::Box(9, Real(0.3)));
    for (int i = 0; i < 200; ++i) {
      BodyDef d;
      d.type = BodyType::kDynamic;
      d.position = {Real(-8 + (i % 16)), Real(2 + i / 16) * Real(1.1)};
      d.linearVelocity = {Real((i % 5) - 2), 0};
      d.shape = i % 3 == 0 ? ShapeDef::Box(Real(0.4), Real(0.4)) : ShapeDef::MakeCircle(Real(0.45));
      d.shape.restitution = Real(0.3);
      d.shape.isSensor = i % 23 == 0;
      d.filter.groupIndex = i % 7 == 0 ? -1 : i % 7 == 1 ? 2 : 0;
      if (i % 7 == 1) d.filter = Filter{2, kAllCategories & ~2u, 2};
      world.CreateBody(d);
    }
    for (int s = 0; s < 150; ++s) {
      world.Step(kDt);
      for (const SensorEvent& e : world.GetSensorBeginEvents()) log->push_back(e);
      log->push_back(SensorEvent{});  // separates begins from ends and steps from steps
      for (const SensorEvent& e : world.GetSensorEndEvents()) log->push_back(e);
      log->push_back(SensorEvent{});
    }
    *hash = world.StateHash();
  };
  std::vector<SensorEvent> one, other;
  uint64_t hashOne = 0, hashOther = 0;
  run(1, true, &one, &hashOne);
  EXPECT_GT(one.size(), 4 * 150 + 200u);  // hundreds of events, not a quiet scene
  for (int threads : {1, 2, 3, 4}) {
    other.clear();
    run(threads, threads == 1 ? false : true, &other, &hashOther);
    EXPECT_EQ(hashOther, hashOne) << threads << " threads";
    EXPECT_EQ(other, one) << threads << " threads";
  }
}

}  // namespace
}  // namespace quadrant
