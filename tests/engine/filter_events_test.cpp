// Per-body user data, collision filtering (Box2D's category/mask rule) and begin/end contact
// events: behaviour, bad input, and that a world not using them is bit-identical to one
// without them.
#include <gtest/gtest.h>

#include <vector>

#include "quadrant/world.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

using namespace test;

BodyId AddFilteredCircle(World& world, Vec2 p, Filter filter) {
  BodyDef def;
  def.type = BodyType::kDynamic;
  def.position = p;
  def.shape = ShapeDef::MakeCircle(Real(0.5));
  def.filter = filter;
  return world.CreateBody(def);
}

TEST(FilterTest, BoxTwoRuleBothWays) {
  World world;
  BodyDef g;
  g.shape = ShapeDef::Box(20, Real(0.5));
  g.filter = {0x1, kAllCategories & ~0x4u};  // the ground ignores category 4
  const BodyId ground = world.CreateBody(g);
  const BodyId plain = AddFilteredCircle(world, {-4, 3}, Filter{});
  const BodyId notGround = AddFilteredCircle(world, {0, 3}, {0x2, kAllCategories & ~0x1u});  // ignores the ground
  const BodyId ignored = AddFilteredCircle(world, {4, 3}, {0x4, kAllCategories});  // the ground ignores it
  StepN(world, 120);
  EXPECT_NEAR(world.GetPosition(plain).y, 1.0, 0.02);  // rests on the ground
  EXPECT_LT(world.GetPosition(notGround).y, -5);        // fell through: its mask excludes the ground
  EXPECT_LT(world.GetPosition(ignored).y, -5);          // fell through: the ground's mask excludes it
  EXPECT_EQ(world.GetFilter(ground).maskBits, kAllCategories & ~0x4u);
  // SetFilter takes effect at the next step: put one back above the ground, restore its filter.
  world.SetTransform(notGround, {0, 3}, 0);
  world.SetLinearVelocity(notGround, {0, 0});
  world.SetFilter(notGround, Filter{});
  StepN(world, 120);
  EXPECT_NEAR(world.GetPosition(notGround).y, 1.0, 0.02);
}

TEST(FilterTest, FiltersThatDropNothingLeaveTheStateBitIdentical) {
  // Every pair passes these filters, so the state must be the plain world's bit for bit: the
  // filter pass runs (the filters are not the default) and only drops pairs.
  for (BroadPhaseType bp : {BroadPhaseType::kUniformGrid, BroadPhaseType::kQuadTree}) {
    WorldDef def;
    def.broadPhase = bp;
    World plain(def), filtered(def);
    for (World* w : {&plain, &filtered}) {
      AddGround(*w);
      for (int i = 0; i < 30; ++i) {
        const Filter f = w == &filtered ? Filter{0x2u << (i % 4), kAllCategories} : Filter{};
        AddFilteredCircle(*w, {Real(i % 6) - 3, Real(1 + i / 6)}, f);
      }
    }
    for (int s = 0; s < 90; ++s) {
      plain.Step(kDt);
      filtered.Step(kDt);
    }
    EXPECT_EQ(plain.StateHash(), filtered.StateHash());
    EXPECT_GT(plain.GetCounters().contacts, 20);
  }
}

TEST(FilterTest, RefusedUnderTheQuadrantsSchemeAndForStaleIds) {
  WorldDef def;
  def.scheme = ParallelScheme::kQuadrants;
  def.threadCount = 2;
  World world(def);
  AddGround(world);
  const BodyId ball = AddCircle(world, {0, 2});
  BodyDef d;
  d.type = BodyType::kDynamic;
  d.shape = ShapeDef::MakeCircle(Real(0.5));
  d.filter = {2, 1};
  const uint64_t hash = world.StateHash();
  ExpectError([&] { world.CreateBody(d); }, "non-default collision filter needs ParallelScheme::kDeterministic",
              "CreateBody under kQuadrants");
  ExpectError([&] { world.SetFilter(ball, {2, 1}); }, "SetFilter: a non-default collision filter needs", "SetFilter");
  EXPECT_EQ(world.GetBodyCount(), 2);
  EXPECT_EQ(world.StateHash(), hash);
  EXPECT_NO_THROW(world.SetFilter(ball, Filter{}));
  world.DestroyBody(ball);
  ExpectError([&] { world.SetFilter(ball, Filter{}); }, "stale or invalid BodyId", "stale SetFilter");
  ExpectError([&] { (void)world.GetFilter(ball); }, "stale or invalid BodyId", "stale GetFilter");
}

TEST(UserDataTest, StoredPerBodyAndRefusedForStaleIds) {
  World world;
  BodyDef def;
  def.type = BodyType::kDynamic;
  def.shape = ShapeDef::MakeCircle(1);
  def.userData = 0xfeedfacecafebeefull;
  const BodyId a = world.CreateBody(def);
  def.userData = 42;
  const BodyId b = world.CreateBody(def);
  EXPECT_EQ(world.GetUserData(a), 0xfeedfacecafebeefull);
  EXPECT_EQ(world.GetUserData(b), 42u);
  world.DestroyBody(a);  // b moves into a's dense place; its data must move with it
  EXPECT_EQ(world.GetUserData(b), 42u);
  world.SetUserData(b, 7);
  EXPECT_EQ(world.GetUserData(b), 7u);
  ExpectError([&] { (void)world.GetUserData(a); }, "stale or invalid BodyId", "stale GetUserData");
  ExpectError([&] { world.SetUserData(a, 1); }, "stale or invalid BodyId", "stale SetUserData");
  EXPECT_EQ(world.GetUserData(b), 7u);
}

