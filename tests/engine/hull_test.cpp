// Tests for MakePolygon / MakeBox (engine/src/collision/hull.cpp): convex hull, ordering, validation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "quadrant/error.h"
#include "quadrant/shapes.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

using test::VecNear;

// Hull vertices are copies of input points (no arithmetic), normals are one normalisation
// in float32: 1e-5 covers the rounding of both on O(1..10) coordinates.
constexpr double kTol = 1e-5;

/// Checks the structural invariants every polygon must satisfy: 3..8 vertices, strictly
/// counter-clockwise and convex, unit outward normals perpendicular to their edges.
void ExpectValidCcwConvex(const Polygon& p) {
  ASSERT_GE(p.count, 3);
  ASSERT_LE(p.count, kMaxPolygonVertices);
  EXPECT_GT(ComputeArea(p), 0);
  for (int i = 0; i < p.count; ++i) {
    Vec2 v0 = p.vertices[i];
    Vec2 v1 = p.vertices[(i + 1) % p.count];
    Vec2 v2 = p.vertices[(i + 2) % p.count];
    Vec2 e = v1 - v0;
    EXPECT_GT(Cross(e, v2 - v1), 0) << "turn at vertex " << (i + 1) % p.count << " not CCW";
    Vec2 n = p.normals[i];
    EXPECT_NEAR(Length(n), 1.0, kTol) << "normal " << i;
    EXPECT_NEAR(Dot(n, e), 0.0, kTol * Length(e)) << "normal " << i << " not perpendicular";
    // Outward: every vertex lies behind (or on) the edge's line.
    for (int j = 0; j < p.count; ++j) {
      EXPECT_LE(Dot(n, p.vertices[j] - v0), kTol) << "normal " << i << " vertex " << j;
    }
    // And it is the clockwise perpendicular of the CCW edge.
    EXPECT_TRUE(VecNear(n, Normalize(RightPerp(e)), kTol));
  }
}

bool HasVertex(const Polygon& p, Vec2 v, double tol = kTol) {
  for (int i = 0; i < p.count; ++i) {
    if (std::abs(p.vertices[i].x - v.x) <= tol && std::abs(p.vertices[i].y - v.y) <= tol) return true;
  }
  return false;
}

TEST(HullTest, UnorderedPointsGiveCcwHull) {
  std::vector<Vec2> pts = {{1, 1}, {-1, -1}, {1, -1}, {-1, 1}};
  Polygon p = MakePolygon(pts);
  EXPECT_EQ(p.count, 4);
  ExpectValidCcwConvex(p);
  for (Vec2 v : pts) EXPECT_TRUE(HasVertex(p, v));
  EXPECT_NEAR(ComputeArea(p), 4.0, kTol);
}

TEST(HullTest, ClockwiseInputIsReordered) {
  // A pentagon listed clockwise.
  std::vector<Vec2> cw = {{0, 2}, {2, Real(0.5)}, {Real(1.2), -2}, {Real(-1.2), -2}, {-2, Real(0.5)}};
  Polygon p = MakePolygon(cw);
  EXPECT_EQ(p.count, 5);
  ExpectValidCcwConvex(p);
  for (Vec2 v : cw) EXPECT_TRUE(HasVertex(p, v));
}

TEST(HullTest, ScrambledOctagonKeepsAllEightPoints) {
  std::vector<Vec2> pts;
  const int order[8] = {3, 7, 0, 5, 2, 6, 1, 4};
  for (int k : order) {
    double a = 2 * test::kPi * k / 8 + 0.1;
    pts.push_back({Real(2 * std::cos(a)), Real(2 * std::sin(a))});
  }
  Polygon p = MakePolygon(pts);
  EXPECT_EQ(p.count, 8);
  ExpectValidCcwConvex(p);
}

