// Box pairs eight at a time (box_batch.h says why). Each step below names the scalar code it
// mirrors (narrow_phase.cpp: CollidePolygonsT<0, 0>, MaxSeparation, ClipPolygons, ClipToTwo);
// a lane does that code's float operations in its order, and a branch of it becomes a mask
// that picks between lanes' values, so a lane's result is the scalar result bit for bit.
// -ffp-contract=off (CMakeLists.txt) keeps the compiler from fusing a multiply and an add here
// as it keeps it from doing so there.
#include "collision/box_batch.h"

#include <cfloat>
#include <cstdint>

#if defined(__SSE2__) && !defined(QUADRANT_DOUBLE) && defined(__x86_64__) && defined(__GNUC__)
#define QUADRANT_BOX_BATCH 1
#include <immintrin.h>
#else
#define QUADRANT_BOX_BATCH 0
#endif

namespace quadrant {

#if QUADRANT_BOX_BATCH
bool BoxBatchInLanes() {
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
}

// AVX2, though only AVX's float operations are used: GCC 12 turns _mm256_blendv_ps into a
// per-lane select, and with AVX alone it lowers that select to a test and a branch for each of
// the eight lanes (a few hundred instructions a batch); with AVX2 it is the one vblendvps.
#pragma GCC push_options
#pragma GCC target("avx2")
namespace {

using V = __m256;

inline V Splat(float x) { return _mm256_set1_ps(x); }
inline V Add(V a, V b) { return _mm256_add_ps(a, b); }
inline V Sub(V a, V b) { return _mm256_sub_ps(a, b); }
inline V Mul(V a, V b) { return _mm256_mul_ps(a, b); }
// -x exactly (the sign bit flipped), as the scalar unary minus.
inline V Neg(V a) { return _mm256_xor_ps(a, _mm256_set1_ps(-0.0f)); }
// b where mask, else a.
inline V Pick(V a, V b, V mask) { return _mm256_blendv_ps(a, b, mask); }
inline V And(V a, V b) { return _mm256_and_ps(a, b); }
inline V Or(V a, V b) { return _mm256_or_ps(a, b); }
template <int kCmp>
inline V Cmp(V a, V b) {
  return _mm256_cmp_ps(a, b, kCmp);
}

// Rows of eight floats (a polygon's vertices or normals: x0 y0 x1 y1 x2 y2 x3 y3), one per
// lane, turned into eight columns: out[c] holds float c of every lane's row.
inline void Transpose8(const float* const rows[8], V out[8]) {
  const V r0 = _mm256_loadu_ps(rows[0]), r1 = _mm256_loadu_ps(rows[1]), r2 = _mm256_loadu_ps(rows[2]),
          r3 = _mm256_loadu_ps(rows[3]), r4 = _mm256_loadu_ps(rows[4]), r5 = _mm256_loadu_ps(rows[5]),
          r6 = _mm256_loadu_ps(rows[6]), r7 = _mm256_loadu_ps(rows[7]);
  const V t0 = _mm256_unpacklo_ps(r0, r1), t1 = _mm256_unpackhi_ps(r0, r1);
  const V t2 = _mm256_unpacklo_ps(r2, r3), t3 = _mm256_unpackhi_ps(r2, r3);
  const V t4 = _mm256_unpacklo_ps(r4, r5), t5 = _mm256_unpackhi_ps(r4, r5);
  const V t6 = _mm256_unpacklo_ps(r6, r7), t7 = _mm256_unpackhi_ps(r6, r7);
  const V s0 = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0)), s1 = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2));
  const V s2 = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0)), s3 = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2));
  const V s4 = _mm256_shuffle_ps(t4, t6, _MM_SHUFFLE(1, 0, 1, 0)), s5 = _mm256_shuffle_ps(t4, t6, _MM_SHUFFLE(3, 2, 3, 2));
  const V s6 = _mm256_shuffle_ps(t5, t7, _MM_SHUFFLE(1, 0, 1, 0)), s7 = _mm256_shuffle_ps(t5, t7, _MM_SHUFFLE(3, 2, 3, 2));
  out[0] = _mm256_permute2f128_ps(s0, s4, 0x20);
  out[1] = _mm256_permute2f128_ps(s1, s5, 0x20);
  out[2] = _mm256_permute2f128_ps(s2, s6, 0x20);
  out[3] = _mm256_permute2f128_ps(s3, s7, 0x20);
  out[4] = _mm256_permute2f128_ps(s0, s4, 0x31);
  out[5] = _mm256_permute2f128_ps(s1, s5, 0x31);
  out[6] = _mm256_permute2f128_ps(s2, s6, 0x31);
  out[7] = _mm256_permute2f128_ps(s3, s7, 0x31);
}

