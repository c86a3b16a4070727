// World::QueryPoint, CastCircle and CastPolygon: exact answers on hand-computed cases, agreement
// with brute force over random scenes (the broad phase loses nothing; a cast's first contact is
// where the moving shape starts to overlap), masks, ties, and bad input refused with nothing
// changed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <vector>

#include "collision/queries.h"
#include "quadrant/world.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

using namespace test;

BodyId AddStatic(World& world, Vec2 p, ShapeDef shape, Real angle = 0, uint32_t category = 1) {
  BodyDef def;
  def.position = p;
  def.angle = angle;
  def.shape = shape;
  def.filter.categoryBits = category;
  return world.CreateBody(def);
}

Transform XfOf(const World& world, BodyId id) { return {world.GetPosition(id), world.GetRotation(id)}; }

std::vector<Vec2> BoxAt(Vec2 c, Real hx, Real hy) {
  return {{c.x - hx, c.y - hy}, {c.x + hx, c.y - hy}, {c.x + hx, c.y + hy}, {c.x - hx, c.y + hy}};
}

TEST(QueryPointTest, ContainsTouchingCountsMaskAndOrder) {
  World world;
  const BodyId circle = AddStatic(world, {0, 0}, ShapeDef::MakeCircle(1), 0, 1);
  const BodyId box = AddStatic(world, {Real(1.5), 0}, ShapeDef::Box(1, 1), 0, 2);  // x in [0.5, 2.5]
  const BodyId diamond = AddStatic(world, {5, 0}, ShapeDef::Box(1, 1), Real(kPi / 4), 4);
  std::vector<BodyId> out;
  world.QueryPoint({Real(0.75), 0}, out);  // inside both the circle and the box
  EXPECT_EQ(out, (std::vector<BodyId>{circle, box}));
  world.QueryPoint({Real(0.75), 0}, out, 2);
  EXPECT_EQ(out, (std::vector<BodyId>{box}));
  world.QueryPoint({1, 0}, out, 1);  // on the circle: touching counts
  EXPECT_EQ(out, (std::vector<BodyId>{circle}));
  world.QueryPoint({Real(2.5), 1}, out);  // the box's corner
  EXPECT_EQ(out, (std::vector<BodyId>{box}));
  world.QueryPoint({5, Real(1.4)}, out);  // inside the diamond, whose top corner is at y = 1.414
  EXPECT_EQ(out, (std::vector<BodyId>{diamond}));
  world.QueryPoint({Real(5.9), Real(0.9)}, out);  // inside its box, outside the diamond
  EXPECT_TRUE(out.empty());
  world.QueryPoint({-5, -5}, out);
  EXPECT_TRUE(out.empty());
}

TEST(QueryPointTest, AgreesWithBruteForceOnARandomScene) {
  for (BroadPhaseType bp : {BroadPhaseType::kUniformGrid, BroadPhaseType::kQuadTree}) {
    WorldDef def;
    def.broadPhase = bp;
    World world(def);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> pos(-20, 20), size(Real(0.1), 2), turn(0, 6);
    for (int i = 0; i < 300; ++i) {
      const ShapeDef s = i % 2 ? ShapeDef::MakeCircle(size(rng)) : ShapeDef::Box(size(rng), size(rng));
      AddStatic(world, {pos(rng), pos(rng)}, s, turn(rng), 1u << (i % 3));
    }
    const std::vector<BodyId> ids = world.GetBodyIds();
    std::vector<BodyId> out, want;
    int found = 0;
    for (int q = 0; q < 2000; ++q) {
      const Vec2 p{pos(rng), pos(rng)};
      const uint32_t mask = q % 4 == 0 ? 5u : kAllCategories;
      world.QueryPoint(p, out, mask);
      want.clear();
      for (BodyId id : ids) {
        if ((world.GetFilter(id).categoryBits & mask) != 0 && ShapeContainsPoint(world.GetShape(id), XfOf(world, id), p)) {
          want.push_back(id);
        }
      }
      ASSERT_EQ(out, want) << q;
      found += int(out.size());
    }
    EXPECT_GT(found, 200);
  }
}

