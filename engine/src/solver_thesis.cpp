// The thesis's solver (its section 4.3), kept as the baseline the study compares against.
//
// For each contact, in order and once: first separate the bodies along the normal, each by a
// share of the penetration given by the masses, then apply one impulse with restitution and
// friction at one point (the centroid of the touching manifold points, standing in for the
// thesis's single Minkowski contact point). No iterations, no warm starting, no speculative
// points: what the baseline costs and how it behaves on stacks is what the suite measures.
//
// The thesis writes the separation share as m / (m + m0); the text's intent ("a small pebble
// cannot move a giant rock") is that the lighter body moves more, so each body moves by its
// inverse mass share, invM / (invMA + invMB), which also handles static bodies (invM = 0).
#include <algorithm>
#include <chrono>

#include "integrate.h"
#include "solver.h"

namespace quadrant {
namespace {

using Clock = std::chrono::steady_clock;
double Ms(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }

class ThesisSolver final : public Solver {
 public:
  const char* Name() const override { return "thesis"; }

  void Step(StepContext& ctx) override {
    ctx.def->effects.rotation ? Run<true>(ctx) : Run<false>(ctx);
  }

 private:
  template <bool kRotation>
  void Run(StepContext& ctx) {
    const WorldDef& def = *ctx.def;
    Bodies& bodies = *ctx.bodies;
    auto t0 = Clock::now();
    IntegrateVelocities(bodies, def, ctx.dt, *ctx.run);
    auto t1 = Clock::now();
    // Sequential by nature (each contact moves bodies the next one reads): the baseline stays
    // on one thread whatever the world's thread count.
    ctx.run->Serial(Stage::kSolve, [&] {
      for (Contact& c : ctx.contacts) Resolve<kRotation>(bodies, def, c);
    });
    auto t2 = Clock::now();
    IntegratePositions(bodies, def, ctx.dt, *ctx.run);
    auto t3 = Clock::now();
    ctx.profile->integrate += Ms(t0, t1) + Ms(t2, t3);
    ctx.profile->solve += Ms(t1, t2);
  }

  // WorldDef::thesisCoupledImpulse: the one impulse solved with its normal and tangential parts
  // coupled, as an iterative solver converges to for one point. A tangential impulse at a lever
  // arm also changes the normal velocity (and the normal one the tangential: the off-diagonal
  // K_nt of the 2x2 effective mass), which the thesis's separate formulas ignore. Stick when the
  // impulse that ends both the approach (at -e vn) and the slip lies in the Coulomb cone; else
  // slide at the cone's edge, with the normal part solved for that friction.
  template <bool kRotation>
  static void CoupleImpulse(Vec2 rA, Vec2 rB, Vec2 n, Vec2 t, Real mSum, Real iA, Real iB, Real knn, Real ktt, Real vn,
                            Real vt, Real e, Real mu, Real& jn, Real& jt) {
    Real knt = 0;
    if constexpr (kRotation) knt = iA * Cross(rA, n) * Cross(rA, t) + iB * Cross(rB, n) * Cross(rB, t);
    (void)mSum;
    const Real det = knn * ktt - knt * knt;
    if (!(det > 0)) return;  // degenerate: keep the separate answer
    // K [jn jt] = [-(1 + e) vn, -vt]
    const Real bn = -(Real(1) + e) * vn, bt = -vt;
    const Real sn = (ktt * bn - knt * bt) / det, st = (knn * bt - knt * bn) / det;
    if (sn >= 0 && std::abs(st) <= mu * sn) {
      jn = sn;
      jt = st;
      return;
    }
    const Real s = st > 0 ? Real(1) : Real(-1);  // slide: friction at the cone's edge, on the stick side
    const Real k = knn + knt * s * mu;
    if (!(k > 0)) return;
    jn = bn / k;
    jt = s * mu * jn;
  }

  template <bool kRotation>
  static void Resolve(Bodies& bodies, const WorldDef& def, Contact& c) {
    const Manifold& m = c.manifold;
    const int a = c.a, b = c.b;
    const Real mA = bodies.inv[a].invMass, mB = bodies.inv[b].invMass;
    const Real iA = kRotation ? bodies.inv[a].invInertia : Real(0);
    const Real iB = kRotation ? bodies.inv[b].invInertia : Real(0);
    const Real mSum = mA + mB;
    if (mSum == 0) return;
    const Vec2 n = m.normal;

    // 1. Penetration: move apart by the deepest point's depth, lighter body more.
    Real deepest = 0;
    for (int k = 0; k < m.pointCount; ++k) deepest = std::min(deepest, m.points[k].separation);
    if (deepest < 0) {
      const Vec2 shift = (-deepest / mSum) * n;
      if (mA > 0) {
        bodies.center[a] -= mA * shift;
        SyncTransform(bodies, a);
      }
      if (mB > 0) {
        bodies.center[b] += mB * shift;
        SyncTransform(bodies, b);
      }
    }

    // 2. One impulse per contact, as the thesis's one-point contacts: at the centroid of the
    // touching points, with restitution along the normal and Coulomb friction along the tangent.
    Vec2 point{0, 0};
    int touching = 0;
    for (int k = 0; k < m.pointCount; ++k) {
      if (m.points[k].separation > 0) continue;
      point += m.points[k].point;
      ++touching;
    }
    if (touching == 0) return;
    point = (Real(1) / Real(touching)) * point;
    const Vec2 t = RightPerp(n);
    {
      const Vec2 rA = point - bodies.center[a];
      const Vec2 rB = point - bodies.center[b];
      BodyVelocity& va = bodies.vel[a];
      BodyVelocity& vb = bodies.vel[b];
      Vec2 dv = vb.v - va.v;
      if constexpr (kRotation) dv += Cross(vb.w, rB) - Cross(va.w, rA);
      const Real vn = Dot(dv, n);
      if (vn >= 0) return;  // already separating
      const Real e = def.effects.restitution && vn < -def.restitutionThreshold ? c.restitution : Real(0);
      Real kn = mSum;
      if constexpr (kRotation) kn += iA * Cross(rA, n) * Cross(rA, n) + iB * Cross(rB, n) * Cross(rB, n);
      Real jn = -(Real(1) + e) * vn / kn;
      Real jt = 0;
      if (def.effects.friction) {
        Real kt = mSum;
        if constexpr (kRotation) kt += iA * Cross(rA, t) * Cross(rA, t) + iB * Cross(rB, t) * Cross(rB, t);
        jt = std::clamp(-Dot(dv, t) / kt, -c.friction * jn, c.friction * jn);
        if (def.thesisCoupledImpulse) CoupleImpulse<kRotation>(rA, rB, n, t, mSum, iA, iB, kn, kt, vn, Dot(dv, t), e, c.friction, jn, jt);
      }
      const Vec2 P = jn * n + jt * t;
      va.v -= mA * P;
      vb.v += mB * P;
      if constexpr (kRotation) {
        va.w -= iA * Cross(rA, P);
        vb.w += iB * Cross(rB, P);
      }
      // Reported on the first point: the thesis has one impulse per contact.
      c.manifold.points[0].normalImpulse = jn;
      c.manifold.points[0].tangentImpulse = jt;
    }
  }
};

}  // namespace

std::unique_ptr<Solver> MakeThesisSolver() { return std::make_unique<ThesisSolver>(); }

}  // namespace quadrant
