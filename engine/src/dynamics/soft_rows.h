// soft_step's contact rows in structure-of-arrays form, solved eight at a time (AVX), four at a
// time (SSE2) or one at a time, with the same result bit for bit.
//
// The rows of one graph colour share no body that moves, so any eight of them can be solved at
// once: a group holds eight consecutive rows of a colour (a colour's last group is padded with
// rows that touch nothing). The kernel is written once over a lane type V (soft_rows_kernels.inc):
// `float` (one row, the scalar path), F4 (four rows in an SSE2 register: a group is two calls) or
// F8 (eight rows in an AVX register, on CPUs with AVX). Every lane does the same IEEE operations
// in the same order in all three (no FMA: -ffp-contract=off, and neither target has it), max and
// min are defined as the SSE instructions define them (a > b ? a : b), and all paths read and
// write the same padded data: so the scalar and the SIMD paths give the same state hash (a
// test checks it), and splitting a colour across threads changes nothing either.
//
// Why: on the base-100 pyramid (10000 two-point contacts) the row passes were 60 % of the
// step's instructions, about 300-400 instructions per row and pass in the array-of-structures
// form (callgrind); docs/soft_step.md gives the figures after.
//
// A one-point manifold's second point is padding: zero mass, zero lever arms and a large
// separation, so it never pushes (its impulse stays 0).
#pragma once

#include <cmath>
#include <cstdint>
#include <atomic>
#include <cstring>
#include <type_traits>
#include <vector>

#include "quadrant/math.h"

#if defined(__SSE2__) && !defined(QUADRANT_DOUBLE)
#include <immintrin.h>
#define QUADRANT_SOFT_SIMD 1
#else
#define QUADRANT_SOFT_SIMD 0
#endif

