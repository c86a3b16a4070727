// Narrow phase: circle-circle, polygon-circle and polygon-polygon manifolds (capsules:
// capsule_collide.cpp; segments and chain segments: segment_collide.cpp).
//
// Polygon pairs use the separating axis test over both polygons' face normals, then clip the
// incident edge against the side planes of the reference edge (Sutherland-Hodgman on one
// segment), which yields the two-point manifold a stack needs. The thesis produced one point
// per pair, which lets a box rock on its single contact and a stack topple.
#include "collision/narrow_phase.h"

#include <algorithm>
#include <cmath>

#include "collision/box_batch.h"
#include "collision/broad_phase.h"
#include "dynamics/restitution_policy.h"
#include "world/world_internal.h"

#include <cfloat>

#if defined(__SSE2__) && !defined(QUADRANT_DOUBLE)
#include <emmintrin.h>
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>  // the AVX box-box search (CollideBoxesVex), compiled for that function only
#endif
#define QUADRANT_NARROW_SIMD 1
#else
#define QUADRANT_NARROW_SIMD 0
#endif

namespace quadrant {
namespace {

// Prefer A's face unless B's is clearly better, so the reference face does not flip between
// two nearly equal axes from step to step (that would change feature ids and lose warm starts).
constexpr Real kAxisPreference = Real(0.0005);

// Largest separation of `b` (given in a's frame) along one of a's face normals. kA and kB are
// the vertex counts when known at compile time (0: read them at run time).
template <int kA, int kB>
Real MaxSeparation(const Polygon& a, const Vec2* bVerts, int bCount, int* edgeOut) {
  const int aCount = kA > 0 ? kA : a.count;
  if constexpr (kB > 0) bCount = kB;
  Real best = -FLT_MAX;
  int bestEdge = 0;
  for (int i = 0; i < aCount; ++i) {
    const Vec2 n = a.normals[i];
    const Vec2 v = a.vertices[i];
    Real minDot = FLT_MAX;
    for (int j = 0; j < bCount; ++j) {
      Real d = Dot(n, bVerts[j] - v);
      minDot = d < minDot ? d : minDot;
    }
    if (minDot > best) {
      best = minDot;
      bestEdge = i;
    }
  }
  *edgeOut = bestEdge;
  return best;
}

struct ClipVertex {
  Vec2 v;
  uint32_t feature;  // incident vertex index, or 0x80 | side when created by clipping
};

// Keeps the part of segment (in[0], in[1]) where Dot(n, p) <= offset.
[[gnu::always_inline]] inline int ClipSegment(ClipVertex out[2], const ClipVertex in[2], Vec2 n, Real offset, uint32_t side) {
  int count = 0;
  Real d0 = Dot(n, in[0].v) - offset;
  Real d1 = Dot(n, in[1].v) - offset;
  if (d0 <= 0) out[count++] = in[0];
  if (d1 <= 0) out[count++] = in[1];
  if (d0 * d1 < 0) {
    Real t = d0 / (d0 - d1);
    out[count].v = in[0].v + t * (in[1].v - in[0].v);
    out[count].feature = 0x80u | side;
    ++count;
  }
  return count;
}

// ClipSegment when only a two-point result is of use (the caller gives up on fewer): the same
// operations and the same order of the points (kept ends first, in order, then the crossing),
// on values instead of arrays. Both ends inside: no crossing (their product is not negative);
// one inside: two points only if the other is strictly outside and the inside one strictly
// inside, which is the product's sign test. Why: the arrays went through the stack (zeroed,
// stored, reloaded) in the box-box collider, and the count's branches (base-100 pyramid).
[[gnu::always_inline]] inline bool ClipToTwo(ClipVertex& out0, ClipVertex& out1, ClipVertex in0, ClipVertex in1, Vec2 n,
                                             Real offset, uint32_t side) {
  const Real d0 = Dot(n, in0.v) - offset;
  const Real d1 = Dot(n, in1.v) - offset;
  const bool keep0 = d0 <= 0, keep1 = d1 <= 0;
  if (keep0 && keep1) {
    out0 = in0;
    out1 = in1;
    return true;
  }
  if (!(d0 * d1 < 0)) return false;
  const Real t = d0 / (d0 - d1);
  out0 = keep0 ? in0 : in1;
  out1 = {in0.v + t * (in1.v - in0.v), 0x80u | side};
  return true;
}

}  // namespace

Manifold CollideCircles(const Circle& a, Transform xfA, const Circle& b, Transform xfB, Real speculative) {
  Manifold m;
  const Vec2 pA = TransformPoint(xfA, a.center);
  const Vec2 pB = TransformPoint(xfB, b.center);
  const Vec2 d = pB - pA;
  const Real dist2 = LengthSquared(d);
  const Real reach = a.radius + b.radius + speculative;
  if (dist2 > reach * reach) return m;
  const Real dist = std::sqrt(dist2);
  // Coincident centres: any direction is as good; pick +x so the result is deterministic.
  const Vec2 normal = dist > Real(1e-9) ? (Real(1) / dist) * d : Vec2{1, 0};
  const Real separation = dist - a.radius - b.radius;
  m.normal = normal;
  m.pointCount = 1;
  m.points[0].point = pA + (a.radius + Real(0.5) * separation) * normal;
  m.points[0].separation = separation;
  m.points[0].id = 0;
  return m;
}

Manifold CollidePolygonAndCircle(const Polygon& a, Transform xfA, const Circle& b, Transform xfB,
                                 Real speculative) {
  Manifold m;
  const Vec2 c = InvTransformPoint(xfA, TransformPoint(xfB, b.center));  // in a's frame
  const Real r = b.radius;

  int face = 0;
  Real faceSep = -FLT_MAX;
  for (int i = 0; i < a.count; ++i) {
    Real s = Dot(a.normals[i], c - a.vertices[i]);
    if (s > faceSep) {
      faceSep = s;
      face = i;
    }
  }
  if (faceSep - r > speculative) return m;

  const Vec2 v1 = a.vertices[face];
  const Vec2 v2 = a.vertices[face + 1 < a.count ? face + 1 : 0];
  Vec2 normal;
  Real separation;
  uint32_t id;
  // Outside the face's extent the nearest feature is a vertex (its Voronoi region).
  if (faceSep > 0 && Dot(c - v1, v2 - v1) < 0) {
    Vec2 d = c - v1;
    Real dist = Length(d);
    normal = (Real(1) / dist) * d;
    separation = dist - r;
    id = MakeFeatureId(face, 0xFE, false);
  } else if (faceSep > 0 && Dot(c - v2, v1 - v2) < 0) {
    Vec2 d = c - v2;
    Real dist = Length(d);
    normal = (Real(1) / dist) * d;
    separation = dist - r;
    id = MakeFeatureId(face, 0xFF, false);
  } else {
    normal = a.normals[face];
    separation = faceSep - r;
    id = MakeFeatureId(face, 0, false);
  }
  if (separation > speculative) return m;

  const Vec2 onCircle = c - r * normal;
  m.normal = Rotate(xfA.q, normal);
  m.pointCount = 1;
  m.points[0].point = TransformPoint(xfA, onCircle - Real(0.5) * separation * normal);
  m.points[0].separation = separation;
  m.points[0].id = id;
  return m;
}

namespace {

// CollidePolygons with the vertex counts kA, kB fixed at compile time (0: at run time). Box
// pairs (4 and 4), the pyramid's and the stacks' only pairs, get fully unrolled loops: the same
// operations in the same order, so the same manifold bit for bit. Base-100 pyramid, soft_step:
// 43.0M -> 40.3M instructions a step (callgrind).
#if QUADRANT_NARROW_SIMD
// The four-vertex case of the searches below four lanes at a time (SSE2): lane i does the
// scalar code's operations for face (or vertex) i in the same order, and _mm_min_ps is the
// scalar `d < m ? d : m`, so the manifold is the same bit for bit (the state hashes did not
// move). Why: box pairs are the pyramid's and the stacks' only pairs, and the 2 x 16 dot
// products of the axis searches and the 8 vertex transforms were most of CollidePolygonsT<4, 4>
// (base-100 pyramid, callgrind: 797 -> 500 instructions a pair with the four lanes).
struct Four {
  __m128 x, y;
};

inline Four LoadFour(const Vec2* v) {
  const __m128 lo = _mm_loadu_ps(&v[0].x), hi = _mm_loadu_ps(&v[2].x);  // x0 y0 x1 y1, x2 y2 x3 y3
  return {_mm_shuffle_ps(lo, hi, _MM_SHUFFLE(2, 0, 2, 0)), _mm_shuffle_ps(lo, hi, _MM_SHUFFLE(3, 1, 3, 1))};
}

// TransformPoint(xf, v) in every lane.
inline Four TransformFour(Transform xf, Four v) {
  const __m128 c = _mm_set1_ps(xf.q.c), s = _mm_set1_ps(xf.q.s);
  return {_mm_add_ps(_mm_sub_ps(_mm_mul_ps(c, v.x), _mm_mul_ps(s, v.y)), _mm_set1_ps(xf.p.x)),
          _mm_add_ps(_mm_add_ps(_mm_mul_ps(s, v.x), _mm_mul_ps(c, v.y)), _mm_set1_ps(xf.p.y))};
}

inline void StoreFour(Four f, Vec2* out) {
  _mm_storeu_ps(&out[0].x, _mm_unpacklo_ps(f.x, f.y));
  _mm_storeu_ps(&out[2].x, _mm_unpackhi_ps(f.x, f.y));
}

template <int kLane>
inline __m128 SplatLane(__m128 v) {
  return _mm_shuffle_ps(v, v, _MM_SHUFFLE(kLane, kLane, kLane, kLane));
}

// The first lane holding the largest of four values, as the scalar search finds it: `best` starts
// at -FLT_MAX and takes a value only when it is strictly larger, so a NaN is never taken, ties go
// to the first lane, and with nothing above -FLT_MAX it is lane 0. _mm_max_ps(v, floor) returns
// floor for a NaN lane (and for -inf), so every lane of `clamped` is at least -FLT_MAX; the
// first lane equal to their maximum is the scalar's lane (with nothing above -FLT_MAX all lanes
// equal it and lane 0 is first). The value may differ from the scalar's only in the sign of a
// zero, which no comparison below sees. Why: the scalar loop over four stored lanes was 12
// compare-and-branch instructions and a store-to-load round trip per search.
inline int ArgMaxFour(__m128 v, Real* bestOut) {
  const __m128 clamped = _mm_max_ps(v, _mm_set1_ps(-FLT_MAX));
  __m128 m = _mm_max_ps(clamped, _mm_shuffle_ps(clamped, clamped, _MM_SHUFFLE(2, 3, 0, 1)));
  m = _mm_max_ps(m, _mm_shuffle_ps(m, m, _MM_SHUFFLE(1, 0, 3, 2)));
  *bestOut = _mm_cvtss_f32(m);
  return __builtin_ctz(unsigned(_mm_movemask_ps(_mm_cmpeq_ps(clamped, m))));
}

// The first lane holding the smallest of four values, as a scalar search from FLT_MAX with a
// strict `<` finds it (ArgMaxFour's argument, mirrored).
inline int ArgMinFour(__m128 v) {
  const __m128 clamped = _mm_min_ps(v, _mm_set1_ps(FLT_MAX));
  __m128 m = _mm_min_ps(clamped, _mm_shuffle_ps(clamped, clamped, _MM_SHUFFLE(2, 3, 0, 1)));
  m = _mm_min_ps(m, _mm_shuffle_ps(m, m, _MM_SHUFFLE(1, 0, 3, 2)));
  return __builtin_ctz(unsigned(_mm_movemask_ps(_mm_cmpeq_ps(clamped, m))));
}

// MaxSeparation<4, 4>: the lanes are a's faces, the loop runs over b's vertices (in a's frame).
inline Real MaxSeparationFour(const Polygon& a, Four b, int* edgeOut) {
  const Four n = LoadFour(a.normals.data()), v = LoadFour(a.vertices.data());
  __m128 minDot = _mm_set1_ps(FLT_MAX);
  auto vertex = [&](__m128 bx, __m128 by) {
    const __m128 d = _mm_add_ps(_mm_mul_ps(n.x, _mm_sub_ps(bx, v.x)), _mm_mul_ps(n.y, _mm_sub_ps(by, v.y)));
    minDot = _mm_min_ps(d, minDot);
  };
  vertex(SplatLane<0>(b.x), SplatLane<0>(b.y));
  vertex(SplatLane<1>(b.x), SplatLane<1>(b.y));
  vertex(SplatLane<2>(b.x), SplatLane<2>(b.y));
  vertex(SplatLane<3>(b.x), SplatLane<3>(b.y));
  Real best;
  *edgeOut = ArgMaxFour(minDot, &best);
  return best;
}
#endif

// The part of CollidePolygonsT after the two axis searches: given each polygon's vertices in the
// other's frame and the best face of each (edge, separation), picks the reference face, finds the
// incident edge and clips it. Shared by the general search below and the boxes' eight-lane one.
// kSideSkin (WorldDef::box2dPolygonClip only): the reference face's side planes are moved out by
// `speculative`, as Box2D 2.4.1 extends them by its polygon radii (b2CollidePolygons).
template <int kA, int kB, bool kSideSkin = false>
[[gnu::always_inline]] inline Manifold ClipPolygons(const Polygon& a, const Transform& xfA, const Polygon& b, const Transform& xfB,
                                                    Real speculative, Real sepA, int edgeA, Real sepB, int edgeB,
                                                    const Vec2* aVerts, const Vec2* bVerts, Rot bInAq, Rot aInBq) {
  Manifold m;
  const bool flip = sepB > sepA + kAxisPreference;
  const Polygon& ref = flip ? b : a;
  const Polygon& inc = flip ? a : b;
  const Vec2* incVerts = flip ? aVerts : bVerts;  // incident vertices in the reference frame
  const Transform& refXf = flip ? xfB : xfA;
  const int refEdge = flip ? edgeB : edgeA;
  // Either polygon may be the reference one: counts are compile-time only when both are.
  const int incCount = kA > 0 && kA == kB ? kA : inc.count;
  const int refCount = kA > 0 && kA == kB ? kA : ref.count;

  // Incident edge: the one whose normal is most anti-parallel to the reference normal.
  const Vec2 refNormal = ref.normals[refEdge];
  const Rot incInRef = flip ? aInBq : bInAq;  // InvMul(xfB.q, xfA.q) or InvMul(xfA.q, xfB.q)
  int incEdge = 0;
#if QUADRANT_NARROW_SIMD
  if constexpr (kA == 4 && kB == 4) {
    // Dot(refNormal, Rotate(incInRef, normal i)) in lane i, the same operations.
    const Four n = LoadFour(inc.normals.data());
    const __m128 c = _mm_set1_ps(incInRef.c), s = _mm_set1_ps(incInRef.s);
    const __m128 rx = _mm_sub_ps(_mm_mul_ps(c, n.x), _mm_mul_ps(s, n.y));
    const __m128 ry = _mm_add_ps(_mm_mul_ps(s, n.x), _mm_mul_ps(c, n.y));
    incEdge = ArgMinFour(_mm_add_ps(_mm_mul_ps(_mm_set1_ps(refNormal.x), rx), _mm_mul_ps(_mm_set1_ps(refNormal.y), ry)));
  } else
#endif
  {
    Real minDot = FLT_MAX;
    for (int i = 0; i < incCount; ++i) {
      Real d = Dot(refNormal, Rotate(incInRef, inc.normals[i]));
      if (d < minDot) {
        minDot = d;
        incEdge = i;
      }
    }
  }
  const int incNext = incEdge + 1 < incCount ? incEdge + 1 : 0;
  const ClipVertex incident[2] = {{incVerts[incEdge], uint32_t(incEdge)}, {incVerts[incNext], uint32_t(incNext)}};

  const Vec2 r1 = ref.vertices[refEdge];
  const Vec2 r2 = ref.vertices[refEdge + 1 < refCount ? refEdge + 1 : 0];
  const Vec2 tangent = Normalize(r2 - r1);
  ClipVertex clip1[2];
  ClipVertex clip2[2];
  if constexpr (kA == 4 && kB == 4) {
    // Boxes: the two-point clip on values (the general path keeps ClipSegment, so the box paths'
    // comparison with it in NarrowPhaseBoxes checks this one too).
    if (!ClipToTwo(clip1[0], clip1[1], incident[0], incident[1], -tangent, -Dot(tangent, r1), 0)) return m;
    if (!ClipToTwo(clip2[0], clip2[1], clip1[0], clip1[1], tangent, Dot(tangent, r2), 1)) return m;
  } else if constexpr (kSideSkin) {
    if (ClipSegment(clip1, incident, -tangent, -Dot(tangent, r1) + speculative, 0) < 2) return m;
    if (ClipSegment(clip2, clip1, tangent, Dot(tangent, r2) + speculative, 1) < 2) return m;
  } else {
    if (ClipSegment(clip1, incident, -tangent, -Dot(tangent, r1), 0) < 2) return m;
    if (ClipSegment(clip2, clip1, tangent, Dot(tangent, r2), 1) < 2) return m;
  }

  m.normal = Rotate(refXf.q, flip ? -refNormal : refNormal);
  // The count in a local and the id's fixed part once (MakeFeatureId's fields): kept in memory
  // and recomputed, they were reloaded for every point.
  const uint32_t idBase = MakeFeatureId(uint32_t(refEdge), 0, flip);
  int count = 0;
  for (const ClipVertex& cv : clip2) {
    const Real separation = Dot(refNormal, cv.v - r1);
    if (separation > speculative) continue;
    ManifoldPoint& mp = m.points[count++];
    mp.separation = separation;
    // Halfway between the incident vertex and the reference face.
    mp.point = TransformPoint(refXf, cv.v - Real(0.5) * separation * refNormal);
    mp.id = idBase | ((cv.feature & 0xFFu) << 8);
  }
  m.pointCount = count;
  return m;
}

template <int kA, int kB, bool kSideSkin = false>
[[gnu::always_inline]] inline Manifold CollidePolygonsT(const Polygon& a, Transform xfA, const Polygon& b, Transform xfB, Real speculative) {
  const int aCount = kA > 0 ? kA : a.count;
  const int bCount = kB > 0 ? kB : b.count;
  // Each polygon's vertices in the other's frame, so both axis searches are plain dot products.
  const Transform bInA = InvMulTransforms(xfA, xfB);
  const Transform aInB = InvMulTransforms(xfB, xfA);
  Vec2 bVerts[kMaxPolygonVertices];
  Vec2 aVerts[kMaxPolygonVertices];
  int edgeA = 0, edgeB = 0;
  Real sepA, sepB;
#if QUADRANT_NARROW_SIMD
  if constexpr (kA == 4 && kB == 4) {
    const Four bFour = TransformFour(bInA, LoadFour(b.vertices.data()));
    sepA = MaxSeparationFour(a, bFour, &edgeA);
    if (sepA > speculative) return Manifold{};
    const Four aFour = TransformFour(aInB, LoadFour(a.vertices.data()));
    sepB = MaxSeparationFour(b, aFour, &edgeB);
    if (sepB > speculative) return Manifold{};
    StoreFour(bFour, bVerts);
    StoreFour(aFour, aVerts);
  } else
#endif
  {
    for (int i = 0; i < bCount; ++i) bVerts[i] = TransformPoint(bInA, b.vertices[i]);
    for (int i = 0; i < aCount; ++i) aVerts[i] = TransformPoint(aInB, a.vertices[i]);
    sepA = MaxSeparation<kA, kB>(a, bVerts, bCount, &edgeA);
    if (sepA > speculative) return Manifold{};
    sepB = MaxSeparation<kB, kA>(b, aVerts, aCount, &edgeB);
    if (sepB > speculative) return Manifold{};
  }
  return ClipPolygons<kA, kB, kSideSkin>(a, xfA, b, xfB, speculative, sepA, edgeA, sepB, edgeB, aVerts, bVerts, bInA.q,
                                         aInB.q);
}

#if QUADRANT_NARROW_SIMD && defined(__x86_64__) && defined(__GNUC__)
// The box-box case for CPUs with AVX: both axis searches at once in eight lanes (lanes 0-3 a's
// faces against b's vertices in a's frame, lanes 4-7 b's faces against a's vertices in b's
// frame), each lane doing the scalar code's operations in its order, then ClipPolygons compiled
// in AVX's three-operand encoding. The same manifold bit for bit (the state hashes did not move;
// NarrowPhaseBoxes compares it with the general path). The searches no longer stop after a's
// when it already separates the boxes: nearly every box pair that reaches this test touches
// (base-100 pyramid: 9998 contacts of 10000 pairs; the bounding circles reject the rest first).
// Base-100 pyramid (callgrind, 10 steps from rest, 100000 calls): 478 instructions a pair with
// the four-lane searches one after the other (590 in SSE2's encoding); 439 with the eight-lane
// search and ArgMaxFour; 413 with the relative transforms below (the transforms by reference);
// 403 with ClipToTwo; 394 with ClipPolygons taking the transforms by reference.
[[gnu::target("avx"), gnu::always_inline]] inline Manifold CollideBoxesVexInline(const Polygon& a, const Transform& xfA,
                                                                              const Polygon& b, const Transform& xfB,
                                                                              Real speculative) {
  // InvMulTransforms(xfA, xfB) in lanes 0-1 and InvMulTransforms(xfB, xfA) in lanes 2-3, the
  // same products and sums (a - b is a + (-b) exactly, so the sign flips are exact): bInA and
  // aInB from one load of each transform ([p.x, p.y, q.c, q.s]) instead of unpacking two
  // register pairs (the transforms came by value in two registers each, then 30 instructions of
  // moves and shifts went into taking them apart).
  const __m128 A = _mm_loadu_ps(&xfA.p.x), B = _mm_loadu_ps(&xfB.p.x);
  const __m128 negOdd = _mm_castsi128_ps(_mm_set_epi32(int(0x80000000u), 0, int(0x80000000u), 0));
  const __m128 dBA = _mm_sub_ps(B, A), dAB = _mm_sub_ps(A, B);
  // InvRotate(q, d) = {c d.x + s d.y, (-s) d.x + c d.y}
  const __m128 relP = _mm_add_ps(
      _mm_mul_ps(_mm_xor_ps(_mm_shuffle_ps(A, B, _MM_SHUFFLE(3, 2, 3, 2)), negOdd), _mm_shuffle_ps(dBA, dAB, 0x00)),
      _mm_mul_ps(_mm_shuffle_ps(A, B, _MM_SHUFFLE(2, 3, 2, 3)), _mm_shuffle_ps(dBA, dAB, 0x55)));
  // InvMul(q, r) = {q.c r.c + q.s r.s, q.c r.s - q.s r.c}
  const __m128 relQ = _mm_add_ps(
      _mm_mul_ps(_mm_shuffle_ps(A, B, 0xAA), _mm_shuffle_ps(B, A, _MM_SHUFFLE(3, 2, 3, 2))),
      _mm_xor_ps(_mm_mul_ps(_mm_shuffle_ps(A, B, 0xFF), _mm_shuffle_ps(B, A, _MM_SHUFFLE(2, 3, 2, 3))), negOdd));
  alignas(16) Real q[4];
  _mm_store_ps(q, relQ);
  // Each transform's values in all four lanes of its half: bInA's in 0-3, aInB's in 4-7.
  const __m256 relP8 = _mm256_set_m128(_mm_movehl_ps(relP, relP), relP);
  const __m256 relQ8 = _mm256_set_m128(_mm_movehl_ps(relQ, relQ), relQ);
  const Four av = LoadFour(a.vertices.data()), bv = LoadFour(b.vertices.data());
  const Four an = LoadFour(a.normals.data()), bn = LoadFour(b.normals.data());
  // TransformFour in each half: b's vertices by bInA, a's by aInB.
  const __m256 vx = _mm256_set_m128(av.x, bv.x), vy = _mm256_set_m128(av.y, bv.y);
  const __m256 c = _mm256_permute_ps(relQ8, 0x00), s = _mm256_permute_ps(relQ8, 0x55);
  const __m256 tx = _mm256_add_ps(_mm256_sub_ps(_mm256_mul_ps(c, vx), _mm256_mul_ps(s, vy)), _mm256_permute_ps(relP8, 0x00));
  const __m256 ty = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(s, vx), _mm256_mul_ps(c, vy)), _mm256_permute_ps(relP8, 0x55));
  // MaxSeparationFour in each half: the faces' normals and first vertices, the other's vertices
  // splatted one at a time (an in-lane permute splats within each half).
  const __m256 nx = _mm256_set_m128(bn.x, an.x), ny = _mm256_set_m128(bn.y, an.y);
  const __m256 fx = _mm256_set_m128(bv.x, av.x), fy = _mm256_set_m128(bv.y, av.y);
  __m256 minDot = _mm256_set1_ps(FLT_MAX);
#define QUADRANT_BOX_VERTEX(j)                                                                            \
  minDot = _mm256_min_ps(                                                                                 \
      _mm256_add_ps(_mm256_mul_ps(nx, _mm256_sub_ps(_mm256_permute_ps(tx, (j) * 0x55), fx)),              \
                    _mm256_mul_ps(ny, _mm256_sub_ps(_mm256_permute_ps(ty, (j) * 0x55), fy))),             \
      minDot)
  QUADRANT_BOX_VERTEX(0);
  QUADRANT_BOX_VERTEX(1);
  QUADRANT_BOX_VERTEX(2);
  QUADRANT_BOX_VERTEX(3);
#undef QUADRANT_BOX_VERTEX
  Real sepA, sepB;
  const int edgeA = ArgMaxFour(_mm256_castps256_ps128(minDot), &sepA);
  if (sepA > speculative) return Manifold{};
  const int edgeB = ArgMaxFour(_mm256_extractf128_ps(minDot, 1), &sepB);
  if (sepB > speculative) return Manifold{};
  // StoreFour in each half: b's vertices (in a's frame) and a's (in b's) as Vec2 arrays.
  alignas(32) Vec2 verts[8];
  const __m256 lo = _mm256_unpacklo_ps(tx, ty), hi = _mm256_unpackhi_ps(tx, ty);
  _mm256_store_ps(&verts[0].x, _mm256_permute2f128_ps(lo, hi, 0x20));
  _mm256_store_ps(&verts[4].x, _mm256_permute2f128_ps(lo, hi, 0x31));
  return ClipPolygons<4, 4>(a, xfA, b, xfB, speculative, sepA, edgeA, sepB, edgeB, verts + 4, verts, Rot{q[0], q[1]},
                            Rot{q[2], q[3]});
}

