// Tests for the narrow phase (engine/src/collision/narrow_phase.h): contact manifolds per shape pair.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "collision/box_batch.h"
#include "collision/narrow_phase.h"
#include "quadrant/shapes.h"
#include "quadrant/world.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

using test::VecNear;

constexpr Real kSpec = Real(0.02);  // speculative distance (m), the world's default
// Geometry here is O(1) m in float32: a few roundings of ~1e-7 relative each. 1e-4 m is a
// thousand times that and still 50x smaller than the smallest feature these tests probe
// (1e-2 m penetrations), so a wrong sign, axis or offset cannot slip through.
constexpr double kTol = 1e-4;

Transform Xf(Real x, Real y, Real angle = 0) { return {{x, y}, MakeRot(angle)}; }

void ExpectUnit(Vec2 n) {
  EXPECT_TRUE(IsFinite(n));
  EXPECT_NEAR(Length(n), 1.0, 1e-5);
}

Real MinSeparation(const Manifold& m) {
  Real s = m.points[0].separation;
  for (int i = 1; i < m.pointCount; ++i) s = std::min(s, m.points[i].separation);
  return s;
}


// The same bits: point count, and normal and points where there are points.
void ExpectSameManifold(const Manifold& fast, const Manifold& general, int pair) {
  ASSERT_EQ(fast.pointCount, general.pointCount) << "pair " << pair;
  if (fast.pointCount == 0) return;
  EXPECT_EQ(std::memcmp(&fast.normal, &general.normal, sizeof(Vec2)), 0) << "pair " << pair;
  for (int k = 0; k < fast.pointCount; ++k) {
    EXPECT_EQ(std::memcmp(&fast.points[k], &general.points[k], sizeof(ManifoldPoint)), 0) << "pair " << pair << " point " << k;
  }
}

// Box pairs through CollideBoxBatch (eight lanes on a CPU with AVX2), in batches of `batch`
// (the last one shorter), each manifold against the general path's.
struct BoxCase {
  Polygon a, b;
  Transform xfA, xfB;
  Real speculative;
};
void ExpectBatchMatchesGeneral(const std::vector<BoxCase>& cases, int batch) {
  std::vector<BoxPair> pairs;
  for (const BoxCase& c : cases) pairs.push_back({&c.a, &c.xfA, &c.b, &c.xfB, c.speculative});
  for (size_t first = 0; first < pairs.size(); first += size_t(batch)) {
    const int count = int(std::min(pairs.size() - first, size_t(batch)));
    Manifold out[kBoxBatch];
    CollideBoxBatch(&pairs[first], count, out);
    for (int k = 0; k < count; ++k) {
      const BoxCase& c = cases[first + size_t(k)];
      ExpectSameManifold(out[k], CollidePolygonsGeneral(c.a, c.xfA, c.b, c.xfB, c.speculative), int(first) + k);
    }
  }
}

// ---------------------------------------------------------------- box pairs: SIMD paths

// Box pairs take a four-lane path (SSE2, or AVX's encoding on a CPU with AVX), and in the pair
// loop the eight-pair batch (box_batch.h, on a CPU with AVX2); each must give the general path's
// manifold bit for bit (the state hashes rest on it). Boxes of several sizes and
// aspect ratios, turned, shifted and overlapping by various amounts, both orders.
TEST(NarrowPhaseBoxes, LanePathsMatchTheGeneralPathBitForBit) {
  int touching = 0;
  uint32_t seed = 12345;
  auto next = [&seed] {
    seed = seed * 1664525u + 1013904223u;
    return Real(seed >> 8) / Real(1u << 24);  // [0, 1)
  };
  std::vector<BoxCase> cases;
  for (int i = 0; i < 4000; ++i) {
    const Polygon a = MakeBox(Real(0.1) + next(), Real(0.1) + next(), {next() - Real(0.5), 0}, next() * 3);
    const Polygon b = MakeBox(Real(0.1) + next(), Real(0.1) + next(), {0, next() - Real(0.5)}, next() * 3);
    const Transform xfA = Xf(next() * 4 - 2, next() * 4 - 2, next() * 7);
    const Transform xfB = Xf(next() * 4 - 2, next() * 4 - 2, i % 5 == 0 ? 0 : next() * 7);
    // Speculative distances vary per pair in a batch (continuous collision widens them).
    const Real spec = i % 3 == 0 ? kSpec : kSpec + next() * Real(0.3);
    const Manifold fast = CollidePolygons(a, xfA, b, xfB, spec);
    const Manifold general = CollidePolygonsGeneral(a, xfA, b, xfB, spec);
    ExpectSameManifold(fast, general, i);
    touching += fast.pointCount > 0;
    cases.push_back({a, b, xfA, xfB, spec});
  }
  EXPECT_GT(touching, 400);  // the comparison saw manifolds, not only misses
  ExpectBatchMatchesGeneral(cases, kBoxBatch);
  ExpectBatchMatchesGeneral(cases, 3);  // partly filled batches
}