namespace quadrant {

// The part of a body the sub-stepping solver reads and writes (32 bytes in float): velocity,
// and how far the body has moved (dp) and turned (dq) since the step began. Kept apart from the
// body arrays so a constraint row touches two of these and nothing else of its bodies.
struct SolverBody {
  Vec2 v;
  Real w = 0;
  Real pad = 0;
  Vec2 dp;
  Rot dq;
};
static_assert(sizeof(SolverBody) == 8 * sizeof(Real));

constexpr int kLanes = 4;  // an SSE2 register's floats
// Rows a group holds: eight, solved eight at a time on CPUs with AVX (F8), as two halves of four
// (SSE2, F4) or one at a time, with the same bits.
constexpr int kGroupRows = 8;

struct SoftPointRows {
  Real rAx[kGroupRows], rAy[kGroupRows], rBx[kGroupRows], rBy[kGroupRows];
  Real separation[kGroupRows];  // at collision time (the padding point: kPadSeparation)
  Real normalMass[kGroupRows], tangentMass[kGroupRows];
  Real normalImpulse[kGroupRows], tangentImpulse[kGroupRows];
  Real collisionImpulse[kGroupRows];  // a sub-step's share of the step's collisions, for the friction bound
};

// Eight rows of one colour. Softness is per row: contacts with a static or kinematic body are
// stiffer (solver_soft_step.cpp says why).
struct alignas(32) SoftRowGroup {
  int32_t a[kGroupRows], b[kGroupRows];
  int32_t constraint[kGroupRows];  // index in the solver's constraint list, -1 for padding
  Real nx[kGroupRows], ny[kGroupRows], friction[kGroupRows];
  Real invMassA[kGroupRows], invIA[kGroupRows], invMassB[kGroupRows], invIB[kGroupRows];
  Real biasRate[kGroupRows], massScale[kGroupRows], impulseScale[kGroupRows];
  SoftPointRows p[2];
};

constexpr Real kPadSeparation = Real(1e6);

// ---- lane types -------------------------------------------------------------------------------

inline Real Load(const Real* x, int lane, Real) { return x[lane]; }
inline void Store(Real* x, int lane, Real v) { x[lane] = v; }
inline Real Splat(Real x, Real) { return x; }
inline Real Max(Real a, Real b) { return a > b ? a : b; }
inline Real Min(Real a, Real b) { return a < b ? a : b; }
inline Real Neg(Real a) { return -a; }
// mask ? a : b, with the mask the result of a comparison.
inline Real Select(bool mask, Real a, Real b) { return mask ? a : b; }
inline bool Greater(Real a, Real b) { return a > b; }
inline bool GreaterEqual(Real a, Real b) { return a >= b; }
inline bool Less(Real a, Real b) { return a < b; }
inline bool And(bool a, bool b) { return a && b; }
inline bool AndNot(bool a, bool b) { return !a && b; }
// mask ? x : +0.
inline Real Masked(bool mask, Real x) { return mask ? x : Real(0); }
inline bool Any(bool m) { return m; }
inline Real Div(Real a, Real b) { return a / b; }
inline Real Sqrt(Real a) { return std::sqrt(a); }

#if QUADRANT_SOFT_SIMD
struct F4 {
  __m128 v;
};
struct M4 {
  __m128 v;
};
inline F4 operator+(F4 a, F4 b) { return {_mm_add_ps(a.v, b.v)}; }
inline F4 operator-(F4 a, F4 b) { return {_mm_sub_ps(a.v, b.v)}; }
inline F4 operator*(F4 a, F4 b) { return {_mm_mul_ps(a.v, b.v)}; }
inline F4& operator+=(F4& a, F4 b) { return a = a + b; }
inline F4& operator-=(F4& a, F4 b) { return a = a - b; }
inline F4 Load(const Real* x, int lane, F4) { return {_mm_load_ps(x + lane)}; }
inline void Store(Real* x, int lane, F4 v) { _mm_store_ps(x + lane, v.v); }
inline F4 Splat(Real x, F4) { return {_mm_set1_ps(x)}; }
inline F4 Max(F4 a, F4 b) { return {_mm_max_ps(a.v, b.v)}; }
inline F4 Min(F4 a, F4 b) { return {_mm_min_ps(a.v, b.v)}; }
inline F4 Neg(F4 a) { return {_mm_xor_ps(a.v, _mm_set1_ps(-0.0f))}; }
inline F4 Select(M4 mask, F4 a, F4 b) { return {_mm_or_ps(_mm_and_ps(mask.v, a.v), _mm_andnot_ps(mask.v, b.v))}; }
inline M4 Greater(F4 a, F4 b) { return {_mm_cmpgt_ps(a.v, b.v)}; }
inline M4 GreaterEqual(F4 a, F4 b) { return {_mm_cmpge_ps(a.v, b.v)}; }
inline M4 Less(F4 a, F4 b) { return {_mm_cmplt_ps(a.v, b.v)}; }
inline M4 And(M4 a, M4 b) { return {_mm_and_ps(a.v, b.v)}; }
inline M4 AndNot(M4 a, M4 b) { return {_mm_andnot_ps(a.v, b.v)}; }
inline F4 Masked(M4 mask, F4 x) { return {_mm_and_ps(mask.v, x.v)}; }
inline bool Any(M4 m) { return _mm_movemask_ps(m.v) != 0; }
inline F4 Div(F4 a, F4 b) { return {_mm_div_ps(a.v, b.v)}; }
inline F4 Sqrt(F4 a) { return {_mm_sqrt_ps(a.v)}; }
#endif

// The bodies of a row (lanes [lane, lane + width)), gathered from the solver states.
template <class V>
struct RowBodies {
  V vx, vy, w, pad, dpx, dpy, qc, qs;
};

template <class V>
inline void Gather(const SolverBody* states, const int32_t* index, int lane, RowBodies<V>& out);
template <class V>
inline void Scatter(SolverBody* states, const int32_t* index, const Real* invMass, int lane, const RowBodies<V>& in);

template <>
[[gnu::always_inline]] inline void Gather<Real>(const SolverBody* states, const int32_t* index, int lane, RowBodies<Real>& out) {
  const SolverBody& s = states[index[lane]];
  out = {s.v.x, s.v.y, s.w, s.pad, s.dp.x, s.dp.y, s.dq.c, s.dq.s};
}
// Static and kinematic bodies (inverse mass 0) are never written: other rows of the colour
// (and other threads) may be reading them.
template <>
[[gnu::always_inline]] inline void Scatter<Real>(SolverBody* states, const int32_t* index, const Real* invMass, int lane,
                          const RowBodies<Real>& in) {
  if (invMass[lane] == 0) return;
  SolverBody& s = states[index[lane]];
  s.v = {in.vx, in.vy};
  s.w = in.w;
}

// The motion half of a state (dp, dq), for the position pass.
template <class V>
inline void ScatterMotion(SolverBody* states, const int32_t* index, const Real* invMass, int lane,
                          const RowBodies<V>& in);
template <>
[[gnu::always_inline]] inline void ScatterMotion<Real>(SolverBody* states, const int32_t* index, const Real* invMass,
                                                       int lane, const RowBodies<Real>& in) {
  if (invMass[lane] == 0) return;
  SolverBody& s = states[index[lane]];
  s.dp = {in.dpx, in.dpy};
  s.dq = {in.qc, in.qs};
}

#if QUADRANT_SOFT_SIMD
// Bit k set: lane k's inverse mass is not zero (the body moves and its state is written).
[[gnu::always_inline]] inline int WrittenLanes(const Real* invMass) {
  return _mm_movemask_ps(_mm_cmpneq_ps(_mm_load_ps(invMass), _mm_setzero_ps()));
}

template <>
[[gnu::always_inline]] inline void Gather<F4>(const SolverBody* states, const int32_t* index, int lane,
                                              RowBodies<F4>& out) {
  index += lane;
  const float* s0 = &states[index[0]].v.x;
  const float* s1 = &states[index[1]].v.x;
  const float* s2 = &states[index[2]].v.x;
  const float* s3 = &states[index[3]].v.x;
  __m128 r0 = _mm_loadu_ps(s0), r1 = _mm_loadu_ps(s1), r2 = _mm_loadu_ps(s2), r3 = _mm_loadu_ps(s3);
  _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
  out.vx = {r0};
  out.vy = {r1};
  out.w = {r2};
  out.pad = {r3};
  r0 = _mm_loadu_ps(s0 + 4), r1 = _mm_loadu_ps(s1 + 4), r2 = _mm_loadu_ps(s2 + 4), r3 = _mm_loadu_ps(s3 + 4);
  _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
  out.dpx = {r0};
  out.dpy = {r1};
  out.qc = {r2};
  out.qs = {r3};
}
template <>
[[gnu::always_inline]] inline void Scatter<F4>(SolverBody* states, const int32_t* index, const Real* invMass, int lane,
                        const RowBodies<F4>& in) {
  index += lane;
  invMass += lane;
  // The pad word is written as zero (it is zero in every state), so the gathered one need not
  // be kept in a register through the row.
  __m128 r0 = in.vx.v, r1 = in.vy.v, r2 = in.w.v, r3 = _mm_setzero_ps();
  _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
  // Which lanes move (invMass != 0, NaN included as the scalar test has it), as one mask from the
  // row's inverse masses (already in a register): four bit tests instead of four float compares.
  const int moves = WrittenLanes(invMass);
  if (moves & 1) _mm_storeu_ps(&states[index[0]].v.x, r0);
  if (moves & 2) _mm_storeu_ps(&states[index[1]].v.x, r1);
  if (moves & 4) _mm_storeu_ps(&states[index[2]].v.x, r2);
  if (moves & 8) _mm_storeu_ps(&states[index[3]].v.x, r3);
}
template <>
[[gnu::always_inline]] inline void ScatterMotion<F4>(SolverBody* states, const int32_t* index, const Real* invMass,
                                                     int lane, const RowBodies<F4>& in) {
  index += lane;
  invMass += lane;
  __m128 r0 = in.dpx.v, r1 = in.dpy.v, r2 = in.qc.v, r3 = in.qs.v;
  _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
  const int moves = WrittenLanes(invMass);
  if (moves & 1) _mm_storeu_ps(&states[index[0]].dp.x, r0);
  if (moves & 2) _mm_storeu_ps(&states[index[1]].dp.x, r1);
  if (moves & 4) _mm_storeu_ps(&states[index[2]].dp.x, r2);
  if (moves & 8) _mm_storeu_ps(&states[index[3]].dp.x, r3);
}
#endif

// ---- the kernels' parameters ----------------------------------------------------------------

struct SoftSolveParams {
  Real invH = 0;
  Real pushMaxDepth = 0;     // WorldDef::contactPushMaxDepth
  Real pushMaxVelocity = 0;  // WorldDef::contactPushMaxVelocity
  // A relax pass that computes the separations sets *deep (when given) if a point is deeper than
  // deepBelow: solver_soft_step.cpp then knows whether its position pass can move anything.
  std::atomic<bool>* deep = nullptr;
  Real deepBelow = 0;
  // The point of a row solved first (0 or 1; the other follows), in the normal and the friction
  // rows alike. solver_soft_step.cpp alternates it (SubStep says why).
  int firstPoint = 0;
};

// What a relax pass does with the speculative bias (sep > 0 ? sep / h : 0). The relax passes of
// a sub-step all run at the same positions (nothing moves the bodies between them), so with two
// or more the first computes it from the separation and stores it, and the later ones load it
// and need neither the bodies' motion nor the separation: the same values, so the same bits.
// Base-100 pyramid: the friction relax pass went from 593 to 471 instructions a group (callgrind).
enum class RelaxBias { kCompute, kComputeAndStore, kLoad };

// The relax bias store of a group: point k's lanes at [k * kGroupRows, (k + 1) * kGroupRows).
struct alignas(32) RelaxBiasRows {
  Real bias[2 * kGroupRows];
};

struct SoftPositionParams {
  Real allowed = 0;        // penetration left alone (WorldDef::contactPushMaxDepth), beyond LoadCompression
  Real baumgarte = 0;
  Real maxCorrection = 0;  // WorldDef::maxLinearCorrection
};

// ---- kernels (soft_rows_kernels.inc) ---------------------------------------------------------

// In a namespace of their own (and wide8's below in another), so that argument-dependent lookup
// from one copy never finds the other.
namespace rows4 {
#include "dynamics/soft_rows_kernels.inc"
}  // namespace rows4

#if QUADRANT_SOFT_SIMD
// The four-body integration in soft_step_state.cpp turns its bodies as the position pass does.
[[gnu::always_inline]] inline void TurnBy(F4& c, F4& s, F4 a) { rows4::TurnBy(c, s, a); }
#endif

// ---- eight rows at a time with AVX, and the entry points ------------------------------------------
//
// On CPUs with AVX (checked once, at run time: WorldDef::softVex) the kernels are compiled a second
// time, eight-wide: F8 is eight rows in a 256-bit register. Rows of one colour share no body that
// moves, so eight lanes do what four or one do, each lane the same IEEE operations in the same
// order (no FMA: -ffp-contract=off and the target does not include it; max and min as the SSE
// instructions define them), and the state is the same bit for bit as the scalar and the SSE2
// paths (SoftSimdTest). A body state is 32 bytes, so a gather is four pairs of 16-byte loads
// (body k and body k + 4 in one register) and a 4x4 transpose in each 128-bit half.
//
// Base-100 pyramid, callgrind, instructions a row and pass (four-wide in AVX's encoding -> eight-wide):
// soft solve 83 -> 48, first relax pass 84 -> 45, friction relax pass 72 -> 41, warm start 39 ->
// 25 (with the stores below; docs/soft_step.md has the step). Eight-wide with AVX-512VL's 32 registers
// (no spills) was 2.4 % faster on one thread, within a loaded machine's noise: not kept.
//
// The kernels are included again (soft_rows_kernels.inc) in namespace wide8 under
// `#pragma GCC target("avx")`, so that they and the F8 operations are compiled for AVX while the
// scalar and SSE2 paths stay SSE2 for CPUs without it.
#if QUADRANT_SOFT_SIMD && defined(__x86_64__) && defined(__GNUC__)
#define QUADRANT_SOFT_VEX 1
struct F8Avx {};  // the lane tag that picks the eight-wide AVX kernels

inline bool CpuHasAvx() {
  static const bool has = __builtin_cpu_supports("avx");
  return has;
}

#pragma GCC push_options
#pragma GCC target("avx")
struct F8 {
  __m256 v;
};
struct M8 {
  __m256 v;
};
inline F8 operator+(F8 a, F8 b) { return {_mm256_add_ps(a.v, b.v)}; }
inline F8 operator-(F8 a, F8 b) { return {_mm256_sub_ps(a.v, b.v)}; }
inline F8 operator*(F8 a, F8 b) { return {_mm256_mul_ps(a.v, b.v)}; }
inline F8& operator+=(F8& a, F8 b) { return a = a + b; }
inline F8& operator-=(F8& a, F8 b) { return a = a - b; }
inline F8 Load(const Real* x, int lane, F8) { return {_mm256_load_ps(x + lane)}; }
inline void Store(Real* x, int lane, F8 v) { _mm256_store_ps(x + lane, v.v); }
inline F8 Splat(Real x, F8) { return {_mm256_set1_ps(x)}; }
inline F8 Max(F8 a, F8 b) { return {_mm256_max_ps(a.v, b.v)}; }
inline F8 Min(F8 a, F8 b) { return {_mm256_min_ps(a.v, b.v)}; }
inline F8 Neg(F8 a) { return {_mm256_xor_ps(a.v, _mm256_set1_ps(-0.0f))}; }
// With and/or, as F4's: GCC 12 turned _mm256_blendv_ps on these masks into a branch per lane (the
// soft solve took 773 instructions a group instead of 413).
inline F8 Select(M8 mask, F8 a, F8 b) {
  return {_mm256_or_ps(_mm256_and_ps(mask.v, a.v), _mm256_andnot_ps(mask.v, b.v))};
}
inline M8 Greater(F8 a, F8 b) { return {_mm256_cmp_ps(a.v, b.v, _CMP_GT_OS)}; }
inline M8 GreaterEqual(F8 a, F8 b) { return {_mm256_cmp_ps(a.v, b.v, _CMP_GE_OS)}; }
inline M8 Less(F8 a, F8 b) { return {_mm256_cmp_ps(a.v, b.v, _CMP_LT_OS)}; }
inline M8 And(M8 a, M8 b) { return {_mm256_and_ps(a.v, b.v)}; }
inline M8 AndNot(M8 a, M8 b) { return {_mm256_andnot_ps(a.v, b.v)}; }
inline F8 Masked(M8 mask, F8 x) { return {_mm256_and_ps(mask.v, x.v)}; }
inline bool Any(M8 m) { return _mm256_movemask_ps(m.v) != 0; }
inline F8 Div(F8 a, F8 b) { return {_mm256_div_ps(a.v, b.v)}; }
inline F8 Sqrt(F8 a) { return {_mm256_sqrt_ps(a.v)}; }

// Bodies k and k + 4's four words at `word` in one register (k in the low half).
[[gnu::always_inline]] inline __m256 LoadPair(const SolverBody* states, const int32_t* index, int k, int word) {
  const float* lo = &states[index[k]].v.x + word;
  const float* hi = &states[index[k + 4]].v.x + word;
  return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(lo)), _mm_loadu_ps(hi), 1);
}
// A 4x4 transpose in each 128-bit half.
[[gnu::always_inline]] inline void Transpose4x2(__m256& r0, __m256& r1, __m256& r2, __m256& r3) {
  const __m256 t0 = _mm256_unpacklo_ps(r0, r1), t1 = _mm256_unpackhi_ps(r0, r1);
  const __m256 t2 = _mm256_unpacklo_ps(r2, r3), t3 = _mm256_unpackhi_ps(r2, r3);
  r0 = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0));
  r1 = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2));
  r2 = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0));
  r3 = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2));
}
[[gnu::always_inline]] inline int WrittenLanes8(const Real* invMass) {
  return _mm256_movemask_ps(_mm256_cmp_ps(_mm256_load_ps(invMass), _mm256_setzero_ps(), _CMP_NEQ_UQ));
}
// Stores body k's four words from the low half of r and body k + 4's from the high half, each
// only if it moves.
[[gnu::always_inline]] inline void StorePair(SolverBody* states, const int32_t* index, int moves, int k, int word,
                                             __m256 r) {
  if (moves & (1 << k)) _mm_storeu_ps(&states[index[k]].v.x + word, _mm256_castps256_ps128(r));
  if (moves & (16 << k)) _mm_storeu_ps(&states[index[k + 4]].v.x + word, _mm256_extractf128_ps(r, 1));
}
// The four pairs' stores: when every lane moves (all but the rows on static bodies and the
// padding), without a test per lane.
[[gnu::always_inline]] inline void StorePairs(SolverBody* states, const int32_t* index, int moves, int word, __m256 r0,
                                              __m256 r1, __m256 r2, __m256 r3) {
  if (moves == 0xFF) {
    StorePair(states, index, 0xFF, 0, word, r0);
    StorePair(states, index, 0xFF, 1, word, r1);
    StorePair(states, index, 0xFF, 2, word, r2);
    StorePair(states, index, 0xFF, 3, word, r3);
  } else {
    StorePair(states, index, moves, 0, word, r0);
    StorePair(states, index, moves, 1, word, r1);
    StorePair(states, index, moves, 2, word, r2);
    StorePair(states, index, moves, 3, word, r3);
  }
}

