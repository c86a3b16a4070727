// World queries (QueryAABB, RayCastClosest, RayCastAll) against brute force over random scenes,
// on both broad phases; the exact shape tests against hand-worked answers; bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "collision/queries.h"
#include "quadrant/world.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

using namespace test;

Transform XfOf(const World& w, BodyId id) { return {w.GetPosition(id), w.GetRotation(id)}; }

// Random circles and convex polygons of 0.1-1.5 m moving in a 60 m square, plus a long ground,
// two walls and a few tiny bodies (the grid's cell size comes from the bodies, so sizes are
// mixed), stepped so bodies have moved since they were created.
void BuildRandomScene(World& world, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-30, 30), size(0.1f, 1.5f), angle(-3.1f, 3.1f), vel(-5, 5);
  AddGround(world, 35, 0.5f, {0, -31});
  AddGround(world, 0.5f, 35, {-31, 0});
  AddGround(world, 0.5f, 35, {31, 0});
  for (int i = 0; i < 400; ++i) {
    BodyDef def;
    def.type = i % 7 == 0 ? BodyType::kStatic : BodyType::kDynamic;
    def.position = {pos(rng), pos(rng)};
    def.angle = angle(rng);
    def.linearVelocity = def.type == BodyType::kDynamic ? Vec2{vel(rng), vel(rng)} : Vec2{};
    def.angularVelocity = def.type == BodyType::kDynamic ? vel(rng) : 0;
    const float s = i % 50 == 0 ? 0.02f : size(rng);
    if (i % 2 == 0) {
      def.shape = ShapeDef::MakeCircle(s);
    } else {
      std::vector<Vec2> pts;
      const int n = 3 + int(rng() % 6);
      const float a0 = angle(rng);
      for (int k = 0; k < n; ++k) {
        const float a = a0 + 6.2831853f * float(k) / float(n);
        pts.push_back({s * std::cos(a), s * std::sin(a)});
      }
      def.shape = ShapeDef::FromPolygon(MakePolygon(pts));
    }
    def.filter.categoryBits = 1u << (i % 3);
    world.CreateBody(def);
  }
  StepN(world, 20);
}

struct Case {
  BroadPhaseType broadPhase;
  uint32_t seed;
};

class QueryVsBruteForce : public ::testing::TestWithParam<Case> {};

TEST_P(QueryVsBruteForce, AabbQueriesAndRayCastsMatch) {
  WorldDef def = NoGravityDef();
  def.broadPhase = GetParam().broadPhase;
  World world(def);
  BuildRandomScene(world, GetParam().seed);
  const std::vector<BodyId> ids = world.GetBodyIds();
  std::mt19937 rng(GetParam().seed + 1);
  std::uniform_real_distribution<float> pos(-40, 40), ext(0, 8), len(0.05f, 90), angle(-3.2f, 3.2f);
  std::uniform_int_distribution<uint32_t> mask(0, 7);

  int nonEmpty = 0, hits = 0, multiHits = 0;
  std::vector<BodyId> got, expected;
  for (int q = 0; q < 300; ++q) {
    const Vec2 lo{pos(rng), pos(rng)};
    AABB box{lo, lo + Vec2{ext(rng), ext(rng)}};
    if (q == 0) box = {{-1e30f, -1e30f}, {1e30f, 1e30f}};  // everything, from absurd coordinates
    if (q == 1) box = {{100, 100}, {101, 101}};            // nothing
    const uint32_t m = q % 4 == 0 ? kAllCategories : mask(rng);
    world.QueryAABB(box, got, m);
    expected.clear();
    for (BodyId id : ids) {
      if ((world.GetFilter(id).categoryBits & m) != 0 && ShapeOverlapsBox(world.GetShape(id), XfOf(world, id), box)) {
        expected.push_back(id);
      }
    }
    ASSERT_EQ(got, expected) << "query " << q;
    nonEmpty += got.empty() ? 0 : 1;
    if (q == 0) {
      EXPECT_EQ(got.size(), ids.size());
    }
  }
  EXPECT_GT(nonEmpty, 100);  // the scene really is queried

  std::vector<RayHit> all, brute;
  for (int q = 0; q < 300; ++q) {
    const Vec2 origin{pos(rng), pos(rng)};
    const float a = angle(rng), l = len(rng);
    Vec2 t{l * std::cos(a), l * std::sin(a)};
    if (q % 10 == 1) t = {l, 0};   // along a row of cells
    if (q % 10 == 2) t = {0, -l};  // along a column
    const uint32_t m = q % 4 == 0 ? kAllCategories : mask(rng);
    world.RayCastAll(origin, t, all, m);
    brute.clear();
    for (BodyId id : ids) {
      RayHit hit;
      if ((world.GetFilter(id).categoryBits & m) == 0) continue;
      if (!RayCastShape(world.GetShape(id), XfOf(world, id), origin, origin + t, hit)) continue;
      hit.body = id;
      brute.push_back(hit);
    }
    std::stable_sort(brute.begin(), brute.end(), [](const RayHit& x, const RayHit& y) { return x.fraction < y.fraction; });
    ASSERT_EQ(all.size(), brute.size()) << "ray " << q;
    for (size_t k = 0; k < all.size(); ++k) {
      EXPECT_EQ(all[k].body, brute[k].body) << "ray " << q << " hit " << k;
      EXPECT_EQ(all[k].fraction, brute[k].fraction) << "ray " << q << " hit " << k;
    }
    const std::optional<RayHit> closest = world.RayCastClosest(origin, t, m);
    ASSERT_EQ(closest.has_value(), !brute.empty()) << "ray " << q;
    if (closest) {
      EXPECT_EQ(closest->body, brute[0].body) << "ray " << q;
      EXPECT_EQ(closest->fraction, brute[0].fraction) << "ray " << q;
      ++hits;
    }
    multiHits += all.size() > 1 ? 1 : 0;
  }
  EXPECT_GT(hits, 100);
  EXPECT_GT(multiHits, 50);
}