// The same comparison where stacks and pyramids live: unturned or quarter-turned boxes placed on
// a grid, so faces touch exactly (separations of exactly 0), axes tie between the two boxes and
// between faces of one box, and clipped ends land exactly on the side planes. These are the
// cases where the box paths' first-lane arg-max/min and two-point clip must pick what the
// general path's scalar loops pick.
// A body whose motion blew up (NaN or infinite position or rotation) shares a batch with pairs
// that touch: its lane gives what the general path gives (no points: every comparison with a NaN
// fails the way the scalar code's does), and the other lanes are not disturbed.
TEST(NarrowPhaseBoxes, NonFiniteTransformsInABatchMatchTheGeneralPath) {
  const Real inf = std::numeric_limits<Real>::infinity(), nan = std::numeric_limits<Real>::quiet_NaN();
  const Polygon box = MakeBox(Real(0.5), Real(0.5));
  const Transform below = Xf(0, 0);
  const Transform bad[] = {{{nan, 1}, MakeRot(0)}, {{0, inf}, MakeRot(0)}, {{0, Real(0.99)}, {nan, 0}},
                           {{-inf, inf}, {1, 0}}, {{0, Real(0.99)}, {inf, inf}}};
  std::vector<BoxCase> cases;
  for (int i = 0; i < 16; ++i) {
    const Transform xf = i % 2 == 0 ? bad[(i / 2) % 5] : Xf(Real(0.1) * Real(i % 5), Real(0.99), Real(0.01) * Real(i));
    cases.push_back(i % 4 < 2 ? BoxCase{box, box, below, xf, kSpec} : BoxCase{box, box, xf, below, kSpec});
  }
  int touching = 0;
  for (const BoxCase& c : cases) touching += CollidePolygonsGeneral(c.a, c.xfA, c.b, c.xfB, c.speculative).pointCount > 0;
  EXPECT_EQ(touching, 8);  // every finite pair touches; no non-finite one does
  ExpectBatchMatchesGeneral(cases, kBoxBatch);
}

TEST(NarrowPhaseBoxes, LanePathsMatchTheGeneralPathOnAlignedStacks) {
  const Real offsets[] = {-1, Real(-0.75), Real(-0.5), Real(-0.25), 0, Real(0.25), Real(0.5), Real(0.75), 1};
  const Real gaps[] = {Real(-0.01), 0, Real(0.005), Real(0.02), Real(0.03)};
  const Real angles[] = {0, Real(1e-7), Real(-1e-7), Real(test::kPi / 2), Real(test::kPi)};
  const Polygon unit = MakeBox(Real(0.5), Real(0.5));
  const Polygon wide = MakeBox(2, Real(0.5));
  int touching = 0, cases = 0;
  std::vector<BoxCase> batchCases;
  for (const Polygon* lower : {&unit, &wide}) {
    for (Real dx : offsets) {
      for (Real gap : gaps) {
        for (Real angle : angles) {
          // b on top of a, and b beside a (the gap along x), each in both orders.
          const Transform xfA = Xf(Real(3.25), Real(-1.5));
          const Transform onTop = Xf(Real(3.25) + dx, Real(-1.5) + 1 + gap, angle);
          const Transform beside = Xf(Real(3.25) + (lower == &wide ? Real(2.5) : 1) + gap, Real(-1.5) + dx, angle);
          for (const Transform& xfB : {onTop, beside}) {
            for (int order = 0; order < 2; ++order) {
              const Polygon& a = order == 0 ? *lower : unit;
              const Polygon& b = order == 0 ? unit : *lower;
              const Transform& xa = order == 0 ? xfA : xfB;
              const Transform& xb = order == 0 ? xfB : xfA;
              const Manifold fast = CollidePolygons(a, xa, b, xb, kSpec);
              const Manifold general = CollidePolygonsGeneral(a, xa, b, xb, kSpec);
              ++cases;
              ExpectSameManifold(fast, general, cases);
              touching += fast.pointCount > 0;
              batchCases.push_back({a, b, xa, xb, kSpec});
            }
          }
        }
      }
    }
  }
  EXPECT_GT(touching, cases / 3);  // most placements touch or are within the speculative distance
  ExpectBatchMatchesGeneral(batchCases, kBoxBatch);
}

