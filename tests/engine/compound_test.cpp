// Tests for compound bodies (BodyDef::extraShapes; collision/narrow_phase_compound.cpp): the exact
// mass, centre and inertia against a hand computation, contacts per pair of shapes (resting,
// stacking, warm started through the cache's repeated keys), a kinematic drum turning boxes, sleep,
// the queries, drawing, the sensor test, the same state hash at 1, 2 and 4 threads, and the
// refusals, each leaving the world unchanged.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "collision/contact_cache.h"
#include "collision/narrow_phase.h"
#include "quadrant/debug_draw.h"
#include "quadrant/world.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

using namespace test;

// Two boxes side by side as one dynamic body: box A (1 x 1, density 1) centred at (-1, 0) and box
// B (2 x 1, density 2) centred at (1, 0), body coordinates.
BodyDef TwoBoxes(Vec2 position = {}, Real angle = 0) {
  BodyDef def;
  def.type = BodyType::kDynamic;
  def.position = position;
  def.angle = angle;
  def.shape = ShapeDef::Box(Real(0.5), Real(0.5), {-1, 0});
  ShapeDef b = ShapeDef::Box(1, Real(0.5), {1, 0});
  b.density = 2;
  def.extraShapes.push_back(b);
  return def;
}

// Box2D 3's compounds body: two right triangles sharing a hypotenuse-free corner, an L of area 2.
BodyDef TwoTriangles(Vec2 position, Real angle = 0) {
  BodyDef def;
  def.type = BodyType::kDynamic;
  def.position = position;
  def.angle = angle;
  const Vec2 t1[3] = {{-1, 0}, {Real(0.5), 0}, {0, Real(0.5)}};
  const Vec2 t2[3] = {{Real(0.5), 0}, {1, 0}, {Real(0.5), Real(1.5)}};
  def.shape = ShapeDef::FromPolygon(MakePolygon(t1));
  def.extraShapes.push_back(ShapeDef::FromPolygon(MakePolygon(t2)));
  return def;
}

TEST(CompoundTest, MassCentreAndInertiaByHand) {
  World world(NoGravityDef());
  BodyDef def = TwoBoxes({3, 4});
  // A circle of density 0 adds no mass (allowed: the total is positive).
  ShapeDef massless = ShapeDef::MakeCircle(Real(0.25), {0, 2});
  massless.density = 0;
  def.extraShapes.push_back(massless);
  const BodyId id = world.CreateBody(def);
  // By hand: m_A = 1, I_A = 1 (1 + 1) / 12 = 1/6; m_B = 2 * 2 = 4, I_B = 4 (4 + 1) / 12 = 5/3.
  // m = 5; x = (1 * -1 + 4 * 1) / 5 = 0.6; I = 1/6 + 1 * 1.6^2 + 5/3 + 4 * 0.4^2 = 5.0333...
  EXPECT_FLOAT_EQ(world.GetMass(id), 5.0f);
  EXPECT_FLOAT_EQ(world.GetWorldCenter(id).x, 3.6f);
  EXPECT_FLOAT_EQ(world.GetWorldCenter(id).y, 4.0f);
  EXPECT_NEAR(world.GetRotationalInertia(id), 1.0 / 6 + 2.56 + 5.0 / 3 + 0.64, 1e-5);
  EXPECT_EQ(world.GetShapeCount(id), 3);
  EXPECT_EQ(world.GetShape(id).polygon.count, 4);
  EXPECT_EQ(world.GetShape(id, 1).density, 2);
  EXPECT_EQ(world.GetShape(id, 2).type, ShapeType::kCircle);
  // The body's box covers every shape: x from 3 - 1.5 to 3 + 2, y up to 4 + 2.25.
  const AABB box = world.GetAABB(id);
  EXPECT_FLOAT_EQ(box.lower.x, 1.5f);
  EXPECT_FLOAT_EQ(box.upper.x, 5.0f);
  EXPECT_FLOAT_EQ(box.lower.y, 3.5f);
  EXPECT_FLOAT_EQ(box.upper.y, 6.25f);
  // SetDensity makes every shape's density 1: m = 3, centre x = (1 * -1 + 2 * 1) / 3.
  const BodyId two = world.CreateBody(TwoBoxes({3, 4}));
  world.SetDensity(two, 1);
  EXPECT_FLOAT_EQ(world.GetMass(two), 3.0f);
  EXPECT_NEAR(world.GetWorldCenter(two).x, 3 + 1.0 / 3, 1e-6);
  EXPECT_FLOAT_EQ(world.GetPosition(two).x, 3.0f);  // the origin stays
  EXPECT_NEAR(world.GetRotationalInertia(two), 1.0 / 6 + (4.0 / 3) * (4.0 / 3) + 2 * 5.0 / 12 + 2 * (2.0 / 3) * (2.0 / 3),
              1e-5);
  // A one-shape body reads one shape.
  const BodyId single = AddBox(world, {10, 0});
  EXPECT_EQ(world.GetShapeCount(single), 1);
}