[[gnu::target("avx"), gnu::noinline]] Manifold CollideBoxesVex(const Polygon& a, const Transform& xfA, const Polygon& b,
                                                                const Transform& xfB, Real speculative) {
  return CollideBoxesVexInline(a, xfA, b, xfB, speculative);
}

bool BoxesVex() {
  static const bool has = __builtin_cpu_supports("avx");
  return has;
}
#endif

// Out of line, so the dispatcher below stays a few instructions (with both inlined it set up a
// frame for both: 45 instructions a call).
[[gnu::noinline]] Manifold CollideBoxes(const Polygon& a, const Transform& xfA, const Polygon& b,
                                        const Transform& xfB, Real speculative) {
  return CollidePolygonsT<4, 4>(a, xfA, b, xfB, speculative);
}
[[gnu::noinline]] Manifold CollideAnyPolygons(const Polygon& a, Transform xfA, const Polygon& b, Transform xfB,
                                              Real speculative) {
  return CollidePolygonsT<0, 0>(a, xfA, b, xfB, speculative);
}

// CollidePolygons and Collide inlined into the pair loop below, which then calls the box-box
// collider straight (base-100 pyramid: Collide and CollidePolygons were 53 instructions a pair
// on the way to it).
[[gnu::always_inline]] inline Manifold CollidePolygonsInline(const Polygon& a, const Transform& xfA, const Polygon& b,
                                                              const Transform& xfB, Real speculative) {
  if (a.count == 4 && b.count == 4) {
#if QUADRANT_NARROW_SIMD && defined(__x86_64__) && defined(__GNUC__)
    if (BoxesVex()) return CollideBoxesVex(a, xfA, b, xfB, speculative);
#endif
    return CollideBoxes(a, xfA, b, xfB, speculative);
  }
  return CollideAnyPolygons(a, xfA, b, xfB, speculative);
}

