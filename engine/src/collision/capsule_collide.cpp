// Narrow phase for capsules: a capsule against a circle, a polygon or a capsule.
//
// A capsule is a segment core grown by its radius, so every pair here is a convex core (a
// polygon, or a capsule's segment as a two-sided two-vertex polygon) against a segment, with the
// two radii added to the gap. The separating-axis test over both cores' face normals gives the
// reference face; the other core's edge is clipped to that face's side planes, which yields the
// two points a capsule lying on a box or on another capsule needs to rest without rocking.
// Where the cores do not overlap, the exact closest points of the cores are computed too: a
// manifold of two clipped points is kept only where the nearer of them is that close (the
// edges lie parallel), otherwise the one closest-point pair is the contact, with its true gap
// and normal, so a capsule's rounded end meets a corner where it really does.
// Nothing here runs for scenes without capsules: Collide tests for them once per pair.
#include <algorithm>
#include <cfloat>
#include <cmath>

#include "collision/narrow_phase.h"

namespace quadrant {
namespace {

// Within this of the closest distance, a clipped point is as near as the closest points:
// the two edges lie parallel (m; a tenth of the default linear slop).
constexpr Real kParallelTolerance = Real(0.0005);
// Prefer A's face unless B's is clearly better (as the polygon pairs do).
constexpr Real kAxisPreference = Real(0.0005);

// Closest points of the segments p1-p2 and q1-q2 (Ericson's clamped parameters, written out).
void ClosestOnSegments(Vec2 p1, Vec2 p2, Vec2 q1, Vec2 q2, Vec2& onP, Vec2& onQ) {
  const Vec2 d1 = p2 - p1, d2 = q2 - q1, r = p1 - q1;
  const Real a = Dot(d1, d1), e = Dot(d2, d2), f = Dot(d2, r);
  Real s = 0, t = 0;
  if (a <= FLT_EPSILON && e <= FLT_EPSILON) {
    s = t = 0;
  } else if (a <= FLT_EPSILON) {
    t = std::clamp(f / e, Real(0), Real(1));
  } else {
    const Real c = Dot(d1, r);
    if (e <= FLT_EPSILON) {
      s = std::clamp(-c / a, Real(0), Real(1));
    } else {
      const Real b = Dot(d1, d2), denom = a * e - b * b;
      s = denom > 0 ? std::clamp((b * f - c * e) / denom, Real(0), Real(1)) : Real(0);
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, Real(0), Real(1));
      } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, Real(0), Real(1));
      }
    }
  }
  onP = p1 + s * d1;
  onQ = q1 + t * d2;
}

// The segment a-b cut to where Dot(t, p) lies in [lo, hi]; false if nothing is left.
bool ClipToSlab(Vec2& a, Vec2& b, Vec2 t, Real lo, Real hi, uint32_t& clippedA, uint32_t& clippedB) {
  const Real da = Dot(t, a), db = Dot(t, b);
  if ((da < lo && db < lo) || (da > hi && db > hi)) return false;
  const Vec2 a0 = a, b0 = b;
  auto at = [&](Real x) { return a0 + ((x - da) / (db - da)) * (b0 - a0); };
  if (da < lo) a = at(lo), clippedA = 1;
  if (da > hi) a = at(hi), clippedA = 2;
  if (db < lo) b = at(lo), clippedB = 1;
  if (db > hi) b = at(hi), clippedB = 2;
  return true;
}