struct XfLanes {
  V px, py, c, s;
};

// Eight transforms ([p.x, p.y, q.c, q.s] each), one per lane, as four columns.
inline XfLanes TransposeXf(const Transform* const xf[8]) {
  auto row = [&](int k) {
    return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(&xf[k]->p.x)), _mm_loadu_ps(&xf[k + 4]->p.x), 1);
  };
  const V r0 = row(0), r1 = row(1), r2 = row(2), r3 = row(3);
  const V u0 = _mm256_unpacklo_ps(r0, r1), u1 = _mm256_unpackhi_ps(r0, r1);
  const V u2 = _mm256_unpacklo_ps(r2, r3), u3 = _mm256_unpackhi_ps(r2, r3);
  return {_mm256_shuffle_ps(u0, u2, _MM_SHUFFLE(1, 0, 1, 0)), _mm256_shuffle_ps(u0, u2, _MM_SHUFFLE(3, 2, 3, 2)),
          _mm256_shuffle_ps(u1, u3, _MM_SHUFFLE(1, 0, 1, 0)), _mm256_shuffle_ps(u1, u3, _MM_SHUFFLE(3, 2, 3, 2))};
}

// A box's four points (vertices or normals) in every lane: x[i], y[i] for point i.
struct Quad {
  V x[4], y[4];
};

inline Quad QuadFromColumns(const V cols[8]) {
  return {{cols[0], cols[2], cols[4], cols[6]}, {cols[1], cols[3], cols[5], cols[7]}};
}

// Lane by lane: q's point idx (idx holds 0.0f, 1.0f, 2.0f or 3.0f).
inline V PickOf(const V v[4], V idx) {
  V r = v[0];
  r = Pick(r, v[1], Cmp<_CMP_EQ_OQ>(idx, Splat(1)));
  r = Pick(r, v[2], Cmp<_CMP_EQ_OQ>(idx, Splat(2)));
  r = Pick(r, v[3], Cmp<_CMP_EQ_OQ>(idx, Splat(3)));
  return r;
}

// TransformPoint(xf, v) for each of the four points: Rotate(q, v) + p.
inline Quad TransformQuad(V px, V py, V c, V s, const Quad& v) {
  Quad out;
  for (int j = 0; j < 4; ++j) {
    out.x[j] = Add(Sub(Mul(c, v.x[j]), Mul(s, v.y[j])), px);
    out.y[j] = Add(Add(Mul(s, v.x[j]), Mul(c, v.y[j])), py);
  }
  return out;
}

// MaxSeparation<4, 4>: for each face i of the box (normal n[i], first vertex v[i]) the smallest
// Dot(n, w - v) over the other box's vertices w (in this box's frame), `d < min ? d : min` from
// FLT_MAX (_mm256_min_ps(d, min) is exactly that); then the first face with the largest, taken
// only when strictly larger than the best so far from -FLT_MAX (a NaN is never taken).
inline V MaxSeparation(const Quad& n, const Quad& v, const Quad& w, V* edge) {
  V best = Splat(-FLT_MAX), bestEdge = Splat(0);
  for (int i = 0; i < 4; ++i) {
    V minDot = Splat(FLT_MAX);
    for (int j = 0; j < 4; ++j) {
      const V d = Add(Mul(n.x[i], Sub(w.x[j], v.x[i])), Mul(n.y[i], Sub(w.y[j], v.y[i])));
      minDot = _mm256_min_ps(d, minDot);
    }
    const V take = Cmp<_CMP_GT_OQ>(minDot, best);
    best = Pick(best, minDot, take);
    bestEdge = Pick(bestEdge, Splat(float(i)), take);
  }
  *edge = bestEdge;
  return best;
}

// A clip vertex in every lane: its point and its feature (ClipVertex::feature as a float: the
// incident vertex 0-3, or 0x80 | side).
struct Clip {
  V x, y, feature;
};

