// The soft step's contact rows (soft_step.h): BuildRows lays the coloured contacts out once a step
// in structure-of-arrays groups of eight rows (soft_rows.h's SoftRowGroup), colour by colour, each
// colour's last group padded with rows that touch nothing, for the sub-steps to solve eight rows
// at a time with AVX, four with SSE2, or one.
//
// Promises: the same row bit for bit whichever way it is built. With restitution each row is
// copied from its prepared constraint; lean (without), straight from its contact with
// PrepareContact's arithmetic, expression for expression, and no constraint list is kept.
// A row carries its softness (contacts with a static body twice as stiff) and, with
// WorldDef::softMassRatioLimit, the scaled masses of a supported heavy-on-light pair.
//
// Measured (base-100 pyramid): lean, BuildRows is 257 instructions a contact, 293 through the
// constraint list; the lean group's lever arms and effective masses are computed for eight lanes
// at once, since the four divisions of a point pair were a chain of scalar dependencies.
#include <atomic>

#include "dynamics/contact_ends.h"
#include "dynamics/soft_step.h"

namespace quadrant {
namespace {

// A point that touches nothing (kPadSeparation: never in contact).
void PadPoint(SoftPointRows& p, int lane) {
  p.rAx[lane] = p.rAy[lane] = p.rBx[lane] = p.rBy[lane] = 0;
  p.separation[lane] = kPadSeparation;
  p.normalMass[lane] = p.tangentMass[lane] = 0;
  p.normalImpulse[lane] = p.tangentImpulse[lane] = 0;
  p.collisionImpulse[lane] = 0;
}

// A row that touches nothing: inverse masses 0, so it writes no body. It reads the bodies of
// the group's first row (always a real one), which only this thread writes in this colour:
// any other body could be written by another thread meanwhile (a race, though its values
// would be discarded).
void PadLane(SoftRowGroup& g, int lane) {
  g.a[lane] = g.a[0];
  g.b[lane] = g.b[0];
  g.constraint[lane] = -1;
  g.nx[lane] = 0;
  g.ny[lane] = 1;
  g.friction[lane] = 0;
  g.invMassA[lane] = g.invIA[lane] = g.invMassB[lane] = g.invIB[lane] = 0;
  g.biasRate[lane] = 0;
  g.massScale[lane] = 1;
  g.impulseScale[lane] = 0;
  PadPoint(g.p[0], lane);
  PadPoint(g.p[1], lane);
}

// FillLeanGroup's vector part for point `pt` of lanes [lane, lane + width of V): FillLeanLane's
// expressions for rA, rB and the two effective masses, with both of its formulas computed and
// the lane's one selected (an unlimited lane: (mA + mB) + (iA rnA rnA + iB rnB rnB), as
// PrepareContact sums it; a limited one: ((mA + mB) + iA rnA rnA) + iB rnB rnB, as BuildRows does).
template <class V>
[[gnu::always_inline]] inline void LeanPointMath(SoftRowGroup& g, int pt, int lane, const Real* ax, const Real* ay,
                                                 const Real* bx, const Real* by, const Real* limitedLane) {
  const V z = Splat(Real(0), V{});
  SoftPointRows& p = g.p[pt];
  const V rAx = Load(ax, lane, z), rAy = Load(ay, lane, z);
  const V rBx = Load(bx, lane, z), rBy = Load(by, lane, z);
  Store(p.rAx, lane, rAx);
  Store(p.rAy, lane, rAy);
  Store(p.rBx, lane, rBx);
  Store(p.rBy, lane, rBy);
  const V nx = Load(g.nx, lane, z), ny = Load(g.ny, lane, z);
  const V tx = ny, ty = Neg(nx);  // RightPerp(n)
  const V rnA = rAx * ny - rAy * nx, rnB = rBx * ny - rBy * nx;
  const V rtA = rAx * ty - rAy * tx, rtB = rBx * ty - rBy * tx;
  const V mA = Load(g.invMassA, lane, z), mB = Load(g.invMassB, lane, z);
  const V iA = Load(g.invIA, lane, z), iB = Load(g.invIB, lane, z);
  const V m = mA + mB;
  const V knFree = m + (iA * rnA * rnA + iB * rnB * rnB);
  const V ktFree = m + (iA * rtA * rtA + iB * rtB * rtB);
  const V knLimited = m + iA * rnA * rnA + iB * rnB * rnB;
  const V ktLimited = m + iA * rtA * rtA + iB * rtB * rtB;
  const auto limited = Greater(Load(limitedLane, lane, z), z);
  const V kn = Select(limited, knLimited, knFree), kt = Select(limited, ktLimited, ktFree);
  const V one = Splat(Real(1), z);
  Store(p.normalMass, lane, Masked(Greater(kn, z), Div(one, kn)));
  Store(p.tangentMass, lane, Masked(Greater(kt, z), Div(one, kt)));
}

}  // namespace

// The part of a lean row's lane that does not depend on its points: bodies, normal, friction,
// inverse masses (with WorldDef::softMassRatioLimit, as BuildRows says) and softness. Returns
// how the limit met the lane (LaneEnds).
template <bool kRotation>
[[gnu::always_inline]] inline LaneEnds SoftStepSolver::FillLaneEnds(SoftRowGroup& g, int lane, int c, const Contact& contact,
                                                                 const Softness& soft, const Softness& staticSoft,
                                                                 Real massLimit) {
  const int a = contact.a, b = contact.b;
  const Vec2 n = contact.manifold.normal;
  const Real invMassA = inv_[a].invMass, invMassB = inv_[b].invMass;
  const Real invIA = kRotation ? inv_[a].invInertia : Real(0), invIB = kRotation ? inv_[b].invInertia : Real(0);
  g.a[lane] = a;
  g.b[lane] = b;
  g.constraint[lane] = c;
  g.nx[lane] = n.x;
  g.ny[lane] = n.y;
  g.friction[lane] = contact.friction;
  Real mA = invMassA, iA = invIA, mB = invMassB, iB = invIB;
  LaneEnds ends = LaneEnds::kPlain;
  if (massLimit > 0 && invMassA > 0 && invMassB > 0) {
    if (invMassA > massLimit * invMassB) {
      MarkOverLimit();
      if (supported_[a] == stamp_) {
        const Real f = massLimit * invMassB / invMassA;
        mA *= f;
        iA *= f;
        ends = LaneEnds::kLimited;
      } else {
        ends = LaneEnds::kCold;
      }
    } else if (invMassB > massLimit * invMassA) {
      MarkOverLimit();
      if (supported_[b] == stamp_) {
        const Real f = massLimit * invMassA / invMassB;
        mB *= f;
        iB *= f;
        ends = LaneEnds::kLimited;
      } else {
        ends = LaneEnds::kCold;
      }
    }
  }
  g.invMassA[lane] = mA;
  g.invIA[lane] = iA;
  g.invMassB[lane] = mB;
  g.invIB[lane] = iB;
  const Softness& s = (invMassA == 0 || invMassB == 0) ? staticSoft : soft;
  g.biasRate[lane] = s.biasRate;
  g.massScale[lane] = s.massScale;
  g.impulseScale[lane] = s.impulseScale;
  return ends;
}

// BuildRows' lane for constraint c straight from its contact (lean, without rotation): with
// PrepareContact's arithmetic and then BuildRows' own, expression for expression.
template <bool kRotation>
void SoftStepSolver::FillLeanLane(const StepContext& ctx, SoftRowGroup& g, int lane, int c, const Softness& soft,
                                  const Softness& staticSoft, Real massLimit) {
  const Bodies& bodies = *ctx.bodies;
  const Contact& contact = contacts_[graph_.ContactOf(c)];
  const int a = contact.a, b = contact.b;
  const Vec2 n = contact.manifold.normal;
  const Real invMassA = inv_[a].invMass, invMassB = inv_[b].invMass;
  const Real invIA = kRotation ? inv_[a].invInertia : Real(0), invIB = kRotation ? inv_[b].invInertia : Real(0);
  const LaneEnds ends = FillLaneEnds<kRotation>(g, lane, c, contact, soft, staticSoft, massLimit);
  const bool limited = ends == LaneEnds::kLimited, cold = ends == LaneEnds::kCold;
  const Real mA = g.invMassA[lane], iA = g.invIA[lane], mB = g.invMassB[lane], iB = g.invIB[lane];
  const Real skin = ContactSkin(*ctx.def, bodies, a, b);
  const Vec2 t = RightPerp(n);
  const int count = contact.manifold.pointCount;
  for (int pt = 0; pt < 2; ++pt) {
    SoftPointRows& p = g.p[pt];
    if (pt >= count) {
      PadPoint(p, lane);
      continue;
    }
    const ManifoldPoint& mp = contact.manifold.points[pt];
    const Vec2 rA = mp.anchorA;
    const Vec2 rB = mp.anchorB;
    p.rAx[lane] = rA.x;
    p.rAy[lane] = rA.y;
    p.rBx[lane] = rB.x;
    p.rBy[lane] = rB.y;
    Real kn, kt;
    if (!limited) {  // PrepareContact's
      kn = invMassA + invMassB;
      kt = kn;
      if constexpr (kRotation) {
        const Real rnA = Cross(rA, n), rnB = Cross(rB, n);
        const Real rtA = Cross(rA, t), rtB = Cross(rB, t);
        kn += invIA * rnA * rnA + invIB * rnB * rnB;
        kt += invIA * rtA * rtA + invIB * rtB * rtB;
      }
    } else {  // BuildRows' for a limited contact
      const Real rnA = Cross(rA, n), rnB = Cross(rB, n);
      const Real rtA = Cross(rA, t), rtB = Cross(rB, t);
      kn = mA + mB + iA * rnA * rnA + iB * rnB * rnB;
      kt = mA + mB + iA * rtA * rtA + iB * rtB * rtB;
    }
    p.normalMass[lane] = kn > 0 ? Real(1) / kn : Real(0);
    p.tangentMass[lane] = kt > 0 ? Real(1) / kt : Real(0);
    p.separation[lane] = mp.separation - skin;
    p.normalImpulse[lane] = cold ? Real(0) : mp.normalImpulse;
    p.tangentImpulse[lane] = cold ? Real(0) : mp.tangentImpulse;
    p.collisionImpulse[lane] = Real(0) * collisionShare_;  // no collisions without restitution
  }
}

// FillLeanLane for a whole group with rotation (the default): the per-lane part lane by lane,
// then the points' lever arms and effective masses for all eight lanes at once (two halves of
// four with SSE2), the same operations per lane in the same order (padded lanes and points are
// padded afterwards, as FillLeanLane pads them).
void SoftStepSolver::FillLeanGroup(const StepContext& ctx, SoftRowGroup& g, int first, int colorEnd, const Softness& soft,
                                   const Softness& staticSoft, Real massLimit) {
  const Bodies& bodies = *ctx.bodies;
  const bool skinOn = ctx.def->polygonSkin > 0;
  // The points and the bodies' centres of each lane; 1 in `limited` for a lane whose masses
  // softMassRatioLimit scaled (its effective masses are computed from the scaled ones, as
  // BuildRows does), and the lanes and points to pad afterwards.
  alignas(32) Real rax[2][kGroupRows] = {}, ray[2][kGroupRows] = {}, rbx[2][kGroupRows] = {}, rby[2][kGroupRows] = {};
  alignas(32) Real limitedLane[kGroupRows] = {};
  unsigned padLane = 0, padPoint[2] = {0, 0};
  PrefetchRowContacts(first + kGroupRows, std::min(first + 2 * kGroupRows, graph_.Count()));  // the next group's
  for (int lane = 0; lane < kGroupRows; ++lane) {
    const int c = first + lane;
    if (c >= colorEnd) {
      padLane |= 1u << lane;
      continue;
    }
    const Contact& contact = contacts_[graph_.ContactOf(c)];
    const int a = contact.a, b = contact.b;
    const LaneEnds ends = FillLaneEnds<true>(g, lane, c, contact, soft, staticSoft, massLimit);
    if (ends == LaneEnds::kLimited) limitedLane[lane] = 1;
    const bool cold = ends == LaneEnds::kCold;
    const Real skin = skinOn ? PolygonSkin(*ctx.def, bodies.shape[a].type == ShapeType::kPolygon,
                                           bodies.shape[b].type == ShapeType::kPolygon)
                             : Real(0);
    const int count = contact.manifold.pointCount;
    for (int pt = 0; pt < 2; ++pt) {
      SoftPointRows& p = g.p[pt];
      if (pt >= count) {
        padPoint[pt] |= 1u << lane;
        continue;
      }
      const ManifoldPoint& mp = contact.manifold.points[pt];
      rax[pt][lane] = mp.anchorA.x;
      ray[pt][lane] = mp.anchorA.y;
      rbx[pt][lane] = mp.anchorB.x;
      rby[pt][lane] = mp.anchorB.y;
      p.separation[lane] = mp.separation - skin;
      p.normalImpulse[lane] = cold ? Real(0) : mp.normalImpulse;
      p.tangentImpulse[lane] = cold ? Real(0) : mp.tangentImpulse;
      p.collisionImpulse[lane] = Real(0) * collisionShare_;  // no collisions without restitution
    }
  }
  for (int pt = 0; pt < 2; ++pt) {
#if QUADRANT_SOFT_SIMD
    for (int lane = 0; lane < kGroupRows; lane += 4) LeanPointMath<F4>(g, pt, lane, rax[pt], ray[pt], rbx[pt], rby[pt], limitedLane);
#else
    for (int lane = 0; lane < kGroupRows; ++lane) LeanPointMath<Real>(g, pt, lane, rax[pt], ray[pt], rbx[pt], rby[pt], limitedLane);
#endif
  }
  for (int lane = 0; lane < kGroupRows; ++lane) {
    if (padLane >> lane & 1u) {
      PadLane(g, lane);
      continue;
    }
    for (int pt = 0; pt < 2; ++pt) {
      if (padPoint[pt] >> lane & 1u) PadPoint(g.p[pt], lane);
    }
  }
}

// The rows in groups of eight, colour by colour (a colour's last group padded). Friction is
// solved in the relax passes only (as Box2D 3 does): during the soft solve the velocities still
// carry the push-out and the normal impulse its soft bias, so friction there resists a sliding
// that is not real, bounded by a load that is not real (the 15-box stack's top crept 0.014 m in
// 9 s with friction in both passes, 0.0003 m with it in the relax pass only). kLean: each row
// straight from its contact (FillLeanGroup, FillLeanLane), not from the prepared constraint.
template <bool kRotation, bool kLean>
void SoftStepSolver::BuildRows(StepContext& ctx, const Softness& soft, const Softness& staticSoft, Real massLimit) {
  StageRunner& run = *ctx.run;
  if (bundles_ > 0) {
    LayOutBundleGroups();  // a bundle's groups hold its rows only
  } else {
    groupStart_.assign(ConstraintGraph::kColors + 2, 0);
    for (int k = 0; k <= ConstraintGraph::kColors; ++k) {
      const int count = graph_.ColorBegin(k + 1) - graph_.ColorBegin(k);
      groupStart_[k + 1] = groupStart_[k] + (count + kGroupRows - 1) / kGroupRows;
    }
  }
  groups_.resize(groupStart_[ConstraintGraph::kColors + 1]);
  relaxBias_.resize(groups_.size());
  PlanPassStages();
  // One stage over every colour's groups: a group is built from its own constraints alone, so
  // no group waits for another colour's; each chunk finds its groups' colours in groupStart_.
  stagePlan_.assign(1, {groupStart_[ConstraintGraph::kColors + 1], ConstraintGraph::kColorGrain / kGroupRows});
  run.Stages(Stage::kSolve, stagePlan_, std::max(1, run.MinHeavyItems() / kGroupRows), [&](int, int gb, int ge) {
    int k = 0;  // the colour of group gb, then of each group in turn
    while (groupStart_[k + 1] <= gb) ++k;
    {
      for (int gi = gb; gi < ge; ++gi) {
        while (groupStart_[k + 1] <= gi) ++k;
        // The group's rows: [first, end) in colour order.
        const int first = bundles_ > 0 ? groupRowBegin_[gi] : graph_.ColorBegin(k) + (gi - groupStart_[k]) * kGroupRows;
        const int end = bundles_ > 0 ? groupRowEnd_[gi] : graph_.ColorBegin(k + 1);
        SoftRowGroup& g = groups_[gi];
        if constexpr (kLean && kRotation) {
          FillLeanGroup(ctx, g, first, end, soft, staticSoft, massLimit);
          continue;
        }
        for (int lane = 0; lane < kGroupRows; ++lane) {
          const int c = first + lane;
          if (c >= end) {
            PadLane(g, lane);
            continue;
          }
          if constexpr (kLean) {
            FillLeanLane<kRotation>(ctx, g, lane, c, soft, staticSoft, massLimit);
            continue;
          }
          const ContactConstraint& cc = constraints_[c];
          g.a[lane] = cc.a;
          g.b[lane] = cc.b;
          g.constraint[lane] = c;
          g.nx[lane] = cc.normal.x;
          g.ny[lane] = cc.normal.y;
          g.friction[lane] = cc.friction;
          g.invMassA[lane] = cc.invMassA;
          g.invIA[lane] = cc.invIA;
          g.invMassB[lane] = cc.invMassB;
          g.invIB[lane] = cc.invIB;
          // WorldDef::softMassRatioLimit: in a contact of two dynamic bodies whose masses differ
          // by more than the limit, the lighter one takes part as if it were only `limit` times
          // lighter (inverse mass and inertia scaled alike), so the heavy body's load cannot drive
          // it out of the way within a sub-step (a 1000 kg box on a 1 kg slab at 4 sub-steps sank
          // 0.16 m without it, 0.004 m with a limit of 10). Only where the lighter body also
          // touches a static or kinematic body, which absorbs momentum there anyway: between free
          // bodies momentum stays exact.
          // Over the limit with the light body unsupported: no warm start (LaneEnds::kCold).
          bool limited = false, cold = false;
          if (massLimit > 0 && cc.invMassA > 0 && cc.invMassB > 0) {
            if (cc.invMassA > massLimit * cc.invMassB) {
              MarkOverLimit();
              if (supported_[cc.a] == stamp_) {
                const Real f = massLimit * cc.invMassB / cc.invMassA;
                g.invMassA[lane] *= f;
                g.invIA[lane] *= f;
                limited = true;
              } else {
                cold = true;
              }
            } else if (cc.invMassB > massLimit * cc.invMassA) {
              MarkOverLimit();
              if (supported_[cc.b] == stamp_) {
                const Real f = massLimit * cc.invMassA / cc.invMassB;
                g.invMassB[lane] *= f;
                g.invIB[lane] *= f;
                limited = true;
              } else {
                cold = true;
              }
            }
          }
          const Softness& s = (cc.invMassA == 0 || cc.invMassB == 0) ? staticSoft : soft;
          g.biasRate[lane] = s.biasRate;
          g.massScale[lane] = s.massScale;
          g.impulseScale[lane] = s.impulseScale;
          for (int pt = 0; pt < 2; ++pt) {
            SoftPointRows& p = g.p[pt];
            if (pt >= cc.pointCount) {
              PadPoint(p, lane);
              continue;
            }
            const PointConstraint& pc = cc.points[pt];
            p.rAx[lane] = pc.rA.x;
            p.rAy[lane] = pc.rA.y;
            p.rBx[lane] = pc.rB.x;
            p.rBy[lane] = pc.rB.y;
            p.separation[lane] = pc.separation;
            p.normalMass[lane] = pc.normalMass;
            p.tangentMass[lane] = pc.tangentMass;
            if (limited) {
              const Vec2 n = cc.normal, t = RightPerp(n);
              const Real rnA = Cross(pc.rA, n), rnB = Cross(pc.rB, n);
              const Real rtA = Cross(pc.rA, t), rtB = Cross(pc.rB, t);
              const Real mA = g.invMassA[lane], mB = g.invMassB[lane], iA = g.invIA[lane], iB = g.invIB[lane];
              const Real kn = mA + mB + iA * rnA * rnA + iB * rnB * rnB;
              const Real kt = mA + mB + iA * rtA * rtA + iB * rtB * rtB;
              p.normalMass[lane] = kn > 0 ? Real(1) / kn : Real(0);
              p.tangentMass[lane] = kt > 0 ? Real(1) / kt : Real(0);
            }
            p.normalImpulse[lane] = cold ? Real(0) : pc.normalImpulse;
            p.tangentImpulse[lane] = cold ? Real(0) : pc.tangentImpulse;
            p.collisionImpulse[lane] = pc.collisionImpulse * collisionShare_;
          }
        }
      }
    }
  });
}

template void SoftStepSolver::BuildRows<true, true>(StepContext&, const Softness&, const Softness&, Real);
template void SoftStepSolver::BuildRows<true, false>(StepContext&, const Softness&, const Softness&, Real);
template void SoftStepSolver::BuildRows<false, true>(StepContext&, const Softness&, const Softness&, Real);
template void SoftStepSolver::BuildRows<false, false>(StepContext&, const Softness&, const Softness&, Real);

void SoftStepSolver::PropagateSupport(StageRunner& run, const StepContext& ctx, Real massLimit) {
  const Bodies& bodies = *ctx.bodies;
  const Contact* contacts = ctx.contacts.data();
  const int m = static_cast<int>(ctx.contacts.size());
  // Support flows across contacts between two dynamic bodies within the limit of each other only,
  // so a light body that touches a heavy one is not supported through it (a light ball striking a
  // heavy box on the ground keeps its own mass). Passes over the contacts, in parallel blocks,
  // until one changes nothing: the set reached is the closure of the supported bodies under that
  // rule, whatever the order, so it is the same for any thread count (a block may or may not see
  // another's marks of the same pass: that changes only how many passes run, and the last pass
  // marks nothing, so it saw every mark). Contacts come in body order, so a pile built bottom up
  // is mostly reached in the first pass. No body arrays are walked: a sparse scene costs a pass
  // or two over its few contacts (polygon_stress 1000 runs this whenever a sliver meets a large
  // polygon). Serial, on 16 threads' partition of a 2-core VM, it took 88 us a step on polygons
  // 64000.
  std::atomic<bool>& changed = support_.flag;
  uint32_t* supported = supported_.data();
  const uint32_t stamp = stamp_;
  do {
    changed.store(false, std::memory_order_relaxed);
    run.For(Stage::kSolve, m, run.MinItems(), [&](int b, int e, int) {
      bool marked = false;
      for (int c = b; c < e; ++c) {
        const int a = contacts[c].a, o = contacts[c].b;
        std::atomic_ref<uint32_t> ra(supported[size_t(a)]), ro(supported[size_t(o)]);
        const bool sa = ra.load(std::memory_order_relaxed) == stamp, so = ro.load(std::memory_order_relaxed) == stamp;
        if (sa == so) continue;
        const Real ia = bodies.inv[a].invMass, io = bodies.inv[o].invMass;
        if (ia <= 0 || io <= 0 || ia > massLimit * io || io > massLimit * ia) continue;
        (sa ? ro : ra).store(stamp, std::memory_order_relaxed);
        marked = true;
      }
      if (marked) changed.store(true, std::memory_order_relaxed);
    });
  } while (changed.load(std::memory_order_relaxed));  // read after the pass's join
}

// This step's stamp for supported_ (MarkRow).
void SoftStepSolver::NextStamp(int bodyCount, bool supported) {
  if (!supported) return;
  supported_.resize(bodyCount, 0);
  if (++stamp_ == 0) {  // wrapped (after 2^32 steps): no flag may hold the new stamp
    std::fill(supported_.begin(), supported_.end(), 0u);
    stamp_ = 1;
  }
}

}  // namespace quadrant