TEST(CastCircleTest, HandComputedHits) {
  World world;
  const BodyId circle = AddStatic(world, {5, 0}, ShapeDef::MakeCircle(1));
  std::optional<RayHit> hit = world.CastCircle({0, 0}, Real(0.5), {10, 0});
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->body, circle);
  EXPECT_NEAR(hit->fraction, 0.35, 1e-6);  // centres 1.5 apart at x = 3.5
  EXPECT_TRUE(VecNear(hit->point, {4, 0}, 1e-5));
  EXPECT_TRUE(VecNear(hit->normal, {-1, 0}, 1e-6));
  world.DestroyBody(circle);

  const BodyId box = AddStatic(world, {5, 0}, ShapeDef::Box(1, 1));  // x, y in [4, 6] x [-1, 1]
  hit = world.CastCircle({0, 0}, Real(0.5), {10, 0});  // its face
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->body, box);
  EXPECT_NEAR(hit->fraction, 0.35, 1e-6);
  EXPECT_TRUE(VecNear(hit->point, {4, 0}, 1e-5));
  EXPECT_TRUE(VecNear(hit->normal, {-1, 0}, 1e-6));
  hit = world.CastCircle({0, Real(1.3)}, Real(0.5), {10, 0});  // its corner (4, 1): 0.3 above it
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->fraction, 0.36, 1e-6);  // the centre at x = 4 - sqrt(0.5^2 - 0.3^2)
  EXPECT_TRUE(VecNear(hit->point, {4, 1}, 1e-5));
  EXPECT_TRUE(VecNear(hit->normal, {Real(-0.8), Real(0.6)}, 1e-5));
  EXPECT_FALSE(world.CastCircle({0, Real(1.6)}, Real(0.5), {10, 0}));  // passes above the corner
  EXPECT_FALSE(world.CastCircle({0, 0}, Real(0.5), {3, 0}));           // stops short
  // Overlapping at the start: not reported (as a ray starting inside a shape); touching at the
  // start and moving in: a hit at 0; touching and moving away: none.
  EXPECT_FALSE(world.CastCircle({4, 0}, Real(0.5), {-10, 0}));
  hit = world.CastCircle({Real(3.5), 0}, Real(0.5), {1, 0});
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->fraction, 0);
  EXPECT_FALSE(world.CastCircle({Real(3.5), 0}, Real(0.5), {-1, 0}));
}

TEST(CastCircleTest, ClosestMaskAndTies) {
  World world;
  const BodyId far = AddStatic(world, {8, 0}, ShapeDef::Box(1, 1), 0, 1);
  const BodyId nearBox = AddStatic(world, {5, 0}, ShapeDef::Box(1, 1), 0, 2);
  std::optional<RayHit> hit = world.CastCircle({0, 0}, Real(0.5), {20, 0});
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->body, nearBox);
  hit = world.CastCircle({0, 0}, Real(0.5), {20, 0}, 1);
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->body, far);
  // Two boxes with the same face: the one earlier in GetBodyIds order.
  World twins;
  const BodyId first = AddStatic(twins, {5, 1}, ShapeDef::Box(1, 1));
  AddStatic(twins, {5, -1}, ShapeDef::Box(1, 1));
  hit = twins.CastCircle({0, 0}, Real(0.5), {10, 0});
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->body, first);
}

