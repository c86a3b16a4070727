// Refused input: every bad call throws quadrant::Error and leaves the world exactly as it was
// (same StateHash, same body count, and the same future as an untouched twin).
#include <gtest/gtest.h>

#include <cstdint>
#include <functional>
#include <limits>
#include <string>

#include "quadrant/error.h"
#include "quadrant/world.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

using namespace test;  // the small-world builders of test_helpers.h

constexpr Real kNaN = std::numeric_limits<Real>::quiet_NaN();
constexpr Real kInf = std::numeric_limits<Real>::infinity();

/// A world with something going on: ground, a falling box, a rolling circle, 10 steps in.
struct Scene {
  World world;
  BodyId ground, box, ball;
  Scene() {
    ground = AddGround(world);
    box = AddBox(world, {0, 2}, Real(0.5), Real(0.5), 1, Real(0.1));
    ball = AddCircle(world, {-2, Real(0.99)}, Real(0.5), {1, 0});
    StepN(world, 10);
  }
};

/// Expects `call` to throw quadrant::Error and to leave hash and body count unchanged.
void ExpectRefused(World& world, const std::function<void()>& call, const std::string& what) {
  SCOPED_TRACE(what);
  const uint64_t hash = world.StateHash();
  const int count = world.GetBodyCount();
  EXPECT_THROW(call(), Error);
  EXPECT_EQ(world.StateHash(), hash);
  EXPECT_EQ(world.GetBodyCount(), count);
}

BodyDef GoodDynamic() {
  BodyDef def;
  def.type = BodyType::kDynamic;
  def.position = {3, 3};
  def.shape = ShapeDef::MakeCircle(Real(0.5));
  return def;
}

/// A circle ShapeDef built by hand, so the radius reaches CreateBody unvalidated.
ShapeDef RawCircle(Real radius) {
  ShapeDef s;
  s.type = ShapeType::kCircle;
  s.circle.center = {0, 0};
  s.circle.radius = radius;
  return s;
}

TEST(BadInputTest, CreateBodyNonFiniteState) {
  Scene s;
  for (Real bad : {kNaN, kInf, -kInf}) {
    std::string v = std::to_string(bad);
    BodyDef d = GoodDynamic();
    d.position.x = bad;
    ExpectRefused(s.world, [&] { s.world.CreateBody(d); }, "position.x " + v);
    d = GoodDynamic();
    d.position.y = bad;
    ExpectRefused(s.world, [&] { s.world.CreateBody(d); }, "position.y " + v);
    d = GoodDynamic();
    d.linearVelocity.x = bad;
    ExpectRefused(s.world, [&] { s.world.CreateBody(d); }, "velocity.x " + v);
    d = GoodDynamic();
    d.linearVelocity.y = bad;
    ExpectRefused(s.world, [&] { s.world.CreateBody(d); }, "velocity.y " + v);
    d = GoodDynamic();
    d.angle = bad;
    ExpectRefused(s.world, [&] { s.world.CreateBody(d); }, "angle " + v);
    d = GoodDynamic();
    d.angularVelocity = bad;
    ExpectRefused(s.world, [&] { s.world.CreateBody(d); }, "angularVelocity " + v);
  }
  // Beyond kMaxCoordinate.
  BodyDef far = GoodDynamic();
  far.position = {kMaxCoordinate * 10, 0};
  ExpectRefused(s.world, [&] { s.world.CreateBody(far); }, "position 1e7");
}

TEST(BadInputTest, CreateBodyBadCircleRadius) {
  Scene s;
  for (Real r : {Real(0), Real(-0.5), kNaN, kInf, kMinFeatureSize / 10}) {
    BodyDef d = GoodDynamic();
    d.shape = RawCircle(r);
    ExpectRefused(s.world, [&] { s.world.CreateBody(d); }, "radius " + std::to_string(r));
    d.type = BodyType::kStatic;  // a static body's shape is validated too
    ExpectRefused(s.world, [&] { s.world.CreateBody(d); }, "static radius " + std::to_string(r));
  }
  BodyDef c = GoodDynamic();
  c.shape.circle.center = {kNaN, 0};
  ExpectRefused(s.world, [&] { s.world.CreateBody(c); }, "circle centre NaN");
}

