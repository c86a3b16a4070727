// Box2D 2.4.1's position pass geometry (WorldDef::box2dPositionSolve, issue #31), for pgs's and
// the thesis solver's position passes.
//
// The default pass holds a point's normal fixed in the world and turns its anchors with their
// bodies. Box2D 2.4.1 (b2PositionSolverManifold) keeps the reference face's normal and plane on
// the reference body, so they turn with it, and measures the incident point, a circle's centre or
// the incident polygon's clipped vertex, to that plane; two circles are measured centre to centre.
// Its correction acts at that incident point, so a circle on a face is never turned by it. On a
// polygon that the hit sets spinning at 30 rad/s, the face turns 0.5 rad in a step: Box2D turns it
// back by 0.16 rad where the fixed normal did not (random campaign seed 34, hit 47: pgs 33.5 %
// from Box2D before, docs/validation.md). The pass also stops, as Box2D's does, after the first
// iteration in which no point was deeper than 3 linearSlop.
//
// The geometry is taken where the narrow phase computed the manifold (the bodies' positions at
// the pass's snapshot) and expressed relative to each body's centre, so it follows the bodies'
// moves and turns since then. Pairs with other shapes, or compound bodies, keep the default.
#pragma once

#include <algorithm>

#include "collision/narrow_phase.h"
#include "dynamics/integrate.h"
#include "world/world_internal.h"

namespace quadrant {

struct Box2dPositionPoint {
  enum Kind : uint8_t { kDefault, kFaceA, kFaceB, kCircles };
  Kind kind = kDefault;
  Vec2 normal;  // faces: the reference normal at the snapshot, from reference body to incident
  Vec2 plane;   // faces: a point of the reference plane (moved out by the skins), from the reference centre
  Vec2 clip;    // faces: the incident point, from the incident body's centre
  Real separation = 0;  // at the snapshot, less the pair's skins
  Real distance = 0;    // circles: centre distance at the snapshot
};

// The geometry of manifold point k of `contact`, whose separation less the skins is `separation`,
// with the bodies where the narrow phase saw them.
inline Box2dPositionPoint MakeBox2dPositionPoint(const Bodies& bodies, const Contact& contact, int k, Real separation) {
  Box2dPositionPoint p;
  p.separation = separation;
  const ShapeType ta = bodies.shape[contact.a].type, tb = bodies.shape[contact.b].type;
  const Vec2 cA = bodies.center[contact.a], cB = bodies.center[contact.b];
  const Vec2 n = contact.manifold.normal;
  const ManifoldPoint& mp = contact.manifold.points[k];
  if (ta == ShapeType::kCircle && tb == ShapeType::kCircle) {
    p.kind = Box2dPositionPoint::kCircles;
    p.distance = Length(cB - cA);
    return p;
  }
  Vec2 clip;
  if (ta == ShapeType::kPolygon && tb == ShapeType::kCircle) {
    p.kind = Box2dPositionPoint::kFaceA;
    clip = cB;
  } else if (ta == ShapeType::kCircle && tb == ShapeType::kPolygon) {
    p.kind = Box2dPositionPoint::kFaceB;
    clip = cA;
  } else if (ta == ShapeType::kPolygon && tb == ShapeType::kPolygon) {
    // The polygon collider marks a reference face on B in the feature id (MakeFeatureId) and
    // puts the point halfway between the incident vertex and the reference face.
    const bool flipped = (mp.id & 0x10000u) != 0;
    p.kind = flipped ? Box2dPositionPoint::kFaceB : Box2dPositionPoint::kFaceA;
    clip = mp.point + (Real(0.5) * mp.separation) * (flipped ? -n : n);
  } else {
    return p;
  }
  const bool faceA = p.kind == Box2dPositionPoint::kFaceA;
  p.normal = faceA ? n : -n;
  p.plane = clip - separation * p.normal - (faceA ? cA : cB);
  p.clip = clip - (faceA ? cB : cA);
  return p;
}

// Where point p stands now: separation (less the skins), normal from A to B and the point the
// correction acts at, given each body's centre and its turn since the snapshot.
inline void Box2dPositionNow(const Box2dPositionPoint& p, Vec2 cA, Rot turnA, Vec2 cB, Rot turnB, Real& separation,
                             Vec2& normal, Vec2& point) {
  if (p.kind == Box2dPositionPoint::kCircles) {
    const Vec2 d = cB - cA;
    const Real distance = Length(d);
    normal = distance > 0 ? (Real(1) / distance) * d : Vec2{1, 0};
    separation = p.separation + (distance - p.distance);
    point = Real(0.5) * (cA + cB);
    return;
  }
  const bool faceA = p.kind == Box2dPositionPoint::kFaceA;
  const Rot turnRef = faceA ? turnA : turnB, turnInc = faceA ? turnB : turnA;
  const Vec2 refNormal = Rotate(turnRef, p.normal);
  const Vec2 plane = (faceA ? cA : cB) + Rotate(turnRef, p.plane);
  point = (faceA ? cB : cA) + Rotate(turnInc, p.clip);
  separation = Dot(point - plane, refNormal);
  normal = faceA ? refNormal : -refNormal;
}

// One point's correction as Box2D 2.4.1 applies it: the Baumgarte fraction of the depth beyond
// linearSlop, at most maxLinearCorrection, as a push along `normal` at lever arms rA and rB.
// Returns whether it moved a body. Static and kinematic bodies are left untouched bit for bit.
template <bool kRotation>
inline bool ApplyBox2dPositionCorrection(Bodies& bodies, const WorldDef& def, int a, Real mA, Real iA, int b, Real mB,
                                         Real iB, Real separation, Vec2 normal, Vec2 rA, Vec2 rB) {
  const Real C = std::clamp(def.baumgarte * (separation + def.linearSlop), -def.maxLinearCorrection, Real(0));
  if (C == 0) return false;
  Real K = mA + mB;
  if constexpr (kRotation) K += iA * Cross(rA, normal) * Cross(rA, normal) + iB * Cross(rB, normal) * Cross(rB, normal);
  if (!(K > 0)) return false;
  const Vec2 P = (-C / K) * normal;
  if (mA > 0) {
    bodies.center[a] -= mA * P;
    if constexpr (kRotation) bodies.xf[a].q = IntegrateRot(bodies.xf[a].q, -iA * Cross(rA, P));
  }
  if (mB > 0) {
    bodies.center[b] += mB * P;
    if constexpr (kRotation) bodies.xf[b].q = IntegrateRot(bodies.xf[b].q, iB * Cross(rB, P));
  }
  return true;
}

}  // namespace quadrant
