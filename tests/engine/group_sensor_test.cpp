// Filter::groupIndex (Box2D's group rule) and sensor shapes with their overlap events:
// behaviour, bad input, and that the state is the same for any thread count with both in use.
#include <gtest/gtest.h>

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

}  // namespace
}  // namespace quadrant
