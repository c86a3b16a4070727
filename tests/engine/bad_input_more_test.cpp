// Refused input, the rows of docs/bad_input.md that bad_input_test.cpp does not cover: polygon
// construction (MakePolygon, MakeBox, raw polygons given to CreateBody), circles, more WorldDef
// fields, every accessor on a destroyed id, and finite but absurd values (huge dt, impulse,
// density) that must neither crash the process nor leave a non-finite world. Each refusal is a
// quadrant::Error whose message names the problem, and leaves the world's StateHash unchanged.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "quadrant/error.h"
#include "quadrant/shapes.h"
#include "quadrant/world.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

using namespace test;  // the small-world builders of test_helpers.h

constexpr Real kNaN = std::numeric_limits<Real>::quiet_NaN();
constexpr Real kInf = std::numeric_limits<Real>::infinity();
constexpr Real kHuge = Real(3e38);  // finite, near float's largest

/// ExpectError, and the world's hash and body count unchanged.
void ExpectRefused(World& world, const std::function<void()>& call, const std::string& message,
                   const std::string& what) {
  const uint64_t hash = world.StateHash();
  const int count = world.GetBodyCount();
  ExpectError(call, message, what);
  EXPECT_EQ(world.StateHash(), hash) << what;
  EXPECT_EQ(world.GetBodyCount(), count) << what;
}

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

std::vector<Vec2> Square() { return {{0, 0}, {1, 0}, {1, 1}, {0, 1}}; }

/// A dynamic body whose polygon is written straight into the ShapeDef, unvalidated, so the
/// vertices reach CreateBody as given.
BodyDef RawPolygonBody(const std::vector<Vec2>& vertices) {
  BodyDef def;
  def.type = BodyType::kDynamic;
  def.position = {5, 5};
  def.shape.type = ShapeType::kPolygon;
  def.shape.polygon.count = static_cast<int>(vertices.size());
  for (size_t i = 0; i < vertices.size() && i < size_t(kMaxPolygonVertices); ++i) def.shape.polygon.vertices[i] = vertices[i];
  return def;
}

BodyDef RawCircleBody(Real radius, Vec2 center = {}) {
  BodyDef def;
  def.type = BodyType::kDynamic;
  def.position = {5, 5};
  def.shape.type = ShapeType::kCircle;
  def.shape.circle = {center, radius};
  return def;
}

bool StateFinite(const World& world) {
  for (BodyId id : world.GetBodyIds()) {
    if (!IsFinite(world.GetPosition(id)) || !IsFinite(world.GetAngle(id)) || !IsFinite(world.GetLinearVelocity(id)) ||
        !IsFinite(world.GetAngularVelocity(id))) {
      return false;
    }
  }
  return true;
}

TEST(BadInputMoreTest, MakePolygonRefusals) {
  ExpectError([] { MakePolygon(std::vector<Vec2>{}); }, "at least 3 vertices, got 0", "no points");
  ExpectError([] { MakePolygon(std::vector<Vec2>{{0, 0}, {1, 0}}); }, "at least 3 vertices, got 2", "two points");
  std::vector<Vec2> nine;
  for (int i = 0; i < 9; ++i) nine.push_back({Real(std::cos(i * 0.698)), Real(std::sin(i * 0.698))});
  ExpectError([&] { MakePolygon(nine); }, "at most 8 vertices, got 9", "nine points");
  ExpectError([] { MakePolygon(std::vector<Vec2>{{0, 0}, {kNaN, 0}, {0, 1}}); }, "vertex 1 is not finite", "NaN");
  ExpectError([] { MakePolygon(std::vector<Vec2>{{0, 0}, {1, 0}, {0, kInf}}); }, "vertex 2 is not finite", "inf");
  ExpectError([] { MakePolygon(std::vector<Vec2>{{0, 0}, {Real(2e6), 0}, {0, 1}}); }, "beyond the coordinate limit",
              "vertex at 2e6 m");
  ExpectError([] { MakePolygon(std::vector<Vec2>{{0, 0}, {1, 0}, {1, 0}, {0, 1}}); }, "are duplicates", "duplicate");
  ExpectError([] { MakePolygon(std::vector<Vec2>{{0, 0}, {1, 0}, {Real(1.0001), 0}, {0, 1}}); }, "are duplicates",
              "closer than 0.005 m");
  ExpectError([] { MakePolygon(std::vector<Vec2>{{0, 0}, {1, 1}, {2, 2}}); }, "collinear", "collinear");
  ExpectError([] { MakePolygon(std::vector<Vec2>{{0, 0}, {1, 0}, {Real(0.5), Real(0.001)}}); }, "nearly collinear",
              "sliver 1 mm thick");
  ExpectError([] { MakePolygon(std::vector<Vec2>{{0, 0}, {2, 0}, {2, 2}, {1, Real(0.5)}, {0, 2}}); }, "not convex",
              "non-convex (a dent)");
  ExpectError([] { MakePolygon(std::vector<Vec2>{{0, 0}, {1, 0}, {2, 0}, {1, 1}}); }, "not convex",
              "a vertex on an edge");
}