TEST(HullTest, TooFewOrTooManyPointsThrow) {
  std::vector<Vec2> none;
  std::vector<Vec2> two = {{0, 0}, {1, 0}};
  EXPECT_THROW(MakePolygon(none), Error);
  EXPECT_THROW(MakePolygon(two), Error);
  std::vector<Vec2> nine;
  for (int k = 0; k < 9; ++k) {
    double a = 2 * test::kPi * k / 9;
    nine.push_back({Real(std::cos(a)), Real(std::sin(a))});
  }
  EXPECT_THROW(MakePolygon(nine), Error);
  // Exactly three (a triangle) is fine.
  std::vector<Vec2> three = {{0, 0}, {1, 0}, {0, 1}};
  EXPECT_NO_THROW(MakePolygon(three));
}

TEST(HullTest, DuplicatePointsThrow) {
  std::vector<Vec2> dup = {{0, 0}, {1, 0}, {1, 0}, {0, 1}};
  EXPECT_THROW(MakePolygon(dup), Error);
  std::vector<Vec2> dup2 = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0, 0}};
  EXPECT_THROW(MakePolygon(dup2), Error);
}

TEST(HullTest, CollinearPointsThrow) {
  std::vector<Vec2> line = {{0, 0}, {1, 0}, {2, 0}};
  EXPECT_THROW(MakePolygon(line), Error);
  std::vector<Vec2> line4 = {{0, 0}, {3, 3}, {1, 1}, {2, 2}};
  EXPECT_THROW(MakePolygon(line4), Error);
  // Nearly collinear: a sliver whose area (1e-6 m^2) is far below kMinFeatureSize.
  std::vector<Vec2> sliver = {{0, 0}, {1, 0}, {Real(0.5), Real(1e-6)}};
  EXPECT_THROW(MakePolygon(sliver), Error);
}

TEST(HullTest, NonFiniteOrHugeCoordinatesThrow) {
  const Real nan = std::numeric_limits<Real>::quiet_NaN();
  const Real inf = std::numeric_limits<Real>::infinity();
  std::vector<Vec2> withNan = {{0, 0}, {1, 0}, {nan, 1}};
  std::vector<Vec2> withInf = {{0, 0}, {inf, 0}, {0, 1}};
  std::vector<Vec2> withNegInf = {{0, 0}, {1, 0}, {0, -inf}};
  std::vector<Vec2> huge = {{0, 0}, {1, 0}, {0, kMaxCoordinate * 10}};
  EXPECT_THROW(MakePolygon(withNan), Error);
  EXPECT_THROW(MakePolygon(withInf), Error);
  EXPECT_THROW(MakePolygon(withNegInf), Error);
  EXPECT_THROW(MakePolygon(huge), Error);
}

TEST(HullTest, NonConvexInputThrowsWhenConvexRequired) {
  // A square with a point strictly inside: the hull would drop it.
  std::vector<Vec2> pts = {{-1, -1}, {1, -1}, {Real(0.2), Real(0.1)}, {1, 1}, {-1, 1}};
  EXPECT_THROW(MakePolygon(pts, true), Error);
  EXPECT_THROW(MakePolygon(pts), Error);  // requireConvex defaults to true
  // A reflex (dart) shape listed in order is not convex either.
  std::vector<Vec2> dart = {{0, 0}, {2, -1}, {Real(0.5), 0}, {2, 1}};
  EXPECT_THROW(MakePolygon(dart), Error);
  // Without the requirement the hull simply drops the interior point.
  Polygon p = MakePolygon(pts, false);
  EXPECT_EQ(p.count, 4);
  ExpectValidCcwConvex(p);
  EXPECT_FALSE(HasVertex(p, {Real(0.2), Real(0.1)}));
}

TEST(HullTest, TooShortEdgeThrows) {
  // A unit square with one corner cut by a 2.8 mm edge: an edge below kMinFeatureSize (5 mm).
  std::vector<Vec2> pts = {{0, 0}, {1, 0}, {1, Real(0.998)}, {Real(0.998), 1}, {0, 1}};
  EXPECT_THROW(MakePolygon(pts, false), Error);
}