// ---------------------------------------------------------------- circle vs circle

TEST(NarrowPhaseCircles, SeparatedBeyondSpeculativeGivesNoPoints) {
  Circle a{{0, 0}, Real(0.5)};
  Circle b{{0, 0}, Real(0.5)};
  Manifold m = CollideCircles(a, Xf(0, 0), b, Xf(Real(1.1), 0), kSpec);  // gap 0.1 m
  EXPECT_EQ(m.pointCount, 0);
  m = CollideCircles(a, Xf(0, 0), b, Xf(Real(1.03), 0), kSpec);  // gap 0.03 m > 0.02 m
  EXPECT_EQ(m.pointCount, 0);
}

TEST(NarrowPhaseCircles, WithinSpeculativeGivesPositiveSeparation) {
  Circle a{{0, 0}, Real(0.5)};
  Circle b{{0, 0}, Real(0.25)};
  Manifold m = CollideCircles(a, Xf(0, 0), b, Xf(0, Real(0.76)), kSpec);  // gap 0.01 m
  ASSERT_EQ(m.pointCount, 1);
  EXPECT_NEAR(m.points[0].separation, 0.01, kTol);
  EXPECT_TRUE(VecNear(m.normal, Vec2{0, 1}, 1e-5));
}

TEST(NarrowPhaseCircles, TouchingGivesOnePointZeroSeparationNormalAToB) {
  Circle a{{0, 0}, Real(0.5)};
  Circle b{{0, 0}, Real(0.5)};
  // Centres 1 m apart along (0.6, 0.8).
  Manifold m = CollideCircles(a, Xf(1, 2), b, Xf(Real(1.6), Real(2.8)), kSpec);
  ASSERT_EQ(m.pointCount, 1);
  EXPECT_NEAR(m.points[0].separation, 0.0, kTol);
  EXPECT_TRUE(VecNear(m.normal, Vec2{Real(0.6), Real(0.8)}, 1e-5));
  ExpectUnit(m.normal);
  EXPECT_TRUE(VecNear(m.points[0].point, Vec2{Real(1.3), Real(2.4)}, kTol));
}

TEST(NarrowPhaseCircles, DeepOverlapSeparationIsDistanceMinusRadii) {
  Circle a{{0, 0}, 1};
  Circle b{{0, 0}, Real(0.5)};
  // d = 1, rA + rB = 1.5 -> separation -0.5; normal (-0.8, 0.6) from A to B.
  Manifold m = CollideCircles(a, Xf(1, 1), b, Xf(Real(0.2), Real(1.6)), kSpec);
  ASSERT_EQ(m.pointCount, 1);
  EXPECT_NEAR(m.points[0].separation, -0.5, kTol);
  EXPECT_TRUE(VecNear(m.normal, Vec2{Real(-0.8), Real(0.6)}, 1e-5));
  // Halfway between A's surface point (0.2, 1.6) and B's surface point (0.6, 1.3).
  EXPECT_TRUE(VecNear(m.points[0].point, Vec2{Real(0.4), Real(1.45)}, kTol));
}