TEST(BadInputMoreTest, MakePolygonAcceptsAnyOrderAndReturnsCounterClockwise) {
  // Documented: MakePolygon takes points in any order (the scene API is stricter and refuses a
  // clockwise list, see bad_input_scene_test.cpp).
  const std::vector<Vec2> clockwise = {{0, 0}, {0, 1}, {1, 1}, {1, 0}};
  const Polygon p = MakePolygon(clockwise);
  EXPECT_EQ(p.count, 4);
  EXPECT_GT(ComputeArea(p), 0);
  // A dent is refused unless the caller asks for the hull.
  const Polygon hull = MakePolygon(std::vector<Vec2>{{0, 0}, {2, 0}, {2, 2}, {1, Real(0.5)}, {0, 2}}, false);
  EXPECT_EQ(hull.count, 4);
}

TEST(BadInputMoreTest, MakeBoxAndCircleRefusals) {
  ExpectError([] { MakeBox(0, 1); }, "half-widths must be finite and at least 0.0025 m", "hx 0");
  ExpectError([] { MakeBox(1, -1); }, "half-widths", "hy -1");
  ExpectError([] { MakeBox(kNaN, 1); }, "half-widths", "hx NaN");
  ExpectError([] { MakeBox(1, 1, {kNaN, 0}); }, "centre and angle must be finite", "centre NaN");
  ExpectError([] { MakeBox(1, 1, {}, kInf); }, "centre and angle must be finite", "angle inf");
  ExpectError([] { MakeBox(1, 1, {Real(2e6), 0}); }, "beyond the coordinate limit", "centre 2e6");
  ExpectError([] { ShapeDef::Box(Real(0.001), 1); }, "half-widths", "ShapeDef::Box 1 mm");
  ExpectError([] { ShapeDef::MakeCircle(0); }, "radius must be at least 0.005 m", "radius 0");
  ExpectError([] { ShapeDef::MakeCircle(-1); }, "radius must be at least 0.005 m", "radius -1");
  ExpectError([] { ShapeDef::MakeCircle(kNaN); }, "radius is not finite", "radius NaN");
  ExpectError([] { ShapeDef::MakeCircle(kInf); }, "radius is not finite", "radius inf");
  ExpectError([] { ShapeDef::MakeCircle(Real(2e6)); }, "beyond the coordinate limit", "radius 2e6");
  ExpectError([] { ShapeDef::MakeCircle(1, {0, kNaN}); }, "centre is not finite", "centre NaN");
  ExpectError([] { ValidateCircle({{0, 0}, Real(0.004)}); }, "at least 0.005 m", "radius 4 mm");
}

