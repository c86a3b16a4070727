// The soft step's body states (soft_step.h). The sub-steps work on a 32-byte solver state per
// body (velocity, and the motion dp, dq since the step began), not on the body arrays, and only
// for the bodies in rows: LoadFixedStates and LoadStates load the states rows read,
// IntegrateStateVelocities and IntegrateStatePositions integrate the rows' bodies each sub-step
// (integrate.cpp's guards; the turn limit is per world step), MoveFreeBodies moves the bodies
// without a row over the whole step at once, and StoreRowStates writes the rows' bodies back.
//
// Promises: the same bits on any thread count; the four-wide paths (SSE2, or AVX's encoding
// where the CPU has it) do the same operations per body in the same order as the one-body paths,
// and hand a group of four back to them where a body needs the speed limit or turns by 0.5 rad
// or more (IntegrateRot's sin and cos).
//
// Measured: on the sparse stress scenes about 95 % of the bodies touch nothing, and integrating
// each of them n times a step was the largest stage (circle stress N = 4000: 21 % of the
// instructions): hence states for the rows' bodies only, and free bodies in closed form.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>

#include "dynamics/integrate.h"
#include "dynamics/soft_step.h"

namespace quadrant {
namespace {

bool Moves(const Bodies& bodies, int i, bool sleep) {
  return sleep ? bodies.awake[i] != 0 : bodies.type[i] != BodyType::kStatic;
}

// Body i of the rows over a sub-step (if it moves), with integrate.cpp's guards.
void IntegrateOne(SolverBody* states, const uint8_t* inRows, const Bodies& bodies, int i, bool sleep, bool rotation,
                  Real h, Real maxSpeed2, Real maxSpeed, Real maxAngularSpeed) {
  if (!inRows[i] || !Moves(bodies, i, sleep)) return;
  SolverBody& st = states[i];
  LimitSpeeds(st.v, st.w, maxSpeed2, maxSpeed, maxAngularSpeed);
  st.dp += h * st.v;
  if (rotation && st.w != 0) st.dq = IntegrateRot(st.dq, h * st.w);
}

#if QUADRANT_SOFT_SIMD
// IntegrateOne for bodies idx[0..3] (distinct) at once; returns false, having written nothing, if
// one of them turns by 0.5 rad or more in the sub-step (IntegrateRot takes sin and cos there).
[[gnu::always_inline]] inline bool IntegrateFour(SolverBody* states, const Bodies& bodies, const int* idx, bool sleep,
                                                 bool rotation, Real h, Real maxSpeed2, Real maxSpeed,
                                                 Real maxAngularSpeed) {
  float* s[kLanes] = {&states[idx[0]].v.x, &states[idx[1]].v.x, &states[idx[2]].v.x, &states[idx[3]].v.x};
  __m128 a0 = _mm_loadu_ps(s[0]), a1 = _mm_loadu_ps(s[1]), a2 = _mm_loadu_ps(s[2]), a3 = _mm_loadu_ps(s[3]);
  __m128 b0 = _mm_loadu_ps(s[0] + 4), b1 = _mm_loadu_ps(s[1] + 4), b2 = _mm_loadu_ps(s[2] + 4), b3 = _mm_loadu_ps(s[3] + 4);
  _MM_TRANSPOSE4_PS(a0, a1, a2, a3);
  _MM_TRANSPOSE4_PS(b0, b1, b2, b3);
  F4 vx{a0}, vy{a1}, w{a2}, dpx{b0}, dpy{b1}, qc{b2}, qs{b3};
  const F4 speed2 = vx * vx + vy * vy;
  const M4 fast = Greater(speed2, Splat(maxSpeed2, F4{}));
  if (Any(fast)) {
    const F4 scale = Div(Splat(maxSpeed, F4{}), Sqrt(speed2));
    vx = Select(fast, scale * vx, vx);
    vy = Select(fast, scale * vy, vy);
  }
  const F4 maxW = Splat(maxAngularSpeed, F4{});
  w = Min(Max(w, Neg(maxW)), maxW);
  const F4 hv = Splat(h, F4{});
  dpx = dpx + hv * vx;
  dpy = dpy + hv * vy;
  if (rotation) {
    const F4 turn = hv * w;
    const M4 turns = {_mm_cmpneq_ps(w.v, _mm_setzero_ps())};
    if (Any(turns)) {
      if (Any(GreaterEqual(Max(turn, Neg(turn)), Splat(Real(0.5), F4{})))) return false;
      F4 c = qc, sn = qs;
      TurnBy(c, sn, turn);
      qc = Select(turns, c, qc);
      qs = Select(turns, sn, qs);
    }
  }
  a0 = vx.v, a1 = vy.v, a2 = w.v, a3 = _mm_setzero_ps();
  b0 = dpx.v, b1 = dpy.v, b2 = qc.v, b3 = qs.v;
  _MM_TRANSPOSE4_PS(a0, a1, a2, a3);
  _MM_TRANSPOSE4_PS(b0, b1, b2, b3);
  const __m128 as[4] = {a0, a1, a2, a3}, bs[4] = {b0, b1, b2, b3};
  for (int k = 0; k < kLanes; ++k) {
    if (!Moves(bodies, idx[k], sleep)) continue;
    _mm_storeu_ps(s[k], as[k]);
    _mm_storeu_ps(s[k] + 4, bs[k]);
  }
  return true;
}

// The same in AVX's encoding (soft_rows.h says why; the same operations, the same bits).
#if QUADRANT_SOFT_VEX
[[gnu::target("avx"), gnu::noinline]] bool IntegrateFourVex(SolverBody* states, const Bodies& bodies, const int* idx,
                                                             bool sleep, bool rotation, Real h, Real maxSpeed2,
                                                             Real maxSpeed, Real maxAngularSpeed) {
  return IntegrateFour(states, bodies, idx, sleep, rotation, h, maxSpeed2, maxSpeed, maxAngularSpeed);
}
#else
bool IntegrateFourVex(SolverBody* states, const Bodies& bodies, const int* idx, bool sleep, bool rotation, Real h,
                      Real maxSpeed2, Real maxSpeed, Real maxAngularSpeed) {
  return IntegrateFour(states, bodies, idx, sleep, rotation, h, maxSpeed2, maxSpeed, maxAngularSpeed);
}
#endif
#endif

// A free body (no contact row, not kinematic: dynamic and awake) over the whole step, as the
// sub-steps would move it but in closed form: with u its velocity after the first sub-step
// (gravity h g, then the step's damping), it ends at u + (n - 1) h g having moved
// n h u + n (n - 1) / 2 h^2 g, and turns by dt w at once. A body that the speed limit would
// touch takes the sub-steps one by one (IntegrateOne's guards).
struct FreeMotion {
  Vec2 hg;        // a sub-step's gravity
  Vec2 dpGravity; // n (n - 1) / 2 h^2 g
  Real nh;        // n h
  Real nMinus1;
  Real maxSpeed2, maxSpeed, maxAngularSpeed;
  Real h, dt;
  int n;
  bool damping, rotation;
};

FreeMotion MakeFreeMotion(const WorldDef& def, Real dt) {
  const int n = def.softSubSteps;
  const Real h = dt / Real(n);
  const Vec2 g = def.effects.gravity ? def.gravity : Vec2{};
  return {h * g,
          (Real(n * (n - 1) / 2) * h) * (h * g),
          Real(n) * h,
          Real(n - 1),
          def.maxLinearSpeed * def.maxLinearSpeed,
          def.maxLinearSpeed,
          def.maxRotation / dt,
          h,
          dt,
          n,
          def.effects.damping,
          def.effects.rotation};
}

void MoveFree(Bodies& bodies, const FreeMotion& fm, int i) {
  Vec2 u = bodies.vel[i].v + fm.hg;  // a free body has no solver state (LoadStates)
  Real w = bodies.vel[i].w;
  Vec2 vOut;
  if (fm.damping) {
    u = (Real(1) / (Real(1) + fm.dt * bodies.linearDamping[i])) * u;
    w *= Real(1) / (Real(1) + fm.dt * bodies.angularDamping[i]);
  }
  const Vec2 vEnd = u + fm.nMinus1 * fm.hg;
  w = std::clamp(w, -fm.maxAngularSpeed, fm.maxAngularSpeed);
  Vec2 dp;
  if (LengthSquared(u) > fm.maxSpeed2 || LengthSquared(vEnd) > fm.maxSpeed2) {
    Vec2 v = u;
    for (int k = 0; k < fm.n; ++k) {
      if (k > 0) v += fm.hg;
      const Real speed2 = LengthSquared(v);
      if (speed2 > fm.maxSpeed2) v = (fm.maxSpeed / std::sqrt(speed2)) * v;
      dp += fm.h * v;
    }
    vOut = v;
  } else {
    dp = fm.nh * u + fm.dpGravity;
    vOut = vEnd;
  }
  bodies.vel[i] = BodyVelocity{vOut, w};
  // Nothing has moved a free body yet in this step: its centre and rotation are where the step
  // began (no snapshot needed: LoadStates takes one of the rows' bodies only).
  bodies.center[i] = bodies.center[i] + dp;
  if (fm.rotation && w != 0) bodies.xf[i].q = IntegrateRot(bodies.xf[i].q, fm.dt * w);
  SyncTransform(bodies, i);
}

#if QUADRANT_SOFT_SIMD
// MoveFree for the free ones among bodies i..i+3 (mask) at once, with the same operations per
// body in the same order (so the same bits): the velocity read from the bodies (a free body's
// state is its velocity unchanged), std::clamp as max then min (the same for a nonzero limit,
// which the caller checks), IntegrateRot's small-angle branch as TurnBy. Returns false, having
// written nothing, when a body needs the speed limit or turns by 0.5 rad or more in the step: the
// caller then moves the four one by one.
[[gnu::always_inline]] inline bool MoveFour(Bodies& bodies, const FreeMotion& fm, int i, int mask) {
  // Only the free lanes' velocities are read: the others belong to bodies in rows, whose
  // velocities the restitution passes may be writing meanwhile (Run's Beside); their lanes are
  // computed from zeros and dropped.
  const BodyVelocity* vel = bodies.vel.data() + i;
  BodyVelocity masked[kLanes];
  if (mask != 0xF) {
    for (int k = 0; k < kLanes; ++k) masked[k] = (mask >> k & 1) ? vel[k] : BodyVelocity{};
    vel = masked;
  }
  F4 ux{_mm_setr_ps(vel[0].v.x, vel[1].v.x, vel[2].v.x, vel[3].v.x)};
  F4 uy{_mm_setr_ps(vel[0].v.y, vel[1].v.y, vel[2].v.y, vel[3].v.y)};
  F4 w{_mm_setr_ps(vel[0].w, vel[1].w, vel[2].w, vel[3].w)};
  ux = ux + Splat(fm.hg.x, F4{});
  uy = uy + Splat(fm.hg.y, F4{});
  if (fm.damping) {
    const F4 one = Splat(Real(1), F4{}), dt = Splat(fm.dt, F4{});
    const F4 fl = Div(one, one + dt * F4{_mm_loadu_ps(bodies.linearDamping.data() + i)});
    ux = fl * ux;
    uy = fl * uy;
    w = w * Div(one, one + dt * F4{_mm_loadu_ps(bodies.angularDamping.data() + i)});
  }
  const Vec2 rest = fm.nMinus1 * fm.hg;
  const F4 ex = ux + Splat(rest.x, F4{}), ey = uy + Splat(rest.y, F4{});
  const F4 maxW = Splat(fm.maxAngularSpeed, F4{});
  w = Min(Max(w, Neg(maxW)), maxW);
  const F4 max2 = Splat(fm.maxSpeed2, F4{});
  if (Any(Greater(ux * ux + uy * uy, max2)) || Any(Greater(ex * ex + ey * ey, max2))) return false;
  // The transforms (p, q: 16 bytes each), four of them transposed into px, py, qc, qs.
  float* xf = &bodies.xf[i].p.x;
  static_assert(sizeof(Transform) == 4 * sizeof(Real));
  __m128 t0 = _mm_loadu_ps(xf), t1 = _mm_loadu_ps(xf + 4), t2 = _mm_loadu_ps(xf + 8), t3 = _mm_loadu_ps(xf + 12);
  _MM_TRANSPOSE4_PS(t0, t1, t2, t3);
  F4 qc{t2}, qs{t3};
  if (fm.rotation) {
    const M4 turns = {_mm_cmpneq_ps(w.v, _mm_setzero_ps())};
    if (Any(turns)) {
      const F4 turn = Splat(fm.dt, F4{}) * w;
      if (Any(GreaterEqual(Max(turn, Neg(turn)), Splat(Real(0.5), F4{})))) return false;
      F4 c = qc, sn = qs;  // a free body's rotation is still the step's first (MoveFree)
      TurnBy(c, sn, turn);
      qc = Select(turns, c, qc);
      qs = Select(turns, sn, qs);
    }
  }
  // Centres (8 bytes each): x0 y0 x1 y1 and x2 y2 x3 y3, split into xs and ys.
  const float* c0 = &bodies.center[i].x;
  const __m128 ca = _mm_loadu_ps(c0), cb = _mm_loadu_ps(c0 + 4);
  const F4 nh = Splat(fm.nh, F4{});
  const F4 cx = F4{_mm_shuffle_ps(ca, cb, _MM_SHUFFLE(2, 0, 2, 0))} + (nh * ux + Splat(fm.dpGravity.x, F4{}));
  const F4 cy = F4{_mm_shuffle_ps(ca, cb, _MM_SHUFFLE(3, 1, 3, 1))} + (nh * uy + Splat(fm.dpGravity.y, F4{}));
  // SyncTransform: p = centre - Rotate(q, localCenter).
  const float* lc = &bodies.localCenter[i].x;
  const __m128 la = _mm_loadu_ps(lc), lb = _mm_loadu_ps(lc + 4);
  const F4 lx{_mm_shuffle_ps(la, lb, _MM_SHUFFLE(2, 0, 2, 0))}, ly{_mm_shuffle_ps(la, lb, _MM_SHUFFLE(3, 1, 3, 1))};
  const F4 px = cx - (qc * lx - qs * ly), py = cy - (qs * lx + qc * ly);
  t0 = px.v, t1 = py.v, t2 = qc.v, t3 = qs.v;
  _MM_TRANSPOSE4_PS(t0, t1, t2, t3);
  // Only the free lanes are written (mask bit k: body i + k); the others were computed from
  // whatever they hold and are dropped.
  float* center = &bodies.center[i].x;
  const __m128 clo = _mm_unpacklo_ps(cx.v, cy.v), chi = _mm_unpackhi_ps(cx.v, cy.v);
  alignas(16) Real vxs[kLanes], vys[kLanes], ws[kLanes];
  _mm_store_ps(vxs, ex.v);
  _mm_store_ps(vys, ey.v);
  _mm_store_ps(ws, w.v);
  BodyVelocity* out = bodies.vel.data() + i;
  if (mask == 0xF) {
    _mm_storeu_ps(xf, t0);
    _mm_storeu_ps(xf + 4, t1);
    _mm_storeu_ps(xf + 8, t2);
    _mm_storeu_ps(xf + 12, t3);
    _mm_storeu_ps(center, clo);
    _mm_storeu_ps(center + 4, chi);
    for (int k = 0; k < kLanes; ++k) out[k] = BodyVelocity{{vxs[k], vys[k]}, ws[k]};
    return true;
  }
  const __m128 ts[kLanes] = {t0, t1, t2, t3};
  for (int k = 0; k < kLanes; ++k) {
    if (!(mask >> k & 1)) continue;
    _mm_storeu_ps(xf + 4 * k, ts[k]);
    out[k] = BodyVelocity{{vxs[k], vys[k]}, ws[k]};
  }
  if (mask & 1) _mm_storel_pi(reinterpret_cast<__m64*>(center), clo);
  if (mask & 2) _mm_storeh_pi(reinterpret_cast<__m64*>(center + 2), clo);
  if (mask & 4) _mm_storel_pi(reinterpret_cast<__m64*>(center + 4), chi);
  if (mask & 8) _mm_storeh_pi(reinterpret_cast<__m64*>(center + 6), chi);
  return true;
}

#if QUADRANT_SOFT_VEX
[[gnu::target("avx"), gnu::noinline]] bool MoveFourVex(Bodies& bodies, const FreeMotion& fm, int i, int mask) {
  return MoveFour(bodies, fm, i, mask);  // in AVX's encoding: the same operations, the same bits
}
#else
bool MoveFourVex(Bodies& bodies, const FreeMotion& fm, int i, int mask) { return MoveFour(bodies, fm, i, mask); }
#endif
#endif

}  // namespace

// First the states of the bodies that rows read but never write (inverse mass 0: static,
// kinematic, sleeping), with the inRows_ flags cleared (a moving kinematic body's set: rows read
// its motion, and a colour may share it, so it is not flagged from the rows); the colouring then
// flags the dynamic bodies in rows (MarkRow). The same pass clears the colour masks the colouring
// left last step: one pass over the bodies instead of three.
void SoftStepSolver::LoadFixedStates(StageRunner& run, const Bodies& bodies, bool sleep) {
  const int count = bodies.Count();
  states_.resize(count);
  warmNext_.resize(count);  // new ones zero, the others zeroed by the sub-steps that used them
  inRows_.resize(count + kFlagPad);  // padded: the scans below read several flags at a time
  std::atomic<bool>& kinematic = kinematicInRows_.flag;
  kinematic.store(false, std::memory_order_relaxed);
  run.Dynamic(Stage::kIntegrate, count, run.MinItems(), kBodyGrain, [&](int b, int e) {
    graph_.ClearColors(b, e);
    // Raw pointers: with the vectors' own, every store reloaded their data pointers.
    const BodyInverseMass* inv = bodies.inv.data();
    const BodyVelocity* vel = bodies.vel.data();
    const BodyType* type = bodies.type.data();
    const uint8_t* awake = bodies.awake.data();
    SolverBody* states = states_.data();
    uint8_t* inRows = inRows_.data();
    for (int i = b; i < e; ++i) {
      // Static, kinematic and sleeping bodies (inverse mass 0) here: rows read them. The
      // dynamic ones in rows in LoadStates; free ones need no state (MoveFreeBodies moves them
      // from their velocity).
      uint8_t kinematicMoving = 0;
      if (inv[i].invMass == 0) {
        states[i] = SolverBody{vel[i].v, vel[i].w, 0, Vec2{}, Rot{}};
        // Moves(): a kinematic body is never static, so without sleep it moves.
        kinematicMoving = type[i] == BodyType::kKinematic && (!sleep || awake[i] != 0);
        if (kinematicMoving && !kinematic.load(std::memory_order_relaxed)) kinematic.store(true, std::memory_order_relaxed);
      }
      inRows[i] = kinematicMoving;
    }
  });
  for (int k = 0; k < kFlagPad; ++k) inRows_[count + k] = 0;
}

// After the colouring (MarkRow): the list of the bodies in rows, their states (velocity, no
// motion yet) and where they start.
void SoftStepSolver::LoadStates(StageRunner& run, const Bodies& bodies) {
  const int count = bodies.Count();
  // The bodies the sub-steps integrate, in index order (the same on any thread count); bundled,
  // grouped by bundle, each bundle's bodies in index order. The sub-step passes walk this list
  // instead of every body (on the sparse stress scenes about 95 % of the bodies are free). The
  // flags are scanned in parallel blocks of words, eight flags a word, each flag 0 or 1, so byte
  // j's is bit 8 j (the flags past the last body are zero: kFlagPad); each block lists its bodies
  // (bundled: with their bundles, counted per bundle), and the blocks are joined in index order,
  // bundled by a parallel scatter to each block's place in each bundle. Serially, on 16 threads'
  // partition of a 2-core VM, the scan took 66-79 us a step on 64000 circles, and the join
  // with the regrouping by bundle 45 us (polygons 64000: 70 us).
  // Bundles kept from last step (ApplyBundles): the same ends, so the same bodies in rows, and
  // the list is last step's, in bundle order.
  if (!bundlesKept_) {
    const int words = (count + 7) / 8;
    const size_t parts = size_t(run.Workers());
    const int bundles = bundles_;
    const size_t stride = size_t(bundles);
    activeParts_.resize(parts);
    activePartBundles_.resize(parts);
    activePartBegin_.assign(parts, words);  // a block that does not run lists nothing
    partBundleStart_.resize(parts * stride);
    run.For(Stage::kIntegrate, words, std::max(1, run.MinItems() / 8), [&](int wb, int we, int block) {
      std::vector<int>& part = activeParts_[size_t(block)];
      part.clear();
      activePartBegin_[size_t(block)] = wb;
      for (int w = wb; w < we; ++w) {
        uint64_t eight;
        std::memcpy(&eight, &inRows_[size_t(w) * 8], sizeof eight);
        for (; eight != 0; eight &= eight - 1) part.push_back(8 * w + (std::countr_zero(eight) >> 3));
      }
      if (bundles == 0) return;
      std::vector<int>& bundleOf = activePartBundles_[size_t(block)];
      int* counts = &partBundleStart_[size_t(block) * stride];
      std::fill(counts, counts + bundles, 0);
      bundleOf.resize(part.size());
      for (size_t k = 0; k < part.size(); ++k) {
        const int bundle = bundleNodes_[size_t(part[k])].bundle;
        bundleOf[k] = bundle;
        ++counts[bundle];
      }
    });
    partOrder_.clear();
    size_t listed = 0;
    for (size_t k = 0; k < parts; ++k) {
      if (activePartBegin_[k] >= words) continue;
      partOrder_.push_back(int(k));
      listed += activeParts_[k].size();
    }
    std::sort(partOrder_.begin(), partOrder_.end(), [&](int x, int y) { return activePartBegin_[size_t(x)] < activePartBegin_[size_t(y)]; });
    active_.resize(listed);
    if (bundles == 0) {
      int* out = active_.data();
      for (const int k : partOrder_) out = std::copy(activeParts_[size_t(k)].begin(), activeParts_[size_t(k)].end(), out);
    } else {
      // Each block's first place in each bundle: bundle by bundle, the blocks in index order.
      bundleBodyStart_.resize(stride + 1);
      int at = 0;
      for (int b = 0; b < bundles; ++b) {
        bundleBodyStart_[size_t(b)] = at;
        for (const int k : partOrder_) {
          int& start = partBundleStart_[size_t(k) * stride + size_t(b)];
          const int n = start;
          start = at;
          at += n;
        }
      }
      bundleBodyStart_[stride] = at;
      // In parallel where the list is long enough to pay for a barrier (about 4000 bodies).
      const int parted = static_cast<int>(partOrder_.size());
      run.For(Stage::kIntegrate, parted, listed >= size_t(2 * run.MinItems()) ? 1 : parted + 1, [&](int pb, int pe, int) {
        for (int p = pb; p < pe; ++p) {
          const size_t k = size_t(partOrder_[size_t(p)]);
          const std::vector<int>& part = activeParts_[k];
          const std::vector<int>& bundleOf = activePartBundles_[k];
          int* place = &partBundleStart_[k * stride];
          for (size_t j = 0; j < part.size(); ++j) active_[size_t(place[bundleOf[j]]++)] = part[j];
        }
      });
    }
  }
  // Where the rows' bodies start (StoreRowStates adds their motion to it); the free bodies
  // need no snapshot (MoveFree).
  center0_.resize(count);
  rot0_.resize(count);
  run.Dynamic(Stage::kIntegrate, ActiveCount(), run.MinItems(), kBodyGrain, [&](int b, int e) {
    for (int k = b; k < e; ++k) {
      const int i = active_[k];
      if (bodies.inv[i].invMass != 0) states_[i] = SolverBody{bodies.vel[i].v, bodies.vel[i].w, 0, Vec2{}, Rot{}};
      center0_[i] = bodies.center[i];
      rot0_[i] = bodies.xf[i].q;
    }
  });
}

// Gravity over a sub-step, as IntegrateVelocities does on the bodies: for bodies with an inverse
// mass (dynamic and awake; a sleeping body has inverse mass 0). Damping acts once per world step
// (dampDt, 0 in the later sub-steps) with the step's factor 1 / (1 + dt c), the law every solver
// and the scene description share (per sub-step the factor over a step was 1 / (1 + h c)^n:
// 0.3 % more speed left after 60 steps at c = 0.7).
//
// addWarm: then each body's warm start as the relax pass before added it up (warmNext_, SubStep),
// after gravity and damping, as the warm start came after them; the sum is zeroed for the next.
void SoftStepSolver::IntegrateStateVelocities(StageRunner& run, const Bodies& bodies, const WorldDef& def, Real h, Real dampDt,
                                              bool addWarm) {
  const Effects& fx = def.effects;
  const bool damp = fx.damping && dampDt > 0;
  if (!fx.gravity && !damp && !addWarm) return;
  const Vec2 dv = fx.gravity ? h * def.gravity : Vec2{};
  SolverBody* warm = warmNext_.data();
  auto addWarmTo = [warm](SolverBody& st, int i) __attribute__((always_inline)) {
    st.v += warm[i].v;
    st.w += warm[i].w;
    warm[i].v = {};
    warm[i].w = 0;
  };
  if (gravityScaled_) {  // gravity times each body's scale (WorldDef gravity on, some scale not 1)
    BodyPass(run, [this, &bodies, dv, damp, dampDt, addWarm, addWarmTo](int b, int e, int) {
      for (int k = b; k < e; ++k) {
        const int i = active_[k];
        if (bodies.inv[i].invMass == 0) continue;
        SolverBody& st = states_[i];
        const Real scale = bodies.gravityScale[i];
        st.v += scale == 1 ? dv : scale * dv;
        if (damp) {
          st.v = (Real(1) / (Real(1) + dampDt * bodies.linearDamping[i])) * st.v;
          st.w *= Real(1) / (Real(1) + dampDt * bodies.angularDamping[i]);
        }
        if (addWarm) addWarmTo(st, i);
      }
    });
    return;
  }
#if QUADRANT_SOFT_SIMD
  // Gravity alone: one four-wide add per body of (dv.x, dv.y, -0, -0), which leaves w and the
  // pad word exactly as they are (x + -0 is x for every x, signed zeros included); then the warm
  // start's (v, w, 0), whose pad word is zero (Scatter writes it so).
  if (!damp && def.softSimd) {
    const __m128 add = _mm_set_ps(-0.0f, -0.0f, dv.y, dv.x);
    if (addWarm) {
      BodyPass(run, [this, &bodies, add, warm](int b, int e, int) {
        for (int k = b; k < e; ++k) {
          const int i = active_[k];
          if (bodies.inv[i].invMass == 0) continue;
          float* v = &states_[i].v.x;
          float* sum = &warm[i].v.x;
          _mm_storeu_ps(v, _mm_add_ps(_mm_add_ps(_mm_loadu_ps(v), add), _mm_loadu_ps(sum)));
          _mm_storeu_ps(sum, _mm_setzero_ps());
        }
      });
      return;
    }
    BodyPass(run, [this, &bodies, add](int b, int e, int) {
      for (int k = b; k < e; ++k) {
        const int i = active_[k];
        if (bodies.inv[i].invMass == 0) continue;
        float* v = &states_[i].v.x;
        _mm_storeu_ps(v, _mm_add_ps(_mm_loadu_ps(v), add));
      }
    });
    return;
  }
#endif
  BodyPass(run, [this, &bodies, dv, damp, dampDt, addWarm, addWarmTo](int b, int e, int) {
    for (int k = b; k < e; ++k) {
      const int i = active_[k];
      if (bodies.inv[i].invMass == 0) continue;
      SolverBody& st = states_[i];
      st.v += dv;
      if (damp) {
        st.v = (Real(1) / (Real(1) + dampDt * bodies.linearDamping[i])) * st.v;
        st.w *= Real(1) / (Real(1) + dampDt * bodies.angularDamping[i]);
      }
      if (addWarm) addWarmTo(st, i);
    }
  });
}

// Motion over a sub-step, with integrate.cpp's guards (speed limit; the turn limit per world
// step stepDt). Every moving body (dynamic awake or kinematic) moves; static ones stay.
void SoftStepSolver::IntegrateStatePositions(StageRunner& run, const Bodies& bodies, const WorldDef& def, Real h, Real stepDt) {
  const Real maxSpeed2 = def.maxLinearSpeed * def.maxLinearSpeed;
  const Real maxAngularSpeed = def.maxRotation / stepDt;
  const bool rotation = def.effects.rotation, sleep = def.effects.sleep;
  // Only the bodies in rows (active_): MoveFreeBodies moves the free ones over the whole step.
  const bool simd = def.softSimd;
  const Real maxLinearSpeed = def.maxLinearSpeed;
  BodyPass(run, [this, &bodies, simd, sleep, rotation, h, maxSpeed2, maxLinearSpeed, maxAngularSpeed](int b, int e, int) {
    int k = b;
#if QUADRANT_SOFT_SIMD
    // Four bodies at a time: the same operations per body as the loop below (IntegrateRot's
    // small-angle branch is TurnBy), so the same bits.
    if (simd) {
      for (; k + kLanes <= e; k += kLanes) {
        const int* idx = &active_[k];
        const bool done =
            vex_ ? IntegrateFourVex(states_.data(), bodies, idx, sleep, rotation, h, maxSpeed2, maxLinearSpeed, maxAngularSpeed)
                 : IntegrateFour(states_.data(), bodies, idx, sleep, rotation, h, maxSpeed2, maxLinearSpeed, maxAngularSpeed);
        if (!done) {
          for (int l = 0; l < kLanes; ++l) {
            IntegrateOne(states_.data(), inRows_.data(), bodies, idx[l], sleep, rotation, h, maxSpeed2, maxLinearSpeed,
                         maxAngularSpeed);
          }
        }
      }
    }
#else
    (void)simd;
#endif
    for (; k < e; ++k) {
      IntegrateOne(states_.data(), inRows_.data(), bodies, active_[k], sleep, rotation, h, maxSpeed2, maxLinearSpeed,
                   maxAngularSpeed);
    }
  });
}

// The free bodies among [b, e): moved over the whole step at once (MoveFree).
void SoftStepSolver::MoveFreeBodies(Bodies& bodies, const WorldDef& def, Real dt, int b, int e) {
  const bool sleep = def.effects.sleep;
  const FreeMotion fm = MakeFreeMotion(def, dt);
  if (gravityScaled_) {  // one by one, each with gravity times its scale
    for (int i = b; i < e; ++i) {
      if (!Moves(bodies, i, sleep) || inRows_[i]) continue;
      const Real scale = bodies.gravityScale[i];
      if (scale == 1) {
        MoveFree(bodies, fm, i);
      } else {
        FreeMotion scaled = fm;
        scaled.hg = scale * fm.hg;
        scaled.dpGravity = scale * fm.dpGravity;
        MoveFree(bodies, scaled, i);
      }
    }
    return;
  }
  int i = b;
#if QUADRANT_SOFT_SIMD
  // Four consecutive bodies at a time (MoveFour), writing the free ones among them.
  if (def.softSimd && fm.maxAngularSpeed > 0) {
    const uint8_t* awake = bodies.awake.data();
    const BodyType* type = bodies.type.data();
    const uint8_t* inRows = inRows_.data();
    for (; i + kLanes <= e; i += kLanes) {
      int mask = 0;  // bit k: body i + k is free (Moves() and not in rows)
      for (int k = 0; k < kLanes; ++k) {
        const bool moves = sleep ? awake[i + k] != 0 : type[i + k] != BodyType::kStatic;
        mask |= int(moves & (inRows[i + k] == 0)) << k;
      }
      if (mask == 0 || (vex_ ? MoveFourVex(bodies, fm, i, mask) : MoveFour(bodies, fm, i, mask))) continue;
      for (int k = 0; k < kLanes; ++k) {
        if (mask >> k & 1) MoveFree(bodies, fm, i + k);
      }
    }
  }
#endif
  for (; i < e; ++i) {
    if (Moves(bodies, i, sleep) && !inRows_[i]) MoveFree(bodies, fm, i);
  }
}

// The bodies in rows (active_): their solver states back to the bodies.
void SoftStepSolver::StoreRowStates(StageRunner& run, Bodies& bodies, const WorldDef& def) {
  const bool sleep = def.effects.sleep;
  // Split from MinHeavyItems bodies on: the rows' bodies are scattered over the arrays, so each
  // costs cache misses more than arithmetic.
  run.Dynamic(Stage::kIntegrate, ActiveCount(), run.MinHeavyItems(), kBodyGrain / 4, [&](int b, int e) {
    for (int k = b; k < e; ++k) {
      const int i = active_[k];
      if (!Moves(bodies, i, sleep)) continue;
      const SolverBody& st = states_[i];
      bodies.vel[i] = BodyVelocity{st.v, st.w};
      bodies.center[i] = center0_[i] + st.dp;
      if (st.dq.s != 0 || st.dq.c != 1) {
        const Rot q = Mul(rot0_[i], st.dq);
        const Real inv = Real(1) / std::sqrt(q.c * q.c + q.s * q.s);
        bodies.xf[i].q = {q.c * inv, q.s * inv};
      }
      SyncTransform(bodies, i);
    }
  });
}

}  // namespace quadrant
