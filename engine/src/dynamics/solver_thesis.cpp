// The thesis's solver (its section 4.3), kept as the baseline the study compares against.
//
// For each contact, in order and once: separate the bodies along the normal, each by its
// inverse-mass share of the penetration, invM / (invMA + invMB) (the thesis writes m / (m + m0);
// its intent, "a small pebble cannot move a giant rock", is that the lighter body moves more, and
// a static body's invM is 0), then apply one impulse with restitution and friction at the
// centroid of the touching points (standing in for the thesis's single Minkowski point). No
// iterations, no warm starting, no speculative impulses.
//
// Bounded (issue #13): under gravity the pass runs from the lowest contact up with shock
// propagation, a body moves at most maxLinearCorrection (0.2 m) in it, a pair touches up to
// linearSlop (5 mm) apart, and contacts with static and kinematic bodies are pushed out once
// more after the pass (ResolveAll, Resolve). A closed box of 2000 circles at area fraction 0.85,
// 2000 steps: no body leaves, kinetic energy at most 299 J of about 325 kJ potential and 36.5 J
// over the second 1000 steps, fastest body 2.84 m/s (tests/engine/solver_thesis_test.cpp). The
// plain pass let that box explode; shock propagation that let a lower body throw an upper one
// kept it from ever coming to rest (issue #26, Resolve).
//
// Box2D 2.4.1 switches (issues #17, #31; all off by default, so the method stays the thesis's):
// thesisPositionPass, thesisAccumulatedImpulse with thesisPasses, thesisCoupledImpulse,
// thesisPointImpulses, thesisBlockImpulse, WorldDef::polygonSkin, box2dPositionSolve. With all
// of them and Box2D's contacts the random campaign (10 seeds x 200 hits) differs from Box2D by
// 0.38 % at p90, its worst class by 0.98 % (median over the seeds; at most 2.31 %): Box2D's
// algorithm, switch by switch. docs/validation.md gives what each changes;
// docs/notes/thesis_solver.md the measurements, the explosion and what was tried.
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <span>
#include <vector>