template <>
[[gnu::always_inline]] inline void Gather<F8>(const SolverBody* states, const int32_t* index, int lane,
                                              RowBodies<F8>& out) {
  index += lane;
  __m256 r0 = LoadPair(states, index, 0, 0), r1 = LoadPair(states, index, 1, 0);
  __m256 r2 = LoadPair(states, index, 2, 0), r3 = LoadPair(states, index, 3, 0);
  Transpose4x2(r0, r1, r2, r3);
  out.vx = {r0};
  out.vy = {r1};
  out.w = {r2};
  out.pad = {r3};
  r0 = LoadPair(states, index, 0, 4), r1 = LoadPair(states, index, 1, 4);
  r2 = LoadPair(states, index, 2, 4), r3 = LoadPair(states, index, 3, 4);
  Transpose4x2(r0, r1, r2, r3);
  out.dpx = {r0};
  out.dpy = {r1};
  out.qc = {r2};
  out.qs = {r3};
}
template <>
[[gnu::always_inline]] inline void Scatter<F8>(SolverBody* states, const int32_t* index, const Real* invMass, int lane,
                                               const RowBodies<F8>& in) {
  index += lane;
  __m256 r0 = in.vx.v, r1 = in.vy.v, r2 = in.w.v, r3 = _mm256_setzero_ps();  // pad written as zero (Scatter<F4>)
  Transpose4x2(r0, r1, r2, r3);
  const int moves = WrittenLanes8(invMass + lane);
  StorePairs(states, index, moves, 0, r0, r1, r2, r3);
}
template <>
[[gnu::always_inline]] inline void ScatterMotion<F8>(SolverBody* states, const int32_t* index, const Real* invMass,
                                                     int lane, const RowBodies<F8>& in) {
  index += lane;
  __m256 r0 = in.dpx.v, r1 = in.dpy.v, r2 = in.qc.v, r3 = in.qs.v;
  Transpose4x2(r0, r1, r2, r3);
  const int moves = WrittenLanes8(invMass + lane);
  StorePairs(states, index, moves, 4, r0, r1, r2, r3);
}