TEST(CompoundTest, PlankOfTwoBoxesRestsFlatOnBothShapes) {
  for (SolverType solver : {SolverType::kSoftStep, SolverType::kPgs}) {
    WorldDef wd;
    wd.solver = solver;
    World world(wd);
    AddGround(world);
    // A 2 x 0.5 plank made of two 1 x 0.5 boxes, dropped from 0.2 m.
    BodyDef def;
    def.type = BodyType::kDynamic;
    def.position = {0, Real(0.5 + 0.25 + 0.2)};
    def.shape = ShapeDef::Box(Real(0.5), Real(0.25), {Real(-0.5), 0});
    def.extraShapes.push_back(ShapeDef::Box(Real(0.5), Real(0.25), {Real(0.5), 0}));
    const BodyId plank = world.CreateBody(def);
    for (int i = 0; i < 120; ++i) world.Step(kDt);
    EXPECT_NEAR(world.GetPosition(plank).y, 0.75, 0.02) << int(solver);
    EXPECT_NEAR(world.GetAngle(plank), 0, 1e-3) << int(solver);
    // One contact per box with the ground, two points each, both holding weight.
    const std::vector<ContactInfo> contacts = world.GetContacts();
    ASSERT_EQ(contacts.size(), 2u) << int(solver);
    for (const ContactInfo& c : contacts) {
      EXPECT_EQ(c.pointCount, 2);
      EXPECT_GT(c.normalImpulses[0] + c.normalImpulses[1], 0);
    }
    EXPECT_LT(contacts[0].points[0].x + contacts[0].points[1].x, 0);  // the left box's, first
    EXPECT_GT(contacts[1].points[0].x + contacts[1].points[1].x, 0);
  }
}

TEST(CompoundTest, CacheRestoresEachShapePairOfOneBodyPair) {
  // Three contacts of bodies (0, 1), told apart by their shape pairs; the cache holds keys twice.
  auto make = [](int shapeA, int shapeB, Real impulse) {
    Contact c;
    c.a = 0;
    c.b = 1;
    c.manifold.pointCount = 2;
    for (int k = 0; k < 2; ++k) {
      c.manifold.points[k].id = CompoundFeatureId(MakeFeatureId(1, uint32_t(k), false), shapeA, shapeB);
      c.manifold.points[k].normalImpulse = impulse + Real(k);
    }
    return c;
  };
  ContactCache cache;
  std::vector<Contact> last = {make(0, 0, 10), make(1, 0, 20), make(1, 1, 30)};
  cache.Keep(last, false);  // keys repeat: stored as entries
  std::vector<Contact> now = {make(0, 0, 0), make(1, 1, 0), make(0, 1, 0)};
  EXPECT_EQ(cache.Restore(now), 4);
  EXPECT_EQ(now[0].manifold.points[0].normalImpulse, 10);
  EXPECT_EQ(now[0].manifold.points[1].normalImpulse, 11);
  EXPECT_EQ(now[1].manifold.points[0].normalImpulse, 30);  // not the key's first entry's
  EXPECT_EQ(now[1].manifold.points[1].normalImpulse, 31);
  EXPECT_EQ(now[2].manifold.points[0].normalImpulse, 0);  // a shape pair new this step
}

