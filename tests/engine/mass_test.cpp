// Tests for ComputeMass / ComputeArea (engine/src/collision/mass.cpp) against closed forms.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

#include "quadrant/shapes.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

using test::kPi;
using test::VecNear;

// The engine computes in float32 (relative epsilon 6e-8); the mass integrals sum a few
// triangles, so 1e-5 relative is ~100 ulp of headroom and still catches any formula error
// (a wrong constant is off by >= several percent).
constexpr double kRel = 1e-5;

double RelTol(double value) { return kRel * std::abs(value); }

/// Regular n-gon of circumradius r centred at c, first vertex at angle phase.
Polygon RegularPolygon(int n, double r, Vec2 c, double phase = 0.2) {
  std::vector<Vec2> pts;
  for (int k = 0; k < n; ++k) {
    double a = phase + 2 * kPi * k / n;
    pts.push_back({Real(c.x + r * std::cos(a)), Real(c.y + r * std::sin(a))});
  }
  return MakePolygon(pts);
}

/// Independent numerical check of a polygon's polar second moment of area about `about`:
/// fan-triangulate, split each triangle into k^2 congruent sub-triangles and sum
/// area * |centroid - about|^2 (the sub-triangles' own moments, O(1/k^2) relative, are
/// ignored). Done in double from the given vertices.
double NumericPolarMoment(const std::vector<std::array<double, 2>>& v, std::array<double, 2> about, int k) {
  double sum = 0;
  for (size_t t = 1; t + 1 < v.size(); ++t) {
    const auto& a = v[0];
    const auto& b = v[t];
    const auto& c = v[t + 1];
    double ux[2] = {(b[0] - a[0]) / k, (b[1] - a[1]) / k};
    double wx[2] = {(c[0] - a[0]) / k, (c[1] - a[1]) / k};
    double subArea = 0.5 * std::abs(ux[0] * wx[1] - ux[1] * wx[0]);
    for (int i = 0; i < k; ++i) {
      for (int j = 0; i + j < k; ++j) {
        // Upward sub-triangle (i,j),(i+1,j),(i,j+1): centroid at (i+1/3, j+1/3).
        double cx = a[0] + (i + 1.0 / 3) * ux[0] + (j + 1.0 / 3) * wx[0];
        double cy = a[1] + (i + 1.0 / 3) * ux[1] + (j + 1.0 / 3) * wx[1];
        sum += subArea * ((cx - about[0]) * (cx - about[0]) + (cy - about[1]) * (cy - about[1]));
        if (i + j + 1 < k) {
          // Downward sub-triangle (i+1,j),(i,j+1),(i+1,j+1): centroid at (i+2/3, j+2/3).
          double dx = a[0] + (i + 2.0 / 3) * ux[0] + (j + 2.0 / 3) * wx[0];
          double dy = a[1] + (i + 2.0 / 3) * ux[1] + (j + 2.0 / 3) * wx[1];
          sum += subArea * ((dx - about[0]) * (dx - about[0]) + (dy - about[1]) * (dy - about[1]));
        }
      }
    }
  }
  return sum;
}

TEST(MassTest, BoxMassAndInertia) {
  const double w = 3, h = 0.8, d = 2.5;
  MassData md = ComputeMass(MakeBox(Real(w / 2), Real(h / 2)), Real(d));
  double m = d * w * h;
  EXPECT_NEAR(md.mass, m, RelTol(m));
  EXPECT_NEAR(md.rotationalInertia, m * (w * w + h * h) / 12, RelTol(m * (w * w + h * h) / 12));
  EXPECT_TRUE(VecNear(md.center, Vec2{0, 0}, 1e-6));
}

TEST(MassTest, OffsetRotatedBoxInertiaIsAboutCentroid) {
  const double w = 1, h = 2, d = 1;
  MassData md = ComputeMass(MakeBox(Real(w / 2), Real(h / 2), {4, -3}, Real(0.7)), Real(d));
  double m = d * w * h;
  EXPECT_NEAR(md.mass, m, RelTol(m));
  // Vertex coordinates ~5 m: parallel-axis cancellation in float costs more digits, so
  // 1e-4 relative (still 100x tighter than any wrong term, e.g. m*|c|^2 = 50 kg m^2).
  EXPECT_NEAR(md.rotationalInertia, m * (w * w + h * h) / 12, 1e-4 * m * (w * w + h * h) / 12);
  EXPECT_TRUE(VecNear(md.center, Vec2{4, -3}, 1e-5));
}

TEST(MassTest, RightTriangle) {
  const double a = 3, b = 1.5, d = 2;
  std::vector<Vec2> pts = {{0, 0}, {Real(a), 0}, {0, Real(b)}};
  Polygon p = MakePolygon(pts);
  EXPECT_NEAR(ComputeArea(p), a * b / 2, RelTol(a * b / 2));
  MassData md = ComputeMass(p, Real(d));
  double m = d * a * b / 2;
  EXPECT_NEAR(md.mass, m, RelTol(m));
  EXPECT_TRUE(VecNear(md.center, Vec2{Real(a / 3), Real(b / 3)}, 1e-5));
  double inertia = m * (a * a + b * b) / 18;
  EXPECT_NEAR(md.rotationalInertia, inertia, RelTol(inertia) * 10);
  // Independent numeric check of the closed form itself.
  std::vector<std::array<double, 2>> v = {{0, 0}, {a, 0}, {0, b}};
  double numeric = d * NumericPolarMoment(v, {a / 3, b / 3}, 64);
  EXPECT_NEAR(numeric, inertia, 1e-3 * inertia);
}

