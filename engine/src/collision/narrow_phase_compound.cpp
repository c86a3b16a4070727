// Compound bodies: several shapes on one body (BodyDef::extraShapes), without making one-shape
// bodies any slower.
//
// The design:
// - Storage. A one-shape body is unchanged: its ShapeDef sits in Bodies::shape, where every hot
//   loop reads it. A compound body keeps all its shapes (first one first) in a side array,
//   Bodies::compound, and its Bodies::shape becomes a stand-in of type kCompoundShape (bit 3 of the
//   type byte; not a type a user can give) whose polygon is the box around all the shapes in body
//   coordinates and whose materials are the first shape's.
// - Mass. The body's mass is the sum of its shapes', its centre of mass their mass-weighted
//   centre, its inertia the sum of theirs moved there by the parallel-axis theorem, in double
//   (validation.cpp, CompoundMass); its bound radius is the farthest shape point from that centre.
// - Broad phase. One box per body as before: the stand-in's, so it covers every shape. The hot box
//   update sends any type above kPolygon out of line already (ShapeBox), and that path reads the
//   stand-in's polygon. (Box2D 3 makes every shape a broad-phase proxy and finds shape pairs; here
//   the unit stays the body, so the one-shape scenes keep their pair loop and contact keys.)
// - Narrow phase. While the world has a compound body, CollidePairs splits the pairs with one off
//   the block (a test of the stand-in's type bit per pair) and the rest go to the pair loops as
//   before; without one the pair loops are reached exactly as before, so circle, polygon and box
//   pairs pay nothing new (one test of a count per block). Every pair of shapes whose boxes (the
//   other body's shape boxed in the compound's frame against the compound's shapes' boxes kept in
//   body coordinates, Bodies::compoundBoxes; grown by the pair's
//   speculative distance) overlap is collided exactly as two one-shape bodies would be, and each
//   manifold that keeps a point becomes one ordinary Contact of the two bodies, with that pair of
//   shapes' materials. Its points' feature ids carry the two shape indices (kCompoundFeature).
// - Contacts. Several contacts of one body pair share the key (a, b); CollideCompoundPair emits them
//   together in a fixed shape order, the sorter keeps equal keys in that order (its sorts are stable), so
//   the list is the same for any thread count. The cache (contact_cache.cpp) matches a point by
//   key and feature id among all of last step's entries of that key, so each shape pair warm
//   starts from its own impulses. A compound contact is never recycled (it carries no recycling
//   pose) and the world then stores impulses instead of keeping the list (keys repeat).
// - The solver, islands and sleep see ordinary contacts; events dedupe by pair already. Queries,
//   drawing, GetAABB and the sensor test walk the shapes (BodyShapes). The state hash is of the
//   bodies' poses and velocities and needs nothing. The quadrants scheme and the distributed world
//   refuse compound bodies.
#include <algorithm>
#include <array>
#include <cmath>

#include "collision/broad_phase.h"
#include "collision/narrow_phase.h"
#include "world/world_internal.h"