// ClipToTwo: keeps the part of (in0, in1) where Dot(n, p) <= offset. Lanes where the scalar
// code gives up (fewer than two points) are cleared in *ok.
inline void ClipToTwo(Clip& out0, Clip& out1, const Clip& in0, const Clip& in1, V nx, V ny, V offset, float side, V* ok) {
  const V d0 = Sub(Add(Mul(nx, in0.x), Mul(ny, in0.y)), offset);
  const V d1 = Sub(Add(Mul(nx, in1.x), Mul(ny, in1.y)), offset);
  const V keep0 = Cmp<_CMP_LE_OQ>(d0, Splat(0)), keep1 = Cmp<_CMP_LE_OQ>(d1, Splat(0));
  const V both = And(keep0, keep1);
  const V cross = Cmp<_CMP_LT_OQ>(Mul(d0, d1), Splat(0));
  *ok = And(*ok, Or(both, cross));
  const V t = _mm256_div_ps(d0, Sub(d0, d1));
  // Both ends kept: (in0, in1). One kept: the kept end, then the crossing.
  out0 = {Pick(in1.x, in0.x, keep0), Pick(in1.y, in0.y, keep0), Pick(in1.feature, in0.feature, keep0)};
  out1 = {Pick(Add(in0.x, Mul(t, Sub(in1.x, in0.x))), in1.x, both), Pick(Add(in0.y, Mul(t, Sub(in1.y, in0.y))), in1.y, both),
          Pick(Splat(float(0x80u | unsigned(side))), in1.feature, both)};
}

}  // namespace