INSTANTIATE_TEST_SUITE_P(BothBroadPhases, QueryVsBruteForce,
                         ::testing::Values(Case{BroadPhaseType::kUniformGrid, 1}, Case{BroadPhaseType::kUniformGrid, 2},
                                           Case{BroadPhaseType::kQuadTree, 1}, Case{BroadPhaseType::kQuadTree, 2}),
                         [](const ::testing::TestParamInfo<Case>& info) {
                           return std::string(info.param.broadPhase == BroadPhaseType::kQuadTree ? "QuadTree" : "UniformGrid") +
                                  "Seed" + std::to_string(info.param.seed);
                         });

TEST(QueriesTest, ExactShapeTests) {
  // A unit circle at (5, 0); a ray from the origin along +x with length 10 enters at x = 4.
  const ShapeDef circle = ShapeDef::MakeCircle(1);
  const Transform at5{{5, 0}, {}};
  RayHit hit;
  ASSERT_TRUE(RayCastShape(circle, at5, {0, 0}, {10, 0}, hit));
  EXPECT_FLOAT_EQ(hit.fraction, 0.4f);
  EXPECT_FLOAT_EQ(hit.normal.x, -1);
  EXPECT_FALSE(RayCastShape(circle, at5, {0, 0}, {3.9f, 0}, hit));    // stops short
  EXPECT_FALSE(RayCastShape(circle, at5, {5, 0}, {10, 0}, hit));      // starts inside
  EXPECT_FALSE(RayCastShape(circle, at5, {0, 1.01f}, {10, 1.01f}, hit));  // passes above
  // A 2 x 2 box turned 45 degrees at the origin: its corner on +x is at sqrt(2).
  const ShapeDef diamond = ShapeDef::Box(1, 1, {}, float(kPi / 4));
  ASSERT_TRUE(RayCastShape(diamond, Transform{}, {10, 0.5f}, {0, 0.5f}, hit));
  EXPECT_NEAR(hit.point.x, std::sqrt(2.0) - 0.5, 1e-5);
  EXPECT_NEAR(hit.normal.x, std::sqrt(0.5), 1e-5);
  EXPECT_NEAR(hit.normal.y, std::sqrt(0.5), 1e-5);
  EXPECT_FALSE(RayCastShape(diamond, Transform{}, {0, 0}, {10, 0}, hit));  // starts inside
  // The box's AABB reaches (1.414, 1.414), but its edge passes x + y = 1.414: a box at (1.2, 1.2)
  // overlaps the AABB and not the shape.
  EXPECT_FALSE(ShapeOverlapsBox(diamond, Transform{}, {{1.2f, 1.2f}, {2, 2}}));
  EXPECT_TRUE(ShapeOverlapsBox(diamond, Transform{}, {{0.6f, 0.6f}, {2, 2}}));
  // The circle against a box near its AABB's corner: apart at (5.8, 0.8), touching at (5.7, 0.7).
  EXPECT_FALSE(ShapeOverlapsBox(circle, at5, {{5.8f, 0.8f}, {7, 7}}));
  EXPECT_TRUE(ShapeOverlapsBox(circle, at5, {{5.7f, 0.7f}, {7, 7}}));
}