[[gnu::always_inline]] inline Manifold CollideInline(const ShapeDef& a, const Transform& xfA, const ShapeDef& b,
                                                     const Transform& xfB, Real speculative) {
  // One test for a capsule or a segment on either side (every type after kPolygon has a bit
  // above bit 0 set; circles and polygons none).
  static_assert(uint8_t(ShapeType::kPolygon) == 1 && uint8_t(ShapeType::kCircle) == 0);
  if ((uint8_t(a.type) | uint8_t(b.type)) > 1) [[unlikely]] return CollideRareShapes(a, xfA, b, xfB, speculative);
  if (a.type == ShapeType::kCircle) {
    if (b.type == ShapeType::kCircle) return CollideCircles(a.circle, xfA, b.circle, xfB, speculative);
    Manifold m = CollidePolygonAndCircle(b.polygon, xfB, a.circle, xfA, speculative);
    m.normal = -m.normal;
    return m;
  }
  if (b.type == ShapeType::kCircle) return CollidePolygonAndCircle(a.polygon, xfA, b.circle, xfB, speculative);
  return CollidePolygonsInline(a.polygon, xfA, b.polygon, xfB, speculative);
}

}  // namespace

Manifold CollidePolygons(const Polygon& a, Transform xfA, const Polygon& b, Transform xfB, Real speculative) {
  return CollidePolygonsInline(a, xfA, b, xfB, speculative);
}