TEST(CompoundTest, WarmStartsEveryShapePair) {
  // A resting plank's two contacts with the ground each start the step from last step's
  // impulses (the cache finds both under one key).
  auto run = [](bool warm) {
    WorldDef wd;
    wd.solver = SolverType::kPgs;
    wd.effects.warmStarting = warm;
    wd.velocityIterations = 1;
    World world(wd);
    AddGround(world);
    BodyDef def;
    def.type = BodyType::kDynamic;
    def.position = {0, Real(0.75)};
    def.shape = ShapeDef::Box(Real(0.5), Real(0.25), {Real(-0.5), 0});
    def.extraShapes.push_back(ShapeDef::Box(Real(0.5), Real(0.25), {Real(0.5), 0}));
    def.extraShapes[0].density = 3;  // unequal loads on the two contacts
    world.CreateBody(def);
    for (int i = 0; i < 90; ++i) world.Step(kDt);
    return world.GetContacts();
  };
  const std::vector<ContactInfo> warm = run(true), cold = run(false);
  ASSERT_EQ(warm.size(), 2u);
  ASSERT_EQ(cold.size(), 2u);
  // The plank's weight over a step, m g dt = (0.5 + 1.5) * 10 / 60: warm started, one velocity
  // iteration carries it; started from zero each step, one iteration does not.
  const double weight = 2.0 * 10 / 60;
  auto total = [](const std::vector<ContactInfo>& cs) {
    double sum = 0;
    for (const ContactInfo& c : cs) sum += double(c.normalImpulses[0]) + double(c.normalImpulses[1]);
    return sum;
  };
  EXPECT_NEAR(total(warm), weight, 0.02 * weight);
  for (const ContactInfo& c : warm) EXPECT_GT(c.normalImpulses[0] + c.normalImpulses[1], 0);
  EXPECT_GT(std::abs(total(cold) - weight), 4 * std::abs(total(warm) - weight)) << total(cold) << " " << total(warm);
}

// A pile of Box2D 3's two-triangle bodies on a ground: the state after 120 steps.
uint64_t TrianglePileHash(int threads, int* contacts = nullptr) {
  WorldDef wd;
  wd.threadCount = threads;
  wd.minParallelItems = 4;
  World world(wd);
  AddGround(world, 20, Real(0.5));
  BodyDef wallL;
  wallL.position = {-6, 5};
  wallL.shape = ShapeDef::Box(Real(0.5), 5);
  wallL.extraShapes.push_back(ShapeDef::Box(5, Real(0.5), {Real(-5.5), 4}));  // a static compound
  world.CreateBody(wallL);
  for (int row = 0; row < 10; ++row) {
    for (int col = 0; col < 8; ++col) {
      world.CreateBody(TwoTriangles({Real(-4.5 + 1.2 * col + 0.1 * (row % 2)), Real(1 + 1.7 * row)}, Real(0.3 * col)));
    }
  }
  for (int i = 0; i < 120; ++i) world.Step(kDt);
  if (contacts != nullptr) *contacts = world.GetCounters().contacts;
  return world.StateHash();
}

TEST(CompoundTest, TrianglePileHashIsTheSameAtOneTwoAndFourThreads) {
  int contacts = 0;
  const uint64_t one = TrianglePileHash(1, &contacts);
  EXPECT_GT(contacts, 80);  // the pile touches: more contacts than bodies
  EXPECT_EQ(TrianglePileHash(2), one);
  EXPECT_EQ(TrianglePileHash(4), one);
}

TEST(CompoundTest, OneShapePairsAreCollidedAsWithoutACompoundInTheWorld) {
  // With a compound body in the world the narrow phase splits its pairs off and sends the rest
  // to the pair loops in runs: a pile of boxes and circles far from it moves bit for bit as beside
  // a one-shape body.
  auto pile = [](bool compound) {
    WorldDef wd;
    wd.threadCount = 2;
    wd.minParallelItems = 4;
    World world(wd);
    AddGround(world);
    BodyDef far = TwoBoxes({100, 100});
    far.type = BodyType::kKinematic;
    if (!compound) far.extraShapes.clear();
    world.CreateBody(far);
    std::vector<BodyId> ids;
    for (int k = 0; k < 40; ++k) {
      ids.push_back(k % 3 == 0 ? AddCircle(world, {Real(-3 + 0.3 * (k % 7)), Real(1 + 1.1 * k)}, Real(0.4))
                               : AddBox(world, {Real(-3 + 0.35 * (k % 5)), Real(1 + 1.1 * k)}, Real(0.4), Real(0.3)));
    }
    for (int i = 0; i < 90; ++i) world.Step(kDt);
    std::vector<Real> state;
    for (BodyId id : ids) state.insert(state.end(), {world.GetPosition(id).x, world.GetPosition(id).y, world.GetAngle(id)});
    return state;
  };
  EXPECT_EQ(pile(true), pile(false));
}