// CollideBoxBatch's eight-lane path (called only where BoxBatchInLanes()).
static void CollideBoxBatchVex(const BoxPair* pairs, int count, Manifold* out) {
  // Lanes past `count` repeat pair 0; their results are not written.
  const float* aVertRows[8];
  const float* aNormRows[8];
  const float* bVertRows[8];
  const float* bNormRows[8];
  const Transform* xfAs[8];
  const Transform* xfBs[8];
  alignas(32) float specs[8];
  for (int k = 0; k < 8; ++k) {
    const BoxPair& p = pairs[k < count ? k : 0];
    aVertRows[k] = &p.a->vertices[0].x;
    aNormRows[k] = &p.a->normals[0].x;
    bVertRows[k] = &p.b->vertices[0].x;
    bNormRows[k] = &p.b->normals[0].x;
    xfAs[k] = p.xfA;
    xfBs[k] = p.xfB;
    specs[k] = p.speculative;
  }
  V cols[8];
  Transpose8(aVertRows, cols);
  const Quad av = QuadFromColumns(cols);
  Transpose8(aNormRows, cols);
  const Quad an = QuadFromColumns(cols);
  Transpose8(bVertRows, cols);
  const Quad bv = QuadFromColumns(cols);
  Transpose8(bNormRows, cols);
  const Quad bn = QuadFromColumns(cols);
  const XfLanes A = TransposeXf(xfAs), B = TransposeXf(xfBs);
  const V spec = _mm256_load_ps(specs);

  // CollidePolygonsT: bInA = InvMulTransforms(xfA, xfB), aInB = InvMulTransforms(xfB, xfA):
  // {InvRotate(a.q, b.p - a.p), InvMul(a.q, b.q)}, InvRotate(q, d) = {c d.x + s d.y, -s d.x + c d.y},
  // InvMul(q, r) = {q.c r.c + q.s r.s, q.c r.s - q.s r.c}.
  const V dx = Sub(B.px, A.px), dy = Sub(B.py, A.py);
  const V bInAx = Add(Mul(A.c, dx), Mul(A.s, dy)), bInAy = Add(Mul(Neg(A.s), dx), Mul(A.c, dy));
  const V bInAc = Add(Mul(A.c, B.c), Mul(A.s, B.s)), bInAs = Sub(Mul(A.c, B.s), Mul(A.s, B.c));
  const V ex = Sub(A.px, B.px), ey = Sub(A.py, B.py);
  const V aInBx = Add(Mul(B.c, ex), Mul(B.s, ey)), aInBy = Add(Mul(Neg(B.s), ex), Mul(B.c, ey));
  const V aInBc = Add(Mul(B.c, A.c), Mul(B.s, A.s)), aInBs = Sub(Mul(B.c, A.s), Mul(B.s, A.c));
  // Each box's vertices in the other's frame, then the two axis searches.
  const Quad bInA = TransformQuad(bInAx, bInAy, bInAc, bInAs, bv);
  const Quad aInB = TransformQuad(aInBx, aInBy, aInBc, aInBs, av);
  V edgeA, edgeB;
  const V sepA = MaxSeparation(an, av, bInA, &edgeA);
  const V sepB = MaxSeparation(bn, bv, aInB, &edgeB);
  // `if (sep > speculative) return Manifold{}` for either search.
  V ok = And(Cmp<_CMP_NGT_UQ>(sepA, spec), Cmp<_CMP_NGT_UQ>(sepB, spec));

  // ClipPolygons: b's face is the reference only when clearly better (kAxisPreference).
  const V flip = Cmp<_CMP_GT_OQ>(sepB, Add(sepA, Splat(0.0005f)));
  const V refEdge = Pick(edgeA, edgeB, flip);
  Quad refN, refV, incN, incV;
  for (int i = 0; i < 4; ++i) {
    refN.x[i] = Pick(an.x[i], bn.x[i], flip);
    refN.y[i] = Pick(an.y[i], bn.y[i], flip);
    refV.x[i] = Pick(av.x[i], bv.x[i], flip);
    refV.y[i] = Pick(av.y[i], bv.y[i], flip);
    incN.x[i] = Pick(bn.x[i], an.x[i], flip);
    incN.y[i] = Pick(bn.y[i], an.y[i], flip);
    incV.x[i] = Pick(bInA.x[i], aInB.x[i], flip);  // the incident vertices in the reference frame
    incV.y[i] = Pick(bInA.y[i], aInB.y[i], flip);
  }
  const V rnx = PickOf(refN.x, refEdge), rny = PickOf(refN.y, refEdge);
  // The incident edge: the first whose normal, turned into the reference frame, has the smallest
  // Dot with the reference normal (strictly smaller than the best so far, from FLT_MAX).
  const V ic = Pick(bInAc, aInBc, flip), is = Pick(bInAs, aInBs, flip);
  V minDot = Splat(FLT_MAX), incEdge = Splat(0);
  for (int i = 0; i < 4; ++i) {
    const V rx = Sub(Mul(ic, incN.x[i]), Mul(is, incN.y[i]));
    const V ry = Add(Mul(is, incN.x[i]), Mul(ic, incN.y[i]));
    const V d = Add(Mul(rnx, rx), Mul(rny, ry));
    const V take = Cmp<_CMP_LT_OQ>(d, minDot);
    minDot = Pick(minDot, d, take);
    incEdge = Pick(incEdge, Splat(float(i)), take);
  }
  const V four = Splat(4);
  const V incNext = [&] {
    const V next = Add(incEdge, Splat(1));
    return Pick(next, Splat(0), Cmp<_CMP_EQ_OQ>(next, four));
  }();
  const Clip in0{PickOf(incV.x, incEdge), PickOf(incV.y, incEdge), incEdge};
  const Clip in1{PickOf(incV.x, incNext), PickOf(incV.y, incNext), incNext};
  // The reference edge's ends and its unit tangent (Normalize: {0, 0} below a length of 1e-12).
  const V refNext = [&] {
    const V next = Add(refEdge, Splat(1));
    return Pick(next, Splat(0), Cmp<_CMP_EQ_OQ>(next, four));
  }();
  const V r1x = PickOf(refV.x, refEdge), r1y = PickOf(refV.y, refEdge);
  const V r2x = PickOf(refV.x, refNext), r2y = PickOf(refV.y, refNext);
  const V ddx = Sub(r2x, r1x), ddy = Sub(r2y, r1y);
  const V len = _mm256_sqrt_ps(Add(Mul(ddx, ddx), Mul(ddy, ddy)));
  const V tiny = Cmp<_CMP_LT_OQ>(len, Splat(1e-12f));
  const V inv = _mm256_div_ps(Splat(1), len);
  const V tx = Pick(Mul(ddx, inv), Splat(0), tiny), ty = Pick(Mul(ddy, inv), Splat(0), tiny);
  // Two clips: against the side plane at r1 (normal -tangent), then at r2 (normal tangent).
  Clip c1a, c1b, c2a, c2b;
  ClipToTwo(c1a, c1b, in0, in1, Neg(tx), Neg(ty), Neg(Add(Mul(tx, r1x), Mul(ty, r1y))), 0, &ok);
  ClipToTwo(c2a, c2b, c1a, c1b, tx, ty, Add(Mul(tx, r2x), Mul(ty, r2y)), 1, &ok);

  // The manifold: the normal Rotate(refXf.q, flip ? -refNormal : refNormal); each clipped point's
  // separation from the reference face, kept when not above `speculative`, placed halfway between
  // the incident vertex and the face (TransformPoint(refXf, v - 0.5 separation refNormal)).
  const V rc = Pick(A.c, B.c, flip), rs = Pick(A.s, B.s, flip);
  const V rpx = Pick(A.px, B.px, flip), rpy = Pick(A.py, B.py, flip);
  const V nnx = Pick(rnx, Neg(rnx), flip), nny = Pick(rny, Neg(rny), flip);
  // Out to arrays, one lane a pair; the lanes' masks as bits. The feature id, refEdge | (flip ?
  // 0x10000 : 0) | (feature & 0xFF) << 8 (MakeFeatureId), is summed in floats: every part is an
  // integer below 2^24 and the fields do not overlap, so the sum is exact.
  alignas(32) float normalX[8], normalY[8], sepOut[2][8], pxOut[2][8], pyOut[2][8];
  alignas(32) int32_t idOut[2][8];
  _mm256_store_ps(normalX, Sub(Mul(rc, nnx), Mul(rs, nny)));
  _mm256_store_ps(normalY, Add(Mul(rs, nnx), Mul(rc, nny)));
  const V idBase = Add(refEdge, And(flip, Splat(65536.0f)));
  const Clip* clipped[2] = {&c2a, &c2b};
  int keepBits[2];
  for (int k = 0; k < 2; ++k) {
    const Clip& cv = *clipped[k];
    const V sep = Add(Mul(rnx, Sub(cv.x, r1x)), Mul(rny, Sub(cv.y, r1y)));
    const V half = Mul(Splat(0.5f), sep);
    const V wx = Sub(cv.x, Mul(half, rnx)), wy = Sub(cv.y, Mul(half, rny));
    keepBits[k] = _mm256_movemask_ps(Cmp<_CMP_NGT_UQ>(sep, spec));
    _mm256_store_ps(sepOut[k], sep);
    _mm256_store_ps(pxOut[k], Add(Sub(Mul(rc, wx), Mul(rs, wy)), rpx));
    _mm256_store_ps(pyOut[k], Add(Add(Mul(rs, wx), Mul(rc, wy)), rpy));
    _mm256_store_si256(reinterpret_cast<__m256i*>(idOut[k]),
                       _mm256_cvttps_epi32(Add(idBase, Mul(cv.feature, Splat(256.0f)))));
  }
  const int okBits = _mm256_movemask_ps(ok);
  for (int k = 0; k < count; ++k) {
    Manifold& m = out[k];
    if (!((okBits >> k) & 1)) {
      m = Manifold{};
      continue;
    }
    m.normal = {normalX[k], normalY[k]};
    int n = 0;
    for (int p = 0; p < 2; ++p) {
      if (!((keepBits[p] >> k) & 1)) continue;
      m.points[n++] = {{pxOut[p][k], pyOut[p][k]}, sepOut[p][k], uint32_t(idOut[p][k]), 0, 0, {}, {}, 0};
    }
    m.pointCount = n;
    for (int p = n; p < 2; ++p) m.points[p] = ManifoldPoint{};
  }
}
#pragma GCC pop_options

void CollideBoxBatch(const BoxPair* pairs, int count, Manifold* out) {
  if (BoxBatchInLanes()) {
    CollideBoxBatchVex(pairs, count, out);
    return;
  }
  for (int k = 0; k < count; ++k) {
    out[k] = CollidePolygons(*pairs[k].a, *pairs[k].xfA, *pairs[k].b, *pairs[k].xfB, pairs[k].speculative);
  }
}
#else
bool BoxBatchInLanes() { return false; }

void CollideBoxBatch(const BoxPair* pairs, int count, Manifold* out) {
  for (int k = 0; k < count; ++k) {
    out[k] = CollidePolygons(*pairs[k].a, *pairs[k].xfA, *pairs[k].b, *pairs[k].xfB, pairs[k].speculative);
  }
}
#endif

}  // namespace quadrant