TEST(BadInputMoreTest, CreateBodyRefusesBadRawPolygons) {
  Scene s;
  auto refuse = [&](const std::vector<Vec2>& v, const std::string& message, const std::string& what) {
    const BodyDef def = RawPolygonBody(v);
    ExpectRefused(s.world, [&] { s.world.CreateBody(def); }, message, what);
  };
  refuse({{0, 0}, {1, 0}}, "vertex count must be in [3, 8], got 2", "two vertices");
  BodyDef nine = RawPolygonBody(Square());
  nine.shape.polygon.count = 9;  // more than the array holds: must be refused, not read past
  ExpectRefused(s.world, [&] { s.world.CreateBody(nine); }, "vertex count must be in [3, 8], got 9", "count 9");
  BodyDef negative = RawPolygonBody(Square());
  negative.shape.polygon.count = -1;
  ExpectRefused(s.world, [&] { s.world.CreateBody(negative); }, "vertex count must be in [3, 8], got -1", "count -1");
  refuse({{0, 0}, {1, 0}, {1, 0}, {0, 1}}, "are duplicates", "duplicate vertices");
  refuse({{0, 0}, {1, 1}, {2, 2}}, "collinear", "collinear vertices");
  refuse({{0, 0}, {2, 0}, {2, 2}, {1, Real(0.5)}, {0, 2}}, "not convex", "non-convex");
  refuse({{0, 0}, {1, 0}, {kNaN, 1}}, "not finite", "NaN vertex");
  refuse({{0, 0}, {Real(-2e6), 0}, {0, 1}}, "beyond the coordinate limit", "vertex at -2e6 m");
  // Clockwise is accepted and stored counter-clockwise (CreateBody re-hulls every polygon).
  const BodyId cw = s.world.CreateBody(RawPolygonBody({{0, 0}, {0, 1}, {1, 1}, {1, 0}}));
  EXPECT_GT(ComputeArea(s.world.GetShape(cw).polygon), 0);
}

TEST(BadInputMoreTest, CreateBodyRefusesBadCirclesAndDensities) {
  Scene s;
  ExpectRefused(s.world, [&] { s.world.CreateBody(RawCircleBody(Real(2e6))); }, "beyond the coordinate limit",
                "radius 2e6");
  ExpectRefused(s.world, [&] { s.world.CreateBody(RawCircleBody(1, {kInf, 0})); }, "centre is not finite",
                "centre inf");
  BodyDef staticNegative = RawCircleBody(1);
  staticNegative.type = BodyType::kStatic;
  staticNegative.shape.density = -1;
  ExpectRefused(s.world, [&] { s.world.CreateBody(staticNegative); }, "density must be finite and >= 0",
                "static density -1");
  BodyDef dynamicZero = RawCircleBody(1);
  dynamicZero.shape.density = 0;
  ExpectRefused(s.world, [&] { s.world.CreateBody(dynamicZero); }, "needs ShapeDef.density > 0", "dynamic density 0");
  BodyDef unknownType = RawCircleBody(1);
  unknownType.type = static_cast<BodyType>(7);
  ExpectRefused(s.world, [&] { s.world.CreateBody(unknownType); }, "BodyDef.type is unknown", "type 7");
  BodyDef unknownShape = RawCircleBody(1);
  unknownShape.shape.type = static_cast<ShapeType>(9);
  ExpectRefused(s.world, [&] { s.world.CreateBody(unknownShape); }, "ShapeDef.type is unknown", "shape type 9");
  // A static body may have density 0 (it has no mass).
  BodyDef staticZero = RawCircleBody(1);
  staticZero.type = BodyType::kStatic;
  staticZero.shape.density = 0;
  EXPECT_NO_THROW(s.world.CreateBody(staticZero));
}

TEST(BadInputMoreTest, FiniteValuesBeyondTheLimitsAreRefused) {
  // Finite but absurd values pass every finiteness check; the limits (kMaxTimeStep,
  // kMaxInputSpeed, a positive finite mass) refuse them before they reach the solver.
  Scene s;
  ExpectRefused(s.world, [&] { s.world.Step(2); }, "Step: dt must be <= 1 s", "Step(2 s)");
  ExpectRefused(s.world, [&] { s.world.Step(kHuge); }, "Step: dt must be <= 1 s", "Step(3e38)");
  BodyDef fast = RawCircleBody(1);
  fast.linearVelocity = {Real(2e6), 0};
  ExpectRefused(s.world, [&] { s.world.CreateBody(fast); }, "velocity is beyond the limit of 1e6 m/s",
                "CreateBody velocity 2e6");
  BodyDef spin = RawCircleBody(1);
  spin.angularVelocity = Real(-2e6);
  ExpectRefused(s.world, [&] { s.world.CreateBody(spin); }, "velocity is beyond the limit of 1e6 m/s",
                "CreateBody angular velocity -2e6");
  ExpectRefused(s.world, [&] { s.world.SetLinearVelocity(s.box, {0, kHuge}); },
                "SetLinearVelocity: velocity is beyond the limit of 1e6 m/s", "SetLinearVelocity 3e38");
  ExpectRefused(s.world, [&] { s.world.SetAngularVelocity(s.box, kHuge); },
                "SetAngularVelocity: angular velocity is beyond the limit of 1e6 rad/s", "SetAngularVelocity 3e38");
  ExpectRefused(s.world, [&] { s.world.ApplyLinearImpulse(s.box, {kHuge, 0}, s.world.GetPosition(s.box)); },
                "ApplyLinearImpulse: the resulting velocity is beyond the limit", "impulse 3e38 on 1 kg");
  ExpectRefused(s.world, [&] { s.world.ApplyLinearImpulse(s.box, {1, 0}, {Real(2e6), 0}); },
                "ApplyLinearImpulse: point is beyond the coordinate limit of 1e6 m", "impulse point 2e6");
  // Density times area overflows float (mass inf) or underflows it (a denormal density: mass 0).
  BodyDef heavy = RawCircleBody(10);
  heavy.shape.density = kHuge;
  ExpectRefused(s.world, [&] { s.world.CreateBody(heavy); },
                "mass or rotational inertia is not a positive finite number", "density 3e38, r = 10 m");
  BodyDef light = RawCircleBody(Real(0.2));
  light.shape.density = Real(1e-40);
  ExpectRefused(s.world, [&] { s.world.CreateBody(light); },
                "mass or rotational inertia is not a positive finite number", "density 1e-40");
}