TEST(ContactEventsTest, BeginOnLandingEndOnLeaving) {
  WorldDef def;
  def.contactEvents = true;
  World world(def);
  const BodyId ground = AddGround(world);
  const BodyId ball = AddCircle(world, {0, 3});
  const ContactEvent pair{ground.index < ball.index ? ground : ball, ground.index < ball.index ? ball : ground};
  int landed = -1, begins = 0, ends = 0;
  for (int s = 0; s < 120; ++s) {
    world.Step(kDt);
    for (const ContactEvent& e : world.GetContactBeginEvents()) {
      EXPECT_EQ(e, pair);
      if (landed < 0) landed = s;
      ++begins;
    }
    ends += int(world.GetContactEndEvents().size());
  }
  EXPECT_EQ(begins, 1);  // it lands once and stays
  EXPECT_EQ(ends, 0);
  EXPECT_GT(landed, 20);  // a 1.5 m fall takes about 0.55 s = 33 steps
  EXPECT_LT(landed, 45);
  world.SetTransform(ball, {0, 10}, 0);
  world.Step(kDt);
  ASSERT_EQ(world.GetContactEndEvents().size(), 1u);
  EXPECT_EQ(world.GetContactEndEvents()[0], pair);
  EXPECT_TRUE(world.GetContactBeginEvents().empty());
}

TEST(ContactEventsTest, FallingAsleepIsNotAnEnd) {
  // A sleeping island's contacts are not recomputed, but its bodies still touch: no end event
  // when it falls asleep, no second begin when it wakes.
  WorldDef def;
  def.contactEvents = true;
  def.effects.sleep = true;
  World world(def);
  AddGround(world);
  const BodyId box = AddBox(world, {0, 2});
  int begins = 0, ends = 0;
  bool slept = false;
  for (int s = 0; s < 240; ++s) {
    world.Step(kDt);
    begins += int(world.GetContactBeginEvents().size());
    ends += int(world.GetContactEndEvents().size());
    slept = slept || !world.IsAwake(box);
  }
  ASSERT_TRUE(slept);  // the case is really asleep
  EXPECT_EQ(begins, 1);
  EXPECT_EQ(ends, 0);
  world.SetAwake(box, true);
  for (int s = 0; s < 5; ++s) {
    world.Step(kDt);
    begins += int(world.GetContactBeginEvents().size());
    ends += int(world.GetContactEndEvents().size());
  }
  EXPECT_EQ(begins, 1);
  EXPECT_EQ(ends, 0);
}

TEST(ContactEventsTest, OffByDefaultAndReadingThemIsRefused) {
  World world;
  AddGround(world);
  AddCircle(world, {0, Real(0.99)});
  world.Step(kDt);
  ExpectError([&] { (void)world.GetContactBeginEvents(); }, "contact events are off (WorldDef::contactEvents)", "begin");
  ExpectError([&] { (void)world.GetContactEndEvents(); }, "contact events are off (WorldDef::contactEvents)", "end");
}

// 200 balls poured into a box with restitution: many begins and ends per step. The events are
// named by id and sorted, so they must be the same for 1, 2, 3 and 4 threads (the grain is
// lowered so the parallel sections really run), and turning them on must not change the state.
TEST(ContactEventsTest, SameEventsForAnyThreadCountAndStateUnchanged) {
  auto run = [](int threads, bool events, std::vector<ContactEvent>* log, uint64_t* hash) {
    WorldDef def;
    def.threadCount = threads;
    def.minParallelItems = 8;
    def.contactEvents = events;
    World world(def);
    AddGround(world, 10, Real(0.5), {0, 0});
    AddGround(world, Real(0.5), 20, {-10, 20});
    AddGround(world, Real(0.5), 20, {10, 20});
    for (int i = 0; i < 200; ++i) {
      AddCircle(world, {Real(-8 + (i % 16)), Real(2 + i / 16) * Real(1.1)}, Real(0.45), {Real((i % 5) - 2), 0}, 1,
                Real(0.3), Real(0.6));
    }
    for (int s = 0; s < 150; ++s) {
      world.Step(kDt);
      if (!events) continue;
      for (const ContactEvent& e : world.GetContactBeginEvents()) log->push_back(e);
      log->push_back(ContactEvent{});  // separates begins from ends and steps from steps
      for (const ContactEvent& e : world.GetContactEndEvents()) log->push_back(e);
      log->push_back(ContactEvent{});
    }
    *hash = world.StateHash();
  };
  std::vector<ContactEvent> one, other, none;
  uint64_t hashOne = 0, hashOther = 0, hashOff = 0;
  run(1, true, &one, &hashOne);
  run(1, false, &none, &hashOff);
  EXPECT_EQ(hashOne, hashOff);
  EXPECT_GT(one.size(), 2 * 150 + 500u);  // hundreds of events, not a quiet scene
  for (int threads : {2, 3, 4}) {
    other.clear();
    run(threads, true, &other, &hashOther);
    EXPECT_EQ(hashOther, hashOne) << threads << " threads";
    EXPECT_EQ(other, one) << threads << " threads";
  }
}

}  // namespace
}  // namespace quadrant