TEST(NarrowPhaseCircles, OffsetCentreIsTransformed) {
  // B's circle sits 0.5 m along its local x; B (origin at (0, 1)) is rotated a quarter
  // turn, so the circle is at (0, 1.5) in world: d = 1.5, rA + rB = 1.6 -> separation -0.1.
  Circle a{{0, 0}, Real(0.6)};
  Circle b{{Real(0.5), 0}, 1};
  Manifold m = CollideCircles(a, Xf(0, 0), b, Xf(0, 1, Real(test::kPi / 2)), kSpec);
  ASSERT_EQ(m.pointCount, 1);
  EXPECT_NEAR(m.points[0].separation, -0.1, kTol);
  EXPECT_TRUE(VecNear(m.normal, Vec2{0, 1}, 1e-5));
}

TEST(NarrowPhaseCircles, CoincidentCentresGiveFiniteUnitNormal) {
  Circle a{{0, 0}, Real(0.5)};
  Circle b{{0, 0}, Real(0.3)};
  Manifold m = CollideCircles(a, Xf(2, 3), b, Xf(2, 3), kSpec);
  ASSERT_EQ(m.pointCount, 1);
  ExpectUnit(m.normal);
  EXPECT_NEAR(m.points[0].separation, -0.8, kTol);
  EXPECT_TRUE(IsFinite(m.points[0].point));
}

// ---------------------------------------------------------------- polygon vs circle

TEST(NarrowPhasePolygonCircle, FaceRegion) {
  Polygon box = MakeBox(1, 1);
  Circle c{{0, 0}, Real(0.5)};
  // Centre 1.4 above the box centre: top face at 1, circle bottom at 0.9 -> sep -0.1.
  Manifold m = CollidePolygonAndCircle(box, Xf(0, 0), c, Xf(Real(0.3), Real(1.4)), kSpec);
  ASSERT_EQ(m.pointCount, 1);
  EXPECT_TRUE(VecNear(m.normal, Vec2{0, 1}, 1e-5));
  EXPECT_NEAR(m.points[0].separation, -0.1, kTol);
  EXPECT_TRUE(VecNear(m.points[0].point, Vec2{Real(0.3), Real(0.95)}, kTol));
}

TEST(NarrowPhasePolygonCircle, FaceRegionWithRotatedTranslatedBox) {
  Polygon box = MakeBox(1, Real(0.5));
  Circle c{{0, 0}, Real(0.5)};
  Transform xfA = Xf(5, -2, Real(test::kPi / 2));  // local +y face now faces world -x
  Vec2 centre = TransformPoint(xfA, Vec2{Real(0.2), Real(0.95)});  // 0.45 above the face
  Manifold m = CollidePolygonAndCircle(box, xfA, c, {centre, MakeRot(0)}, kSpec);
  ASSERT_EQ(m.pointCount, 1);
  EXPECT_TRUE(VecNear(m.normal, Vec2{-1, 0}, 1e-5));
  EXPECT_NEAR(m.points[0].separation, -0.05, kTol);
}

TEST(NarrowPhasePolygonCircle, VertexRegion) {
  Polygon box = MakeBox(1, 1);
  Circle c{{0, 0}, Real(0.6)};
  // Centre (1.3, 1.4) is beyond corner (1, 1) at distance 0.5 along (0.6, 0.8).
  Manifold m = CollidePolygonAndCircle(box, Xf(0, 0), c, Xf(Real(1.3), Real(1.4)), kSpec);
  ASSERT_EQ(m.pointCount, 1);
  EXPECT_TRUE(VecNear(m.normal, Vec2{Real(0.6), Real(0.8)}, 1e-4));
  EXPECT_NEAR(m.points[0].separation, -0.1, kTol);
}

TEST(NarrowPhasePolygonCircle, VertexRegionOutOfRangeGivesNoPoints) {
  // Same centre, radius 0.45: 0.05 m from the corner (beyond the speculative 0.02), although
  // the distance to the top face's line alone (0.4 - 0.45 = -0.05) would suggest overlap.
  Polygon box = MakeBox(1, 1);
  Circle c{{0, 0}, Real(0.45)};
  Manifold m = CollidePolygonAndCircle(box, Xf(0, 0), c, Xf(Real(1.3), Real(1.4)), kSpec);
  EXPECT_EQ(m.pointCount, 0);
}