// Regular n-gon of circumradius R: fan of n isosceles triangles with apex angle t = 2pi/n.
// Area = n R^2 sin(t)/2. A triangle (0, p1, p2) has polar moment about the origin
// m_tri (|p1|^2 + |p2|^2 + p1.p2)/6 = m_tri R^2 (2 + cos t)/6, so the n-gon has
// I = m R^2 (2 + cos(2pi/n))/6 = m R^2 (1 + 2cos^2(pi/n))/6 (cos 2x = 2cos^2 x - 1).
// Sanity: n=4, R = h sqrt2 gives 2/3 m h^2 = m((2h)^2+(2h)^2)/12, the box formula; n->inf
// gives m R^2/2, the disc.
class RegularPolygonMassTest : public ::testing::TestWithParam<int> {};

TEST_P(RegularPolygonMassTest, AreaAndInertiaMatchClosedForm) {
  const int n = GetParam();
  const double R = 1.3, d = 0.7;
  const Vec2 c{Real(2), Real(-1)};
  Polygon p = RegularPolygon(n, R, c);
  ASSERT_EQ(p.count, n);
  double area = n * R * R * std::sin(2 * kPi / n) / 2;
  // The vertices are rounded to float (~1e-7 relative) and sit 2 m off the origin.
  EXPECT_NEAR(ComputeArea(p), area, 1e-5 * area);
  MassData md = ComputeMass(p, Real(d));
  double m = d * area;
  EXPECT_NEAR(md.mass, m, 1e-5 * m);
  EXPECT_TRUE(VecNear(md.center, c, 1e-5));
  double cosPiN = std::cos(kPi / n);
  double inertia = m * R * R * (1 + 2 * cosPiN * cosPiN) / 6;
  // Offset centre: parallel-axis cancellation in float32, see OffsetRotatedBox.
  EXPECT_NEAR(md.rotationalInertia, inertia, 1e-4 * inertia);

  // Independent check of the closed form by numeric integration over the actual vertices.
  std::vector<std::array<double, 2>> v;
  for (int i = 0; i < p.count; ++i) v.push_back({double(p.vertices[i].x), double(p.vertices[i].y)});
  double numeric = d * NumericPolarMoment(v, {double(c.x), double(c.y)}, 64);
  // The ignored sub-triangle moments make the sum low by ~1e-4..2.5e-4 relative for k = 64
  // (measured for n = 3..8); a wrong formula would be off by percent.
  EXPECT_NEAR(numeric, inertia, 1e-3 * inertia);
}

INSTANTIATE_TEST_SUITE_P(NGon, RegularPolygonMassTest, ::testing::Range(3, 9));

TEST(MassTest, CircleAtOrigin) {
  const double r = 0.75, d = 3;
  Circle c{{0, 0}, Real(r)};
  MassData md = ComputeMass(c, Real(d));
  double m = d * kPi * r * r;
  EXPECT_NEAR(md.mass, m, RelTol(m));
  EXPECT_NEAR(md.rotationalInertia, m * r * r / 2, RelTol(m * r * r / 2));
  EXPECT_TRUE(VecNear(md.center, Vec2{0, 0}, 0));
}

TEST(MassTest, CircleWithOffsetCentre) {
  const double r = 0.5, d = 1;
  Circle c{{1, 2}, Real(r)};
  MassData md = ComputeMass(c, Real(d));
  double m = d * kPi * r * r;
  EXPECT_NEAR(md.mass, m, RelTol(m));
  EXPECT_TRUE(VecNear(md.center, Vec2{1, 2}, 1e-6));
  // About the centre of mass, not the body origin (which would add m*|c|^2 = 5m).
  EXPECT_NEAR(md.rotationalInertia, m * r * r / 2, RelTol(m * r * r / 2));
}

TEST(MassTest, MassScalesLinearlyWithDensity) {
  Polygon p = MakeBox(1, 2);
  MassData a = ComputeMass(p, 1);
  MassData b = ComputeMass(p, 4);
  EXPECT_NEAR(b.mass, 4 * a.mass, RelTol(4 * a.mass));
  EXPECT_NEAR(b.rotationalInertia, 4 * a.rotationalInertia, RelTol(4 * a.rotationalInertia));
}

TEST(MassTest, AreaPositiveForCcw) {
  EXPECT_NEAR(ComputeArea(MakeBox(1, Real(0.5))), 2.0, 1e-6);
  std::vector<Vec2> cw = {{0, 0}, {0, 2}, {2, 0}};  // given clockwise, stored CCW
  Polygon tri = MakePolygon(cw);
  EXPECT_NEAR(ComputeArea(tri), 2.0, 1e-6);
  // A hand-built clockwise polygon has negative signed area.
  Polygon manual = tri;
  std::swap(manual.vertices[1], manual.vertices[2]);
  EXPECT_NEAR(ComputeArea(manual), -2.0, 1e-6);
}

}  // namespace
}  // namespace quadrant
