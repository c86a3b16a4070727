// Box2D 2.4.1's position pass geometry (engine/src/dynamics/box2d_position.h, issue #31): the
// reference face's normal and plane turn with the reference body, the incident point with its
// own, two circles are measured centre to centre; and a world with WorldDef::box2dPositionSolve
// still pushes overlapping bodies apart.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <utility>

#include "dynamics/box2d_position.h"
#include "quadrant/world.h"

namespace quadrant {
namespace {

constexpr Real kTol = Real(1e-5);

// Two bodies, A at the origin and B at `cB`, with the given shapes: what the geometry reads.
Bodies TwoBodies(ShapeType ta, ShapeType tb, Vec2 cB) {
  Bodies bodies;
  bodies.shape.resize(2);
  bodies.shape[0].type = ta;
  bodies.shape[1].type = tb;
  bodies.center = {Vec2{0, 0}, cB};
  return bodies;
}

Contact OnePointContact(Vec2 normal, Vec2 point, Real separation, uint32_t id = 0) {
  Contact c;
  c.a = 0;
  c.b = 1;
  c.manifold.normal = normal;
  c.manifold.pointCount = 1;
  c.manifold.points[0].point = point;
  c.manifold.points[0].separation = separation;
  c.manifold.points[0].id = id;
  return c;
}

TEST(Box2dPosition, CircleOnAFaceIsMeasuredFromItsCentreToTheTurnedFace) {
  // A polygon A with its top face's normal +y; a circle B of radius 0.5 whose centre is 0.48 above
  // that face (2 cm deep). The point of the correction is the circle's centre.
  const Bodies bodies = TwoBodies(ShapeType::kPolygon, ShapeType::kCircle, Vec2{0.3f, 0.98f});
  const Contact c = OnePointContact(Vec2{0, 1}, Vec2{0.3f, 0.49f}, Real(-0.02));
  const Box2dPositionPoint p = MakeBox2dPositionPoint(bodies, c, 0, Real(-0.02));
  ASSERT_EQ(p.kind, Box2dPositionPoint::kFaceA);
  Real s;
  Vec2 n, point;
  Box2dPositionNow(p, Vec2{0, 0}, Rot{}, Vec2{0.3f, 0.98f}, Rot{}, s, n, point);
  EXPECT_NEAR(s, -0.02, kTol);
  EXPECT_NEAR(point.x, 0.3, kTol);
  EXPECT_NEAR(point.y, 0.98, kTol);
  // The circle 1 cm up (and spun: its turn changes nothing): 1 cm less deep.
  Box2dPositionNow(p, Vec2{0, 0}, Rot{}, Vec2{0.3f, 0.99f}, MakeRot(1.0f), s, n, point);
  EXPECT_NEAR(s, -0.01, kTol);
  // A turned by 0.1 rad about its centre: the face's normal turns with it, and the circle's
  // centre is measured to the turned plane. That plane is the face moved out by the circle's
  // radius, through (0.3, 0.98) + 0.02 (0, 1) = (0.3, 1.0) before the turn.
  const Rot turn = MakeRot(0.1f);
  Box2dPositionNow(p, Vec2{0, 0}, turn, Vec2{0.3f, 0.98f}, Rot{}, s, n, point);
  EXPECT_NEAR(n.x, -std::sin(0.1), kTol);
  EXPECT_NEAR(n.y, std::cos(0.1), kTol);
  const Vec2 plane = Rotate(turn, Vec2{0.3f, 1.0f});
  EXPECT_NEAR(s, Dot(Vec2{0.3f, 0.98f} - plane, n), kTol);
  EXPECT_LT(s, -0.05);  // the turned face lifts into the circle: deeper than before
}

TEST(Box2dPosition, FaceOnBTurnsWithBAndTheNormalStillPointsFromAToB) {
  // Circle A below polygon B's bottom face (B's face normal -y): the reference is B.
  const Bodies bodies = TwoBodies(ShapeType::kCircle, ShapeType::kPolygon, Vec2{0, 1});
  const Contact c = OnePointContact(Vec2{0, 1}, Vec2{0, 0.49f}, Real(-0.02));
  const Box2dPositionPoint p = MakeBox2dPositionPoint(bodies, c, 0, Real(-0.02));
  ASSERT_EQ(p.kind, Box2dPositionPoint::kFaceB);
  Real s;
  Vec2 n, point;
  Box2dPositionNow(p, Vec2{0, 0}, Rot{}, Vec2{0, 1}, Rot{}, s, n, point);
  EXPECT_NEAR(s, -0.02, kTol);
  EXPECT_NEAR(n.y, 1, kTol);
  EXPECT_NEAR(point.y, 0, kTol);  // A's centre
  Box2dPositionNow(p, Vec2{0, 0}, Rot{}, Vec2{0, 1.05f}, MakeRot(0.3f), s, n, point);
  EXPECT_NEAR(n.x, -std::sin(0.3), kTol);  // -(B's -y normal turned by 0.3 rad)
  EXPECT_NEAR(n.y, std::cos(0.3), kTol);
}

TEST(Box2dPosition, TwoCirclesAreMeasuredCentreToCentre) {
  const Bodies bodies = TwoBodies(ShapeType::kCircle, ShapeType::kCircle, Vec2{0.96f, 0});
  const Contact c = OnePointContact(Vec2{1, 0}, Vec2{0.48f, 0}, Real(-0.04));
  const Box2dPositionPoint p = MakeBox2dPositionPoint(bodies, c, 0, Real(-0.04));
  ASSERT_EQ(p.kind, Box2dPositionPoint::kCircles);
  Real s;
  Vec2 n, point;
  Box2dPositionNow(p, Vec2{0, 0}, MakeRot(2.0f), Vec2{0, 0.98f}, Rot{}, s, n, point);
  EXPECT_NEAR(s, -0.02, kTol);
  EXPECT_NEAR(n.y, 1, kTol);
  EXPECT_NEAR(point.y, 0.49, kTol);
}

TEST(Box2dPosition, PolygonPairsTakeTheReferenceFromTheFeatureId) {
  // The collider's point is halfway between the incident vertex and the reference face; with the
  // reference face on B (flipped) the incident vertex is A's, below the point by half the depth.
  const Bodies bodies = TwoBodies(ShapeType::kPolygon, ShapeType::kPolygon, Vec2{0, 1});
  const Contact c = OnePointContact(Vec2{0, 1}, Vec2{0.1f, 0.5f}, Real(-0.02), MakeFeatureId(1, 2, true));
  const Box2dPositionPoint p = MakeBox2dPositionPoint(bodies, c, 0, Real(-0.02));
  ASSERT_EQ(p.kind, Box2dPositionPoint::kFaceB);
  Real s;
  Vec2 n, point;
  Box2dPositionNow(p, Vec2{0, 0}, Rot{}, Vec2{0, 1}, Rot{}, s, n, point);
  EXPECT_NEAR(s, -0.02, kTol);
  EXPECT_NEAR(point.x, 0.1, kTol);
  EXPECT_NEAR(point.y, 0.51, kTol);  // A's vertex: 0.5 + 0.01
  const Contact unflipped = OnePointContact(Vec2{0, 1}, Vec2{0.1f, 0.5f}, Real(-0.02), MakeFeatureId(1, 2, false));
  EXPECT_EQ(MakeBox2dPositionPoint(bodies, unflipped, 0, Real(-0.02)).kind, Box2dPositionPoint::kFaceA);
}

TEST(Box2dPosition, OtherShapesKeepTheDefaultGeometry) {
  const Bodies bodies = TwoBodies(ShapeType::kCapsule, ShapeType::kPolygon, Vec2{0, 1});
  const Contact c = OnePointContact(Vec2{0, 1}, Vec2{0, 0.5f}, Real(-0.01));
  EXPECT_EQ(MakeBox2dPositionPoint(bodies, c, 0, Real(-0.01)).kind, Box2dPositionPoint::kDefault);
}

// A static ground box (its top at y = 0.5) and dynamic boxes of half size 0.5.
void AddGround(World& world, Real halfWidth) {
  BodyDef ground;
  ground.type = BodyType::kStatic;
  ground.shape.type = ShapeType::kPolygon;
  ground.shape.polygon = MakeBox(halfWidth, 0.5f);
  world.CreateBody(ground);
}

BodyId AddBox(World& world, Vec2 position, Real angle = 0) {
  BodyDef box;
  box.type = BodyType::kDynamic;
  box.shape.type = ShapeType::kPolygon;
  box.shape.polygon = MakeBox(0.5f, 0.5f);
  box.position = position;
  box.angle = angle;
  return world.CreateBody(box);
}

TEST(Box2dPosition, WorldWithBox2dPositionPassPushesAnOverlapOut) {
  // A box created 5 cm into the ground, at rest, no gravity: pgs's position pass with Box2D's
  // geometry moves it out to within its stopping rule (3 linearSlop), as the default pass does;
  // so does soft_step's with it, whose rows then push nothing.
  for (auto [solver, box2d] : {std::pair{SolverType::kPgs, false}, std::pair{SolverType::kPgs, true},
                               std::pair{SolverType::kSoftStep, true}}) {
    WorldDef def;
    def.solver = solver;
    def.gravity = Vec2{0, 0};
    def.box2dPositionSolve = box2d;
    World world(def);
    AddGround(world, 5);
    const BodyId id = AddBox(world, Vec2{0.2f, 0.95f});
    for (int i = 0; i < 30; ++i) world.Step(1.0f / 60);
    const Real y = world.GetPosition(id).y;
    EXPECT_GT(y, 1 - 3 * def.linearSlop - kTol) << box2d;
    EXPECT_LT(y, 1.01) << box2d;
    EXPECT_NEAR(world.GetAngle(id), 0, 1e-3) << box2d;
  }
}

TEST(Box2dPosition, SoftStepWithTheBox2dPassIsTheSameOnAnyThreadCount) {
  // The pass runs serially in colour order after the sub-steps and the free bodies' pass: a pile
  // of 60 boxes gives the same bits on 1, 2 and 4 threads, alone (the rows' part split across the
  // threads) and with 4000 free circles beside it (the rows' part on one thread beside them).
  auto run = [](int threads, int freeCircles) {
    WorldDef def;
    def.box2dPositionSolve = true;
    def.threadCount = threads;
    World world(def);
    AddGround(world, 20);
    for (int i = 0; i < 60; ++i) {
      AddBox(world, Vec2{Real(-6 + (i % 12) * 1.02f + 0.1f * (i / 12)), Real(1.2f + (i / 12) * 1.05f)}, Real(0.05f * (i % 5)));
    }
    for (int i = 0; i < freeCircles; ++i) {  // far from the pile and from each other
      BodyDef c;
      c.type = BodyType::kDynamic;
      c.shape.type = ShapeType::kCircle;
      c.shape.circle.radius = 0.4f;
      c.position = Vec2{Real(100 + 2 * (i % 80)), Real(10 + 2 * (i / 80))};
      world.CreateBody(c);
    }
    for (int i = 0; i < 120; ++i) world.Step(1.0f / 60);
    return world.StateHash();
  };
  for (int freeCircles : {0, 4000}) {
    const uint64_t one = run(1, freeCircles);
    EXPECT_EQ(run(2, freeCircles), one) << freeCircles << " free circles";
    EXPECT_EQ(run(4, freeCircles), one) << freeCircles << " free circles";
  }
}

}  // namespace
}  // namespace quadrant