// Core A (counter-clockwise vertices with outward normals; two vertices: a segment, both
// sides) grown by rA, against the segment q1-q2 grown by rB, all in A's frame. The manifold's
// normal points from A to B; points lie halfway between the two surfaces.
Manifold CollideCoreAndSegment(const Vec2* av, const Vec2* an, int aCount, Real rA, Vec2 q1, Vec2 q2, Real rB,
                               Real speculative) {
  Manifold m;
  const Real radii = rA + rB;
  // A's faces.
  int faceA = 0;
  Real sepA = -FLT_MAX;
  for (int i = 0; i < aCount; ++i) {
    const Real s = std::min(Dot(an[i], q1 - av[i]), Dot(an[i], q2 - av[i]));
    if (s > sepA) sepA = s, faceA = i;
  }
  // The segment's two sides.
  const Vec2 e = q2 - q1;
  const Real length = Length(e);
  const Vec2 tangent = (Real(1) / length) * e;
  Vec2 nB{tangent.y, -tangent.x};
  Real sepB = -FLT_MAX;
  for (int side = 0; side < 2; ++side) {
    const Vec2 n = side == 0 ? nB : -nB;
    Real s = FLT_MAX;
    for (int k = 0; k < aCount; ++k) s = std::min(s, Dot(n, av[k] - q1));
    if (s > sepB) sepB = s, nB = n;
  }
  if (std::max(sepA, sepB) - radii > speculative) return m;

  // The exact gap between the cores, where they are apart.
  const bool apart = std::max(sepA, sepB) > 0;
  Real gap = 0;
  Vec2 closeA, closeB;
  if (apart) {
    gap = FLT_MAX;
    for (int i = 0; i < aCount; ++i) {
      Vec2 pa, pb;
      ClosestOnSegments(av[i], av[i + 1 < aCount ? i + 1 : 0], q1, q2, pa, pb);
      const Real d = Length(pb - pa);
      if (d < gap) gap = d, closeA = pa, closeB = pb;
    }
    if (gap - radii > speculative) return m;
  }

  // Clip the incident edge to the reference face's side planes.
  Manifold clip;
  if (sepB > sepA + kAxisPreference) {
    // B's side is the reference; A's edge most against it is incident. Normal A -> B is -nB.
    int inc = 0;
    Real least = FLT_MAX;
    for (int k = 0; k < aCount; ++k) {
      const Real d = Dot(an[k], nB);
      if (d < least) least = d, inc = k;
    }
    Vec2 p1 = av[inc], p2 = av[inc + 1 < aCount ? inc + 1 : 0];
    uint32_t c1 = 0, c2 = 0;
    if (ClipToSlab(p1, p2, tangent, Dot(tangent, q1), Dot(tangent, q2), c1, c2)) {
      const Vec2 normal = -nB;
      clip.normal = normal;
      const Vec2 pts[2] = {p1, p2};
      const uint32_t clipped[2] = {c1, c2};
      for (int j = 0; j < 2; ++j) {
        const Real sep = Dot(nB, pts[j] - q1) - radii;
        ManifoldPoint& mp = clip.points[clip.pointCount++];
        mp.point = pts[j] + (rA + Real(0.5) * sep) * normal;
        mp.separation = sep;
        mp.id = MakeFeatureId(nB.x == tangent.y ? 0 : 1, clipped[j] ? 0x80u | clipped[j] : uint32_t(inc + j), true);
      }
    }
  } else {
    // A's face is the reference; the segment is incident. Normal A -> B is A's face normal.
    const Vec2 v1 = av[faceA], v2 = av[faceA + 1 < aCount ? faceA + 1 : 0];
    const Vec2 n = an[faceA];
    const Vec2 t{-n.y, n.x};  // along the face, v1 -> v2
    Vec2 p1 = q1, p2 = q2;
    uint32_t c1 = 0, c2 = 0;
    if (ClipToSlab(p1, p2, t, Dot(t, v1), Dot(t, v2), c1, c2)) {
      clip.normal = n;
      const Vec2 pts[2] = {p1, p2};
      const uint32_t clipped[2] = {c1, c2};
      for (int j = 0; j < 2; ++j) {
        const Real sep = Dot(n, pts[j] - v1) - radii;
        ManifoldPoint& mp = clip.points[clip.pointCount++];
        mp.point = pts[j] - (rB + Real(0.5) * sep) * n;
        mp.separation = sep;
        mp.id = MakeFeatureId(uint32_t(faceA), clipped[j] ? 0x80u | clipped[j] : uint32_t(j), false);
      }
    }
  }

  const auto nearer = [](const Manifold& c) {
    return c.pointCount == 0 ? FLT_MAX : std::min(c.points[0].separation, c.points[c.pointCount - 1].separation);
  };
  if (apart && !(clip.pointCount == 2 && nearer(clip) + radii <= gap + kParallelTolerance)) {
    // One point: the cores' closest points.
    const Vec2 d = closeB - closeA;
    const Vec2 normal = gap > Real(1e-9) ? (Real(1) / gap) * d : (sepB > sepA ? -nB : an[faceA]);
    const Real sep = gap - radii;
    m.normal = normal;
    m.pointCount = 1;
    m.points[0].point = closeA + (rA + Real(0.5) * sep) * normal;
    m.points[0].separation = sep;
    m.points[0].id = MakeFeatureId(0xFD, 0xFD, false);
    return m;
  }
  if (clip.pointCount == 0) {
    // Overlapping cores and nothing inside the reference face's slab (a deep crossing near
    // a corner): the segment's end deepest along A's face normal.
    const Vec2 n = an[faceA], v1 = av[faceA];
    const Vec2 q = Dot(n, q1 - v1) <= Dot(n, q2 - v1) ? q1 : q2;
    const Real sep = Dot(n, q - v1) - radii;
    m.normal = n;
    m.pointCount = 1;
    m.points[0].point = q - (rB + Real(0.5) * sep) * n;
    m.points[0].separation = sep;
    m.points[0].id = MakeFeatureId(0xFC, 0xFC, false);
    return m;
  }
  // Keep the points within the speculative distance, in order.
  m.normal = clip.normal;
  for (int j = 0; j < clip.pointCount; ++j) {
    if (clip.points[j].separation <= speculative) m.points[m.pointCount++] = clip.points[j];
  }
  return m;
}

