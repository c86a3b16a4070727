// World::Draw: a recording DebugDraw sees every body's shape in GetBodyIds order, in world
// coordinates and coloured by what the body is, then the boxes and the contact points when
// asked; a DebugDraw with only the two shape calls works; unknown flags are refused.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "quadrant/world.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

using namespace test;

struct Recorder : DebugDraw {
  struct Call {
    std::string what;
    std::vector<Vec2> points;  // circle: centre; polygon: vertices; contact: point, normal; box: corners
    Real radius = 0, angle = 0;
    Color color;
  };
  std::vector<Call> calls;
  void DrawCircle(Vec2 center, Real radius, Real angle, Color color) override {
    calls.push_back({"circle", {center}, radius, angle, color});
  }
  void DrawPolygon(std::span<const Vec2> vertices, Color color) override {
    calls.push_back({"polygon", {vertices.begin(), vertices.end()}, 0, 0, color});
  }
  void DrawContact(Vec2 point, Vec2 normal) override { calls.push_back({"contact", {point, normal}, 0, 0, {}}); }
  void DrawAABB(const AABB& box, Color color) override { calls.push_back({"box", {box.lower, box.upper}, 0, 0, color}); }
};

struct ShapesOnly : DebugDraw {
  int shapes = 0;
  void DrawCircle(Vec2, Real, Real, Color) override { ++shapes; }
  void DrawPolygon(std::span<const Vec2>, Color) override { ++shapes; }
};

TEST(DebugDrawTest, ShapesInBodyOrderThenBoxesThenContacts) {
  WorldDef def;
  def.effects.sleep = true;
  World world(def);
  const BodyId ground = AddGround(world, 10, Real(0.5));
  BodyDef k;
  k.type = BodyType::kKinematic;
  k.position = {-5, 5};
  k.angle = Real(0.5);
  k.shape = ShapeDef::Box(1, Real(0.5));
  const BodyId kinematic = world.CreateBody(k);
  BodyDef c;
  c.type = BodyType::kDynamic;
  c.position = {0, Real(0.99)};
  c.angle = Real(0.3);
  c.shape = ShapeDef::MakeCircle(Real(0.5), {Real(0.1), 0});  // off the body's origin
  const BodyId ball = world.CreateBody(c);
  BodyDef s;
  s.position = {5, 5};
  s.shape = ShapeDef::MakeCircle(1);
  s.shape.isSensor = true;
  world.CreateBody(s);
  const BodyId sleeper = AddBox(world, {5, 1});
  world.SetAwake(sleeper, false);
  world.Step(kDt);

  Recorder r;
  world.Draw(r);  // kDrawShapes by default
  const std::vector<BodyId> ids = world.GetBodyIds();
  ASSERT_EQ(r.calls.size(), ids.size());
  const std::vector<std::string> kinds{"polygon", "polygon", "circle", "circle", "polygon"};
  const std::vector<Color> colors{kStaticColor, kKinematicColor, kDynamicColor, kSensorColor, kSleepingColor};
  for (size_t i = 0; i < ids.size(); ++i) {
    EXPECT_EQ(r.calls[i].what, kinds[i]) << i;
    EXPECT_EQ(r.calls[i].color, colors[i]) << i;
  }
  // The kinematic box's vertices, in world coordinates, counter-clockwise.
  const ShapeDef& box = world.GetShape(kinematic);
  ASSERT_EQ(r.calls[1].points.size(), 4u);
  const Transform xf{world.GetPosition(kinematic), world.GetRotation(kinematic)};
  for (int v = 0; v < 4; ++v) EXPECT_TRUE(VecNear(r.calls[1].points[size_t(v)], TransformPoint(xf, box.polygon.vertices[v]), 1e-6));
  // The ball: its circle's centre in the world, and the body's angle.
  const Transform bxf{world.GetPosition(ball), world.GetRotation(ball)};
  EXPECT_TRUE(VecNear(r.calls[2].points[0], TransformPoint(bxf, {Real(0.1), 0}), 1e-6));
  EXPECT_EQ(r.calls[2].radius, Real(0.5));
  EXPECT_FLOAT_EQ(r.calls[2].angle, world.GetAngle(ball));
  (void)ground;

  Recorder all;
  world.Draw(all, kDrawAll);
  const std::vector<ContactInfo> contacts = world.GetContacts();
  size_t points = 0;
  for (const ContactInfo& ci : contacts) points += size_t(ci.pointCount);
  ASSERT_GT(points, 0u);
  ASSERT_EQ(all.calls.size(), 2 * ids.size() + points);
  for (size_t i = 0; i < ids.size(); ++i) {
    const Recorder::Call& b = all.calls[ids.size() + i];
    EXPECT_EQ(b.what, "box");
    const AABB want = world.GetAABB(ids[i]);
    EXPECT_EQ(b.points[0], want.lower);
    EXPECT_EQ(b.points[1], want.upper);
  }
  size_t at = 2 * ids.size();
  for (const ContactInfo& ci : contacts) {
    for (int k = 0; k < ci.pointCount; ++k, ++at) {
      EXPECT_EQ(all.calls[at].what, "contact");
      EXPECT_EQ(all.calls[at].points[0], ci.points[k]);
      EXPECT_EQ(all.calls[at].points[1], ci.normal);
    }
  }

  Recorder contactsOnly;
  world.Draw(contactsOnly, kDrawContacts);
  EXPECT_EQ(contactsOnly.calls.size(), points);

  ShapesOnly minimal;  // the optional calls default to nothing
  world.Draw(minimal, kDrawAll);
  EXPECT_EQ(minimal.shapes, int(ids.size()));
}

TEST(DebugDrawTest, UnknownFlagsRefusedAndNothingDrawn) {
  World world;
  AddCircle(world, {0, 2});
  const uint64_t hash = world.StateHash();
  Recorder r;
  ExpectError([&] { world.Draw(r, 8); }, "Draw: unknown flag bits (use kDrawShapes, kDrawAABBs, kDrawContacts)", "8");
  ExpectError([&] { world.Draw(r, kDrawAll | 0x80000000u); }, "Draw: unknown flag bits", "high bit");
  EXPECT_TRUE(r.calls.empty());
  EXPECT_EQ(world.StateHash(), hash);
  world.Draw(r, 0);  // nothing asked, nothing drawn
  EXPECT_TRUE(r.calls.empty());
}

}  // namespace
}  // namespace quadrant