// A cast's answer checked against the shapes themselves: at the hit the moving shape touches the
// shape hit (overlaps a hair further on), and nowhere before it does it overlap any shape of the
// mask (sampled); without a hit it overlaps none along the whole path.
template <class CastAt, class ShapeAt>
void CheckCasts(const char* what, CastAt cast, ShapeAt shapeAt) {
  for (BroadPhaseType bp : {BroadPhaseType::kUniformGrid, BroadPhaseType::kQuadTree}) {
    SCOPED_TRACE(what);
    WorldDef def;
    def.broadPhase = bp;
    World world(def);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> pos(-15, 15), size(Real(0.2), Real(1.5)), turn(0, 6), unit(0, 1);
    for (int i = 0; i < 120; ++i) {
      const ShapeDef s = i % 2 ? ShapeDef::MakeCircle(size(rng)) : ShapeDef::Box(size(rng), size(rng));
      AddStatic(world, {pos(rng), pos(rng)}, s, turn(rng), 1u << (i % 3));
    }
    const std::vector<BodyId> ids = world.GetBodyIds();
    auto overlapsAny = [&](Vec2 at, uint32_t mask) {
      const auto [shape, xf] = shapeAt(at);
      for (BodyId id : ids) {
        if ((world.GetFilter(id).categoryBits & mask) != 0 && ShapesOverlap(shape, xf, world.GetShape(id), XfOf(world, id))) {
          return true;
        }
      }
      return false;
    };
    int hits = 0, casts = 0;
    for (int q = 0; q < 400; ++q) {
      const Vec2 origin{pos(rng), pos(rng)};
      const uint32_t mask = q % 3 == 0 ? 6u : kAllCategories;
      if (overlapsAny(origin, mask)) continue;  // starts overlapping: not what this checks
      const Real angle = Real(6.2831853) * unit(rng), length = 30 * unit(rng) + Real(0.1);
      const Vec2 d{length * std::cos(angle), length * std::sin(angle)};
      const std::optional<RayHit> hit = cast(world, origin, d, mask);
      ++casts;
      const double end = hit ? double(hit->fraction) : 1.0;
      for (int k = 0; k < 200; ++k) {
        const double t = end * k / 200.0 - 1e-4;
        if (t > 0) {
          ASSERT_FALSE(overlapsAny(origin + Real(t) * d, mask)) << q << " at " << t;
        }
      }
      if (!hit) continue;
      ++hits;
      ASSERT_NE((world.GetFilter(hit->body).categoryBits & mask), 0u);
      // A millimetre into the shape along its normal (or, at a corner, along the motion) the two
      // overlap; a millimetre out along the normal they do not.
      const Vec2 at = origin + hit->fraction * d;
      const ShapeDef& other = world.GetShape(hit->body);
      const auto [inShape, inXf] = shapeAt(at - Real(1e-3) * hit->normal);
      const auto [onShape, onXf] = shapeAt(at + (Real(1e-3) / length) * d);
      EXPECT_TRUE(ShapesOverlap(inShape, inXf, other, XfOf(world, hit->body)) ||
                  ShapesOverlap(onShape, onXf, other, XfOf(world, hit->body)))
          << q;
      const auto [outShape, outXf] = shapeAt(at + Real(1e-3) * hit->normal);
      EXPECT_FALSE(ShapesOverlap(outShape, outXf, other, XfOf(world, hit->body))) << q;
      // The point is on the shape hit, and the normal is a unit vector against the motion.
      const Real reach = Real(1e-3);
      std::vector<BodyId> near;
      world.QueryAABB({hit->point - Vec2{reach, reach}, hit->point + Vec2{reach, reach}}, near);
      EXPECT_NE(std::find(near.begin(), near.end(), hit->body), near.end()) << q;
      EXPECT_NEAR(Length(hit->normal), 1.0, 1e-4);
      EXPECT_LE(Dot(hit->normal, d), 1e-4 * length);
    }
    EXPECT_GT(hits, 40);
    EXPECT_GT(casts - hits, 10);
  }
}

TEST(CastCircleTest, AgreesWithTheShapesOnARandomScene) {
  const Real r = Real(0.4);
  CheckCasts(
      "circle", [&](const World& w, Vec2 o, Vec2 d, uint32_t m) { return w.CastCircle(o, r, d, m); },
      [&](Vec2 at) { return std::pair{ShapeDef::MakeCircle(r), Transform{at, MakeRot(0)}}; });
}

TEST(CastPolygonTest, AgreesWithTheShapesOnARandomScene) {
  const ShapeDef tri = ShapeDef::FromPolygon(MakePolygon(std::vector<Vec2>{{-Real(0.5), -Real(0.3)}, {Real(0.6), -Real(0.2)}, {0, Real(0.5)}}));
  CheckCasts(
      "triangle",
      [&](const World& w, Vec2 o, Vec2 d, uint32_t m) {
        std::vector<Vec2> v;
        for (int k = 0; k < tri.polygon.count; ++k) v.push_back(o + tri.polygon.vertices[k]);
        return w.CastPolygon(v, d, m);
      },
      [&](Vec2 at) { return std::pair{tri, Transform{at, MakeRot(0)}}; });
}

TEST(CastPolygonTest, HandComputedHits) {
  World world;
  const BodyId box = AddStatic(world, {5, 0}, ShapeDef::Box(1, 1));  // [4, 6] x [-1, 1]
  std::optional<RayHit> hit = world.CastPolygon(BoxAt({0, 0}, Real(0.5), Real(0.5)), {10, 0});
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->body, box);
  EXPECT_NEAR(hit->fraction, 0.35, 1e-6);  // the right face at x = 4
  EXPECT_TRUE(VecNear(hit->normal, {-1, 0}, 1e-6));
  EXPECT_TRUE(VecNear(hit->point, {4, 0}, 1e-5));  // the middle of the common stretch
  hit = world.CastPolygon(BoxAt({0, Real(1.25)}, Real(0.5), Real(0.5)), {10, 0});  // overlaps y in [0.75, 1]
  ASSERT_TRUE(hit);
  EXPECT_TRUE(VecNear(hit->point, {4, Real(0.875)}, 1e-5));
  // A diamond's corner on the face.
  const Real h = Real(0.5);
  hit = world.CastPolygon(std::vector<Vec2>{{-h, 0}, {0, -h}, {h, Real(0.2)}, {0, h}}, {10, 0});
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->fraction, 0.35, 1e-6);
  EXPECT_TRUE(VecNear(hit->point, {4, Real(0.2)}, 1e-5));
  // The box's corner on the moving box's face: falling onto it from above, offset.
  hit = world.CastPolygon(BoxAt({Real(6.3), 3}, Real(0.5), Real(0.5)), {0, -10});
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->fraction, 0.15, 1e-6);  // bottom face from y = 2.5 down to 1
  EXPECT_TRUE(VecNear(hit->normal, {0, 1}, 1e-6));
  EXPECT_TRUE(VecNear(hit->point, {Real(5.9), 1}, 1e-5));  // the common stretch x in [5.8, 6]: its middle
  world.DestroyBody(box);
  const BodyId circle = AddStatic(world, {5, 0}, ShapeDef::MakeCircle(1));
  hit = world.CastPolygon(BoxAt({0, 0}, Real(0.5), Real(0.5)), {10, 0});
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->body, circle);
  EXPECT_NEAR(hit->fraction, 0.35, 1e-6);
  EXPECT_TRUE(VecNear(hit->point, {4, 0}, 1e-5));
  EXPECT_TRUE(VecNear(hit->normal, {-1, 0}, 1e-6));
  EXPECT_FALSE(world.CastPolygon(BoxAt({5, 0}, Real(0.5), Real(0.5)), {10, 0}));  // overlapping at the start
}

