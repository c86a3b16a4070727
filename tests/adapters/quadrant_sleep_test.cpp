// The Quadrant adapter maps the scene's sleep flag onto the engine (deterministic scheme) and
// refuses it under the quadrants scheme; a sleeping body reads back velocity 0.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "adapter.h"
#include "quadrant/error.h"
#include "quadrant/math.h"
#include "scenes.h"

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

// The effects tool's sleep scene must really come to rest, or its sleep row would time an
// engine that cannot sleep: after 120 steps every box of the field reads velocity 0 and the
// state no longer changes.
TEST(QuadrantAdapterSleep, PyramidFieldFallsAsleep) {
  Scene field = MakePyramidField(4, 8);
  ASSERT_EQ(field.bodies.size(), 1u + 4u * 36u);
  field.effects.sleep = true;
  auto a = MakeAdapter("quadrant");
  a->Load(field, 1);
  for (int s = 0; s < 120; ++s) a->Step();
  const uint64_t settled = a->StateHash();
  std::vector<BodyState> out;
  a->ReadBodies(out);
  for (size_t i = 1; i < out.size(); ++i) {
    EXPECT_EQ(out[i].velocity.x, 0) << "box " << i;
    EXPECT_EQ(out[i].velocity.y, 0) << "box " << i;
  }
  for (int s = 0; s < 30; ++s) a->Step();
  EXPECT_EQ(a->StateHash(), settled);
}

TEST(QuadrantAdapterSleep, PyramidFieldRefusesBadSizes) {
  EXPECT_THROW(MakePyramidField(0, 8), Error);
  EXPECT_THROW(MakePyramidField(4, 0), Error);
  EXPECT_THROW(MakePyramidField(4, 101), Error);
}

}  // namespace
}  // namespace quadrant::scene