TEST(BadInputTest, CreateBodyBadPolygon) {
  Scene s;
  BodyDef d = GoodDynamic();
  d.shape = ShapeDef{};
  d.shape.type = ShapeType::kPolygon;  // default Polygon: zero vertices
  ExpectRefused(s.world, [&] { s.world.CreateBody(d); }, "empty polygon");
}

TEST(BadInputTest, CreateBodyBadDensity) {
  Scene s;
  for (Real rho : {Real(0), Real(-1), kNaN, kInf}) {
    BodyDef d = GoodDynamic();
    d.shape.density = rho;
    ExpectRefused(s.world, [&] { s.world.CreateBody(d); }, "circle density " + std::to_string(rho));
    d.shape = ShapeDef::Box(Real(0.5), Real(0.5));
    d.shape.density = rho;
    ExpectRefused(s.world, [&] { s.world.CreateBody(d); }, "box density " + std::to_string(rho));
  }
}

TEST(BadInputTest, CreateBodyBadMaterial) {
  Scene s;
  for (Real f : {Real(-0.1), kNaN}) {
    BodyDef d = GoodDynamic();
    d.shape.friction = f;
    ExpectRefused(s.world, [&] { s.world.CreateBody(d); }, "friction " + std::to_string(f));
  }
  for (Real e : {Real(-0.1), Real(1.01), kNaN}) {
    BodyDef d = GoodDynamic();
    d.shape.restitution = e;
    ExpectRefused(s.world, [&] { s.world.CreateBody(d); }, "restitution " + std::to_string(e));
  }
  BodyDef d = GoodDynamic();
  d.linearDamping = -1;
  ExpectRefused(s.world, [&] { s.world.CreateBody(d); }, "linearDamping -1");
  d = GoodDynamic();
  d.angularDamping = kNaN;
  ExpectRefused(s.world, [&] { s.world.CreateBody(d); }, "angularDamping NaN");
  // The limits themselves are accepted.
  d = GoodDynamic();
  d.shape.restitution = 1;
  d.shape.friction = 0;
  EXPECT_NO_THROW(s.world.CreateBody(d));
}

TEST(BadInputTest, StepBadParameters) {
  Scene s;
  ExpectRefused(s.world, [&] { s.world.Step(0); }, "Step(0)");
  ExpectRefused(s.world, [&] { s.world.Step(-1); }, "Step(-1)");
  ExpectRefused(s.world, [&] { s.world.Step(kNaN); }, "Step(NaN)");
  ExpectRefused(s.world, [&] { s.world.Step(kInf); }, "Step(inf)");
  ExpectRefused(s.world, [&] { s.world.StepRepeated(kDt, 0); }, "StepRepeated(1/60, 0)");
  ExpectRefused(s.world, [&] { s.world.StepRepeated(kDt, -2); }, "StepRepeated(1/60, -2)");
}

TEST(BadInputTest, WorldConstructionRefused) {
  {
    WorldDef d;
    d.velocityIterations = 0;
    EXPECT_THROW(World w(d), Error);
  }
  {
    WorldDef d;
    d.gravity = {0, kNaN};
    EXPECT_THROW(World w(d), Error);
  }
  {
    WorldDef d;
    d.gravity = {kInf, 0};
    EXPECT_THROW(World w(d), Error);
  }
  {
    WorldDef d;
    d.threadCount = 0;
    EXPECT_THROW(World w(d), Error);
  }
  {
    WorldDef d;
    d.positionIterations = -1;  // documented >= 0
    EXPECT_THROW(World w(d), Error);
  }
  {
    WorldDef d;
    d.quadTreeMaxDepth = 13;  // documented 1..12
    EXPECT_THROW(World w(d), Error);
  }
  {
    WorldDef d;
    d.quadTreeMaxDepth = 0;
    EXPECT_THROW(World w(d), Error);
  }
  // The defaults are fine.
  EXPECT_NO_THROW(World w(WorldDef{}));
}