// Boxes falling onto a static ring of 36 boxes on one body: a box touching two pieces makes two
// contacts with one key, which the sorter must see as repeated at any split of the work (its
// insertion pass once missed a key moved back next to its twin, and 2 threads kept the list
// as strictly increasing where 1 thread stored it: different warm starts).
uint64_t RingHash(int threads) {
  WorldDef wd;
  wd.threadCount = threads;
  wd.minParallelItems = 64;
  World world(wd);
  BodyDef ring;
  ring.position = {0, 10};
  for (int k = 0; k < 36; ++k) {
    const Real angle = Real(2 * kPi * k / 36);
    const ShapeDef wall = ShapeDef::Box(1, Real(1.6), {Real(17) * std::cos(angle), Real(17) * std::sin(angle)}, angle);
    if (k == 0) ring.shape = wall;
    else ring.extraShapes.push_back(wall);
  }
  world.CreateBody(ring);
  for (int i = 0; i < 30; ++i) {
    for (int j = 0; j < 30; ++j) AddBox(world, {Real(-3 + 0.21 * j), Real(7 + 0.21 * i)}, Real(0.1), Real(0.1));
  }
  for (int i = 0; i < 130; ++i) world.Step(kDt);
  return world.StateHash();
}

TEST(CompoundTest, RingOfShapesHashIsTheSameAtOneAndTwoThreads) { EXPECT_EQ(RingHash(1), RingHash(2)); }

TEST(CompoundTest, TrianglesStackWithoutSinking) {
  World world(WorldDef{});
  AddGround(world);
  std::vector<BodyId> ids;
  for (int k = 0; k < 4; ++k) ids.push_back(world.CreateBody(TwoTriangles({0, Real(0.5 + 1.6 * k + 0.05)})));
  for (int i = 0; i < 240; ++i) world.Step(kDt);
  // Each L is 1.5 m tall at its right triangle, 0.5 m at its left one; every body stays above the
  // ground's top (0.5) and the pile stays ordered and awake-free of NaN.
  Real lastY = -1;
  for (BodyId id : ids) {
    const Vec2 p = world.GetPosition(id);
    ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y));
    EXPECT_GT(p.y, Real(0.45));
    EXPECT_GT(p.y, lastY);
    lastY = p.y;
  }
  EXPECT_LT(world.GetLinearVelocity(ids.back()).y, Real(0.05));
}

TEST(CompoundTest, KinematicDrumOfPolygonsTurnsTheBoxesInside) {
  WorldDef wd;
  wd.hitEvents = true;
  World world(wd);
  // Box2D 3's washer drum, small: 20 boxes on a ring of radius 4 on one kinematic body.
  BodyDef drum;
  drum.type = BodyType::kKinematic;
  drum.angularVelocity = Real(1);
  constexpr int kSides = 20;
  for (int k = 0; k < kSides; ++k) {
    const Real angle = Real(2 * kPi * k / kSides);
    const ShapeDef wall = ShapeDef::Box(Real(0.25), Real(0.7), {Real(4.25) * std::cos(angle), Real(4.25) * std::sin(angle)}, angle);
    if (k == 0) drum.shape = wall;
    else drum.extraShapes.push_back(wall);
  }
  const BodyId drumId = world.CreateBody(drum);
  EXPECT_EQ(world.GetShapeCount(drumId), kSides);
  std::vector<BodyId> boxes;
  for (int k = 0; k < 25; ++k) boxes.push_back(AddBox(world, {Real(-2 + 0.8 * (k % 5)), Real(-2 + 0.8 * (k / 5))}, Real(0.25), Real(0.25)));
  int hits = 0;
  Real sumX = 0;
  for (int i = 0; i < 240; ++i) {
    world.Step(kDt);
    hits += int(world.GetContactHitEvents().size());
  }
  for (BodyId id : boxes) {
    const Vec2 p = world.GetPosition(id);
    EXPECT_LT(Length(p), Real(4.0)) << "a box left the drum";
    sumX += p.x;
  }
  EXPECT_GT(hits, 0);
  // The drum turns counter-clockwise, its bottom moving towards +x: the boxes ride up its right side.
  EXPECT_GT(sumX / Real(boxes.size()), Real(0.3));
  EXPECT_NEAR(world.GetAngle(drumId), 4.0 - 2 * kPi, 1e-3);
}

TEST(CompoundTest, PileFallsAsleepAndWakes) {
  WorldDef wd;
  wd.effects.sleep = true;
  World world(wd);
  AddGround(world);
  const BodyId a = world.CreateBody(TwoTriangles({0, Real(0.55)}));
  const BodyId b = world.CreateBody(TwoTriangles({Real(0.2), Real(2.2)}));
  for (int i = 0; i < 300; ++i) world.Step(kDt);
  EXPECT_FALSE(world.IsAwake(a));
  EXPECT_FALSE(world.IsAwake(b));
  world.SetLinearVelocity(b, {0, 1});
  EXPECT_TRUE(world.IsAwake(a));  // one island
}