TEST(NarrowPhasePolygonCircle, CentreInsideUsesDeepestFace) {
  Polygon box = MakeBox(1, 1);
  Circle c{{0, 0}, Real(0.5)};
  // Centre (0.2, 0.7): 0.3 below the top face (the nearest), 0.8 from the right face.
  Manifold m = CollidePolygonAndCircle(box, Xf(0, 0), c, Xf(Real(0.2), Real(0.7)), kSpec);
  ASSERT_EQ(m.pointCount, 1);
  EXPECT_TRUE(VecNear(m.normal, Vec2{0, 1}, 1e-5));
  EXPECT_NEAR(m.points[0].separation, -0.8, kTol);
  // Centre (0.8, 0.1): the right face is nearest (0.2).
  m = CollidePolygonAndCircle(box, Xf(0, 0), c, Xf(Real(0.8), Real(0.1)), kSpec);
  ASSERT_EQ(m.pointCount, 1);
  EXPECT_TRUE(VecNear(m.normal, Vec2{1, 0}, 1e-5));
  EXPECT_NEAR(m.points[0].separation, -0.7, kTol);
}

// ---------------------------------------------------------------- polygon vs polygon

TEST(NarrowPhasePolygons, BoxRestingOnBoxGivesTwoPoints) {
  Polygon ground = MakeBox(2, Real(0.5));
  Polygon box = MakeBox(Real(0.5), Real(0.5));
  // Box bottom at 0.49: 0.01 m into the ground's top face at 0.5.
  Manifold m = CollidePolygons(ground, Xf(0, 0), box, Xf(Real(0.3), Real(0.99)), kSpec);
  ASSERT_EQ(m.pointCount, 2);
  EXPECT_TRUE(VecNear(m.normal, Vec2{0, 1}, 1e-5));
  Real xs[2];
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(m.points[i].separation, -0.01, kTol);
    EXPECT_NEAR(m.points[i].point.y, 0.495, kTol);  // halfway between the two surfaces
    xs[i] = m.points[i].point.x;
  }
  EXPECT_NEAR(std::min(xs[0], xs[1]), -0.2, kTol);
  EXPECT_NEAR(std::max(xs[0], xs[1]), 0.8, kTol);
  EXPECT_NE(m.points[0].id, m.points[1].id);
}

TEST(NarrowPhasePolygons, SwappedOrderFlipsNormal) {
  Polygon ground = MakeBox(2, Real(0.5));
  Polygon box = MakeBox(Real(0.5), Real(0.5));
  Manifold m = CollidePolygons(box, Xf(Real(0.3), Real(0.99)), ground, Xf(0, 0), kSpec);
  ASSERT_EQ(m.pointCount, 2);
  EXPECT_TRUE(VecNear(m.normal, Vec2{0, -1}, 1e-5));
  for (int i = 0; i < 2; ++i) EXPECT_NEAR(m.points[i].separation, -0.01, kTol);
}

TEST(NarrowPhasePolygons, SeparatedAndSpeculative) {
  Polygon ground = MakeBox(2, Real(0.5));
  Polygon box = MakeBox(Real(0.5), Real(0.5));
  Manifold far = CollidePolygons(ground, Xf(0, 0), box, Xf(0, Real(1.1)), kSpec);  // gap 0.1
  EXPECT_EQ(far.pointCount, 0);
  Manifold near = CollidePolygons(ground, Xf(0, 0), box, Xf(0, Real(1.01)), kSpec);  // gap 0.01
  ASSERT_EQ(near.pointCount, 2);
  for (int i = 0; i < 2; ++i) EXPECT_NEAR(near.points[i].separation, 0.01, kTol);
  EXPECT_TRUE(VecNear(near.normal, Vec2{0, 1}, 1e-5));
}

