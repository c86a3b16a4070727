// Contact hit events (WorldDef::hitEvents): one per landing with the approach speed, point and
// normal; none for resting or already touching pairs; bad input; the same events for any thread
// count and the state unchanged by turning them on.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "quadrant/world.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

using namespace test;

WorldDef HitDef(Real threshold = 1) {
  WorldDef def;
  def.hitEvents = true;
  def.hitEventThreshold = threshold;
  return def;
}

TEST(HitEventsTest, OneHitOnLandingWithSpeedPointAndNormal) {
  World world(HitDef());
  const BodyId ground = AddGround(world);   // top at y = 0.5
  const BodyId ball = AddCircle(world, {2, 3});  // bottom at 2.5: a 2 m fall
  std::vector<ContactHitEvent> hits;
  Real speedBefore = 0;  // the ball's speed when the step of the hit began
  for (int s = 0; s < 120; ++s) {
    const Real v = -world.GetLinearVelocity(ball).y;
    world.Step(kDt);
    for (const ContactHitEvent& e : world.GetContactHitEvents()) {
      hits.push_back(e);
      speedBefore = v;
    }
  }
  ASSERT_EQ(hits.size(), 1u);  // it lands once and stays
  const ContactHitEvent& e = hits[0];
  EXPECT_EQ(e.bodyA, ground);  // created first: the lower index
  EXPECT_EQ(e.bodyB, ball);
  EXPECT_FLOAT_EQ(e.approachSpeed, speedBefore);  // the velocity before the solver
  EXPECT_NEAR(e.approachSpeed, std::sqrt(2 * 10 * 2.0), 0.3);
  EXPECT_TRUE(VecNear(e.normal, {0, 1}, 1e-5));  // from the ground (A) up to the ball (B)
  EXPECT_NEAR(e.point.x, 2.0, 1e-3);
  EXPECT_NEAR(e.point.y, 0.5, 0.15);  // between the surfaces, which are a step's travel apart at most

  // Above the threshold only: the same fall with a threshold above its speed reports nothing.
  World calm(HitDef(Real(7)));
  AddGround(calm);
  AddCircle(calm, {2, 3});
  for (int s = 0; s < 120; ++s) {
    calm.Step(kDt);
    EXPECT_TRUE(calm.GetContactHitEvents().empty());
  }
}

TEST(HitEventsTest, BouncesHitEachTimeAndTouchingPairsDoNot) {
  World world(HitDef());
  AddGround(world);
  const BodyId ball = AddCircle(world, {0, 4}, Real(0.5), {}, 1, Real(0.6), Real(0.8));
  const BodyId box = AddBox(world, {5, 1});  // resting on the ground from the start
  std::vector<Real> speeds;
  for (int s = 0; s < 240; ++s) {
    if (s == 100) world.SetLinearVelocity(box, {0, -5});  // pushed into the ground it touches
    world.Step(kDt);
    for (const ContactHitEvent& e : world.GetContactHitEvents()) {
      EXPECT_EQ(e.bodyB, ball);  // never the box: it touched the ground all along
      speeds.push_back(e.approachSpeed);
    }
  }
  ASSERT_GE(speeds.size(), 3u);  // bounces, each a hit, each slower
  for (size_t k = 1; k < speeds.size(); ++k) EXPECT_LT(speeds[k], speeds[k - 1]);
  for (Real v : speeds) EXPECT_GT(v, 1);
}

TEST(HitEventsTest, OffByDefaultAndBadInputRefused) {
  World world;
  AddGround(world);
  AddCircle(world, {0, 2});
  world.Step(kDt);
  ExpectError([&] { (void)world.GetContactHitEvents(); }, "GetContactHitEvents: hit events are off (WorldDef::hitEvents)",
              "off");
  for (Real bad : {Real(-1), Real(NAN), Real(INFINITY)}) {
    WorldDef def = HitDef(bad);
    ExpectError([&] { World w(def); }, "WorldDef.hitEventThreshold must be finite and >= 0", "threshold");
  }
  WorldDef quadrants = HitDef();
  quadrants.scheme = ParallelScheme::kQuadrants;
  ExpectError([&] { World w(quadrants); }, "WorldDef.hitEvents is not supported with ParallelScheme::kQuadrants",
              "quadrants");
}

// Balls and boxes poured into a box with restitution: many hits. The events must be the same for
// 1, 2, 3 and 4 threads, and turning them on must not change the state.
TEST(HitEventsTest, SameEventsForAnyThreadCountAndStateUnchanged) {
  auto run = [](int threads, bool events, std::vector<ContactHitEvent>* log, uint64_t* hash) {
    WorldDef def;
    def.threadCount = threads;
    def.minParallelItems = 8;
    def.hitEvents = events;
    World world(def);
    AddGround(world, 10, Real(0.5), {0, 0});
    AddGround(world, Real(0.5), 20, {-10, 20});
    AddGround(world, Real(0.5), 20, {10, 20});
    for (int i = 0; i < 200; ++i) {
      const Vec2 p{Real(-8 + (i % 16)), Real(2 + i / 16) * Real(1.1)};
      if (i % 3 == 0) {
        AddBox(world, p, Real(0.4), Real(0.4), 1, Real(0.1 * (i % 5)), {Real((i % 5) - 2), 0});
      } else {
        AddCircle(world, p, Real(0.45), {Real((i % 5) - 2), 0}, 1, Real(0.3), Real(0.6));
      }
    }
    for (int s = 0; s < 150; ++s) {
      world.Step(kDt);
      if (!events) continue;
      for (const ContactHitEvent& e : world.GetContactHitEvents()) log->push_back(e);
      log->push_back(ContactHitEvent{});  // separates steps
    }
    *hash = world.StateHash();
  };
  std::vector<ContactHitEvent> one, other, none;
  uint64_t hashOne = 0, hashOther = 0, hashOff = 0;
  run(1, true, &one, &hashOne);
  run(1, false, &none, &hashOff);
  EXPECT_EQ(hashOne, hashOff);
  EXPECT_GT(one.size(), 150 + 200u);  // hundreds of hits
  for (int threads : {2, 3, 4}) {
    other.clear();
    run(threads, true, &other, &hashOther);
    EXPECT_EQ(hashOther, hashOne) << threads << " threads";
    EXPECT_EQ(other, one) << threads << " threads";
  }
}

}  // namespace
}  // namespace quadrant