Manifold CollidePolygonsGeneral(const Polygon& a, Transform xfA, const Polygon& b, Transform xfB, Real speculative) {
  return CollideAnyPolygons(a, xfA, b, xfB, speculative);
}

Manifold CollidePolygonsBox2d(const Polygon& a, Transform xfA, const Polygon& b, Transform xfB, Real radius) {
  return CollidePolygonsT<0, 0, true>(a, xfA, b, xfB, radius);
}

Manifold Collide(const ShapeDef& a, Transform xfA, const ShapeDef& b, Transform xfB, Real speculative) {
  return CollideInline(a, xfA, b, xfB, speculative);
}

// The pair loop of the narrow phase (narrow_pair_loop.inc), in two builds: for CPUs with AVX
// (the box collider inlined) and for the rest (the SSE2 box collider called).
namespace {

struct CallBoxes {
  static constexpr bool kBatch = false;  // one pair at a time
  Manifold operator()(const Polygon& a, const Transform& xfA, const Polygon& b, const Transform& xfB, Real spec) const {
    return CollideBoxes(a, xfA, b, xfB, spec);
  }
};

namespace pairs_default {
#include "collision/narrow_pair_loop.inc"
}  // namespace pairs_default

#if QUADRANT_NARROW_SIMD && defined(__x86_64__) && defined(__GNUC__)
// Box pairs eight at a time (box_batch.h). Base-100 pyramid, 2-core VM: the narrow phase
// 0.618 -> 0.322 ms a step at 1 thread, 0.345 -> 0.220 ms at 2.
struct VexBoxes {
  static constexpr bool kBatch = true;  // eight at a time (CollideBoxBatch)
  [[gnu::target("avx"), gnu::always_inline]] Manifold operator()(const Polygon& a, const Transform& xfA, const Polygon& b,
                                                                   const Transform& xfB, Real spec) const {
    return CollideBoxesVexInline(a, xfA, b, xfB, spec);
  }
};

// The pair loop compiled for AVX with the box collider inlined into it: called, the collider
// cost about 40 instructions a pair in the call itself (arguments, the caller's spills and
// reloads around it, the callee's frame) and the copy of its manifold out of the return slot.
#pragma GCC push_options
#pragma GCC target("avx")
namespace pairs_vex {
#include "collision/narrow_pair_loop.inc"
}  // namespace pairs_vex
#pragma GCC pop_options

[[gnu::target("avx"), gnu::noinline]] void CollidePairsVex(const Bodies& bodies, const WorldDef& def, Real dt,
                                                            std::span<const CandidatePair> pairs,
                                                            std::vector<Contact>& out, const RecycleSource* recycle) {
  pairs_vex::PairLoop(bodies, def, dt, pairs, out, VexBoxes{}, recycle);
}
#endif

}  // namespace