TEST(NarrowPhasePolygons, FeatureIdsPersistUnderSmallMotion) {
  Polygon ground = MakeBox(2, Real(0.5));
  Polygon box = MakeBox(Real(0.5), Real(0.5));
  Manifold m0 = CollidePolygons(ground, Xf(0, 0), box, Xf(Real(0.3), Real(0.99)), kSpec);
  Manifold m1 = CollidePolygons(ground, Xf(0, 0), box, Xf(Real(0.35), Real(0.993), Real(0.002)), kSpec);
  ASSERT_EQ(m0.pointCount, 2);
  ASSERT_EQ(m1.pointCount, 2);
  EXPECT_NE(m0.points[0].id, m0.points[1].id);
  // Match points by which box corner they come from (left or right) and compare ids.
  auto leftIndex = [](const Manifold& m) { return m.points[0].point.x < m.points[1].point.x ? 0 : 1; };
  int l0 = leftIndex(m0), l1 = leftIndex(m1);
  EXPECT_EQ(m0.points[l0].id, m1.points[l1].id);
  EXPECT_EQ(m0.points[1 - l0].id, m1.points[1 - l1].id);
}

TEST(NarrowPhasePolygons, RotatedBoxCornerIntoFace) {
  Polygon ground = MakeBox(2, Real(0.5));
  Polygon box = MakeBox(Real(0.5), Real(0.5));
  // Box turned 45 degrees: its lowest corner is 0.5*sqrt(2) below its centre. Put that
  // corner 0.05 m into the ground's top face (y = 0.5). The side corners are then
  // 0.5*sqrt(2) - 0.05 = 0.657 m above the face, far beyond the speculative distance.
  const double h = 0.5 * std::sqrt(2.0);
  Manifold m = CollidePolygons(ground, Xf(0, 0), box, Xf(Real(0.1), Real(0.5 + h - 0.05), Real(test::kPi / 4)), kSpec);
  ASSERT_GE(m.pointCount, 1);
  EXPECT_TRUE(VecNear(m.normal, Vec2{0, 1}, 1e-5));
  EXPECT_NEAR(MinSeparation(m), -0.05, kTol);
  int deepest = (m.pointCount == 2 && m.points[1].separation < m.points[0].separation) ? 1 : 0;
  // Halfway between the corner (0.1, 0.45) and the face point (0.1, 0.5).
  EXPECT_TRUE(VecNear(m.points[deepest].point, Vec2{Real(0.1), Real(0.475)}, kTol));
  for (int i = 0; i < m.pointCount; ++i) EXPECT_LE(m.points[i].separation, kSpec + 1e-6);
  EXPECT_EQ(m.pointCount, 1);  // the other incident vertex is 0.657 m away: not kept
}

TEST(NarrowPhasePolygons, SlightlyTiltedBoxKeepsBothPointsWithHandComputedSeparations) {
  Polygon ground = MakeBox(2, Real(0.5));
  Polygon box = MakeBox(Real(0.5), Real(0.5));
  const double t = 0.02;  // rad
  // Corner heights below the centre: 0.5(cos t + sin t) (deepest) and 0.5(cos t - sin t).
  const double deep = 0.5 * (std::cos(t) + std::sin(t));
  const double yc = 0.5 + deep - 0.01;  // deepest corner 0.01 m into the face
  Manifold m = CollidePolygons(ground, Xf(0, 0), box, Xf(0, Real(yc), Real(t)), kSpec);
  ASSERT_EQ(m.pointCount, 2);
  EXPECT_TRUE(VecNear(m.normal, Vec2{0, 1}, 1e-5));
  Real lo = std::min(m.points[0].separation, m.points[1].separation);
  Real hi = std::max(m.points[0].separation, m.points[1].separation);
  EXPECT_NEAR(lo, -0.01, kTol);
  EXPECT_NEAR(hi, -0.01 + std::sin(t), kTol);  // = +0.00999 m: speculative, kept
}

// ---------------------------------------------------------------- dispatch