TEST(ShapeQueriesTest, BadInputIsRefusedAndChangesNothing) {
  World world;
  AddGround(world);
  AddCircle(world, {0, 2});
  world.Step(kDt);
  const uint64_t hash = world.StateHash();
  std::vector<BodyId> out{BodyId{9, 9}};
  const Real nan = NAN, inf = INFINITY;
  ExpectError([&] { world.QueryPoint({nan, 0}, out); }, "QueryPoint: the point is not finite", "point NaN");
  ExpectError([&] { world.QueryPoint({0, inf}, out); }, "QueryPoint: the point is not finite", "point inf");
  EXPECT_EQ(out, (std::vector<BodyId>{BodyId{9, 9}}));  // left as it was
  ExpectError([&] { (void)world.CastCircle({0, 5}, 0, {1, 0}); }, "CastCircle: the radius must be > 0 and <= 1e6 m", "r 0");
  ExpectError([&] { (void)world.CastCircle({0, 5}, -1, {1, 0}); }, "CastCircle: the radius must be", "r -1");
  ExpectError([&] { (void)world.CastCircle({0, 5}, nan, {1, 0}); }, "CastCircle: the radius must be", "r NaN");
  ExpectError([&] { (void)world.CastCircle({0, 5}, Real(2e6), {1, 0}); }, "CastCircle: the radius must be", "r 2e6");
  ExpectError([&] { (void)world.CastCircle({0, 5}, 1, {0, 0}); }, "CastCircle: the translation is zero", "zero");
  ExpectError([&] { (void)world.CastCircle({nan, 5}, 1, {1, 0}); }, "CastCircle: origin or translation is not finite",
              "origin NaN");
  ExpectError([&] { (void)world.CastCircle({0, 5}, 1, {Real(2e6), 0}); },
              "CastCircle: origin or end is beyond the coordinate limit of 1e6 m", "far");
  const std::vector<Vec2> box = BoxAt({0, 5}, 1, 1);
  ExpectError([&] { (void)world.CastPolygon(std::vector<Vec2>{{0, 0}, {1, 0}}, {1, 0}); },
              "CastPolygon: the polygon needs 3 to 8 vertices, got 2", "two vertices");
  ExpectError([&] { (void)world.CastPolygon(std::vector<Vec2>(9, Vec2{0, 0}), {1, 0}); },
              "CastPolygon: the polygon needs 3 to 8 vertices, got 9", "nine vertices");
  ExpectError([&] { (void)world.CastPolygon(std::vector<Vec2>{{0, 0}, {1, 0}, {2, 0}}, {1, 0}); },
              "CastPolygon: polygon vertices are collinear", "collinear");
  ExpectError([&] { (void)world.CastPolygon(std::vector<Vec2>{{0, 0}, {1, 0}, {nan, 1}}, {1, 0}); },
              "CastPolygon: polygon vertex 2 is not finite", "vertex NaN");
  ExpectError([&] { (void)world.CastPolygon(box, {0, 0}); }, "CastPolygon: the translation is zero", "zero");
  ExpectError([&] { (void)world.CastPolygon(box, {inf, 0}); }, "CastPolygon: the translation is not finite", "inf");
  ExpectError([&] { (void)world.CastPolygon(box, {Real(2e6), 0}); },
              "CastPolygon: a vertex's end is beyond the coordinate limit of 1e6 m", "far");
  EXPECT_EQ(world.StateHash(), hash);
  EXPECT_EQ(world.GetBodyCount(), 2);
}

}  // namespace
}  // namespace quadrant