TEST(BadInputTest, SettersRefuseNonFinite) {
  Scene s;
  ExpectRefused(s.world, [&] { s.world.SetTransform(s.box, {kNaN, 0}, 0); }, "SetTransform pos NaN");
  ExpectRefused(s.world, [&] { s.world.SetTransform(s.box, {0, 1}, kNaN); }, "SetTransform angle NaN");
  ExpectRefused(s.world, [&] { s.world.SetTransform(s.box, {0, kInf}, 0); }, "SetTransform pos inf");
  ExpectRefused(s.world, [&] { s.world.SetLinearVelocity(s.box, {kInf, 0}); }, "SetLinearVelocity inf");
  ExpectRefused(s.world, [&] { s.world.SetLinearVelocity(s.ball, {0, kNaN}); }, "SetLinearVelocity NaN");
  ExpectRefused(s.world, [&] { s.world.SetAngularVelocity(s.box, kNaN); }, "SetAngularVelocity NaN");
  ExpectRefused(s.world, [&] { s.world.ApplyLinearImpulse(s.box, {kNaN, 0}, {0, 2}); }, "impulse NaN");
  ExpectRefused(s.world, [&] { s.world.ApplyLinearImpulse(s.box, {1, 0}, {0, kNaN}); }, "impulse point NaN");
  ExpectRefused(s.world, [&] { s.world.ApplyLinearImpulse(s.box, {0, kInf}, {0, 2}); }, "impulse inf");
}

TEST(BadInputTest, StaleIdRefused) {
  Scene s;
  BodyId doomed = AddCircle(s.world, {4, 4});
  s.world.DestroyBody(doomed);
  ExpectRefused(s.world, [&] { s.world.GetPosition(doomed); }, "GetPosition stale");
  ExpectRefused(s.world, [&] { s.world.GetAngle(doomed); }, "GetAngle stale");
  ExpectRefused(s.world, [&] { s.world.GetMass(doomed); }, "GetMass stale");
  ExpectRefused(s.world, [&] { s.world.GetShape(doomed); }, "GetShape stale");
  ExpectRefused(s.world, [&] { s.world.SetLinearVelocity(doomed, {1, 1}); }, "SetLinearVelocity stale");
  ExpectRefused(s.world, [&] { s.world.SetTransform(doomed, {1, 1}, 0); }, "SetTransform stale");
  ExpectRefused(s.world, [&] { s.world.ApplyLinearImpulse(doomed, {1, 1}, {4, 4}); }, "impulse stale");
  ExpectRefused(s.world, [&] { s.world.DestroyBody(doomed); }, "DestroyBody twice");
  ExpectRefused(s.world, [&] { s.world.DestroyBody(BodyId{}); }, "DestroyBody null");
  ExpectRefused(s.world, [&] { s.world.GetPosition(BodyId{}); }, "GetPosition null");
  // A live index with the wrong generation.
  BodyId forged = s.box;
  forged.generation += 7;
  ExpectRefused(s.world, [&] { s.world.GetPosition(forged); }, "forged generation");
}

TEST(BadInputTest, RefusedCallsLeaveNoTraceInTheFuture) {
  // A twin world that never saw the bad calls must evolve bit-identically.
  Scene bad, good;
  ASSERT_EQ(bad.world.StateHash(), good.world.StateHash());
  BodyDef d = GoodDynamic();
  d.shape = RawCircle(-1);
  EXPECT_THROW(bad.world.CreateBody(d), Error);
  d = GoodDynamic();
  d.position = {kNaN, 0};
  EXPECT_THROW(bad.world.CreateBody(d), Error);
  EXPECT_THROW(bad.world.Step(kNaN), Error);
  EXPECT_THROW(bad.world.SetLinearVelocity(bad.box, {kInf, 0}), Error);
  EXPECT_THROW(bad.world.SetTransform(bad.ball, {0, 0}, kNaN), Error);
  // Both get the same good body afterwards (same id if no slot was leaked).
  BodyId g1 = bad.world.CreateBody(GoodDynamic());
  BodyId g2 = good.world.CreateBody(GoodDynamic());
  EXPECT_TRUE(g1 == g2);
  StepN(bad.world, 60);
  StepN(good.world, 60);
  EXPECT_EQ(bad.world.StateHash(), good.world.StateHash());
  EXPECT_EQ(bad.world.GetBodyCount(), good.world.GetBodyCount());
}

}  // namespace
}  // namespace quadrant