TEST(NarrowPhaseCollide, CirclePolygonIsFlippedSoNormalPointsFromAToB) {
  ShapeDef circle = ShapeDef::MakeCircle(Real(0.5));
  ShapeDef box = ShapeDef::Box(1, 1);
  // Circle A above box B: the normal from A to B points down.
  Manifold m = Collide(circle, Xf(Real(0.3), Real(1.4)), box, Xf(0, 0), kSpec);
  ASSERT_EQ(m.pointCount, 1);
  EXPECT_TRUE(VecNear(m.normal, Vec2{0, -1}, 1e-5));
  EXPECT_NEAR(m.points[0].separation, -0.1, kTol);
  EXPECT_TRUE(VecNear(m.points[0].point, Vec2{Real(0.3), Real(0.95)}, kTol));
  // And the unflipped order points up.
  Manifold r = Collide(box, Xf(0, 0), circle, Xf(Real(0.3), Real(1.4)), kSpec);
  ASSERT_EQ(r.pointCount, 1);
  EXPECT_TRUE(VecNear(r.normal, Vec2{0, 1}, 1e-5));
  EXPECT_NEAR(r.points[0].separation, -0.1, kTol);
}

TEST(NarrowPhaseCollide, DispatchesCirclesAndPolygons) {
  ShapeDef c1 = ShapeDef::MakeCircle(Real(0.5));
  ShapeDef c2 = ShapeDef::MakeCircle(Real(0.5));
  Manifold cc = Collide(c1, Xf(0, 0), c2, Xf(Real(0.9), 0), kSpec);
  ASSERT_EQ(cc.pointCount, 1);
  EXPECT_NEAR(cc.points[0].separation, -0.1, kTol);
  EXPECT_TRUE(VecNear(cc.normal, Vec2{1, 0}, 1e-5));
  ShapeDef b1 = ShapeDef::Box(2, Real(0.5));
  ShapeDef b2 = ShapeDef::Box(Real(0.5), Real(0.5));
  Manifold pp = Collide(b1, Xf(0, 0), b2, Xf(0, Real(0.99)), kSpec);
  EXPECT_EQ(pp.pointCount, 2);
  EXPECT_TRUE(VecNear(pp.normal, Vec2{0, 1}, 1e-5));
}

// Box2D 2.4.1's polygon clip (WorldDef::box2dPolygonClip, issue #31): a box's corner sits on the
// top face of a wide box 0.1 m from its end, its bottom edge rising at slope 0.19 past that end.
// Clipped at the face's end (x = 1) the edge's far point lies 0.0185 m above the face, within the
// pair's 0.02 m of skin: a second touching point. Box2D clips at x = 1.02 (the side plane moved
// out by the skins), where the edge is 0.0223 m above the face: one point, the corner.
TEST(NarrowPhase, Box2dClipExtendsTheSidePlanesBySkin) {
  const Polygon ground = MakeBox(1, Real(0.5));
  const Polygon box = MakeBox(Real(0.2), Real(0.2));
  const double angle = std::atan(0.19), c = std::cos(angle), s = std::sin(angle);
  // The bottom-left corner (-0.2, -0.2) at (0.9, 0.4995): 0.5 mm into the face.
  const Real x = Real(0.9 - (-0.2 * c + 0.2 * s)), y = Real(0.4995 - (-0.2 * s - 0.2 * c));
  const Transform xfBox = Xf(x, y, Real(angle));
  const Real skin = Real(0.02);
  const Manifold own = CollidePolygons(ground, Xf(0, 0), box, xfBox, skin);
  const Manifold b2 = CollidePolygonsBox2d(ground, Xf(0, 0), box, xfBox, skin);
  ASSERT_EQ(own.pointCount, 2);
  EXPECT_NEAR(std::max(own.points[0].separation, own.points[1].separation), 0.0185, 2e-4);
  ASSERT_EQ(b2.pointCount, 1);
  EXPECT_NEAR(b2.points[0].separation, -0.0005, 1e-4);
  EXPECT_NEAR(b2.points[0].point.x, 0.9, 1e-4);
  EXPECT_TRUE(VecNear(b2.normal, own.normal, 1e-6));
  // Where both keep the point (a gentler slope), both clip the same edge to the same points but
  // for the side plane's offset: the far point moves 0.02 m along the edge.
  const double gentle = std::atan(0.05);
  const Transform xf2 = Xf(Real(0.9 - (-0.2 * std::cos(gentle) + 0.2 * std::sin(gentle))),
                           Real(0.4995 - (-0.2 * std::sin(gentle) - 0.2 * std::cos(gentle))), Real(gentle));
  const Manifold own2 = CollidePolygons(ground, Xf(0, 0), box, xf2, skin);
  const Manifold b22 = CollidePolygonsBox2d(ground, Xf(0, 0), box, xf2, skin);
  ASSERT_EQ(own2.pointCount, 2);
  ASSERT_EQ(b22.pointCount, 2);
  const Real farOwn = std::max(own2.points[0].point.x, own2.points[1].point.x);
  const Real farB2 = std::max(b22.points[0].point.x, b22.points[1].point.x);
  EXPECT_NEAR(farB2 - farOwn, 0.02, 2e-4);
}