namespace {

// Box2D 2.4.1's contacts, on out[first..] after the pair loop (so the default path pays one test
// per block of pairs): with WorldDef::box2dPolygonClip each polygon pair's manifold is computed
// again as Box2D computes it (CollidePolygonsBox2d: touching points only); with
// WorldDef::speculativeContacts off every point still apart (beyond the pair's polygon skin) is
// dropped. A contact left with no point is dropped. Only pairs the loop kept are seen: one whose
// incident edge lies wholly beyond the face's ends but within the skin of them (a corner grazing
// a corner) gets no contact here where Box2D's extended side planes would give it one.
void KeepTouchingPoints(const Bodies& bodies, const WorldDef& def, std::vector<Contact>& out, size_t first) {
  size_t kept = first;
  for (size_t i = first; i < out.size(); ++i) {
    Contact c = out[i];
    const ShapeDef& sa = bodies.shape[c.a];
    const ShapeDef& sb = bodies.shape[c.b];
    const Real skin = PolygonSkin(def, sa.type == ShapeType::kPolygon, sb.type == ShapeType::kPolygon);
    if (def.box2dPolygonClip && sa.type == ShapeType::kPolygon && sb.type == ShapeType::kPolygon) {
      const Manifold m = CollidePolygonsBox2d(sa.polygon, bodies.xf[c.a], sb.polygon, bodies.xf[c.b], skin);
      c.manifold = m;
      for (int k = 0; k < m.pointCount; ++k) {
        ManifoldPoint& mp = c.manifold.points[k];
        mp.anchorA = mp.point - bodies.center[c.a];
        mp.anchorB = mp.point - bodies.center[c.b];
        mp.baseSeparation = mp.separation;
      }
      c.recycleQA = c.recycleQB = Rot{0, 0};  // never recycled
    }
    int n = 0;
    for (int k = 0; k < c.manifold.pointCount; ++k) {
      if (def.speculativeContacts || c.manifold.points[k].separation <= skin) c.manifold.points[n++] = c.manifold.points[k];
    }
    c.manifold.pointCount = n;
    if (n > 0) out[kept++] = c;
  }
  out.resize(kept);
}

}  // namespace

