// Tests for quadrant/math.h: rotations, cross products, transforms and AABBs.
#include <gtest/gtest.h>

#include <cmath>

#include "quadrant/math.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

using test::VecNear;

// Float32 has a 6e-8 relative epsilon; a handful of multiply-adds on O(1..10) values stays
// well below 1e-5 absolute.
constexpr double kTol = 1e-5;

TEST(MathTest, RotateInvRotateRoundTrip) {
  const Vec2 vs[] = {{1, 0}, {0, 1}, {Real(3.5), Real(-2.25)}, {Real(-7), Real(0.125)}};
  for (Real angle : {Real(0), Real(0.3), Real(-1.2), Real(2.9), Real(-3.1)}) {
    Rot q = MakeRot(angle);
    for (Vec2 v : vs) {
      EXPECT_TRUE(VecNear(InvRotate(q, Rotate(q, v)), v, kTol)) << "angle " << angle;
      EXPECT_TRUE(VecNear(Rotate(q, InvRotate(q, v)), v, kTol)) << "angle " << angle;
      // Rotation preserves length.
      EXPECT_NEAR(Length(Rotate(q, v)), Length(v), kTol);
    }
  }
  // A quarter turn maps x onto y.
  EXPECT_TRUE(VecNear(Rotate(MakeRot(Real(test::kPi / 2)), Vec2{1, 0}), Vec2{0, 1}, kTol));
}

TEST(MathTest, MulAndInvMulComposeAngles) {
  Rot a = MakeRot(Real(0.7));
  Rot b = MakeRot(Real(-0.2));
  EXPECT_NEAR(GetAngle(Mul(a, b)), 0.5, kTol);
  EXPECT_NEAR(GetAngle(InvMul(a, b)), -0.9, kTol);
  Rot r = InvMul(a, Mul(a, b));
  EXPECT_NEAR(r.c, b.c, kTol);
  EXPECT_NEAR(r.s, b.s, kTol);
}

TEST(MathTest, TransformRoundTripAndRelative) {
  Transform a{{Real(1.5), Real(-2)}, MakeRot(Real(0.4))};
  Transform b{{Real(-3), Real(0.5)}, MakeRot(Real(-1.1))};
  Vec2 v{Real(0.3), Real(2.2)};
  EXPECT_TRUE(VecNear(InvTransformPoint(a, TransformPoint(a, v)), v, kTol));
  // A^-1 * B applied to v equals A^-1(B(v)).
  Transform rel = InvMulTransforms(a, b);
  EXPECT_TRUE(VecNear(TransformPoint(rel, v), InvTransformPoint(a, TransformPoint(b, v)), kTol));
  EXPECT_NEAR(GetAngle(rel.q), -1.5, kTol);
}

TEST(MathTest, IntegrateRotKeepsUnitLengthAndAdvancesAngle) {
  Rot q = MakeRot(Real(0.25));
  const Real w = Real(3.0);
  const Real dt = Real(1.0 / 60.0);
  const Real wdt = w * dt;  // 0.05 rad
  for (int i = 0; i < 200; ++i) {
    Real before = GetAngle(q);
    q = IntegrateRot(q, wdt);
    EXPECT_NEAR(q.c * q.c + q.s * q.s, 1.0, 1e-6);  // renormalised each step
    double step = std::remainder(double(GetAngle(q)) - double(before), 2 * test::kPi);
    // q + wdt*perp(q) renormalised advances by atan(wdt) = wdt - wdt^3/3 + ...: the
    // truncation is wdt^3/3 ~ 4.2e-5; allow that plus float rounding of the atan2 (~1e-6).
    EXPECT_NEAR(step, double(wdt), double(wdt) * double(wdt) * double(wdt) / 3 + 2e-6);
    EXPECT_GT(step, 0.0);
  }
}

TEST(MathTest, IntegrateRotZeroRateIsIdentity) {
  Rot q = MakeRot(Real(1.3));
  Rot r = IntegrateRot(q, 0);
  EXPECT_NEAR(r.c, q.c, 1e-7);
  EXPECT_NEAR(r.s, q.s, 1e-7);
  // Negative rates turn clockwise.
  Rot n = IntegrateRot(MakeRot(0), Real(-0.01));
  EXPECT_LT(GetAngle(n), 0);
}