namespace wide8 {
#include "dynamics/soft_rows_kernels.inc"

template <bool kRotation>
[[gnu::noinline]] void WarmStartRows8(SolverBody* states, SoftRowGroup& g) {
  WarmStartRowsImpl<F8, kRotation>(states, g, 0);
}
template <bool kRotation, bool kFriction, bool kBias, RelaxBias kRelax>
[[gnu::noinline]] void SolveRows8(SolverBody* states, SoftRowGroup& g, const SoftSolveParams& prm,
                                  RelaxBiasRows* cache) {
  if (prm.firstPoint != 0) {
    SolveRowsImpl<F8, kRotation, kFriction, kBias, kRelax, 1>(states, g, 0, prm, cache);
  } else {
    SolveRowsImpl<F8, kRotation, kFriction, kBias, kRelax, 0>(states, g, 0, prm, cache);
  }
}
template <bool kRotation>
[[gnu::noinline]] bool SolvePositionRows8(SolverBody* states, const SoftRowGroup& g, const SoftPositionParams& prm,
                                          bool& moved) {
  return SolvePositionRowsImpl<F8, kRotation>(states, g, 0, prm, moved);
}
}  // namespace wide8
#pragma GCC pop_options
#else
#define QUADRANT_SOFT_VEX 0
struct F8Avx {};  // never passed: no AVX path in this build
inline bool CpuHasAvx() { return false; }
#endif