TEST(BadInputMoreTest, EveryAccessorRefusesADestroyedId) {
  Scene s;
  const BodyId doomed = AddCircle(s.world, {4, 4});
  s.world.DestroyBody(doomed);
  EXPECT_FALSE(s.world.IsValid(doomed));
  const std::string stale = "stale or invalid BodyId";
  ExpectRefused(s.world, [&] { s.world.GetRotation(doomed); }, stale, "GetRotation");
  ExpectRefused(s.world, [&] { s.world.GetLinearVelocity(doomed); }, stale, "GetLinearVelocity");
  ExpectRefused(s.world, [&] { s.world.GetAngularVelocity(doomed); }, stale, "GetAngularVelocity");
  ExpectRefused(s.world, [&] { s.world.GetWorldCenter(doomed); }, stale, "GetWorldCenter");
  ExpectRefused(s.world, [&] { s.world.GetRotationalInertia(doomed); }, stale, "GetRotationalInertia");
  ExpectRefused(s.world, [&] { s.world.GetType(doomed); }, stale, "GetType");
  ExpectRefused(s.world, [&] { s.world.GetAABB(doomed); }, stale, "GetAABB");
  ExpectRefused(s.world, [&] { s.world.SetAngularVelocity(doomed, 1); }, stale, "SetAngularVelocity");
  // An id that was never issued (index past every slot) and one from another world's numbering.
  const BodyId never{1000, 1};
  EXPECT_FALSE(s.world.IsValid(never));
  ExpectRefused(s.world, [&] { s.world.GetPosition(never); }, stale, "index 1000");
  ExpectRefused(s.world, [&] { s.world.DestroyBody(never); }, stale, "DestroyBody index 1000");
  // The slot is reused with a new generation: the old id stays stale.
  const BodyId reborn = AddCircle(s.world, {4, 4});
  EXPECT_EQ(reborn.index, doomed.index);
  EXPECT_FALSE(s.world.IsValid(doomed));
  ExpectRefused(s.world, [&] { s.world.GetPosition(doomed); }, stale, "old id after slot reuse");
}

TEST(BadInputMoreTest, StepRepeatedRefusesMoreThanAThousandRepeats) {
  Scene s;
  ExpectRefused(s.world, [&] { s.world.StepRepeated(kDt, 1001); }, "pipelineRepeats must be <= 1000", "StepRepeated(1/60, 1001)");
  ExpectRefused(s.world, [&] { s.world.StepRepeated(kDt, 1000000000); }, "pipelineRepeats must be <= 1000", "StepRepeated(1/60, 1e9)");
  const uint64_t before = s.world.StateHash();
  s.world.StepRepeated(kDt, 1000);  // the limit itself is accepted
  EXPECT_NE(s.world.StateHash(), before);
}

