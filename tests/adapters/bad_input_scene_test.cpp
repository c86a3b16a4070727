// Bad input through the scene API (the scene rows of docs/bad_input.md): every invalid scene is
// refused by ValidateScene and by every adapter's Load with a quadrant::Error naming the problem,
// and a refused Load leaves the adapter's loaded world exactly as it was (same state hash, same
// body count, and the same future as a twin that never saw the bad scene). Also: thread counts,
// SetVelocity, Step before Load, and unknown engine, variant and scene names.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "adapter.h"
#include "quadrant/error.h"
#include "scene.h"
#include "scenes.h"

namespace quadrant::scene {
namespace {

constexpr Real kNaN = std::numeric_limits<Real>::quiet_NaN();
constexpr Real kInf = std::numeric_limits<Real>::infinity();
const std::vector<std::string> kEngines = {"quadrant", "box2d", "bullet", "chipmunk"};

constexpr int kBox = 1;   // the polygon body of the good scene
constexpr int kBall = 2;  // the circle body

// A static ground, a dynamic box and a dynamic circle: every adapter runs it.
Scene Good() {
  Scene s;
  s.name = "bad_input_base";
  BodyDesc ground;
  ground.dynamic = false;
  ground.shape = ShapeKind::kPolygon;
  ground.vertices = {{-10, Real(-0.5)}, {10, Real(-0.5)}, {10, Real(0.5)}, {-10, Real(0.5)}};
  ground.position = {0, Real(-0.5)};
  ground.density = 0;
  BodyDesc box = ground;
  box.dynamic = true;
  box.density = 1;
  box.vertices = {{Real(-0.5), Real(-0.5)}, {Real(0.5), Real(-0.5)}, {Real(0.5), Real(0.5)}, {Real(-0.5), Real(0.5)}};
  box.position = {0, 2};
  BodyDesc ball;
  ball.shape = ShapeKind::kCircle;
  ball.radius = Real(0.5);
  ball.position = {2, 1};
  ball.velocity = {-1, 0};
  s.bodies = {ground, box, ball};
  return s;
}

struct Row {
  std::string what;
  std::function<void(Scene&)> spoil;
  std::string message;  // a part of the error message
};

std::vector<Row> Rows() {
  auto body = [](int i, std::function<void(BodyDesc&)> f) { return [i, f](Scene& s) { f(s.bodies[i]); }; };
  auto verts = [](std::vector<Vec2> v) { return [v](Scene& s) { s.bodies[kBox].vertices = v; }; };
  return {
      {"position x NaN", body(kBox, [](BodyDesc& b) { b.position.x = kNaN; }), "scene body 1: BodyDef position or angle is not finite"},
      {"position y +inf", body(kBall, [](BodyDesc& b) { b.position.y = kInf; }), "scene body 2: BodyDef position or angle is not finite"},
      {"angle NaN", body(kBox, [](BodyDesc& b) { b.angle = kNaN; }), "position or angle is not finite"},
      {"velocity NaN", body(kBall, [](BodyDesc& b) { b.velocity.x = kNaN; }), "scene body 2: BodyDef velocity is not finite"},
      {"velocity -inf", body(kBox, [](BodyDesc& b) { b.velocity.y = -kInf; }), "velocity is not finite"},
      {"angular velocity inf", body(kBox, [](BodyDesc& b) { b.angularVelocity = kInf; }), "velocity is not finite"},
      {"position beyond 1e6 m", body(kBall, [](BodyDesc& b) { b.position.x = Real(2e6); }),
       "position is beyond the coordinate limit of 1e6 m"},
      {"velocity 2e6 m/s", body(kBox, [](BodyDesc& b) { b.velocity.x = Real(2e6); }),
       "scene body 1: BodyDef velocity is beyond the limit of 1e6 m/s (rad/s)"},
      {"angular velocity -2e6 rad/s", body(kBall, [](BodyDesc& b) { b.angularVelocity = Real(-2e6); }),
       "velocity is beyond the limit of 1e6 m/s (rad/s)"},
      {"density 3e38 on a 20 m box (mass overflows)", body(kBox, [](BodyDesc& b) {
         b.vertices = {{-10, -10}, {10, -10}, {10, 10}, {-10, 10}};
         b.density = Real(3e38);
       }),
       "scene body 1: the body's mass or rotational inertia is not a positive finite number"},
      {"density 1e-40 (mass underflows)", body(kBall, [](BodyDesc& b) { b.density = Real(1e-40); }),
       "mass or rotational inertia is not a positive finite number"},
      {"capsule with 3 centres", body(kBall, [](BodyDesc& b) {
         b.shape = ShapeKind::kCapsule;
         b.vertices = {{0, 0}, {1, 0}, {2, 0}};
       }),
       "scene body 2: a capsule has 2 centres, got 3"},
      {"capsule centres 1 mm apart", body(kBall, [](BodyDesc& b) {
         b.shape = ShapeKind::kCapsule;
         b.vertices = {{0, 0}, {Real(0.001), 0}};
         b.radius = Real(0.2);
       }),
       "scene body 2: capsule length (centre to centre) must be at least 0.005 m"},
      {"segment on a dynamic body", body(kBall, [](BodyDesc& b) {
         b.shape = ShapeKind::kSegment;
         b.vertices = {{0, 0}, {1, 0}};
       }),
       "scene body 2: a segment has no area (mass 0): only a static or kinematic body may carry it"},
      {"chain segment on a dynamic body", body(kBall, [](BodyDesc& b) {
         b.shape = ShapeKind::kChainSegment;
         b.vertices = {{2, 0}, {1, 0}, {0, 0}, {-1, 0}};
       }),
       "scene body 2: a segment has no area"},
      {"segment with 3 points", body(0, [](BodyDesc& b) {
         b.shape = ShapeKind::kSegment;
         b.vertices = {{0, 0}, {1, 0}, {2, 0}};
       }),
       "scene body 0: a segment has 2 points, got 3"},
      {"segment points 1 mm apart", body(0, [](BodyDesc& b) {
         b.shape = ShapeKind::kSegment;
         b.vertices = {{0, 0}, {Real(0.001), 0}};
       }),
       "scene body 0: segment length must be at least 0.005 m, got 0.001000"},
      {"segment point NaN", body(0, [](BodyDesc& b) {
         b.shape = ShapeKind::kSegment;
         b.vertices = {{kNaN, 0}, {1, 0}};
       }),
       "scene body 0: segment point is not finite"},
      {"segment beyond 1e6 m", body(0, [](BodyDesc& b) {
         b.shape = ShapeKind::kSegment;
         b.vertices = {{0, 0}, {Real(2e6), 0}};
       }),
       "scene body 0: segment is beyond the coordinate limit of 1e6 m"},
      {"chain segment with 2 vertices", body(0, [](BodyDesc& b) {
         b.shape = ShapeKind::kChainSegment;
         b.vertices = {{0, 0}, {1, 0}};
       }),
       "scene body 0: a chain segment has 4 vertices (ghost1, point1, point2, ghost2), got 2"},
      {"chain segment ghost on its end", body(0, [](BodyDesc& b) {
         b.shape = ShapeKind::kChainSegment;
         b.vertices = {{1, 0}, {1, 0}, {0, 0}, {-1, 0}};
       }),
       "scene body 0: chain segment ghost vertex must be at least 0.005 m from its end"},
      {"density 0 (dynamic)", body(kBox, [](BodyDesc& b) { b.density = 0; }), "scene body 1: a dynamic body needs ShapeDef.density > 0"},
      {"density -1", body(kBall, [](BodyDesc& b) { b.density = -1; }), "ShapeDef.density must be finite and >= 0"},
      {"density NaN", body(kBox, [](BodyDesc& b) { b.density = kNaN; }), "ShapeDef.density must be finite and >= 0"},
      {"density inf", body(kBall, [](BodyDesc& b) { b.density = kInf; }), "ShapeDef.density must be finite and >= 0"},
      {"friction -0.1", body(kBox, [](BodyDesc& b) { b.friction = Real(-0.1); }), "ShapeDef.friction must be finite and >= 0"},
      {"friction NaN", body(kBall, [](BodyDesc& b) { b.friction = kNaN; }), "ShapeDef.friction must be finite and >= 0"},
      {"linear damping -1", body(kBox, [](BodyDesc& b) { b.linearDamping = -1; }), "linearDamping must be finite and >= 0"},
      {"angular damping NaN", body(kBall, [](BodyDesc& b) { b.angularDamping = kNaN; }),
       "angularDamping must be finite and >= 0"},
      {"restitution 1.5", body(kBox, [](BodyDesc& b) { b.restitution = Real(1.5); }), "restitution must be in [0, 1]"},
      {"restitution -0.1", body(kBall, [](BodyDesc& b) { b.restitution = Real(-0.1); }), "restitution must be in [0, 1]"},
      {"radius 0", body(kBall, [](BodyDesc& b) { b.radius = 0; }), "scene body 2: circle radius must be at least 0.005 m"},
      {"radius -0.5", body(kBall, [](BodyDesc& b) { b.radius = Real(-0.5); }), "circle radius must be at least 0.005 m"},
      {"radius 0.004", body(kBall, [](BodyDesc& b) { b.radius = Real(0.004); }), "circle radius must be at least 0.005 m"},
      {"radius NaN", body(kBall, [](BodyDesc& b) { b.radius = kNaN; }), "circle radius is not finite"},
      {"radius inf", body(kBall, [](BodyDesc& b) { b.radius = kInf; }), "circle radius is not finite"},
      {"radius 2e6", body(kBall, [](BodyDesc& b) { b.radius = Real(2e6); }), "circle is beyond the coordinate limit"},
      {"0 vertices", verts({}), "scene body 1: a polygon needs at least 3 vertices, got 0"},
      {"2 vertices", verts({{0, 0}, {1, 0}}), "a polygon needs at least 3 vertices, got 2"},
      {"9 vertices", verts({{1, 0}, {Real(0.77), Real(0.64)}, {Real(0.17), Real(0.98)}, {Real(-0.5), Real(0.87)},
                            {Real(-0.94), Real(0.34)}, {Real(-0.94), Real(-0.34)}, {Real(-0.5), Real(-0.87)},
                            {Real(0.17), Real(-0.98)}, {Real(0.77), Real(-0.64)}}),
       "a polygon has at most 8 vertices, got 9"},
      {"duplicate vertices", verts({{0, 0}, {1, 0}, {1, 0}, {0, 1}}), "are duplicates (closer than 0.005 m)"},
      {"collinear vertices", verts({{0, 0}, {1, 0}, {2, 0}}), "polygon vertices are collinear"},
      {"sliver (1 mm thick)", verts({{0, 0}, {1, 0}, {Real(0.5), Real(0.001)}}), "nearly collinear"},
      {"clockwise vertices", verts({{0, 0}, {0, 1}, {1, 1}, {1, 0}}),
       "polygon vertices are clockwise; the scene API takes counter-clockwise"},
      {"non-convex vertices", verts({{0, 0}, {2, 0}, {2, 2}, {1, Real(0.5)}, {0, 2}}), "polygon is not convex"},
      {"self-intersecting order", verts({{0, 0}, {1, 1}, {1, 0}, {0, 1}}), "not in convex order (self-intersecting"},
      {"vertex NaN", verts({{0, 0}, {1, 0}, {kNaN, 1}}), "polygon vertex 2 is not finite"},
      {"vertex beyond 1e6 m", verts({{0, 0}, {Real(2e6), 0}, {0, 1}}), "is beyond the coordinate limit of 1e6 m"},
      {"time step 0", [](Scene& s) { s.timeStep = 0; }, "scene time step must be > 0"},
      {"time step -1/60", [](Scene& s) { s.timeStep = Real(-1.0 / 60.0); }, "scene time step must be > 0"},
      {"time step 2 s", [](Scene& s) { s.timeStep = 2; }, "scene time step must be <= 1 s"},
      {"time step NaN", [](Scene& s) { s.timeStep = kNaN; }, "scene time step is not finite"},
      {"time step inf", [](Scene& s) { s.timeStep = kInf; }, "scene time step is not finite"},
      {"pipelineRepeats 0", [](Scene& s) { s.pipelineRepeats = 0; }, "scene pipelineRepeats must be >= 1"},
      {"velocity iterations 0", [](Scene& s) { s.velocityIterations = 0; }, "scene velocity iterations must be >= 1"},
      {"position iterations -1", [](Scene& s) { s.positionIterations = -1; }, "scene position iterations must be >= 0"},
      {"gravity NaN", [](Scene& s) { s.gravity.y = kNaN; }, "scene gravity is not finite"},
      {"restitution threshold -1", [](Scene& s) { s.restitutionThreshold = -1; }, "restitution threshold must be >= 0"},
      {"restitution threshold NaN", [](Scene& s) { s.restitutionThreshold = kNaN; }, "restitution threshold is not finite"},
  };
}

std::unique_ptr<Adapter> Loaded(const std::string& engine, const Scene& scene, int steps) {
  auto a = MakeAdapter(engine);
  a->Load(scene, 1);
  for (int i = 0; i < steps; ++i) a->Step();
  return a;
}

void ExpectMessage(const std::function<void()>& call, const std::string& message, const std::string& what) {
  try {
    call();
    ADD_FAILURE() << what << ": no quadrant::Error (expected one containing '" << message << "')";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(message), std::string::npos)
        << what << ": message '" << e.what() << "' lacks '" << message << "'";
  }
}

TEST(BadInputScene, IterationAndSubStepLimits) {
  Scene bad = Good();
  bad.pipelineRepeats = 1001;
  ExpectMessage([&] { ValidateScene(bad); }, "pipelineRepeats must be <= 1000", "scene pipelineRepeats 1001");
  bad = Good();
  bad.velocityIterations = 1000000000;
  ExpectMessage([&] { ValidateScene(bad); }, "velocity iterations must be <= 1000", "scene velocity its 1e9");
  bad = Good();
  bad.positionIterations = 1001;
  ExpectMessage([&] { ValidateScene(bad); }, "position iterations must be <= 1000", "scene position its 1001");
}

TEST(BadInputScene, ValidateSceneRefusesEveryRow) {
  EXPECT_NO_THROW(ValidateScene(Good()));
  for (const Row& row : Rows()) {
    Scene bad = Good();
    row.spoil(bad);
    ExpectMessage([&] { ValidateScene(bad); }, row.message, row.what);
  }
}

class BadInputSceneEngine : public ::testing::TestWithParam<std::string> {};

TEST_P(BadInputSceneEngine, LoadRefusesEveryRowAndKeepsTheLoadedWorld) {
  const std::string engine = GetParam();
  const Scene good = Good();
  auto a = Loaded(engine, good, 5);
  auto twin = Loaded(engine, good, 5);
  const uint64_t hash = a->StateHash();
  ASSERT_EQ(hash, twin->StateHash());
  for (const Row& row : Rows()) {
    Scene bad = Good();
    row.spoil(bad);
    ExpectMessage([&] { a->Load(bad, 1); }, row.message, engine + ", " + row.what);
    EXPECT_EQ(a->StateHash(), hash) << engine << ", " << row.what;
    EXPECT_EQ(a->BodyCount(), 3) << engine << ", " << row.what;
  }
  // The refused loads left no trace in the future either.
  for (int i = 0; i < 30; ++i) {
    a->Step();
    twin->Step();
  }
  EXPECT_EQ(a->StateHash(), twin->StateHash()) << engine;
}

TEST_P(BadInputSceneEngine, ThreadCountsBelowOneAreErrors) {
  const std::string engine = GetParam();
  const Scene good = Good();
  auto a = Loaded(engine, good, 3);
  const uint64_t hash = a->StateHash();
  for (int threads : {0, -1}) {
    ExpectMessage([&] { a->Load(good, threads); }, "threads must be", engine + ", threads " + std::to_string(threads));
    EXPECT_EQ(a->StateHash(), hash) << engine;
  }
  // Above what the engine runs: a capability limit (Unsupported) for every engine, Quadrant's
  // 64 included, with the engine's reason (adapter.h, one protocol in the base).
  try {
    a->Load(good, 65);
    ADD_FAILURE() << engine << ": 65 threads accepted";
  } catch (const Unsupported& e) {
    EXPECT_NE(std::string(e.what()).find("runs at most"), std::string::npos) << e.what();
  }
  EXPECT_EQ(a->StateHash(), hash) << engine;
}

TEST_P(BadInputSceneEngine, SetVelocityRefusesBadIndicesAndValuesAndChangesNothing) {
  const std::string engine = GetParam();
  const Scene good = Good();
  auto a = Loaded(engine, good, 3);
  const uint64_t hash = a->StateHash();
  ExpectMessage([&] { a->SetVelocity(-1, {1, 0}, 0); }, "SetVelocity", engine + ", index -1");
  ExpectMessage([&] { a->SetVelocity(3, {1, 0}, 0); }, "SetVelocity", engine + ", index 3 of 3");
  ExpectMessage([&] { a->SetVelocity(1, {kNaN, 0}, 0); }, "SetVelocity", engine + ", NaN velocity");
  ExpectMessage([&] { a->SetVelocity(1, {1, 0}, kInf); }, "SetVelocity", engine + ", infinite spin");
  EXPECT_EQ(a->StateHash(), hash) << engine;
}

TEST_P(BadInputSceneEngine, StepBeforeLoadIsAnError) {
  auto a = MakeAdapter(GetParam());
  EXPECT_THROW(a->Step(), Error) << GetParam();
  std::vector<BodyState> out;
  a->ReadBodies(out);  // nothing loaded: nothing to read, no crash
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(a->BodyCount(), 0);
}

INSTANTIATE_TEST_SUITE_P(Engines, BadInputSceneEngine, ::testing::ValuesIn(kEngines),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });

TEST(BadInputScene, UnknownNamesAreErrors) {
  ExpectMessage([] { MakeAdapter("havok"); }, "unknown engine 'havok'", "engine name");
  ExpectMessage([] { MakeAdapter(""); }, "unknown engine ''", "empty engine name");
  ExpectMessage([] { MakeAdapter("quadrant:fastest"); }, "unknown quadrant variant 'fastest'", "quadrant variant");
  ExpectMessage([] { MakeScene("spinnr", 100); }, "unknown scene 'spinnr'", "scene name");
  ExpectMessage([] { MakeScene("tumbler", 3000); }, "tumbler: count must be in [1, 2116]", "tumbler count");
  ExpectMessage([] { MakeScene("circle_stress", 0); }, "body count must be > 0", "scene count 0");
  ExpectMessage([] { MakeScene("polygon_stress", -5); }, "body count must be > 0", "scene count -5");
}

}  // namespace
}  // namespace quadrant::scene