TEST(MathTest, CrossIdentities) {
  Vec2 a{Real(1.5), Real(-2)};
  Vec2 b{Real(0.25), Real(4)};
  Real w = Real(2.5);
  EXPECT_EQ(Cross(a, a), 0);
  EXPECT_FLOAT_EQ(Cross(a, b), -Cross(b, a));
  // Cross(a, b) = |a||b| sin(angle from a to b): x cross y = +1.
  EXPECT_EQ(Cross(Vec2{1, 0}, Vec2{0, 1}), 1);
  // w x r is r rotated a quarter turn CCW, scaled by w; perpendicular to r.
  Vec2 wr = Cross(w, a);
  EXPECT_TRUE(VecNear(wr, w * LeftPerp(a), kTol));
  EXPECT_NEAR(Dot(wr, a), 0, kTol);
  // r x w = -(w x r).
  EXPECT_TRUE(VecNear(Cross(a, w), -wr, kTol));
  // Cross(a, b) = Dot(LeftPerp(a), b); RightPerp = -LeftPerp.
  EXPECT_FLOAT_EQ(Cross(a, b), Dot(LeftPerp(a), b));
  EXPECT_TRUE(VecNear(RightPerp(a), -LeftPerp(a), 0));
  // Triple-product identity used by the solver: Cross(r, Cross(w, r)) = w |r|^2.
  EXPECT_NEAR(Cross(a, Cross(w, a)), w * LengthSquared(a), 1e-4);
}

TEST(MathTest, NormalizeHandlesZero) {
  Vec2 n = Normalize(Vec2{3, 4});
  EXPECT_TRUE(VecNear(n, Vec2{Real(0.6), Real(0.8)}, kTol));
  Vec2 z = Normalize(Vec2{0, 0});
  EXPECT_TRUE(IsFinite(z));
  EXPECT_EQ(z.x, 0);
  EXPECT_EQ(z.y, 0);
}

TEST(MathTest, AabbOverlapsIncludingTouchingEdges) {
  AABB a{{0, 0}, {1, 1}};
  EXPECT_TRUE(Overlaps(a, AABB{{Real(0.5), Real(0.5)}, {2, 2}}));
  // Touching along an edge (x = 1) and at a single corner counts as overlapping.
  EXPECT_TRUE(Overlaps(a, AABB{{1, 0}, {2, 1}}));
  EXPECT_TRUE(Overlaps(AABB{{1, 0}, {2, 1}}, a));
  EXPECT_TRUE(Overlaps(a, AABB{{1, 1}, {2, 2}}));
  EXPECT_TRUE(Overlaps(a, AABB{{-1, -1}, {0, 0}}));
  // Separated by the next float above 1 does not overlap.
  Real justAbove = std::nextafter(Real(1), Real(2));
  EXPECT_FALSE(Overlaps(a, AABB{{justAbove, 0}, {2, 1}}));
  EXPECT_FALSE(Overlaps(a, AABB{{0, justAbove}, {1, 2}}));
  EXPECT_FALSE(Overlaps(a, AABB{{-2, -2}, {-1, -1}}));
  // Containment overlaps.
  EXPECT_TRUE(Overlaps(a, AABB{{Real(0.2), Real(0.2)}, {Real(0.3), Real(0.3)}}));
  EXPECT_TRUE(Overlaps(AABB{{-5, -5}, {5, 5}}, a));
}

TEST(MathTest, AabbContains) {
  AABB outer{{-1, -1}, {1, 1}};
  EXPECT_TRUE(Contains(outer, outer));  // boundaries are inclusive
  EXPECT_TRUE(Contains(outer, AABB{{-1, 0}, {0, 1}}));
  EXPECT_TRUE(Contains(outer, AABB{{0, 0}, {0, 0}}));
  EXPECT_FALSE(Contains(outer, AABB{{0, 0}, {Real(1.01), Real(0.5)}}));
  EXPECT_FALSE(Contains(AABB{{0, 0}, {Real(0.5), Real(0.5)}}, outer));
  EXPECT_FALSE(Contains(outer, AABB{{-2, -2}, {-Real(1.5), -Real(1.5)}}));
}

TEST(MathTest, AabbUnion) {
  AABB a{{0, 1}, {2, 3}};
  AABB b{{-1, 2}, {Real(0.5), 5}};
  AABB u = Union(a, b);
  EXPECT_EQ(u.lower.x, -1);
  EXPECT_EQ(u.lower.y, 1);
  EXPECT_EQ(u.upper.x, 2);
  EXPECT_EQ(u.upper.y, 5);
  EXPECT_TRUE(Contains(u, a));
  EXPECT_TRUE(Contains(u, b));
  AABB self = Union(a, a);
  EXPECT_TRUE(self.lower == a.lower && self.upper == a.upper);
}

}  // namespace
}  // namespace quadrant
