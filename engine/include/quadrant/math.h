// Quadrant: small 2D math types used by every stage.
//
// Everything is a plain aggregate so it can live in flat arrays and be copied by value.
// Units are SI throughout: metres, radians, seconds, kilograms.
#pragma once

#include <cmath>
#include <cstdint>

namespace quadrant {

/// Scalar type of the engine. Float by default (as Box2D); build with
/// -DQUADRANT_DOUBLE=ON to study what float32 costs in accuracy.
#ifdef QUADRANT_DOUBLE
using Real = double;
#else
using Real = float;
#endif

/// A 2D vector (also used for points).
struct Vec2 {
  Real x = 0;
  Real y = 0;
};

constexpr Vec2 operator+(Vec2 a, Vec2 b) { return {a.x + b.x, a.y + b.y}; }
constexpr Vec2 operator-(Vec2 a, Vec2 b) { return {a.x - b.x, a.y - b.y}; }
constexpr Vec2 operator-(Vec2 a) { return {-a.x, -a.y}; }
constexpr Vec2 operator*(Real s, Vec2 a) { return {s * a.x, s * a.y}; }
constexpr Vec2 operator*(Vec2 a, Real s) { return {s * a.x, s * a.y}; }
constexpr Vec2& operator+=(Vec2& a, Vec2 b) { a.x += b.x; a.y += b.y; return a; }
constexpr Vec2& operator-=(Vec2& a, Vec2 b) { a.x -= b.x; a.y -= b.y; return a; }
constexpr bool operator==(Vec2 a, Vec2 b) { return a.x == b.x && a.y == b.y; }

constexpr Real Dot(Vec2 a, Vec2 b) { return a.x * b.x + a.y * b.y; }
/// z component of the 3D cross product of (a, 0) and (b, 0).
constexpr Real Cross(Vec2 a, Vec2 b) { return a.x * b.y - a.y * b.x; }
/// Cross of a scalar (angular velocity along z) with a vector: w x r.
constexpr Vec2 Cross(Real w, Vec2 r) { return {-w * r.y, w * r.x}; }
/// Cross of a vector with a scalar: r x w.
constexpr Vec2 Cross(Vec2 r, Real w) { return {w * r.y, -w * r.x}; }
/// Counter-clockwise perpendicular.
constexpr Vec2 LeftPerp(Vec2 a) { return {-a.y, a.x}; }
/// Clockwise perpendicular (outward normal of a counter-clockwise edge).
constexpr Vec2 RightPerp(Vec2 a) { return {a.y, -a.x}; }
constexpr Real LengthSquared(Vec2 a) { return a.x * a.x + a.y * a.y; }
inline Real Length(Vec2 a) { return std::sqrt(LengthSquared(a)); }
inline Real Distance(Vec2 a, Vec2 b) { return Length(b - a); }
inline Vec2 Normalize(Vec2 a) {
  Real len = Length(a);
  if (len < Real(1e-12)) return {0, 0};
  Real inv = Real(1) / len;
  return {a.x * inv, a.y * inv};
}
inline bool IsFinite(Real x) { return std::isfinite(x); }
inline bool IsFinite(Vec2 a) { return std::isfinite(a.x) && std::isfinite(a.y); }
constexpr Vec2 Min(Vec2 a, Vec2 b) { return {a.x < b.x ? a.x : b.x, a.y < b.y ? a.y : b.y}; }
constexpr Vec2 Max(Vec2 a, Vec2 b) { return {a.x > b.x ? a.x : b.x, a.y > b.y ? a.y : b.y}; }

/// A rotation stored as cosine and sine, so rotating a vector costs no trig call.
struct Rot {
  Real c = 1;
  Real s = 0;
};

inline Rot MakeRot(Real angle) { return {std::cos(angle), std::sin(angle)}; }
inline Real GetAngle(Rot q) { return std::atan2(q.s, q.c); }
constexpr Vec2 Rotate(Rot q, Vec2 v) { return {q.c * v.x - q.s * v.y, q.s * v.x + q.c * v.y}; }
constexpr Vec2 InvRotate(Rot q, Vec2 v) { return {q.c * v.x + q.s * v.y, -q.s * v.x + q.c * v.y}; }
/// Rotation q * r.
constexpr Rot Mul(Rot q, Rot r) { return {q.c * r.c - q.s * r.s, q.s * r.c + q.c * r.s}; }
/// Rotation q^-1 * r.
constexpr Rot InvMul(Rot q, Rot r) { return {q.c * r.c + q.s * r.s, q.c * r.s - q.s * r.c}; }

/// Advances a rotation by the angle wdt. Small angles (every step below 30 rad/s at 60 Hz) use
/// sine and cosine polynomials accurate to ~1e-8 rad with no trig call; larger angles call
/// std::sin/cos. The result is renormalised so rounding does not accumulate over steps.
inline Rot IntegrateRot(Rot q, Real wdt) {
  Real dc, ds;
  if (std::abs(wdt) < Real(0.5)) {
    const Real x2 = wdt * wdt;
    dc = Real(1) - x2 * (Real(0.5) - x2 * (Real(1) / Real(24)));
    ds = wdt * (Real(1) - x2 * (Real(1) / Real(6) - x2 * (Real(1) / Real(120))));
  } else {
    dc = std::cos(wdt);
    ds = std::sin(wdt);
  }
  const Real c = q.c * dc - q.s * ds;
  const Real s = q.s * dc + q.c * ds;
  const Real inv = Real(1) / std::sqrt(c * c + s * s);
  return {c * inv, s * inv};
}

/// A rigid transform: rotate then translate.
struct Transform {
  Vec2 p;
  Rot q;
};

constexpr Vec2 TransformPoint(Transform xf, Vec2 v) { return Rotate(xf.q, v) + xf.p; }
constexpr Vec2 InvTransformPoint(Transform xf, Vec2 v) { return InvRotate(xf.q, v - xf.p); }
/// Transform of B relative to A: A^-1 * B.
constexpr Transform InvMulTransforms(Transform a, Transform b) {
  return {InvRotate(a.q, b.p - a.p), InvMul(a.q, b.q)};
}

/// Axis-aligned bounding box.
struct AABB {
  Vec2 lower;
  Vec2 upper;
};

constexpr bool Overlaps(const AABB& a, const AABB& b) {
  return !(b.lower.x > a.upper.x || b.lower.y > a.upper.y || a.lower.x > b.upper.x ||
           a.lower.y > b.upper.y);
}
constexpr bool Contains(const AABB& outer, const AABB& inner) {
  return outer.lower.x <= inner.lower.x && outer.lower.y <= inner.lower.y &&
         inner.upper.x <= outer.upper.x && inner.upper.y <= outer.upper.y;
}
constexpr AABB Union(const AABB& a, const AABB& b) { return {Min(a.lower, b.lower), Max(a.upper, b.upper)}; }

}  // namespace quadrant