// WorldDef::speculativeContacts off (issue #31): a contact holds touching points only, as Box2D
// 2.4.1's do. Two circles 0.01 m apart closing at 1 m/s: by default a speculative contact acts in
// the first step (the gap closes, no more); without speculative points nothing acts until they
// overlap, and then the contact is there.
TEST(NarrowPhase, WithoutSpeculativeContactsOnlyTouchingPointsAreKept) {
  auto run = [](bool speculative, int steps) {
    WorldDef def;
    def.gravity = {0, 0};
    def.solver = SolverType::kPgs;
    def.effects.continuous = false;
    def.speculativeContacts = speculative;
    World world(def);
    BodyDef a;
    a.type = BodyType::kDynamic;
    a.shape.type = ShapeType::kCircle;
    a.shape.circle.radius = Real(0.5);
    a.position = {0, 0};
    a.linearVelocity = {1, 0};
    BodyDef b = a;
    b.position = {Real(1.01), 0};
    b.linearVelocity = {0, 0};
    world.CreateBody(a);
    world.CreateBody(b);
    for (int k = 0; k < steps; ++k) world.Step(Real(1.0 / 60));
    return world.GetContacts();
  };
  const std::vector<ContactInfo> own = run(true, 1), touching = run(false, 1);
  ASSERT_EQ(own.size(), 1u);
  EXPECT_GT(own[0].separations[0], 0);  // speculative: still apart when found
  EXPECT_TRUE(touching.empty());
  // One step later (moved 1/60 m: 0.0067 m into each other) the contact exists, touching.
  const std::vector<ContactInfo> later = run(false, 2);
  ASSERT_EQ(later.size(), 1u);
  EXPECT_LE(later[0].separations[0], 0);
}

// Box2D 2.4.1's contacts (speculativeContacts off, box2dPolygonClip, its skin) on a pile of boxes
// and triangles dropped under gravity: the same state on one and on two threads (the filter runs
// on each block of pairs, in order), and a different one from the engine's own contacts.
TEST(NarrowPhase, Box2dContactsGiveTheSameStateOnAnyThreadCount) {
  auto run = [](int threads, bool box2d) {
    WorldDef def;
    def.solver = SolverType::kPgs;
    def.threadCount = threads;
    def.minParallelItems = 8;  // the narrow phase in blocks of one pair and up: several blocks
    def.speculativeContacts = !box2d;
    def.box2dPolygonClip = box2d;
    def.polygonSkin = box2d ? Real(0.01) : Real(0);
    World world(def);
    BodyDef ground;
    ground.shape.type = ShapeType::kPolygon;
    ground.shape.polygon = MakeBox(20, Real(0.5));
    world.CreateBody(ground);
    const Vec2 tri[] = {{Real(-0.3), Real(-0.2)}, {Real(0.3), Real(-0.2)}, {0, Real(0.3)}};
    for (int i = 0; i < 60; ++i) {
      BodyDef b;
      b.type = BodyType::kDynamic;
      b.shape.type = ShapeType::kPolygon;
      b.shape.polygon = i % 2 == 0 ? MakeBox(Real(0.25), Real(0.2)) : MakePolygon(tri);
      b.position = {Real(-3 + (i % 10) * 0.62), Real(1 + (i / 10) * 0.7)};
      b.angle = Real(0.1 * (i % 7));
      world.CreateBody(b);
    }
    for (int k = 0; k < 120; ++k) world.Step(Real(1.0 / 60));
    return world.StateHash();
  };
  EXPECT_EQ(run(1, true), run(2, true));
  EXPECT_NE(run(1, true), run(1, false));
}

}  // namespace
}  // namespace quadrant