TEST(CompoundTest, QueriesSeeEveryShape) {
  World world(NoGravityDef());
  const BodyId id = world.CreateBody(TwoBoxes());  // boxes over x in [-1.5, -0.5] and [0, 2]
  // A ray from the right hits box B's right face; from the left, box A's left face.
  const std::optional<RayHit> right = world.RayCastClosest({5, 0}, {-10, 0});
  ASSERT_TRUE(right.has_value());
  EXPECT_EQ(right->body, id);
  EXPECT_NEAR(right->point.x, 2, 1e-5);
  const std::optional<RayHit> left = world.RayCastClosest({-5, 0}, {10, 0});
  ASSERT_TRUE(left.has_value());
  EXPECT_NEAR(left->point.x, -1.5, 1e-5);
  // Between the boxes (x = -0.25) nothing: a ray down through the gap misses.
  EXPECT_FALSE(world.RayCastClosest({Real(-0.25), 5}, {0, -10}).has_value());
  std::vector<BodyId> found;
  world.QueryPoint({Real(1.5), 0}, found);
  EXPECT_EQ(found.size(), 1u);
  world.QueryPoint({Real(-0.25), 0}, found);
  EXPECT_TRUE(found.empty());
  world.QueryAABB({{Real(-0.4), -1}, {Real(-0.1), 1}}, found);
  EXPECT_TRUE(found.empty());
  world.QueryAABB({{Real(-0.6), -1}, {Real(-0.1), 1}}, found);
  EXPECT_EQ(found.size(), 1u);
  const std::optional<RayHit> cast = world.CastCircle({5, 0}, Real(0.25), {-10, 0});
  ASSERT_TRUE(cast.has_value());
  EXPECT_NEAR(cast->point.x, 2, 1e-4);
  const Vec2 square[4] = {{-Real(0.1), -Real(0.1)}, {Real(0.1), -Real(0.1)}, {Real(0.1), Real(0.1)}, {-Real(0.1), Real(0.1)}};
  std::vector<Vec2> moving;
  for (Vec2 v : square) moving.push_back(v + Vec2{Real(-0.25), 5});
  EXPECT_FALSE(world.CastPolygon(moving, {0, -10}).has_value());  // through the gap
  moving.clear();
  for (Vec2 v : square) moving.push_back(v + Vec2{1, 5});
  const std::optional<RayHit> down = world.CastPolygon(moving, {0, -10});
  ASSERT_TRUE(down.has_value());
  EXPECT_NEAR(down->point.y, 0.5, 1e-4);
}

TEST(CompoundTest, SensorSeesACompoundVisitorBySecondShape) {
  World world(NoGravityDef(SolverType::kSoftStep));
  BodyDef sensor;
  sensor.position = {Real(1.5), 0};
  sensor.shape = ShapeDef::MakeCircle(Real(0.2));
  sensor.shape.isSensor = true;
  world.CreateBody(sensor);
  world.CreateBody(TwoBoxes());  // dynamic, no gravity: box B covers the sensor, box A does not
  world.Step(kDt);
  EXPECT_EQ(world.GetSensorBeginEvents().size(), 1u);
}

struct CountingDraw : DebugDraw {
  int polygons = 0, circles = 0, boxes = 0;
  void DrawCircle(Vec2, Real, Real, Color) override { ++circles; }
  void DrawPolygon(std::span<const Vec2>, Color) override { ++polygons; }
  void DrawAABB(const AABB&, Color) override { ++boxes; }
};

TEST(CompoundTest, DrawsEveryShapeAndOneBoxPerBody) {
  World world(NoGravityDef());
  BodyDef def = TwoBoxes();
  def.extraShapes.push_back(ShapeDef::MakeCircle(Real(0.25), {0, 2}));
  world.CreateBody(def);
  CountingDraw draw;
  world.Draw(draw, kDrawShapes | kDrawAABBs);
  EXPECT_EQ(draw.polygons, 2);
  EXPECT_EQ(draw.circles, 1);
  EXPECT_EQ(draw.boxes, 1);
}