// Compound bodies (narrow_phase_compound.cpp) never reach the pair loops: with any in the world,
// their pairs are split off here, so the loops are the same code with or without them. Box2D
// 2.4.1's contacts (KeepTouchingPoints) filter whatever either path produced.
void CollidePairs(const Bodies& bodies, const WorldDef& def, Real dt, std::span<const CandidatePair> pairs,
                  std::vector<Contact>& out, const RecycleSource* recycle) {
  const size_t first = out.size();
  if (bodies.compoundCount > 0) [[unlikely]] {
    CollidePairsWithCompounds(bodies, def, dt, pairs, out, recycle);
  } else {
    CollideSimplePairs(bodies, def, dt, pairs, out, recycle);
  }
  if (!def.speculativeContacts || def.box2dPolygonClip) [[unlikely]] KeepTouchingPoints(bodies, def, out, first);
}

void CollideSimplePairs(const Bodies& bodies, const WorldDef& def, Real dt, std::span<const CandidatePair> pairs,
                        std::vector<Contact>& out, const RecycleSource* recycle) {
  if (!def.effects.continuous && bodies.bulletCount > 0) {  // bullets without continuous collision
    pairs_default::PairLoop<CallBoxes, true>(bodies, def, dt, pairs, out, CallBoxes{}, recycle);
    return;
  }
#if QUADRANT_NARROW_SIMD && defined(__x86_64__) && defined(__GNUC__)
  if (BoxesVex()) {
    CollidePairsVex(bodies, def, dt, pairs, out, recycle);
    return;
  }
#endif
  pairs_default::PairLoop(bodies, def, dt, pairs, out, CallBoxes{}, recycle);
}

}  // namespace quadrant