TEST(BadInputMoreTest, UnderflowingDensityIsPrintedWithItsExponent) {
  World world;
  BodyDef def;
  def.type = BodyType::kDynamic;
  def.shape = ShapeDef::MakeCircle(Real(0.5));
  def.shape.density = Real(1e-40);
  try {
    world.CreateBody(def);
    ADD_FAILURE() << "density 1e-40 was accepted";
  } catch (const Error& e) {
    // 1e-40 is a float denormal (9.99995e-41): the message must show it, not "0.000000".
    const std::string message = e.what();
    EXPECT_NE(message.find("e-41"), std::string::npos) << message;
    EXPECT_EQ(message.find("0.000000"), std::string::npos) << message;
  }
}

TEST(BadInputMoreTest, WorldDefMoreRefusals) {
  auto refuse = [](const std::function<void(WorldDef&)>& edit, const std::string& message, const std::string& what) {
    WorldDef d;
    edit(d);
    ExpectError([&] { World w(d); }, message, what);
  };
  refuse([](WorldDef& d) { d.threadCount = 65; }, "threadCount must be in [1, 64]", "threads 65");
  refuse([](WorldDef& d) { d.threadCount = -3; }, "threadCount must be in [1, 64]", "threads -3");
  refuse([](WorldDef& d) { d.restitutionIterations = 0; }, "restitutionIterations must be >= 1", "restitution its 0");
  // Upper limits (kMaxIterations = 1000): without them one Step could run for hours.
  refuse([](WorldDef& d) { d.velocityIterations = 1001; }, "velocityIterations must be <= 1000", "velocity its 1001");
  refuse([](WorldDef& d) { d.positionIterations = 1000000000; }, "positionIterations must be <= 1000", "position its 1e9");
  refuse([](WorldDef& d) { d.restitutionIterations = 1001; }, "restitutionIterations must be <= 1000", "restitution its 1001");
  refuse([](WorldDef& d) { d.softSubSteps = 1001; }, "softSubSteps must be <= 1000", "soft sub-steps 1001");
  refuse([](WorldDef& d) { d.linearSlop = kNaN; }, "linearSlop", "slop NaN");
  refuse([](WorldDef& d) { d.baumgarte = Real(1.5); }, "baumgarte must be in [0, 1]", "baumgarte 1.5");
  refuse([](WorldDef& d) { d.maxLinearCorrection = 0; }, "maxLinearCorrection must be > 0", "max correction 0");
  refuse([](WorldDef& d) { d.speculativeDistance = -1; }, "speculativeDistance", "speculative -1");
  refuse([](WorldDef& d) { d.restitutionThreshold = -1; }, "restitutionThreshold", "threshold -1");
  refuse([](WorldDef& d) { d.restitutionThreshold = kInf; }, "restitutionThreshold", "threshold inf");
  refuse([](WorldDef& d) { d.maxLinearSpeed = 0; }, "maxLinearSpeed must be > 0", "max speed 0");
  refuse([](WorldDef& d) { d.velocityIterations = -5; }, "velocityIterations must be >= 1", "iterations -5");
  refuse([](WorldDef& d) { d.solver = static_cast<SolverType>(9); }, "WorldDef.solver is unknown", "solver 9");
  refuse([](WorldDef& d) { d.broadPhase = static_cast<BroadPhaseType>(9); }, "WorldDef.broadPhase is unknown",
         "broad phase 9");
  // soft_step's contact settings (checked whichever solver is chosen).
  refuse([](WorldDef& d) { d.softSubSteps = 0; }, "softSubSteps must be >= 1", "soft sub-steps 0");
  refuse([](WorldDef& d) { d.contactHertz = 0; }, "contactHertz must be > 0", "hertz 0");
  refuse([](WorldDef& d) { d.contactHertz = kNaN; }, "contactHertz must be > 0", "hertz NaN");
  refuse([](WorldDef& d) { d.contactDampingRatio = -1; }, "contactDampingRatio", "damping ratio -1");
  refuse([](WorldDef& d) { d.contactPushMaxVelocity = 0; }, "contactPushMaxVelocity must be > 0", "push speed 0");
  refuse([](WorldDef& d) { d.contactPushMaxDepth = 0; }, "contactPushMaxDepth must be > 0", "push depth 0");
  refuse([](WorldDef& d) { d.contactPushMaxDepth = kInf; }, "contactPushMaxDepth must be > 0", "push depth inf");
  refuse([](WorldDef& d) { d.contactPushMaxDepth = kNaN; }, "contactPushMaxDepth must be > 0", "push depth NaN");
  WorldDef two;
  two.threadCount = 2;
  EXPECT_NO_THROW(World w(two));
}