TEST(CompoundTest, BadCompoundsAreRefusedAndChangeNothing) {
  World world(NoGravityDef());
  AddBox(world, {5, 5});
  const uint64_t hash = world.StateHash();
  auto refuses = [&](const BodyDef& def, const char* needle) {
    try {
      world.CreateBody(def);
      ADD_FAILURE() << "accepted: " << needle;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
    EXPECT_EQ(world.GetBodyCount(), 1);
    EXPECT_EQ(world.StateHash(), hash);
    EXPECT_THROW(CheckBodyDef(def), Error);
  };
  BodyDef many = TwoBoxes();
  many.extraShapes.assign(kMaxBodyShapes, ShapeDef::MakeCircle(Real(0.1)));
  refuses(many, "at most 64");
  BodyDef badPolygon = TwoBoxes();
  badPolygon.extraShapes[0].polygon.count = 2;
  refuses(badPolygon, "BodyDef.extraShapes[0]: polygon vertex count");
  BodyDef badCircle = TwoBoxes();
  badCircle.extraShapes.push_back(ShapeDef::MakeCircle(Real(0.5)));
  badCircle.extraShapes.back().circle.radius = std::nanf("");
  refuses(badCircle, "BodyDef.extraShapes[1]:");
  BodyDef badFriction = TwoBoxes();
  badFriction.extraShapes[0].friction = -1;
  refuses(badFriction, "BodyDef.extraShapes[0]: ShapeDef.friction");
  BodyDef sensor = TwoBoxes();
  sensor.extraShapes[0].isSensor = true;
  refuses(sensor, "cannot be sensors");
  BodyDef massless = TwoBoxes();
  massless.shape.density = 0;
  massless.extraShapes[0].density = 0;
  refuses(massless, "total mass");
  BodyDef segment = TwoBoxes();
  segment.extraShapes.push_back(ShapeDef::MakeSegment({0, 0}, {1, 0}));
  refuses(segment, "BodyDef.extraShapes[1]: a segment has no area");
  BodyDef unknown = TwoBoxes();
  unknown.extraShapes[0].type = ShapeType(8);
  refuses(unknown, "ShapeDef.type is unknown");
  // A static body of segments is fine, and SetType cannot make it dynamic.
  BodyDef fence;
  fence.shape = ShapeDef::MakeSegment({0, 0}, {1, 0});
  fence.extraShapes.push_back(ShapeDef::MakeSegment({1, 0}, {1, 1}));
  const BodyId fenceId = world.CreateBody(fence);
  auto message = [](auto&& call) -> std::string {
    try {
      call();
    } catch (const Error& e) {
      return e.what();
    }
    return "accepted";
  };
  EXPECT_EQ(message([&] { world.SetType(fenceId, BodyType::kDynamic); }),
            "SetType: a segment has no area (mass 0): only a static or kinematic body may carry it");
  EXPECT_EQ(world.GetType(fenceId), BodyType::kStatic);
  // A compound of density-0 shapes stays static: SetType refuses dynamic, SetDensity(0) on a
  // dynamic compound too.
  BodyDef light = TwoBoxes({-5, -5});
  light.type = BodyType::kStatic;
  light.shape.density = 0;
  light.extraShapes[0].density = 0;
  const BodyId lightId = world.CreateBody(light);
  EXPECT_EQ(message([&] { world.SetType(lightId, BodyType::kDynamic); }),
            "SetType: a dynamic compound body's total mass or rotational inertia is not a positive finite number (2 "
            "shapes; every one of density 0?)");
  const BodyId heavy = world.CreateBody(TwoBoxes({-10, -10}));
  const uint64_t before = world.StateHash();
  EXPECT_EQ(message([&] { world.SetDensity(heavy, 0); }), "SetDensity: a dynamic body needs density > 0");
  EXPECT_FLOAT_EQ(world.GetMass(heavy), 5.0f);
  EXPECT_EQ(world.GetShape(heavy, 1).density, 2);
  EXPECT_EQ(message([&] { world.GetShape(heavy, 2); }), "GetShape: shape index 2 is outside [0, 2)");
  EXPECT_THROW(world.GetShape(heavy, -1), Error);
  EXPECT_EQ(world.StateHash(), before);
  // The quadrants scheme refuses compound bodies.
  WorldDef quadrants;
  quadrants.scheme = ParallelScheme::kQuadrants;
  quadrants.solver = SolverType::kPgs;
  World q(quadrants);
  try {
    q.CreateBody(TwoBoxes());
    ADD_FAILURE() << "quadrants accepted a compound";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("compound body"), std::string::npos) << e.what();
  }
  EXPECT_EQ(q.GetBodyCount(), 0);
}

}  // namespace
}  // namespace quadrant