#include "dynamics/box2d_position.h"
#include "dynamics/contact_constraints.h"
#include "dynamics/integrate.h"
#include "dynamics/restitution_policy.h"
#include "dynamics/solver.h"

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
    ctx.run->Serial(Stage::kSolve, [&] { ResolveAll<kRotation>(ctx); });
    auto t2 = Clock::now();
    if (def.thesisPositionPass) SnapshotPoints<kRotation>(ctx);
    IntegratePositions(bodies, def, ctx.dt, *ctx.run);
    if (def.thesisPositionPass) ctx.run->Serial(Stage::kSolve, [&] { CorrectPositions<kRotation>(ctx); });
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
  static void CoupleImpulse(Vec2 rA, Vec2 rB, Vec2 n, Vec2 t, Real iA, Real iB, Real knn, Real ktt, Real bn, Real bt,
                            Real mu, Real& jn, Real& jt) {
    Real knt = 0;
    if constexpr (kRotation) knt = iA * Cross(rA, n) * Cross(rA, t) + iB * Cross(rB, n) * Cross(rB, t);
    const Real det = knn * ktt - knt * knt;
    if (!(det > 0)) return;  // degenerate: keep the separate answer
    // K [jn jt] = [bn, bt]: the fresh impulse's bn = -(1 + e) vn, bt = -vt; the accumulated
    // total's (WorldDef::thesisAccumulatedImpulse) adds K times the total so far.
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

  // WorldDef::thesisPositionPass: the penetration is removed after the positions are integrated,
  // as Box2D 2.4.1 and pgs do, by positionIterations passes of non-linear Gauss-Seidel over the
  // touching points (Baumgarte fraction of the depth beyond linearSlop, at most
  // maxLinearCorrection, applied at the point so the bodies turn too), instead of the thesis's
  // translation push before the impulses.
  struct PositionPoint {
    int a, b;
    Vec2 n, rA, rB;
    Real separation;  // at the narrow phase, less the pair's skins
    Box2dPositionPoint box2d;  // WorldDef::box2dPositionSolve
  };
  std::vector<PositionPoint> posPoints_;
  std::vector<Vec2> center0_;
  std::vector<Rot> rot0_;

  template <bool kRotation>
  void SnapshotPoints(StepContext& ctx) {
    const WorldDef& def = *ctx.def;
    Bodies& bodies = *ctx.bodies;
    posPoints_.clear();
    for (const Contact& c : ctx.contacts) {
      if (bodies.inv[c.a].invMass + bodies.inv[c.b].invMass == 0) continue;
      const Real skin = def.polygonSkin > 0 ? PolygonSkin(def, bodies.shape[c.a].type == ShapeType::kPolygon,
                                                          bodies.shape[c.b].type == ShapeType::kPolygon)
                                            : Real(0);
      for (int k = 0; k < c.manifold.pointCount; ++k) {
        const ManifoldPoint& mp = c.manifold.points[k];
        posPoints_.push_back({c.a, c.b, c.manifold.normal, mp.point - bodies.center[c.a], mp.point - bodies.center[c.b],
                              mp.separation - skin,
                              def.box2dPositionSolve ? MakeBox2dPositionPoint(bodies, c, k, mp.separation - skin)
                                                     : Box2dPositionPoint{}});
      }
    }
    center0_.assign(bodies.center.begin(), bodies.center.end());
    rot0_.resize(bodies.Count());
    for (int i = 0; i < bodies.Count(); ++i) rot0_[i] = bodies.xf[i].q;
  }

  template <bool kRotation>
  void CorrectPositions(StepContext& ctx) {
    const WorldDef& def = *ctx.def;
    Bodies& bodies = *ctx.bodies;
    bool any = false;
    for (int it = 0; it < def.positionIterations; ++it) {
      bool moved = false;
      if (def.box2dPositionSolve) {
        // Box2D 2.4.1's geometry and stopping rule (box2d_position.h).
        Real minSeparation = 0;
        for (const PositionPoint& p : posPoints_) {
          const Rot turnA = kRotation ? InvMul(rot0_[p.a], bodies.xf[p.a].q) : Rot{};
          const Rot turnB = kRotation ? InvMul(rot0_[p.b], bodies.xf[p.b].q) : Rot{};
          Real sep;
          Vec2 n = p.n, rA = p.rA, rB = p.rB;
          if (p.box2d.kind == Box2dPositionPoint::kDefault) {
            rA = Rotate(turnA, p.rA);
            rB = Rotate(turnB, p.rB);
            const Vec2 d = (bodies.center[p.b] - center0_[p.b]) - (bodies.center[p.a] - center0_[p.a]) + (rB - p.rB) - (rA - p.rA);
            sep = p.separation + Dot(p.n, d);
          } else {
            Vec2 point;
            Box2dPositionNow(p.box2d, bodies.center[p.a], turnA, bodies.center[p.b], turnB, sep, n, point);
            rA = point - bodies.center[p.a];
            rB = point - bodies.center[p.b];
          }
          minSeparation = std::min(minSeparation, sep);
          const Real mA = bodies.inv[p.a].invMass, mB = bodies.inv[p.b].invMass;
          const Real iA = kRotation ? bodies.inv[p.a].invInertia : Real(0), iB = kRotation ? bodies.inv[p.b].invInertia : Real(0);
          any |= ApplyBox2dPositionCorrection<kRotation>(bodies, def, p.a, mA, iA, p.b, mB, iB, sep, n, rA, rB);
        }
        if (minSeparation >= -3 * def.linearSlop) break;
        continue;
      }
      for (const PositionPoint& p : posPoints_) {
        const Real mA = bodies.inv[p.a].invMass, mB = bodies.inv[p.b].invMass;
        const Real iA = kRotation ? bodies.inv[p.a].invInertia : Real(0), iB = kRotation ? bodies.inv[p.b].invInertia : Real(0);
        Vec2 rA = p.rA, rB = p.rB;
        if constexpr (kRotation) {
          rA = Rotate(InvMul(rot0_[p.a], bodies.xf[p.a].q), p.rA);
          rB = Rotate(InvMul(rot0_[p.b], bodies.xf[p.b].q), p.rB);
        }
        const Vec2 d = (bodies.center[p.b] - center0_[p.b]) - (bodies.center[p.a] - center0_[p.a]) + (rB - p.rB) - (rA - p.rA);
        const Real sep = p.separation + Dot(p.n, d);
        const Real C = std::clamp(def.baumgarte * (sep + def.linearSlop), -def.maxLinearCorrection, Real(0));
        if (C == 0) continue;
        Real K = mA + mB;
        if constexpr (kRotation) K += iA * Cross(rA, p.n) * Cross(rA, p.n) + iB * Cross(rB, p.n) * Cross(rB, p.n);
        if (!(K > 0)) continue;
        const Vec2 P = (-C / K) * p.n;
        moved = true;
        if (mA > 0) {
          bodies.center[p.a] -= mA * P;
          if constexpr (kRotation) bodies.xf[p.a].q = IntegrateRot(bodies.xf[p.a].q, -iA * Cross(rA, P));
        }
        if (mB > 0) {
          bodies.center[p.b] += mB * P;
          if constexpr (kRotation) bodies.xf[p.b].q = IntegrateRot(bodies.xf[p.b].q, iB * Cross(rB, P));
        }
      }
      if (!moved) break;
      any = true;
    }
    if (!any) return;
    for (const PositionPoint& p : posPoints_) {
      if (bodies.inv[p.a].invMass > 0) SyncTransform(bodies, p.a);
      if (bodies.inv[p.b].invMass > 0) SyncTransform(bodies, p.b);
    }
  }

  // The one pass over the contacts, lowest first along gravity, then the containment pass.
  template <bool kRotation>
  void ResolveAll(StepContext& ctx) {
    const WorldDef& def = *ctx.def;
    Bodies& bodies = *ctx.bodies;
    const std::span<Contact> contacts = ctx.contacts;
    start_.assign(bodies.center.begin(), bodies.center.end());
    // Height of each contact along -gravity (its first point; with no gravity every key is 0
    // and the stable sort keeps the contacts' own order).
    const Vec2 up = def.effects.gravity ? -def.gravity : Vec2{0, 0};
    order_.resize(contacts.size());
    height_.resize(contacts.size());
    for (size_t i = 0; i < contacts.size(); ++i) {
      order_[i] = uint32_t(i);
      height_[i] = Dot(up, contacts[i].manifold.points[0].point);
    }
    std::stable_sort(order_.begin(), order_.end(), [&](uint32_t x, uint32_t y) { return height_[x] < height_[y]; });
    // WorldDef::thesisPasses: the thesis makes one pass; more repeat it (a second pass finds no
    // depth left to push, only the approach the later contacts' impulses left at the earlier ones).
    // WorldDef::thesisAccumulatedImpulse: each point's impulse is a running total over the
    // step's passes (in its manifold point), clamped as a total; its restitution target is set on
    // the first pass.
    const bool accumulate = def.thesisAccumulatedImpulse;
    if (accumulate) {
      target_.assign(2 * contacts.size(), Real(0));
      for (Contact& c : contacts) {
        for (int k = 0; k < c.manifold.pointCount; ++k) c.manifold.points[k].normalImpulse = c.manifold.points[k].tangentImpulse = 0;
      }
    }
    for (int pass = 0; pass < def.thesisPasses; ++pass) {
      for (uint32_t i : order_) {
        Resolve<kRotation>(bodies, def, contacts[i], start_, up, true, accumulate ? &target_[2 * i] : nullptr, pass == 0);
      }
    }
    for (Contact& c : contacts) {
      if (bodies.inv[c.a].invMass == 0 || bodies.inv[c.b].invMass == 0) {
        Resolve<kRotation>(bodies, def, c, start_, up, false, nullptr, false);
      }
    }
  }

  std::vector<uint32_t> order_;
  std::vector<Real> height_;
  std::vector<Vec2> start_;  // centres at the start of the pass, for the current depth
  std::vector<Real> target_;  // accumulated mode: each point's normal velocity target (2 per contact)

  template <bool kRotation>
  static void Resolve(Bodies& bodies, const WorldDef& def, Contact& c, const std::vector<Vec2>& start, Vec2 up,
                      bool impulse, Real* target, bool firstPass) {
    const Manifold& m = c.manifold;
    const int a = c.a, b = c.b;
    Real mA = bodies.inv[a].invMass, mB = bodies.inv[b].invMass;
    Real iA = kRotation ? bodies.inv[a].invInertia : Real(0);
    Real iB = kRotation ? bodies.inv[b].invInertia : Real(0);
    // Shock propagation (Guendelman, Bridson and Fedkiw 2003): under gravity the pass runs from
    // the lowest contact up, and between two movable bodies the lower one counts as immovable,
    // since the contacts below it have already placed and stopped it. One pass then carries a
    // pile's weight to the ground instead of letting it sink through itself. Not where the lower
    // body moves toward the upper one and the upper one is not the heavier: immovable, the lower
    // body would hand its motion to the upper one with no reaction on itself, energy from nothing
    // (issue #26: 6-8 kJ a second in a closed box of 2000 equal circles, which never came to
    // rest); such a contact is an ordinary collision of the two bodies. A heavier upper body keeps
    // the shock: as a collision it would drive the light body under it into what is below (the
    // 1000 kg box on a 1 kg slab sank 0.2 m into it).
    int upper = -1, lower = -1;
    if (up != Vec2{0, 0} && mA > 0 && mB > 0) {
      const bool aUpper = Dot(up, bodies.center[a]) > Dot(up, bodies.center[b]);
      const int hi = aUpper ? a : b, lo = aUpper ? b : a;
      const bool lowerApproaches = Dot(bodies.vel[lo].v, aUpper ? -m.normal : m.normal) > 0;
      if (!lowerApproaches || bodies.inv[hi].invMass < bodies.inv[lo].invMass) {
        upper = aUpper ? a : b;
        lower = aUpper ? b : a;
        (aUpper ? mB : mA) = 0;
        (aUpper ? iB : iA) = 0;
      }
    }
    const Real mSum = mA + mB;
    if (mSum == 0) return;
    const Vec2 n = m.normal;

    // 1. Penetration: move apart by the deepest point's depth, lighter body more. The depth is
    // the narrow phase's, less what earlier contacts of this pass have already moved the two
    // bodies apart along the normal (translations only, as the push itself).
    const Real moved = Dot((bodies.center[b] - start[b]) - (bodies.center[a] - start[a]), n);
    Real deepest = 0;
    for (int k = 0; k < m.pointCount; ++k) deepest = std::min(deepest, m.points[k].separation + moved);
    if (deepest < 0 && !def.thesisPositionPass) {
      const Vec2 shift = (-deepest / mSum) * n;
      // Under gravity, in the main pass, a body moves at most maxLinearCorrection from where the
      // step found it, however many contacts push it: chains of full pushes through a dense pile
      // moved bodies through a 1 m wall within one step (a contact found beyond the wall's middle
      // pushes the wrong way). Without gravity the push is not limited (the limit let one polygon
      // of the 3000-step polygon_stress soak leave its box, 0.25 m past the wall at step 1509,
      // which the unlimited push keeps in). The containment pass is never limited: the walls have
      // the last word.
      auto push = [&](int body, Vec2 by) {
        Vec2 to = bodies.center[body] + by;
        const Vec2 d = to - start[body];
        const Real len = Length(d);
        if (impulse && up != Vec2{0, 0} && len > def.maxLinearCorrection) to = start[body] + (def.maxLinearCorrection / len) * d;
        bodies.center[body] = to;
        SyncTransform(bodies, body);
      };
      if (mA > 0) push(a, -mA * shift);
      if (mB > 0) push(b, mB * shift);
    }

    if (!impulse) return;

    // 2. One impulse per contact, as the thesis's one-point contacts: at the centroid of the
    // touching points, with restitution along the normal and Coulomb friction along the tangent.
    // WorldDef::thesisPointImpulses: one impulse at each touching point in turn instead.
    Vec2 points[2];
    int index[2] = {0, 0};
    int count = 0;
    Vec2 point{0, 0};
    int touching = 0;
    // WorldDef::polygonSkin (Box2D 2.4.1's polygon radius): points within the pair's skins touch
    // too. Shapes are read only with a skin (the quadrants scheme's body copies carry none).
    const Real skin = def.polygonSkin > 0 ? PolygonSkin(def, bodies.shape[a].type == ShapeType::kPolygon,
                                                        bodies.shape[b].type == ShapeType::kPolygon)
                                          : Real(0);
    for (int k = 0; k < m.pointCount; ++k) {
      if (m.points[k].separation - skin > def.linearSlop) continue;
      point += m.points[k].point;
      index[count] = k;
      points[count++] = m.points[k].point;
      ++touching;
    }
    if (touching == 0) return;
    point = (Real(1) / Real(touching)) * point;
    if (!def.thesisPointImpulses) {
      points[0] = point;
      count = 1;
    }
    const Vec2 t = RightPerp(n);
    // One impulse per contact, in sequence, overshoots where a body rests on two supports
    // (projecting onto one slanted normal, then the other, leaves it moving up), and with the
    // supports immovable that lift would be handed up the whole pile every step: a body is
    // not sent up faster than what it rests on moves up.
    auto limitRise = [&] {
      if (upper < 0) return;
      const Vec2 u = Normalize(up);
      const Real rise = Dot(u, bodies.vel[upper].v) - std::max(Dot(u, bodies.vel[lower].v), Real(0));
      if (rise > 0) bodies.vel[upper].v -= rise * u;
    };
    if (target != nullptr && def.thesisBlockImpulse && count == 2 &&
        ResolveBlock<kRotation>(bodies, def, c, index, mA, mB, iA, iB, target, firstPass)) {
      limitRise();
      return;
    }
    for (int k = 0; k < count; ++k) {
      point = points[k];
      const Vec2 rA = point - bodies.center[a];
      const Vec2 rB = point - bodies.center[b];
      BodyVelocity& va = bodies.vel[a];
      BodyVelocity& vb = bodies.vel[b];
      Vec2 dv = vb.v - va.v;
      if constexpr (kRotation) dv += Cross(vb.w, rB) - Cross(va.w, rA);
      const Real vn = Dot(dv, n);
      auto tangentMass = [&] {
        Real kt = mSum;
        if constexpr (kRotation) kt += iA * Cross(rA, t) * Cross(rA, t) + iB * Cross(rB, t) * Cross(rB, t);
        return kt;
      };
      Real jn = 0, jt = 0;  // the impulse applied now
      ManifoldPoint& mp = c.manifold.points[index[k]];
      if (target != nullptr) {
        Real kn = mSum;
        if constexpr (kRotation) kn += iA * Cross(rA, n) * Cross(rA, n) + iB * Cross(rB, n) * Cross(rB, n);
        // Accumulated: the new total is the old one plus what ends the approach at the target,
        // clamped as a total (>= 0, friction within mu times it), so a later pass can take back
        // what an earlier one gave a point once its neighbour carries the load.
        if (firstPass) {
          const bool bounce = def.effects.restitution && vn < -def.restitutionThreshold;
          target[k] = bounce ? -c.restitution * vn : Real(0);
        }
        const Real oldN = mp.normalImpulse, oldT = mp.tangentImpulse;
        Real newN = std::max(oldN - (vn - target[k]) / kn, Real(0));
        Real newT = 0;
        if (def.effects.friction) {
          const Real kt = tangentMass();
          newT = std::clamp(oldT - Dot(dv, t) / kt, -c.friction * newN, c.friction * newN);
          if (def.thesisCoupledImpulse) {
            // The totals solved together: K (J - old) = [target - vn, -vt]; with no approach
            // left once the total is taken away, the total is zero.
            Real knt = 0;
            if constexpr (kRotation) knt = iA * Cross(rA, n) * Cross(rA, t) + iB * Cross(rB, n) * Cross(rB, t);
            const Real bn = target[k] - vn + kn * oldN + knt * oldT, bt = -Dot(dv, t) + knt * oldN + kt * oldT;
            if (bn <= 0) {
              newN = newT = 0;
            } else {
              CoupleImpulse<kRotation>(rA, rB, n, t, iA, iB, kn, kt, bn, bt, c.friction, newN, newT);
            }
          }
        }
        jn = newN - oldN;
        jt = newT - oldT;
        mp.normalImpulse = newN;
        mp.tangentImpulse = newT;
      } else {
        if (vn >= 0) continue;  // already separating
        const Real e = def.effects.restitution && vn < -def.restitutionThreshold ? c.restitution : Real(0);
        Real kn = mSum;
        if constexpr (kRotation) kn += iA * Cross(rA, n) * Cross(rA, n) + iB * Cross(rB, n) * Cross(rB, n);
        jn = -(Real(1) + e) * vn / kn;
        if (def.effects.friction) {
          const Real kt = tangentMass();
          jt = std::clamp(-Dot(dv, t) / kt, -c.friction * jn, c.friction * jn);
          if (def.thesisCoupledImpulse) {
            CoupleImpulse<kRotation>(rA, rB, n, t, iA, iB, kn, kt, -(Real(1) + e) * vn, -Dot(dv, t), c.friction, jn, jt);
          }
        }
        // Reported on the point: the thesis has one impulse per contact (per point with
        // thesisPointImpulses: the manifold's touching points in order).
        mp.normalImpulse = jn;
        mp.tangentImpulse = jt;
      }
      const Vec2 P = jn * n + jt * t;
      va.v -= mA * P;
      vb.v += mB * P;
      if constexpr (kRotation) {
        va.w -= iA * Cross(rA, P);
        vb.w += iB * Cross(rB, P);
      }
      limitRise();
    }
  }

  // WorldDef::thesisBlockImpulse: a contact's two touching points (accumulated totals, index
  // into its manifold) as Box2D 2.4.1 takes them. Both restitution targets are read first, then
  // each point's friction row is clamped by its normal total, then the two normal totals solve
  // the 2x2 complementarity problem together (SolveLcp2). Returns false, touching nothing, where
  // the two points nearly coincide (the matrix's condition over 1000, Box2D's bound): the caller
  // takes them one after the other.
  template <bool kRotation>
  static bool ResolveBlock(Bodies& bodies, const WorldDef& def, Contact& c, const int index[2], Real mA, Real mB,
                           Real iA, Real iB, Real* target, bool firstPass) {
    const Vec2 n = c.manifold.normal, t = RightPerp(n);
    BodyVelocity& va = bodies.vel[c.a];
    BodyVelocity& vb = bodies.vel[c.b];
    ManifoldPoint* mp[2] = {&c.manifold.points[index[0]], &c.manifold.points[index[1]]};
    Vec2 rA[2], rB[2];
    Real kn[2], kt[2];
    for (int k = 0; k < 2; ++k) {
      rA[k] = mp[k]->point - bodies.center[c.a];
      rB[k] = mp[k]->point - bodies.center[c.b];
      kn[k] = kt[k] = mA + mB;
      if constexpr (kRotation) {
        kn[k] += iA * Cross(rA[k], n) * Cross(rA[k], n) + iB * Cross(rB[k], n) * Cross(rB[k], n);
        kt[k] += iA * Cross(rA[k], t) * Cross(rA[k], t) + iB * Cross(rB[k], t) * Cross(rB[k], t);
      }
    }
    Real k12 = mA + mB;
    if constexpr (kRotation) k12 += iA * Cross(rA[0], n) * Cross(rA[1], n) + iB * Cross(rB[0], n) * Cross(rB[1], n);
    constexpr Real kMaxCondition = 1000;
    if (!(kn[0] > 0 && kn[0] * kn[0] < kMaxCondition * (kn[0] * kn[1] - k12 * k12))) return false;
    auto velocity = [&](int k) {
      Vec2 dv = vb.v - va.v;
      if constexpr (kRotation) dv += Cross(vb.w, rB[k]) - Cross(va.w, rA[k]);
      return dv;
    };
    auto apply = [&](int k, Vec2 P) {
      va.v -= mA * P;
      vb.v += mB * P;
      if constexpr (kRotation) {
        va.w -= iA * Cross(rA[k], P);
        vb.w += iB * Cross(rB[k], P);
      }
    };
    if (firstPass) {
      for (int k = 0; k < 2; ++k) {
        const Real vn = Dot(velocity(k), n);
        target[k] = def.effects.restitution && vn < -def.restitutionThreshold ? -c.restitution * vn : Real(0);
      }
    }
    if (def.effects.friction) {
      for (int k = 0; k < 2; ++k) {
        const Real oldT = mp[k]->tangentImpulse, bound = c.friction * mp[k]->normalImpulse;
        const Real newT = std::clamp(oldT - Dot(velocity(k), t) / kt[k], -bound, bound);
        apply(k, (newT - oldT) * t);
        mp[k]->tangentImpulse = newT;
      }
    }
    const Real a0 = mp[0]->normalImpulse, a1 = mp[1]->normalImpulse;
    const Real b0 = Dot(velocity(0), n) - target[0] - (kn[0] * a0 + k12 * a1);
    const Real b1 = Dot(velocity(1), n) - target[1] - (k12 * a0 + kn[1] * a1);
    Real x0, x1;
    if (!SolveLcp2(kn[0], k12, kn[1], b0, b1, x0, x1)) return true;  // no case fits: keep the totals
    apply(0, (x0 - a0) * n);
    apply(1, (x1 - a1) * n);
    mp[0]->normalImpulse = x0;
    mp[1]->normalImpulse = x1;
    return true;
  }
};

}  // namespace

std::unique_ptr<Solver> MakeThesisSolver() { return std::make_unique<ThesisSolver>(); }

}  // namespace quadrant
