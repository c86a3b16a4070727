// The Quadrant adapter maps the scene's sleep flag onto the engine (deterministic scheme) and
// refuses it under the quadrants scheme; a sleeping body reads back velocity 0.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "adapter.h"
#include "quadrant/math.h"

namespace quadrant::scene {
namespace {

Scene CreepingBody(bool sleep) {
  // A lone body creeping at 0.005 m/s in zero gravity: below the 0.01 m/s tolerance.
  Scene s;
  s.gravity = {0, 0};
  s.effects.sleep = sleep;
  BodyDesc b;
  b.velocity = {Real(0.005), 0};
  s.bodies = {b};
  return s;
}

TEST(QuadrantAdapterSleep, CreepingBodyFallsAsleepAndReadsVelocityZero) {
  for (bool sleep : {false, true}) {
    auto a = MakeAdapter("quadrant");
    EXPECT_TRUE(a->Caps().sleep);
    a->Load(CreepingBody(sleep), 1);
    for (int s = 0; s < 120; ++s) a->Step();
    std::vector<BodyState> out;
    a->ReadBodies(out);
    ASSERT_EQ(out.size(), 1u);
    if (sleep) {
      EXPECT_EQ(out[0].velocity.x, 0) << "a sleeping body reads back velocity 0";
      EXPECT_LT(out[0].position.x, Real(0.006)) << "asleep after about 0.5 s";
    } else {
      EXPECT_EQ(out[0].velocity.x, Real(0.005));
      EXPECT_NEAR(out[0].position.x, 0.01, 1e-4);
    }
  }
}

TEST(QuadrantAdapterSleep, QuadrantsSchemeRefusesSleep) {
  auto a = MakeAdapter("quadrant:quadrants");
  EXPECT_FALSE(a->Caps().sleep);
  EXPECT_THROW(a->Load(CreepingBody(true), 2), Unsupported);
  EXPECT_NO_THROW(a->Load(CreepingBody(false), 2));
}

}  // namespace
}  // namespace quadrant::scene
