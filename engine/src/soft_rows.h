// soft_step's contact rows in structure-of-arrays form, solved four at a time (SSE2) or one at a
// time, with the same result bit for bit.
//
// The rows of one graph colour share no body that moves, so any four of them can be solved at
// once: a group holds four consecutive rows of a colour (a colour's last group is padded with
// rows that touch nothing). The kernel is written once over a lane type V: `float` (one row,
// the scalar path) or F4 (four rows in an SSE2 register). Every lane does the same IEEE
// operations in the same order in both (no FMA: -ffp-contract=off, and SSE2 has none), max and
// min are defined as the SSE2 instructions define them (a > b ? a : b), and both paths read and
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
#include <emmintrin.h>
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

constexpr int kLanes = 4;

struct SoftPointRows {
  Real rAx[kLanes], rAy[kLanes], rBx[kLanes], rBy[kLanes];
  Real separation[kLanes];  // at collision time (the padding point: kPadSeparation)
  Real normalMass[kLanes], tangentMass[kLanes];
  Real normalImpulse[kLanes], tangentImpulse[kLanes];
  Real collisionImpulse[kLanes];  // a sub-step's share of the step's collisions, for the friction bound
};

// Four rows of one colour. Softness is per row: contacts with a static or kinematic body are
// stiffer (solver_soft_step.cpp says why).
struct alignas(16) SoftRowGroup {
  int32_t a[kLanes], b[kLanes];
  int32_t constraint[kLanes];  // index in the solver's constraint list, -1 for padding
  Real nx[kLanes], ny[kLanes], friction[kLanes];
  Real invMassA[kLanes], invIA[kLanes], invMassB[kLanes], invIB[kLanes];
  Real biasRate[kLanes], massScale[kLanes], impulseScale[kLanes];
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
[[gnu::always_inline]] inline void Gather<F4>(const SolverBody* states, const int32_t* index, int, RowBodies<F4>& out) {
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
[[gnu::always_inline]] inline void Scatter<F4>(SolverBody* states, const int32_t* index, const Real* invMass, int,
                        const RowBodies<F4>& in) {
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
                                                     int, const RowBodies<F4>& in) {
  __m128 r0 = in.dpx.v, r1 = in.dpy.v, r2 = in.qc.v, r3 = in.qs.v;
  _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
  const int moves = WrittenLanes(invMass);
  if (moves & 1) _mm_storeu_ps(&states[index[0]].dp.x, r0);
  if (moves & 2) _mm_storeu_ps(&states[index[1]].dp.x, r1);
  if (moves & 4) _mm_storeu_ps(&states[index[2]].dp.x, r2);
  if (moves & 8) _mm_storeu_ps(&states[index[3]].dp.x, r3);
}
#endif

// ---- kernels ----------------------------------------------------------------------------------

// The impulse (Px, Py) through a row's point, taken off body A and put on body B at the lever
// arms rA, rB (the warm start, the normal and the friction rows all apply it so).
template <class V, bool kRotation>
[[gnu::always_inline]] inline void ApplyRowImpulse(RowBodies<V>& A, RowBodies<V>& B, V mA, V iA, V mB, V iB, V rAx,
                                                   V rAy, V rBx, V rBy, V Px, V Py) {
  A.vx -= mA * Px;
  A.vy -= mA * Py;
  B.vx += mB * Px;
  B.vy += mB * Py;
  if constexpr (kRotation) {
    A.w -= iA * (rAx * Py - rAy * Px);
    B.w += iB * (rBx * Py - rBy * Px);
  }
}

struct SoftSolveParams {
  Real invH = 0;
  Real pushMaxDepth = 0;     // WorldDef::contactPushMaxDepth
  Real pushMaxVelocity = 0;  // WorldDef::contactPushMaxVelocity
  // A relax pass that computes the separations sets *deep (when given) if a point is deeper than
  // deepBelow: solver_soft_step.cpp then knows whether its position pass can move anything.
  std::atomic<bool>* deep = nullptr;
  Real deepBelow = 0;
};

// Warm start: last sub-step's (or step's) accumulated impulses applied again.
template <class V, bool kRotation>
[[gnu::always_inline]] inline void WarmStartRowsImpl(SolverBody* states, SoftRowGroup& g, int lane) {
  RowBodies<V> A, B;
  Gather<V>(states, g.a, lane, A);
  Gather<V>(states, g.b, lane, B);
  const V nx = Load(g.nx, lane, V{}), ny = Load(g.ny, lane, V{});
  const V tx = ny, ty = Neg(nx);  // RightPerp(n)
  const V mA = Load(g.invMassA, lane, V{}), iA = Load(g.invIA, lane, V{});
  const V mB = Load(g.invMassB, lane, V{}), iB = Load(g.invIB, lane, V{});
  for (int k = 0; k < 2; ++k) {
    SoftPointRows& p = g.p[k];
    const V ni = Load(p.normalImpulse, lane, V{}), ti = Load(p.tangentImpulse, lane, V{});
    const V Px = ni * nx + ti * tx, Py = ni * ny + ti * ty;
    V rAx{}, rAy{}, rBx{}, rBy{};
    if constexpr (kRotation) {
      rAx = Load(p.rAx, lane, V{}), rAy = Load(p.rAy, lane, V{});
      rBx = Load(p.rBx, lane, V{}), rBy = Load(p.rBy, lane, V{});
    }
    ApplyRowImpulse<V, kRotation>(A, B, mA, iA, mB, iB, rAx, rAy, rBx, rBy, Px, Py);
  }
  Scatter<V>(states, g.a, g.invMassA, lane, A);
  Scatter<V>(states, g.b, g.invMassB, lane, B);
}

// What a relax pass does with the speculative bias (sep > 0 ? sep / h : 0). The relax passes of
// a sub-step all run at the same positions (nothing moves the bodies between them), so with two
// or more the first computes it from the separation and stores it, and the later ones load it
// and need neither the bodies' motion nor the separation: the same values, so the same bits.
// Base-100 pyramid: the friction relax pass went from 593 to 471 instructions a group (callgrind).
enum class RelaxBias { kCompute, kComputeAndStore, kLoad };

// The relax bias store of a group: point k's lanes at [k * kLanes, k * kLanes + kLanes).
struct alignas(16) RelaxBiasRows {
  Real bias[2 * kLanes];
};

// One pass over the rows: with kBias the soft solve (push-out toward zero separation at a
// bounded speed), without it the relax pass (rigid rows, no bias) and friction.
// solver_soft_step.cpp says why each is as it is. kRelax says where a relax pass takes its
// speculative bias from (`cache`: this group's store; unused by the soft solve).
template <class V, bool kRotation, bool kFriction, bool kBias, RelaxBias kRelax>
[[gnu::always_inline]] inline void SolveRowsImpl(SolverBody* states, SoftRowGroup& g, int lane,
                                                 const SoftSolveParams& prm, RelaxBiasRows* cache) {
  static_assert(!kBias || kRelax == RelaxBias::kCompute);
  RowBodies<V> A, B;
  Gather<V>(states, g.a, lane, A);
  Gather<V>(states, g.b, lane, B);
  const V zero = Splat(Real(0), V{}), one = Splat(Real(1), V{});
  const V nx = Load(g.nx, lane, V{}), ny = Load(g.ny, lane, V{});
  const V mA = Load(g.invMassA, lane, V{}), iA = Load(g.invIA, lane, V{});
  const V mB = Load(g.invMassB, lane, V{}), iB = Load(g.invIB, lane, V{});
  const V invH = Splat(prm.invH, V{});
  // The separation of point k now: the prepared one plus the normal part of how far the anchors
  // moved. A relax pass takes both points' first, so the bodies' motion is dead before the
  // impulses (fewer registers spilled: 434 -> 418 instructions a group, the bias stores
  // included); the soft solve, with more live values of its own, was 8 instructions a group slower
  // so and takes each where it is used (511 -> 505 with the lambda).
  const V dpx = B.dpx - A.dpx, dpy = B.dpy - A.dpy;
  auto separation = [&](int k) __attribute__((always_inline)) {
    const SoftPointRows& p = g.p[k];
    V dx = dpx, dy = dpy;
    if constexpr (kRotation) {
      const V rAx = Load(p.rAx, lane, V{}), rAy = Load(p.rAy, lane, V{});
      const V rBx = Load(p.rBx, lane, V{}), rBy = Load(p.rBy, lane, V{});
      dx += ((B.qc * rBx - B.qs * rBy) - rBx) - ((A.qc * rAx - A.qs * rAy) - rAx);
      dy += ((B.qs * rBx + B.qc * rBy) - rBy) - ((A.qs * rAx + A.qc * rAy) - rAy);
    }
    return Load(p.separation, lane, V{}) + (nx * dx + ny * dy);
  };
  V sepK[2];
  if constexpr (!kBias && kRelax != RelaxBias::kLoad) {
    sepK[0] = separation(0);
    sepK[1] = separation(1);
    if (prm.deep != nullptr) {
      const V below = Splat(prm.deepBelow, V{});
      if (Any(Less(sepK[0], below)) || Any(Less(sepK[1], below))) prm.deep->store(true, std::memory_order_relaxed);
    }
  }
  for (int k = 0; k < 2; ++k) {
    SoftPointRows& p = g.p[k];
    const V rAx = Load(p.rAx, lane, V{}), rAy = Load(p.rAy, lane, V{});
    const V rBx = Load(p.rBx, lane, V{}), rBy = Load(p.rBy, lane, V{});
    V bias, massScale = one, impulseScale = zero;
    if constexpr (kRelax == RelaxBias::kLoad) {
      bias = Load(cache->bias + k * kLanes, lane, V{});
    } else {
      const V sep = kBias ? separation(k) : sepK[k];
      // Speculative (still apart): may close the gap within the sub-step, no more.
      const auto apart = Greater(sep, zero);
      bias = Select(apart, sep * invH, zero);
      if constexpr (kRelax == RelaxBias::kComputeAndStore) Store(cache->bias + k * kLanes, lane, bias);
      if constexpr (kBias) {
        const V biasRate = Load(g.biasRate, lane, V{});
        const V maxVel = Neg(Splat(prm.pushMaxVelocity, V{}));
        const auto soft = GreaterEqual(sep, Neg(Splat(prm.pushMaxDepth, V{})));
        // Soft down to the depth cap; deeper, a rigid row pushing at the cap's rate.
        const V softBias = Max(biasRate * sep, maxVel);
        const V rigidBias = Max(Neg(biasRate) * Splat(prm.pushMaxDepth, V{}), maxVel);
        bias = Select(apart, bias, Select(soft, softBias, rigidBias));
        // A soft touching point takes the softness; apart or deep ones are rigid (scale 1, 0).
        // One mask for both: the same values as selecting on apart, then soft.
        const auto softTouching = AndNot(apart, soft);
        massScale = Select(softTouching, Load(g.massScale, lane, V{}), one);
        impulseScale = Masked(softTouching, Load(g.impulseScale, lane, V{}));
      }
    }
    V dvx = B.vx - A.vx, dvy = B.vy - A.vy;
    if constexpr (kRotation) {
      dvx += Neg(B.w) * rBy - Neg(A.w) * rAy;
      dvy += B.w * rBx - A.w * rAx;
    }
    const V vn = dvx * nx + dvy * ny;
    const V ni = Load(p.normalImpulse, lane, V{});
    const V impulse = Neg(Load(p.normalMass, lane, V{})) * massScale * (vn + bias) - impulseScale * ni;
    const V newImpulse = Max(ni + impulse, zero);
    const V lambda = newImpulse - ni;
    Store(p.normalImpulse, lane, newImpulse);
    const V Px = lambda * nx, Py = lambda * ny;
    ApplyRowImpulse<V, kRotation>(A, B, mA, iA, mB, iB, rAx, rAy, rBx, rBy, Px, Py);
  }
  if constexpr (kFriction && !kBias) {
    const V tx = ny, ty = Neg(nx);  // RightPerp(n)
    const V friction = Load(g.friction, lane, V{});
    for (int k = 0; k < 2; ++k) {
      SoftPointRows& p = g.p[k];
      const V rAx = Load(p.rAx, lane, V{}), rAy = Load(p.rAy, lane, V{});
      const V rBx = Load(p.rBx, lane, V{}), rBy = Load(p.rBy, lane, V{});
      V dvx = B.vx - A.vx, dvy = B.vy - A.vy;
      if constexpr (kRotation) {
        dvx += Neg(B.w) * rBy - Neg(A.w) * rAy;
        dvy += B.w * rBx - A.w * rAx;
      }
      const V vt = dvx * tx + dvy * ty;
      // Coulomb over the whole impact, as pgs: the step's collision impulse (ApplyCollisions)
      // counts, a 1/n share per sub-step (solver_soft_step.cpp says why). Bounded by the
      // sub-steps' normal impulse alone, a bouncing hit got almost no friction: the random
      // campaign's p90 difference to Box2D was 49 %, then 9.5 %, 6.7 % with the share (2000 hits,
      // seed 17).
      const V maxFriction = friction * (Load(p.normalImpulse, lane, V{}) + Load(p.collisionImpulse, lane, V{}));
      const V ti = Load(p.tangentImpulse, lane, V{});
      const V newImpulse = Min(Max(ti - Load(p.tangentMass, lane, V{}) * vt, Neg(maxFriction)), maxFriction);
      const V lambda = newImpulse - ti;
      Store(p.tangentImpulse, lane, newImpulse);
      const V Px = lambda * tx, Py = lambda * ty;
      ApplyRowImpulse<V, kRotation>(A, B, mA, iA, mB, iB, rAx, rAy, rBx, rBy, Px, Py);
    }
  }
  Scatter<V>(states, g.a, g.invMassA, lane, A);
  Scatter<V>(states, g.b, g.invMassB, lane, B);
}

// Turns a rotation by the angle a, as IntegrateRot (math.h) does for |a| < 0.5: the same
// polynomials and renormalisation, operation for operation. Larger angles need sin and cos,
// which have no four-wide form here: `small` says whether every lane is below 0.5.
template <class V>
[[gnu::always_inline]] inline void TurnBy(V& c, V& s, V a) {
  const V one = Splat(Real(1), V{});
  const V x2 = a * a;
  const V dc = one - x2 * (Splat(Real(0.5), V{}) - x2 * Splat(Real(1) / Real(24), V{}));
  const V ds = a * (one - x2 * (Splat(Real(1) / Real(6), V{}) - x2 * Splat(Real(1) / Real(120), V{})));
  const V nc = c * dc - s * ds;
  const V ns = s * dc + c * ds;
  const V inv = Div(one, Sqrt(nc * nc + ns * ns));
  c = nc * inv;
  s = ns * inv;
}

struct SoftPositionParams {
  Real allowed = 0;        // penetration left alone (WorldDef::contactPushMaxDepth)
  Real baumgarte = 0;
  Real maxCorrection = 0;  // WorldDef::maxLinearCorrection
};

// One non-linear Gauss-Seidel pass of the position correction (the same as pgs's
// SolvePositions in contact_solver.h, on the solver states): the penetration beyond `allowed`
// is reduced by the Baumgarte fraction, at most maxCorrection at a time, moving and turning the
// bodies without giving them velocity. Lever arms are the anchors turned by the bodies' turn
// since the step began. Returns false, having written nothing, when the four-wide path would
// need a turn of 0.5 rad or more (the caller then solves the group one row at a time, where
// IntegrateRot takes sin and cos); sets `moved` when a row moved something.
template <class V, bool kRotation>
[[gnu::always_inline]] inline bool SolvePositionRowsImpl(SolverBody* states, const SoftRowGroup& g, int lane,
                                                         const SoftPositionParams& prm, bool& moved) {
  RowBodies<V> A, B;
  Gather<V>(states, g.a, lane, A);
  Gather<V>(states, g.b, lane, B);
  const V zero = Splat(Real(0), V{});
  const V nx = Load(g.nx, lane, V{}), ny = Load(g.ny, lane, V{});
  const V mA = Load(g.invMassA, lane, V{}), iA = Load(g.invIA, lane, V{});
  const V mB = Load(g.invMassB, lane, V{}), iB = Load(g.invIB, lane, V{});
  const V allowed = Splat(prm.allowed, V{}), baumgarte = Splat(prm.baumgarte, V{});
  const V maxCorrection = Neg(Splat(prm.maxCorrection, V{}));
  for (int k = 0; k < 2; ++k) {
    const SoftPointRows& p = g.p[k];
    const V pAx = Load(p.rAx, lane, V{}), pAy = Load(p.rAy, lane, V{});
    const V pBx = Load(p.rBx, lane, V{}), pBy = Load(p.rBy, lane, V{});
    V rAx = pAx, rAy = pAy, rBx = pBx, rBy = pBy;
    if constexpr (kRotation) {
      rAx = A.qc * pAx - A.qs * pAy;
      rAy = A.qs * pAx + A.qc * pAy;
      rBx = B.qc * pBx - B.qs * pBy;
      rBy = B.qs * pBx + B.qc * pBy;
    }
    const V dx = ((B.dpx - A.dpx) + (rBx - pBx)) - (rAx - pAx);
    const V dy = ((B.dpy - A.dpy) + (rBy - pBy)) - (rAy - pAy);
    const V sep = Load(p.separation, lane, V{}) + (nx * dx + ny * dy);
    const V C = Min(Max(baumgarte * (sep + allowed), maxCorrection), zero);
    V K = mA + mB;
    V rnA = zero, rnB = zero;
    if constexpr (kRotation) {
      rnA = rAx * ny - rAy * nx;
      rnB = rBx * ny - rBy * nx;
      K = K + (iA * rnA * rnA + iB * rnB * rnB);
    }
    const auto active = And(Less(C, zero), Greater(K, zero));
    if (!Any(active)) continue;
    const V impulse = Select(active, Div(Neg(C), K), zero);
    const V Px = impulse * nx, Py = impulse * ny;
    V turnA = zero, turnB = zero;
    if constexpr (kRotation) {
      turnA = Neg(iA) * (rAx * Py - rAy * Px);
      turnB = iB * (rBx * Py - rBy * Px);
      if constexpr (!std::is_same_v<V, Real>) {
        const V half = Splat(Real(0.5), V{});
        if (Any(GreaterEqual(Max(turnA, Neg(turnA)), half)) || Any(GreaterEqual(Max(turnB, Neg(turnB)), half))) {
          return false;
        }
      }
    }
    moved = true;
    A.dpx = Select(active, A.dpx - mA * Px, A.dpx);
    A.dpy = Select(active, A.dpy - mA * Py, A.dpy);
    B.dpx = Select(active, B.dpx + mB * Px, B.dpx);
    B.dpy = Select(active, B.dpy + mB * Py, B.dpy);
    if constexpr (kRotation) {
      if constexpr (std::is_same_v<V, Real>) {
        if (active) {
          const Rot qa = IntegrateRot(Rot{A.qc, A.qs}, turnA), qb = IntegrateRot(Rot{B.qc, B.qs}, turnB);
          A.qc = qa.c;
          A.qs = qa.s;
          B.qc = qb.c;
          B.qs = qb.s;
        }
      } else {
        V ac = A.qc, as = A.qs, bc = B.qc, bs = B.qs;
        TurnBy(ac, as, turnA);
        TurnBy(bc, bs, turnB);
        A.qc = Select(active, ac, A.qc);
        A.qs = Select(active, as, A.qs);
        B.qc = Select(active, bc, B.qc);
        B.qs = Select(active, bs, B.qs);
      }
    }
  }
  ScatterMotion<V>(states, g.a, g.invMassA, lane, A);
  ScatterMotion<V>(states, g.b, g.invMassB, lane, B);
  return true;
}

// ---- entry points and the AVX (VEX) encoding -----------------------------------------------------
//
// The kernels above are also compiled a second time for CPUs with AVX (gnu::target("avx")), called
// with the lane tag F4Vex: the same four-wide SSE operations on the same data, in AVX's
// three-operand encoding, which needs no register copies and spills less (16 xmm registers either
// way). The arithmetic is the same instruction for instruction (no FMA: -ffp-contract=off, and
// the target does not include it), so the state is the same bit for bit (SoftSimdTest, and the
// whole engine built with -mavx2 gave the same pyramid hash). WorldDef::softSimd picks it when the
// CPU has AVX (checked once, at run time); WorldDef::softVex = false keeps the SSE2 encoding.
// Base-100 pyramid, callgrind, instructions a group of four rows (SSE2 -> AVX encoding): soft
// solve 481 -> 330, first relax pass 404 -> 337, friction relax pass 453 -> 286, warm start 189 ->
// 156; the step 36.6M -> 32.3M.
#if QUADRANT_SOFT_SIMD && defined(__x86_64__) && defined(__GNUC__)
#define QUADRANT_SOFT_VEX 1
struct F4Vex {};

inline bool CpuHasAvx() {
  static const bool has = __builtin_cpu_supports("avx");
  return has;
}

template <bool kRotation>
[[gnu::target("avx"), gnu::noinline]] void WarmStartRowsVex(SolverBody* states, SoftRowGroup& g) {
  WarmStartRowsImpl<F4, kRotation>(states, g, 0);
}
template <bool kRotation, bool kFriction, bool kBias, RelaxBias kRelax>
[[gnu::target("avx"), gnu::noinline]] void SolveRowsVex(SolverBody* states, SoftRowGroup& g, const SoftSolveParams& prm,
                                                         RelaxBiasRows* cache) {
  SolveRowsImpl<F4, kRotation, kFriction, kBias, kRelax>(states, g, 0, prm, cache);
}
template <bool kRotation>
[[gnu::target("avx"), gnu::noinline]] bool SolvePositionRowsVex(SolverBody* states, const SoftRowGroup& g,
                                                                 const SoftPositionParams& prm, bool& moved) {
  return SolvePositionRowsImpl<F4, kRotation>(states, g, 0, prm, moved);
}
#else
#define QUADRANT_SOFT_VEX 0
struct F4Vex {};  // never passed: no AVX path in this build
inline bool CpuHasAvx() { return false; }
#endif

// The kernels by lane type V: Real (one row), F4 (four, SSE2) or F4Vex (four, AVX encoding).
template <class V, bool kRotation>
inline void WarmStartRows(SolverBody* states, SoftRowGroup& g, int lane) {
#if QUADRANT_SOFT_VEX
  if constexpr (std::is_same_v<V, F4Vex>) {
    WarmStartRowsVex<kRotation>(states, g);
    return;
  } else
#endif
  {
    if constexpr (!std::is_same_v<V, F4Vex>) WarmStartRowsImpl<V, kRotation>(states, g, lane);
  }
}

template <class V, bool kRotation, bool kFriction, bool kBias, RelaxBias kRelax = RelaxBias::kCompute>
inline void SolveRows(SolverBody* states, SoftRowGroup& g, int lane, const SoftSolveParams& prm,
                      RelaxBiasRows* cache = nullptr) {
#if QUADRANT_SOFT_VEX
  if constexpr (std::is_same_v<V, F4Vex>) {
    SolveRowsVex<kRotation, kFriction, kBias, kRelax>(states, g, prm, cache);
    return;
  } else
#endif
  {
    if constexpr (!std::is_same_v<V, F4Vex>) SolveRowsImpl<V, kRotation, kFriction, kBias, kRelax>(states, g, lane, prm, cache);
  }
}

template <class V, bool kRotation>
inline bool SolvePositionRows(SolverBody* states, const SoftRowGroup& g, int lane, const SoftPositionParams& prm,
                              bool& moved) {
#if QUADRANT_SOFT_VEX
  if constexpr (std::is_same_v<V, F4Vex>) {
    return SolvePositionRowsVex<kRotation>(states, g, prm, moved);
  } else
#endif
  {
    if constexpr (!std::is_same_v<V, F4Vex>) return SolvePositionRowsImpl<V, kRotation>(states, g, lane, prm, moved);
    return false;
  }
}

}  // namespace quadrant
