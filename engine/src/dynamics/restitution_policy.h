// The restitution policies of the pgs solver (WorldDef::restitution), in one place so the solver
// names them at three call sites: Prepare (the bias), the normal rows (their target) and the
// step (whether collisions run).
//
// kCollisions: pairwise collisions before the velocity iterations (ApplyCollisions in
// contact_constraints.h); the normal rows only keep points from approaching, and a speculative point
// may close its gap s this step (target vn >= -s/dt).
//
// kBox2d: Box2D 2.4.1's velocity bias. The approach speed is captured once, before the solve;
// above the threshold a touching point's row targets -e vn. Speculative points keep their
// speculative row (Box2D has none: it lets the bodies overlap and bounces a step later).
// soft_step applies the same targets in rigid rows after its first sub-step's relax pass
// (soft_step_restitution.cpp, ApplyBox2dRestitution): with the skin, friction in each of four relax
// passes (softFrictionEveryRelaxPass) its p90 difference to Box2D is 0.69 %, 0.05 % against the
// analytic impact (same campaign).
// Measured on the random campaign (results/amd-epyc-2c/validation_random.md, 2000 hits, seed 17):
// the p90 difference of pgs to Box2D 2.4.1 goes from 5.21 % to 0.88 % with kBox2d, 0.61 % with
// the polygon skin too; against the analytic impact from 4.01 % to 0.04 %. The default stays
// kCollisions: it passes Newton's cradle and never ended a hit with more energy than it began
// (kBox2d, like Box2D and Newton's law with friction itself, reached 1.33 times).
#pragma once

#include "quadrant/types.h"

namespace quadrant {

/// Box2D 2.4.1's velocity bias of a point whose normal velocity before the solve is vn (m/s,
/// negative when approaching): -e vn above the threshold, else 0. Only touching points
/// (separation <= 0) get one: Box2D has a point only where shapes touch, and a speculative point
/// that bounced at once pushed off before its partner points had acted (campaign seed 17, hit
/// 101: 12.7 % from Box2D and from the analytic answer; a spinning corner passing 1-2 cm from a
/// circle in hit 187: 77 %).
inline Real Box2dRestitutionBias(Real restitution, Real threshold, Real vn, Real separation) {
  return restitution > 0 && separation <= 0 && vn < -threshold ? -restitution * vn : Real(0);
}

/// What a normal row adds to the point's normal velocity before clamping: the row keeps
/// vn + offset >= 0. A bias (kBox2d) asks for vn >= bias; otherwise a speculative gap s may
/// close this step (vn >= -s/dt); a touching point may not approach (vn >= 0).
inline Real NormalRowOffset(Real separation, Real restitutionBias, Real invDt) {
  if (restitutionBias > 0) return -restitutionBias;
  return separation > 0 ? separation * invDt : Real(0);
}

/// The separation a pair's points lose to WorldDef::polygonSkin (Box2D 2.4.1's polygon radius):
/// one skin per polygon of the pair. Here with the restitution policy because the two together
/// are what reproduces Box2D's responses; neither changes anything at its default.
inline Real PolygonSkin(const WorldDef& def, bool polygonA, bool polygonB) {
  return def.polygonSkin * Real(int(polygonA) + int(polygonB));
}

}  // namespace quadrant
