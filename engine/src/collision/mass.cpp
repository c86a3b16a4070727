// Exact mass properties. The thesis approximated polygon inertia by the bounding box; here
// area, centroid and second moment come from the polygon itself (sum over a triangle fan).
#include <numbers>

#include "quadrant/shapes.h"

namespace quadrant {

MassData ComputeMass(const Circle& circle, Real density) {
  const Real r2 = circle.radius * circle.radius;
  MassData md;
  md.mass = density * std::numbers::pi_v<Real> * r2;
  md.center = circle.center;
  md.rotationalInertia = md.mass * Real(0.5) * r2;  // about the centre of mass
  return md;
}

MassData ComputeMass(const Capsule& capsule, Real density) {
  // A rectangle of length L and width 2r plus a disc of radius r cut in two, each half's
  // centroid 4r/(3 pi) beyond its end of the segment. Each half's inertia about its own
  // centroid is (m_disc/2)(r^2/2 - c^2); moved to the capsule's centre by the parallel axis.
  const Real r = capsule.radius, r2 = r * r;
  const Vec2 axis = capsule.center2 - capsule.center1;
  const Real length = Length(axis);
  const Real rectMass = density * length * 2 * r;
  const Real discMass = density * std::numbers::pi_v<Real> * r2;
  const Real c = Real(4) * r / (Real(3) * std::numbers::pi_v<Real>);
  const Real d = Real(0.5) * length + c;
  MassData md;
  md.mass = rectMass + discMass;
  md.center = Real(0.5) * (capsule.center1 + capsule.center2);
  md.rotationalInertia = rectMass * (length * length + 4 * r2) / Real(12) + discMass * (Real(0.5) * r2 - c * c) + discMass * d * d;
  return md;
}

AABB ComputeAABB(const Capsule& capsule, Transform xf) {
  const Vec2 p1 = TransformPoint(xf, capsule.center1), p2 = TransformPoint(xf, capsule.center2);
  const Vec2 r{capsule.radius, capsule.radius};
  return {Min(p1, p2) - r, Max(p1, p2) + r};
}

MassData ComputeMass(const Segment& segment) {
  MassData md;
  md.center = Real(0.5) * (segment.point1 + segment.point2);
  return md;
}

AABB ComputeAABB(const Segment& segment, Transform xf) {
  const Vec2 p1 = TransformPoint(xf, segment.point1), p2 = TransformPoint(xf, segment.point2);
  return {Min(p1, p2), Max(p1, p2)};
}

Real ComputeArea(const Polygon& polygon) {
  Real area = 0;
  const Vec2 o = polygon.vertices[0];
  for (int i = 1; i + 1 < polygon.count; ++i) {
    area += Real(0.5) * Cross(polygon.vertices[i] - o, polygon.vertices[i + 1] - o);
  }
  return area;
}

MassData ComputeMass(const Polygon& polygon, Real density) {
  // Fan of triangles (o, v_i, v_i+1) with o the first vertex. For a triangle with edge vectors
  // e1, e2 from o, the second moment about o is (area/6) (e1.e1 + e1.e2 + e2.e2); sum, then
  // move to the centroid with the parallel axis theorem.
  const Vec2 o = polygon.vertices[0];
  Real area = 0;
  Vec2 center{0, 0};
  Real inertiaAboutO = 0;
  for (int i = 1; i + 1 < polygon.count; ++i) {
    Vec2 e1 = polygon.vertices[i] - o;
    Vec2 e2 = polygon.vertices[i + 1] - o;
    Real a = Real(0.5) * Cross(e1, e2);
    area += a;
    center += (a / Real(3)) * (e1 + e2);
    inertiaAboutO += (a / Real(6)) * (Dot(e1, e1) + Dot(e1, e2) + Dot(e2, e2));
  }
  MassData md;
  md.mass = density * area;
  Vec2 c = (Real(1) / area) * center;  // relative to o
  md.center = o + c;
  md.rotationalInertia = density * inertiaAboutO - md.mass * Dot(c, c);
  return md;
}

AABB ComputeAABB(const Circle& circle, Transform xf) {
  Vec2 p = TransformPoint(xf, circle.center);
  Vec2 r{circle.radius, circle.radius};
  return {p - r, p + r};
}

AABB ComputeAABB(const Polygon& polygon, Transform xf) {
  Vec2 lower = TransformPoint(xf, polygon.vertices[0]);
  Vec2 upper = lower;
  for (int i = 1; i < polygon.count; ++i) {
    Vec2 v = TransformPoint(xf, polygon.vertices[i]);
    lower = Min(lower, v);
    upper = Max(upper, v);
  }
  return {lower, upper};
}

}  // namespace quadrant