// Lanes a kernel call covers: 1 (Real), 4 (F4, SSE2) or 8 (F8Avx, AVX).
template <class V>
constexpr int kLaneWidth = std::is_same_v<V, F8Avx> ? 8 : std::is_same_v<V, Real> ? 1 : 4;

// The kernels by lane type V: Real (the row at `lane`), F4 (the four from `lane`) or F8Avx (all
// eight; lane 0).
template <class V, bool kRotation>
inline void WarmStartRows(SolverBody* states, SoftRowGroup& g, int lane) {
#if QUADRANT_SOFT_VEX
  if constexpr (std::is_same_v<V, F8Avx>) {
    wide8::WarmStartRows8<kRotation>(states, g);
    return;
  } else
#endif
  {
    if constexpr (!std::is_same_v<V, F8Avx>) rows4::WarmStartRowsImpl<V, kRotation>(states, g, lane);
  }
}

template <class V, bool kRotation, bool kFriction, bool kBias, RelaxBias kRelax = RelaxBias::kCompute>
inline void SolveRows(SolverBody* states, SoftRowGroup& g, int lane, const SoftSolveParams& prm,
                      RelaxBiasRows* cache = nullptr) {
#if QUADRANT_SOFT_VEX
  if constexpr (std::is_same_v<V, F8Avx>) {
    wide8::SolveRows8<kRotation, kFriction, kBias, kRelax>(states, g, prm, cache);
    return;
  } else
#endif
  {
    if constexpr (!std::is_same_v<V, F8Avx>) {
      if (prm.firstPoint != 0) {
        rows4::SolveRowsImpl<V, kRotation, kFriction, kBias, kRelax, 1>(states, g, lane, prm, cache);
      } else {
        rows4::SolveRowsImpl<V, kRotation, kFriction, kBias, kRelax, 0>(states, g, lane, prm, cache);
      }
    }
  }
}

template <class V, bool kRotation>
inline bool SolvePositionRows(SolverBody* states, const SoftRowGroup& g, int lane, const SoftPositionParams& prm,
                              bool& moved) {
#if QUADRANT_SOFT_VEX
  if constexpr (std::is_same_v<V, F8Avx>) {
    return wide8::SolvePositionRows8<kRotation>(states, g, prm, moved);
  } else
#endif
  {
    if constexpr (!std::is_same_v<V, F8Avx>) return rows4::SolvePositionRowsImpl<V, kRotation>(states, g, lane, prm, moved);
    return false;
  }
}

}  // namespace quadrant
