// Narrow phase: exact contact manifolds for one pair of shapes.
//
// Every function returns points in world coordinates with the normal pointing from shape A
// to shape B. Points are kept while their separation is below `speculative` (m), so the solver
// sees a contact a little before it touches (speculative contacts: no tunnelling at stress-
// scene speeds and no jitter when resting contacts flicker).
#pragma once

#include <cstdint>

#include "quadrant/math.h"
#include "quadrant/shapes.h"
#include "quadrant/types.h"

namespace quadrant {

/// Feature id of a manifold point: which reference edge, which incident vertex, and whether
/// A and B were swapped. Equal ids across steps mean the same geometric feature pair, so the
/// point's impulses can warm-start the next step.
inline constexpr uint32_t MakeFeatureId(uint32_t referenceEdge, uint32_t incidentVertex, bool flipped) {
  return (referenceEdge & 0xFFu) | ((incidentVertex & 0xFFu) << 8) | (flipped ? 0x10000u : 0u);
}

/// A compound body's contact (Bodies::compound) names its pair of shapes in each point's feature
/// id, above the feature bits: this flag, shape index of A in bits 20-25, of B in bits 26-31.
/// Several contacts of one pair of bodies share a key; the ids tell them apart for warm starting.
inline constexpr uint32_t kCompoundFeature = 1u << 19;
inline constexpr uint32_t CompoundFeatureId(uint32_t id, int shapeA, int shapeB) {
  return id | kCompoundFeature | (uint32_t(shapeA) << 20) | (uint32_t(shapeB) << 26);
}

struct ManifoldPoint {
  Vec2 point;             ///< world, halfway between the two surfaces
  Real separation = 0;    ///< negative when penetrating (m)
  uint32_t id = 0;        ///< feature id
  Real normalImpulse = 0; ///< accumulated by the solver (N s)
  Real tangentImpulse = 0;
  /// The point relative to each body's centre of mass (world axes), as the solvers' lever arms:
  /// `point` minus the centre when the manifold was computed (the pair loop sets them; a recycled
  /// manifold keeps them, world.h's WorldDef::contactRecycleDistance).
  Vec2 anchorA, anchorB;
  Real baseSeparation = 0;  ///< `separation` when the manifold was computed (for recycling)
};

struct Manifold {
  Vec2 normal;  ///< unit, from A to B
  ManifoldPoint points[2];
  int pointCount = 0;
};

Manifold CollideCircles(const Circle& a, Transform xfA, const Circle& b, Transform xfB, Real speculative);
Manifold CollidePolygonAndCircle(const Polygon& a, Transform xfA, const Circle& b, Transform xfB, Real speculative);
Manifold CollidePolygons(const Polygon& a, Transform xfA, const Polygon& b, Transform xfB, Real speculative);
/// CollidePolygons by its general path (vertex counts read at run time, no SIMD), which the
/// four-vertex pairs' SSE2 and AVX paths must match bit for bit: for the tests.
Manifold CollidePolygonsGeneral(const Polygon& a, Transform xfA, const Polygon& b, Transform xfB, Real speculative);
/// Box2D 2.4.1's polygon manifold (b2CollidePolygons): the reference face's side planes are
/// extended by `radius` (the pair's polygon skins) before the incident edge is clipped, and only
/// points within `radius` are kept. WorldDef::box2dPolygonClip's collider, out of the pair loop.
Manifold CollidePolygonsBox2d(const Polygon& a, Transform xfA, const Polygon& b, Transform xfB, Real radius);

/// Capsule pairs (capsule_collide.cpp). CollideWithCapsule takes any pair with a capsule in it.
Manifold CollideCapsuleAndCircle(const Capsule& a, Transform xfA, const Circle& b, Transform xfB, Real speculative);
Manifold CollidePolygonAndCapsule(const Polygon& a, Transform xfA, const Capsule& b, Transform xfB, Real speculative);
Manifold CollideCapsules(const Capsule& a, Transform xfA, const Capsule& b, Transform xfB, Real speculative);
Manifold CollideWithCapsule(const ShapeDef& a, Transform xfA, const ShapeDef& b, Transform xfB, Real speculative);
/// Any pair with a shape other than a circle or a polygon in it (segment_collide.cpp): capsule
/// pairs as CollideWithCapsule, segments as capsules of radius 0, chain segments one-sided with
/// their ghost vertices; two segments of either kind never collide.
Manifold CollideRareShapes(const ShapeDef& a, Transform xfA, const ShapeDef& b, Transform xfB, Real speculative);

/// Dispatches on the shape types. For a circle A and polygon B it collides (B, A) and flips
/// the normal so the result still points from A to B.
Manifold Collide(const ShapeDef& a, Transform xfA, const ShapeDef& b, Transform xfB, Real speculative);

}  // namespace quadrant
