// Narrow phase for segments and chain segments against circles, polygons and capsules, and the
// dispatch of every pair that has a shape other than a circle or a polygon in it.
//
// A two-sided segment is exactly a capsule of radius 0: its pairs are the capsule pairs
// (capsule_collide.cpp) with that capsule. Two segments (of either kind) never collide: both
// ride static or kinematic bodies, and neither has an inside.
//
// A chain segment is one-sided and knows its neighbours' far ends (ghost1 -> point1 -> point2 ->
// ghost2). Without them a box sliding along a chain of segments catches at each join: just past
// a join, the next segment's end lies inside the box's leading side, and the separating axis with
// the least penetration is that side, so the contact pushes the box back. The chain segment keeps
// the two-sided manifold only where its normal is one the segment may have there (the Gauss map
// of Box2D's "ghost collisions" post, box2d.org/posts/2020/06/ghost-collisions/): a normal
// pointing past a convex neighbour's normal belongs to that neighbour and is skipped; one near a
// flat or concave join is turned to the segment's own normal (snapped), and the other shape's
// edge is clipped to the segment's face instead. A body whose centroid is behind the segment
// gets no contact (one-sided).
#include <algorithm>
#include <cfloat>
#include <cmath>

#include "collision/narrow_phase.h"

namespace quadrant {
namespace {

// Sine below which a normal counts as a neighbour's (Box2D's tolerance for the Gauss map).
constexpr Real kSinTolerance = Real(0.01);
// Turn (cross product of unit edges) above which a join is convex; below it, flat or concave.
constexpr Real kConvexTolerance = Real(0.01);
// A normal within this cosine of the segment's own is its face normal: always admitted.
constexpr Real kFaceCosine = Real(0.9999);
// A normal this far against the segment's own is its back face: snapped (a deep contact).
constexpr Real kBackCosine = Real(-0.99);

Vec2 Unit(Vec2 v) { return (Real(1) / Length(v)) * v; }

Manifold Flipped(Manifold m) {
  m.normal = -m.normal;
  return m;
}

// The two-sided manifold of the segment p1-p2 (A, as a capsule of radius 0) and B.
Manifold CollideTwoSided(const Segment& seg, Transform xfA, const ShapeDef& b, Transform xfB, Real speculative) {
  const Capsule core{seg.point1, seg.point2, 0};
  switch (b.type) {
    case ShapeType::kCircle: return CollideCapsuleAndCircle(core, xfA, b.circle, xfB, speculative);
    case ShapeType::kPolygon: return Flipped(CollidePolygonAndCapsule(b.polygon, xfB, core, xfA, speculative));
    case ShapeType::kCapsule: return CollideCapsules(core, xfA, b.capsule, xfB, speculative);
    case ShapeType::kSegment:
    case ShapeType::kChainSegment: break;
  }
  return {};
}

// A chain segment in world coordinates with its neighbours' normals.
struct ChainFrame {
  Vec2 p1, p2;
  Vec2 edge1;     // unit, p1 -> p2
  Vec2 normal1;   // the segment's normal (right of edge1)
  Vec2 normal0;   // the previous segment's
  Vec2 normal2;   // the next segment's
  bool convex1;   // the join at p1 turns left (the chain's solid side is convex there)
  bool convex2;   // the join at p2
};

ChainFrame MakeFrame(const ChainSegment& c, const Transform& xf) {
  ChainFrame f;
  const Vec2 g1 = TransformPoint(xf, c.ghost1), g2 = TransformPoint(xf, c.ghost2);
  f.p1 = TransformPoint(xf, c.segment.point1), f.p2 = TransformPoint(xf, c.segment.point2);
  f.edge1 = Unit(f.p2 - f.p1);
  const Vec2 edge0 = Unit(f.p1 - g1), edge2 = Unit(g2 - f.p2);
  f.normal1 = RightPerp(f.edge1);
  f.normal0 = RightPerp(edge0);
  f.normal2 = RightPerp(edge2);
  f.convex1 = Cross(edge0, f.edge1) >= kConvexTolerance;
  f.convex2 = Cross(f.edge1, edge2) >= kConvexTolerance;
  return f;
}

enum class NormalUse { kSkip, kAdmit, kSnap };

// Which segment owns a contact normal (from the segment to the other shape). Towards p1 it must
// not pass the previous segment's normal at a convex join; at a flat or concave join only the
// segment's own normal is admissible. The same towards p2.
NormalUse Classify(const ChainFrame& f, Vec2 n) {
  const Real along = Dot(n, f.normal1);
  if (along >= kFaceCosine) return NormalUse::kAdmit;
  if (along <= kBackCosine) return NormalUse::kSnap;
  if (Dot(n, f.edge1) <= 0) {
    if (!f.convex1) return NormalUse::kSnap;
    return Cross(n, f.normal0) > kSinTolerance ? NormalUse::kSkip : NormalUse::kAdmit;
  }
  if (!f.convex2) return NormalUse::kSnap;
  return Cross(f.normal2, n) > kSinTolerance ? NormalUse::kSkip : NormalUse::kAdmit;
}

// The other shape as a convex outline in world coordinates: a circle's centre (1 vertex), a
// capsule's segment (2) or a polygon's vertices and outward normals, and its radius.
struct Outline {
  Vec2 v[kMaxPolygonVertices];
  Vec2 n[kMaxPolygonVertices];
  int count = 0;
  Real radius = 0;
  Vec2 centroid;
};

Outline MakeOutline(const ShapeDef& b, const Transform& xf) {
  Outline o;
  if (b.type == ShapeType::kCircle) {
    o.v[0] = TransformPoint(xf, b.circle.center), o.count = 1, o.radius = b.circle.radius;
    o.centroid = o.v[0];
  } else if (b.type == ShapeType::kCapsule) {
    o.v[0] = TransformPoint(xf, b.capsule.center1), o.v[1] = TransformPoint(xf, b.capsule.center2);
    o.count = 2, o.radius = b.capsule.radius;
    o.centroid = Real(0.5) * (o.v[0] + o.v[1]);
  } else {
    o.count = b.polygon.count;
    for (int k = 0; k < o.count; ++k) {
      o.v[k] = TransformPoint(xf, b.polygon.vertices[k]);
      o.n[k] = Rotate(xf.q, b.polygon.normals[k]);
    }
    o.centroid = TransformPoint(xf, b.polygon.centroid);
  }
  return o;
}

// The manifold with the normal snapped to the segment's own: the outline's edge (or point) most
// against the normal, clipped to the segment's extent, each point's depth below the segment's
// line. Nothing outside that extent: there a neighbour owns the contact.
Manifold SnapToFace(const ChainFrame& f, const Outline& o, Real speculative) {
  Manifold m;
  const Vec2 n = f.normal1, t = f.edge1;
  const Real lo = Dot(t, f.p1), hi = Dot(t, f.p2);
  Vec2 q1 = o.v[0], q2 = o.v[0];
  uint32_t i1 = 0, i2 = 0;
  if (o.count == 2) {
    q2 = o.v[1], i2 = 1;
  } else if (o.count > 2) {
    int inc = 0;
    Real least = FLT_MAX;
    for (int k = 0; k < o.count; ++k) {
      const Real d = Dot(o.n[k], n);
      if (d < least) least = d, inc = k;
    }
    i1 = uint32_t(inc), i2 = uint32_t(inc + 1 < o.count ? inc + 1 : 0);
    q1 = o.v[i1], q2 = o.v[i2];
  }
  const Real d1 = Dot(t, q1), d2 = Dot(t, q2);
  if ((d1 < lo && d2 < lo) || (d1 > hi && d2 > hi)) return m;
  const Vec2 pts[2] = {q1, q2};
  const Real along[2] = {d1, d2};
  const uint32_t ids[2] = {i1, i2};
  const int points = o.count == 1 ? 1 : 2;
  for (int j = 0; j < points; ++j) {
    Vec2 p = pts[j];
    uint32_t id = ids[j];
    const Real other = along[1 - j];
    // Clip the end that lies beyond the extent to it (the other end is inside or beyond the
    // other side, so the edge crosses the bound).
    if (along[j] < lo || along[j] > hi) {
      const Real bound = along[j] < lo ? lo : hi;
      p = pts[j] + ((bound - along[j]) / (other - along[j])) * (pts[1 - j] - pts[j]);
      id = 0x80u | (along[j] < lo ? 1u : 2u);
    }
    const Real sep = Dot(n, p - f.p1) - o.radius;
    if (sep > speculative) continue;
    ManifoldPoint& mp = m.points[m.pointCount++];
    mp.point = p - (o.radius + Real(0.5) * sep) * n;
    mp.separation = sep;
    mp.id = MakeFeatureId(0xFB, id, false);
  }
  if (m.pointCount > 0) m.normal = n;
  return m;
}

// A chain segment (A) against a circle, a polygon or a capsule (B).
Manifold CollideChainSegment(const ChainSegment& c, Transform xfA, const ShapeDef& b, Transform xfB, Real speculative) {
  const ChainFrame f = MakeFrame(c, xfA);
  const Outline o = MakeOutline(b, xfB);
  // One-sided: nothing for a body whose centroid is behind the segment and behind each convex
  // neighbour (a body round a convex corner may still touch this segment's end).
  const bool behind1 = Dot(f.normal1, o.centroid - f.p1) < 0;
  const bool behind0 = !f.convex1 || Dot(f.normal0, o.centroid - f.p1) < 0;
  const bool behind2 = !f.convex2 || Dot(f.normal2, o.centroid - f.p2) < 0;
  if (behind1 && behind0 && behind2) return {};
  Manifold m = CollideTwoSided(c.segment, xfA, b, xfB, speculative);
  if (m.pointCount == 0) return m;
  switch (Classify(f, m.normal)) {
    case NormalUse::kAdmit: return m;
    case NormalUse::kSkip: return {};
    case NormalUse::kSnap: break;
  }
  // Snapping a body that is behind the segment would push it through to the front.
  if (behind1) return {};
  return SnapToFace(f, o, speculative);
}

// A segment of either kind (A) against B, which is not a segment.
Manifold CollideSegmentWith(const ShapeDef& a, Transform xfA, const ShapeDef& b, Transform xfB, Real speculative) {
  if (a.type == ShapeType::kSegment) return CollideTwoSided(a.segment, xfA, b, xfB, speculative);
  return CollideChainSegment(a.chainSegment, xfA, b, xfB, speculative);
}

}  // namespace

Manifold CollideRareShapes(const ShapeDef& a, Transform xfA, const ShapeDef& b, Transform xfB, Real speculative) {
  const bool segmentA = IsSegmentType(a.type), segmentB = IsSegmentType(b.type);
  if (!segmentA && !segmentB) return CollideWithCapsule(a, xfA, b, xfB, speculative);
  if (segmentA && segmentB) return {};
  if (segmentA) return CollideSegmentWith(a, xfA, b, xfB, speculative);
  return Flipped(CollideSegmentWith(b, xfB, a, xfA, speculative));
}

}  // namespace quadrant