TEST(HullTest, TriangleCentroid) {
  std::vector<Vec2> tri = {{0, 0}, {3, 0}, {0, 3}};
  Polygon p = MakePolygon(tri);
  EXPECT_TRUE(VecNear(p.centroid, Vec2{1, 1}, kTol));
}

TEST(HullTest, MakeBoxAxisAligned) {
  Polygon p = MakeBox(Real(1.5), Real(0.25));
  EXPECT_EQ(p.count, 4);
  ExpectValidCcwConvex(p);
  for (Vec2 v : {Vec2{Real(-1.5), Real(-0.25)}, Vec2{Real(1.5), Real(-0.25)}, Vec2{Real(1.5), Real(0.25)},
                 Vec2{Real(-1.5), Real(0.25)}}) {
    EXPECT_TRUE(HasVertex(p, v)) << v.x << ", " << v.y;
  }
  EXPECT_NEAR(ComputeArea(p), 4 * 1.5 * 0.25, kTol);
  EXPECT_TRUE(VecNear(p.centroid, Vec2{0, 0}, kTol));
  // Axis-aligned box: normals are exactly the four axis directions.
  int axis = 0;
  for (int i = 0; i < 4; ++i) {
    Vec2 n = p.normals[i];
    if (std::abs(std::abs(n.x) - 1) < kTol || std::abs(std::abs(n.y) - 1) < kTol) ++axis;
  }
  EXPECT_EQ(axis, 4);
}

TEST(HullTest, MakeBoxRotatedAndOffset) {
  const Real hx = 2, hy = Real(0.5), angle = Real(0.6);
  const Vec2 c{3, -1};
  Polygon p = MakeBox(hx, hy, c, angle);
  EXPECT_EQ(p.count, 4);
  ExpectValidCcwConvex(p);
  Rot q = MakeRot(angle);
  // Coordinates up to ~5 m: 2e-5 covers float rotation rounding.
  for (Vec2 corner : {Vec2{-hx, -hy}, Vec2{hx, -hy}, Vec2{hx, hy}, Vec2{-hx, hy}}) {
    Vec2 want = c + Rotate(q, corner);
    EXPECT_TRUE(HasVertex(p, want, 2e-5)) << want.x << ", " << want.y;
  }
  EXPECT_TRUE(VecNear(p.centroid, c, 2e-5));
  EXPECT_NEAR(ComputeArea(p), 4 * hx * hy, 1e-4);
  // One normal points along the rotated x axis.
  bool found = false;
  for (int i = 0; i < 4; ++i) found = found || VecNear(p.normals[i], Rotate(q, Vec2{1, 0}), kTol);
  EXPECT_TRUE(found);
}

TEST(HullTest, MakeBoxRejectsBadSizes) {
  EXPECT_THROW(MakeBox(0, 1), Error);
  EXPECT_THROW(MakeBox(1, -1), Error);
  EXPECT_THROW(MakeBox(std::numeric_limits<Real>::quiet_NaN(), 1), Error);
  EXPECT_THROW(MakeBox(1, 1, {std::numeric_limits<Real>::infinity(), 0}), Error);
}

TEST(HullTest, MakeBoxRejectsCoordinatesBeyondTheLimit) {
  // shapes.h: kMaxCoordinate is the largest coordinate accepted for vertices, and MakeBox
  // "validates the input" like MakePolygon (which refuses such vertices).
  EXPECT_THROW(MakeBox(1, 1, {kMaxCoordinate * 2, 0}), Error);
  EXPECT_THROW(MakeBox(kMaxCoordinate * 2, 1), Error);
  // Just inside the limit is fine.
  EXPECT_NO_THROW(MakeBox(1, 1, {kMaxCoordinate / 2, 0}));
}

}  // namespace
}  // namespace quadrant