TEST(BadInputMoreTest, SettersRefuseBeyondTheCoordinateLimitAndNegativeZeroDt) {
  Scene s;
  ExpectRefused(s.world, [&] { s.world.SetTransform(s.box, {Real(2e6), 0}, 0); }, "beyond the coordinate limit",
                "SetTransform 2e6");
  ExpectRefused(s.world, [&] { s.world.Step(Real(-0.0)); }, "dt must be finite and > 0", "Step(-0)");
  ExpectRefused(s.world, [&] { s.world.StepRepeated(kDt, std::numeric_limits<int>::min()); }, "pipelineRepeats must be >= 1",
                "StepRepeated(1/60, INT_MIN)");
}

// Finite but absurd values. The engine may refuse them (an Error, world unchanged) or run them,
// but must not crash and must not leave NaN or infinity in the world. Run in a child process
// (a death-test fork), so a crash fails this test instead of killing the test binary.
void ExpectSurvives(const std::function<void(World&, BodyId)>& call) {
  auto child = [&] {
    World world;
    AddGround(world);
    // Half a kilogram: an impulse of 3e38 N s then asks for a velocity beyond float's range.
    const BodyId box = AddBox(world, {0, 2}, Real(0.5), Real(0.5), Real(0.5), Real(0.1), {3, 0});
    AddCircle(world, {-2, Real(0.99)}, Real(0.5), {1, 0});
    StepN(world, 5);
    const uint64_t hash = world.StateHash();
    bool refused = false;
    try {
      call(world, box);
    } catch (const Error&) {
      refused = true;
    }
    if (refused && world.StateHash() != hash) std::_Exit(2);
    if (!refused) StepN(world, 3);
    std::_Exit(StateFinite(world) ? 0 : 3);
  };
  // Exit code 0: refused cleanly or ran with a finite state; 2: refused but changed the world;
  // 3: left NaN or infinity; a signal or abort: crashed.
  EXPECT_EXIT(child(), ::testing::ExitedWithCode(0), "");
}

TEST(BadInputMoreDeathTest, HugeFiniteDtNeitherCrashesNorCorrupts) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  ExpectSurvives([](World& w, BodyId) { w.Step(kHuge); });
  ExpectSurvives([](World& w, BodyId) { w.Step(Real(1e30)); });
}

TEST(BadInputMoreDeathTest, HugeFiniteImpulseNeitherCrashesNorCorrupts) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  ExpectSurvives([](World& w, BodyId box) { w.ApplyLinearImpulse(box, {kHuge, 0}, w.GetPosition(box)); });
  ExpectSurvives([](World& w, BodyId box) { w.SetLinearVelocity(box, {kHuge, kHuge}); });
  ExpectSurvives([](World& w, BodyId box) { w.SetAngularVelocity(box, kHuge); });
}

TEST(BadInputMoreDeathTest, TheLargestAcceptedValuesNeitherCrashNorCorrupt) {
  // At the edge of the limits: 1e6 m/s (and rad/s) for the longest step, 1 s. A body then
  // leaves the coordinate range within the step; the world must stay finite and alive.
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  ExpectSurvives([](World& w, BodyId box) {
    w.SetLinearVelocity(box, {Real(1e6), Real(-1e6)});
    w.Step(1);
  });
  ExpectSurvives([](World& w, BodyId box) {
    w.SetAngularVelocity(box, Real(1e6));
    w.Step(1);
  });
  ExpectSurvives([](World& w, BodyId box) {
    w.SetTransform(box, {Real(1e6), Real(-1e6)}, 0);
    w.SetLinearVelocity(box, {Real(1e6), 0});
    w.Step(1);
  });
}

TEST(BadInputMoreDeathTest, HugeFiniteGravityNeitherCrashesNorCorrupts) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  auto child = [] {
    WorldDef def;
    def.gravity.x = 0;
    def.gravity.y = -kHuge;
    World world(def);
    AddGround(world);
    AddBox(world, {0, 2});
    StepN(world, 3);
    std::_Exit(StateFinite(world) ? 0 : 3);
  };
  EXPECT_EXIT(child(), ::testing::ExitedWithCode(0), "");
}

}  // namespace
}  // namespace quadrant