namespace quadrant {

namespace {

// A pair (a < b) in which either body is compound: the pair loop's tests (a dynamic body, the
// bounding circles within reach), then every pair of shapes whose boxes, grown by the pair's
// speculative distance, overlap, in a fixed order (the other body's shapes, then M's).
void CollideCompoundPair(const Bodies& bodies, const WorldDef& def, Real dt, int a, int b, std::vector<Contact>& out) {
  if (!(bodies.dynamic[size_t(a)] | bodies.dynamic[size_t(b)])) return;
  const BodyVelocity va = bodies.vel[size_t(a)], vb = bodies.vel[size_t(b)];
  const Vec2 ca = bodies.center[size_t(a)], cb = bodies.center[size_t(b)];
  const Real ra = bodies.boundRadius[size_t(a)], rb = bodies.boundRadius[size_t(b)];
  const Real base = def.speculativeDistance;
  const bool bullet = bodies.bulletCount > 0 && (bodies.bullet[size_t(a)] | bodies.bullet[size_t(b)]) != 0;
  const Real sweep = def.effects.continuous || bullet ? dt : Real(0);
  const Real speculative =
      sweep > 0 ? base + sweep * (Length(vb.v - va.v) + std::abs(va.w) * ra + std::abs(vb.w) * rb) : base;
  const Real reach = ra + rb + speculative;
  if (LengthSquared(cb - ca) > reach * reach) return;
  const std::span<const ShapeDef> shapesA = BodyShapes(bodies, a), shapesB = BodyShapes(bodies, b);
  const Transform xfA = bodies.xf[size_t(a)], xfB = bodies.xf[size_t(b)];
  // Which pairs of shapes may touch, tested in the frame of the body with more shapes (M), against
  // its shapes' boxes kept in body coordinates (Bodies::compoundBoxes): each shape of the other
  // body (O) gives one box in M's frame (its world box's corners taken there), so a drum of 40
  // pieces costs a box test per piece, not 40 boxes turned into the world.
  const bool mIsA = shapesA.size() >= shapesB.size();
  const int bodyM = mIsA ? a : b;
  const std::span<const ShapeDef> shapesO = mIsA ? shapesB : shapesA;
  const Transform xfM = mIsA ? xfA : xfB, xfO = mIsA ? xfB : xfA;
  const std::vector<AABB>& boxesM = bodies.compoundBoxes[size_t(bodyM)];
  for (size_t o = 0; o < shapesO.size(); ++o) {
    const AABB world = ComputeShapeAABB(shapesO[o], xfO);
    const Vec2 corners[4] = {world.lower, {world.upper.x, world.lower.y}, world.upper, {world.lower.x, world.upper.y}};
    AABB boxO{InvTransformPoint(xfM, corners[0]), InvTransformPoint(xfM, corners[0])};
    for (const Vec2& c : corners) {
      const Vec2 local = InvTransformPoint(xfM, c);
      boxO.lower = Min(boxO.lower, local);
      boxO.upper = Max(boxO.upper, local);
    }
    // Grown by the reach and a little for the rounding of the two transforms (relative to the
    // coordinates' size: float's 1.2e-7 a few times over, with room to spare).
    const Real far = std::max({std::abs(world.lower.x), std::abs(world.lower.y), std::abs(world.upper.x),
                               std::abs(world.upper.y), std::abs(xfM.p.x), std::abs(xfM.p.y)});
    const Real pad = speculative + Real(1e-5) * (Real(1) + far);
    boxO.lower = boxO.lower - Vec2{pad, pad};
    boxO.upper = boxO.upper + Vec2{pad, pad};
    for (size_t mi = 0; mi < boxesM.size(); ++mi) {
      const AABB& boxM = boxesM[mi];
      if (boxO.lower.x > boxM.upper.x || boxM.lower.x > boxO.upper.x || boxO.lower.y > boxM.upper.y ||
          boxM.lower.y > boxO.upper.y) {
        continue;
      }
      const size_t i = mIsA ? mi : o, j = mIsA ? o : mi;
      const ShapeDef& sa = shapesA[i];
      const ShapeDef& sb = shapesB[j];
      Manifold m = Collide(sa, xfA, sb, xfB, speculative);
      // The pair loop's rule: a point still apart beyond the base distance stays only if it can
      // close within the step at its current approach speed.
      int kept = 0;
      for (int k = 0; k < m.pointCount; ++k) {
        const ManifoldPoint& mp = m.points[k];
        if (mp.separation > base) {
          const Vec2 dv = vb.v + Cross(vb.w, mp.point - cb) - va.v - Cross(va.w, mp.point - ca);
          const Real approach = -Dot(dv, m.normal);
          if (mp.separation > base + sweep * approach) continue;
        }
        m.points[kept++] = mp;
      }
      m.pointCount = kept;
      if (kept == 0) continue;
      Contact c;
      c.a = a;
      c.b = b;
      c.friction = std::sqrt(sa.friction * sb.friction);
      c.restitution = std::max(sa.restitution, sb.restitution);
      c.manifold = m;
      for (int k = 0; k < m.pointCount; ++k) {
        ManifoldPoint& mp = c.manifold.points[k];
        mp.id = CompoundFeatureId(mp.id, int(i), int(j));
        mp.anchorA = mp.point - ca;
        mp.anchorB = mp.point - cb;
        mp.baseSeparation = mp.separation;
      }
      // recycleQA and recycleQB stay {0, 0}: the recycling turn test fails, so it is never recycled.
      out.push_back(c);
    }
  }
}

}  // namespace

void CollidePairsWithCompounds(const Bodies& bodies, const WorldDef& def, Real dt, std::span<const CandidatePair> pairs,
                               std::vector<Contact>& out, const RecycleSource* recycle) {
  const ShapeDef* const shape = bodies.shape.data();
  size_t run = 0;  // the first pair of the current run without a compound body
  for (size_t i = 0; i < pairs.size(); ++i) {
    const CandidatePair p = pairs[i];
    if (!IsCompoundType(ShapeType(uint8_t(shape[p.a].type) | uint8_t(shape[p.b].type)))) continue;
    if (i > run) CollideSimplePairs(bodies, def, dt, pairs.subspan(run, i - run), out, recycle);
    run = i + 1;
    CollideCompoundPair(bodies, def, dt, p.a, p.b, out);
  }
  if (run < pairs.size()) CollideSimplePairs(bodies, def, dt, pairs.subspan(run), out, recycle);
}

}  // namespace quadrant
