// The soft step's restitution (soft_step.h), on the solver states. By default restitution is
// applied before the sub-steps as pairwise collisions (ContactConstraints::ApplyCollisionPasses,
// shared with pgs), and the early-bounce shifts (ApplyStateBounceShifts) follow the last
// sub-step. With RestitutionPolicy::kBox2d it is Box2D's velocity target instead, applied after
// the first sub-step (ApplyBox2dRestitution).
//
// Promises: a bounce's friction stays within mu times the step's normal impulses, collision
// included (RestitutionPolicyTest.SlidingBounceGetsCoulombFrictionOverTheWholeImpact).
//
// Measured: applied after the sub-steps from the approach speed before the step (Box2D 3's way),
// restitution gained energy here (elastic polygon stress: +63 % kinetic energy), which is why
// the default applies it first.
#include <algorithm>
#include <type_traits>

#include "dynamics/soft_step.h"

namespace quadrant {

// RestitutionPolicy::kBox2d (restitution_policy.h): Box2D's restitution as a velocity target
// rather than a collision before the sub-steps. Each point whose approach speed before the step
// gave it a bias (touching, above the threshold) gets rigid rows after the first sub-step's relax
// pass: restitutionIterations passes of, per contact, friction then normal rows, the normal row
// keeping vn >= -e vn0 with an impulse of its own (it can only push apart), friction bounded by
// mu times the sub-step's normal impulse plus that one, as Box2D 2.4.1's iterations bound it by
// the whole biased impulse. The later sub-steps' warm start repeats this sub-step's friction and
// their relax pass clamps it back to their own bound, so the step's friction stays within mu
// times its normal impulses (RestitutionPolicyTest.SlidingBounceGetsCoulombFrictionOverTheWholeImpact).
//
// Why after the first sub-step, not after the last as Box2D 3 applies it: the bodies then move
// apart within the step, as in Box2D 2.4.1. One row at a time (no four-wide path), colour by
// colour as the rows are solved: it runs once per step, on bouncing points, under this setting.
template <bool kRotation, bool kFriction>
void SoftStepSolver::ApplyBox2dRestitution(StageRunner& run, const WorldDef& def, Real h) {
  SolverBody* states = states_.data();
  auto row = [&](SoftRowGroup& g, int lane) {
    const int c = g.constraint[lane];
    if (c < 0) return;
    const ContactConstraint& cc = constraints_[c];
    if (cc.points[0].restitutionBias <= 0 && (cc.pointCount < 2 || cc.points[1].restitutionBias <= 0)) return;
    const Vec2 n = cc.normal, t = RightPerp(n);
    SolverBody& A = states[cc.a];
    SolverBody& B = states[cc.b];
    SolverBody a = A, b = B;
    auto relative = [&](const PointConstraint& pc) { return RelativeVelocity<kRotation>(a, b, pc); };
    auto apply = [&](const PointConstraint& pc, Vec2 P) { ApplyPointImpulse<kRotation>(cc, pc, P, a, b); };
    Real bounce[2] = {0, 0};  // the normal rows' bounce impulses
    for (int it = 0; it < def.restitutionIterations; ++it) {
      if constexpr (kFriction) {
        for (int k = 0; k < cc.pointCount; ++k) {
          SoftPointRows& p = g.p[k];
          p.tangentImpulse[lane] = SolveFrictionRow<kRotation>(cc, cc.points[k], t, p.tangentImpulse[lane],
                                                               p.normalImpulse[lane] + bounce[k], a, b);
        }
      }
      const PointConstraint& p0 = cc.points[0];
      const PointConstraint& p1 = cc.points[1];
      if (cc.pointCount == 2 && cc.block && p0.restitutionBias > 0 && p1.restitutionBias > 0) {
        // Both points of a face together (the 2x2 problem, as pgs's block solver): one after the
        // other, four passes left a box landing flat spinning at 0.006 rad/s.
        const Real k11 = Real(1) / p0.normalMass, k22 = Real(1) / p1.normalMass;
        const Real b0 = Dot(relative(p0), n) - p0.restitutionBias - (k11 * bounce[0] + cc.k12 * bounce[1]);
        const Real b1 = Dot(relative(p1), n) - p1.restitutionBias - (cc.k12 * bounce[0] + k22 * bounce[1]);
        Real x0, x1;
        if (SolveLcp2(k11, cc.k12, k22, b0, b1, x0, x1)) {
          apply(p0, (x0 - bounce[0]) * n);
          apply(p1, (x1 - bounce[1]) * n);
          bounce[0] = x0;
          bounce[1] = x1;
        }
        continue;
      }
      for (int k = 0; k < cc.pointCount; ++k) {
        const PointConstraint& pc = cc.points[k];
        if (pc.restitutionBias <= 0) continue;
        const Real vn = Dot(relative(pc), n);
        const Real newImpulse = std::max(bounce[k] - pc.normalMass * (vn - pc.restitutionBias), Real(0));
        apply(pc, (newImpulse - bounce[k]) * n);
        bounce[k] = newImpulse;
      }
    }
    // The first sub-step's motion as if the bounce had acted from its start, as Box2D 2.4.1's
    // bias does within the step it is captured in.
    auto move = [&](SolverBody& to, const SolverBody& from) {
      to.dp += h * (from.v - to.v);
      if constexpr (kRotation) {
        if (from.w != to.w) to.dq = IntegrateRot(to.dq, h * (from.w - to.w));
      }
      to.v = from.v;
      to.w = from.w;
    };
    if (cc.invMassA > 0) move(A, a);
    if (cc.invMassB > 0) move(B, b);
  };
  ForEachGroup(run, false, [&](auto lanes, SoftRowGroup& g, int lane) {
    if constexpr (std::is_same_v<decltype(lanes), Real>) {
      row(g, lane);
    } else {
      for (int l = lane; l < lane + kLaneWidth<decltype(lanes)>; ++l) row(g, l);
    }
  });
}

template void SoftStepSolver::ApplyBox2dRestitution<true, true>(StageRunner&, const WorldDef&, Real);
template void SoftStepSolver::ApplyBox2dRestitution<true, false>(StageRunner&, const WorldDef&, Real);
template void SoftStepSolver::ApplyBox2dRestitution<false, true>(StageRunner&, const WorldDef&, Real);
template void SoftStepSolver::ApplyBox2dRestitution<false, false>(StageRunner&, const WorldDef&, Real);

// ApplyBounceShifts (contact_constraints.h) on the solver states.
void SoftStepSolver::ApplyStateBounceShifts(int begin, int end) {
  for (int c = begin; c < end; ++c) {
    const ContactConstraint& cc = constraints_[c];
    Vec2 d;
    if (!ContactConstraints::BounceShift(cc, d)) continue;
    if (cc.invMassA > 0) states_[cc.a].dp += cc.invMassA * d;
    if (cc.invMassB > 0) states_[cc.b].dp -= cc.invMassB * d;
  }
}

}  // namespace quadrant