TEST(QueriesTest, QueriesSeeBodiesWhereTheyAreNow) {
  for (BroadPhaseType bp : {BroadPhaseType::kUniformGrid, BroadPhaseType::kQuadTree}) {
    WorldDef def;
    def.broadPhase = bp;
    World world(def);
    AddGround(world);
    const BodyId ball = AddCircle(world, {0, 10});
    std::vector<BodyId> out;
    world.QueryAABB({{-1, 9}, {1, 11}}, out);
    ASSERT_EQ(out, std::vector<BodyId>{ball});
    world.SetTransform(ball, {20, 30}, 0);  // moved: the next query must not use the old index
    world.QueryAABB({{-1, 9}, {1, 11}}, out);
    EXPECT_TRUE(out.empty());
    world.QueryAABB({{19, 29}, {21, 31}}, out);
    EXPECT_EQ(out, std::vector<BodyId>{ball});
    const BodyId late = AddCircle(world, {-5, 10});  // created after the last query
    world.QueryAABB({{-6, 9}, {-4, 11}}, out);
    EXPECT_EQ(out, std::vector<BodyId>{late});
    StepN(world, 30);  // falls: the ray from above now hits it lower
    const std::optional<RayHit> hit = world.RayCastClosest({-5, 50}, {0, -60});
    ASSERT_TRUE(hit.has_value());
    EXPECT_EQ(hit->body, late);
    EXPECT_NEAR(hit->point.y, world.GetPosition(late).y + 0.5f, 1e-4);
    world.DestroyBody(late);
    EXPECT_NE(world.RayCastClosest({-5, 50}, {0, -60})->body, late);  // the ground now
  }
}

TEST(QueriesTest, BadInputIsRefusedAndChangesNothing) {
  World world;
  AddGround(world);
  AddCircle(world, {0, 2});
  StepN(world, 3);
  const uint64_t hash = world.StateHash();
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  std::vector<BodyId> out{BodyId{1, 1}};
  std::vector<RayHit> hits(1);
  ExpectError([&] { world.QueryAABB({{nan, 0}, {1, 1}}, out); }, "QueryAABB: the box is not finite", "NaN box");
  ExpectError([&] { world.QueryAABB({{0, 0}, {inf, 1}}, out); }, "QueryAABB: the box is not finite", "inf box");
  ExpectError([&] { world.QueryAABB({{1, 0}, {0, 1}}, out); }, "lower corner is above or right", "inverted box");
  ExpectError([&] { (void)world.RayCastClosest({0, 0}, {0, 0}); }, "RayCastClosest: the translation is zero",
              "zero-length ray");
  ExpectError([&] { world.RayCastAll({0, 0}, {0, 0}, hits); }, "RayCastAll: the translation is zero", "zero ray");
  ExpectError([&] { (void)world.RayCastClosest({nan, 0}, {1, 0}); }, "origin or translation is not finite", "NaN");
  ExpectError([&] { world.RayCastAll({0, 0}, {inf, 0}, hits); }, "origin or translation is not finite", "inf");
  ExpectError([&] { (void)world.RayCastClosest({0, 0}, {2e6f, 0}); }, "beyond the coordinate limit", "far end");
  EXPECT_EQ(out.size(), 1u);  // refused calls leave the output alone too
  EXPECT_EQ(hits.size(), 1u);
  EXPECT_EQ(world.StateHash(), hash);
  // A query is not a change: stepping after one gives the state stepping without one gives.
  World twin;
  AddGround(twin);
  AddCircle(twin, {0, 2});
  StepN(twin, 3);
  world.QueryAABB({{-5, -5}, {5, 5}}, out);
  EXPECT_EQ(out.size(), 2u);
  (void)world.RayCastClosest({0, 10}, {0, -20});
  StepN(world, 5);
  StepN(twin, 5);
  EXPECT_EQ(world.StateHash(), twin.StateHash());
}

}  // namespace
}  // namespace quadrant