Manifold ToWorld(Manifold m, const Transform& xfA) {
  m.normal = Rotate(xfA.q, m.normal);
  for (int j = 0; j < m.pointCount; ++j) m.points[j].point = TransformPoint(xfA, m.points[j].point);
  return m;
}

// A capsule's segment as a two-sided core: vertices and outward normals.
void SegmentCore(const Capsule& c, Vec2 v[2], Vec2 n[2]) {
  v[0] = c.center1, v[1] = c.center2;
  const Vec2 t = (Real(1) / Length(c.center2 - c.center1)) * (c.center2 - c.center1);
  n[0] = {t.y, -t.x};
  n[1] = -n[0];
}

}  // namespace

Manifold CollideCapsuleAndCircle(const Capsule& a, Transform xfA, const Circle& b, Transform xfB, Real speculative) {
  Manifold m;
  const Vec2 c = InvTransformPoint(xfA, TransformPoint(xfB, b.center));
  const Vec2 e = a.center2 - a.center1;
  const Real u = std::clamp(Dot(c - a.center1, e) / Dot(e, e), Real(0), Real(1));
  const Vec2 p = a.center1 + u * e;
  const Vec2 d = c - p;
  const Real dist = Length(d);
  const Real sep = dist - a.radius - b.radius;
  if (sep > speculative) return m;
  // On the segment itself any side will do; its right normal keeps the result deterministic.
  const Vec2 normal = dist > Real(1e-9) ? (Real(1) / dist) * d : (Real(1) / Length(e)) * Vec2{e.y, -e.x};
  m.normal = Rotate(xfA.q, normal);
  m.pointCount = 1;
  m.points[0].point = TransformPoint(xfA, p + (a.radius + Real(0.5) * sep) * normal);
  m.points[0].separation = sep;
  m.points[0].id = 0;
  return m;
}

Manifold CollidePolygonAndCapsule(const Polygon& a, Transform xfA, const Capsule& b, Transform xfB, Real speculative) {
  const Transform rel = InvMulTransforms(xfA, xfB);
  const Vec2 q1 = TransformPoint(rel, b.center1), q2 = TransformPoint(rel, b.center2);
  return ToWorld(CollideCoreAndSegment(a.vertices.data(), a.normals.data(), a.count, 0, q1, q2, b.radius, speculative), xfA);
}

Manifold CollideCapsules(const Capsule& a, Transform xfA, const Capsule& b, Transform xfB, Real speculative) {
  Vec2 v[2], n[2];
  SegmentCore(a, v, n);
  const Transform rel = InvMulTransforms(xfA, xfB);
  const Vec2 q1 = TransformPoint(rel, b.center1), q2 = TransformPoint(rel, b.center2);
  return ToWorld(CollideCoreAndSegment(v, n, 2, a.radius, q1, q2, b.radius, speculative), xfA);
}

Manifold CollideWithCapsule(const ShapeDef& a, Transform xfA, const ShapeDef& b, Transform xfB, Real speculative) {
  const auto flipped = [](Manifold m) {
    m.normal = -m.normal;
    return m;
  };
  if (a.type == ShapeType::kCapsule) {
    switch (b.type) {
      case ShapeType::kCircle: return CollideCapsuleAndCircle(a.capsule, xfA, b.circle, xfB, speculative);
      case ShapeType::kCapsule: return CollideCapsules(a.capsule, xfA, b.capsule, xfB, speculative);
      case ShapeType::kPolygon: return flipped(CollidePolygonAndCapsule(b.polygon, xfB, a.capsule, xfA, speculative));
      case ShapeType::kSegment:
      case ShapeType::kChainSegment: return {};  // CollideRareShapes takes segment pairs
    }
  }
  if (a.type == ShapeType::kCircle) return flipped(CollideCapsuleAndCircle(b.capsule, xfB, a.circle, xfA, speculative));
  return CollidePolygonAndCapsule(a.polygon, xfA, b.capsule, xfB, speculative);
}

}  // namespace quadrant
