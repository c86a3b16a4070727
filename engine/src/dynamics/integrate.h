// Integration: symplectic Euler at a fixed time step (velocities first, then positions with the
// new velocities). The thesis used the wall-clock duration of the previous step as dt, which
// made runs unrepeatable; the suite needs fixed steps.
#pragma once

#include <algorithm>
#include <cmath>

#include "world/world_internal.h"

namespace quadrant {

/// v += dt * gravity (if the effect is on), then damping (if on): v *= 1 / (1 + dt * c).
void IntegrateVelocities(Bodies& bodies, const WorldDef& def, Real dt, StageRunner& run);

/// centre += dt * v, rotation += dt * w (if rotation is on); updates the origin transform.
/// Speeds above def.maxLinearSpeed and rotations above def.maxRotation per step are limited to
/// them (numerical guards, as in Box2D).
void IntegratePositions(Bodies& bodies, const WorldDef& def, Real dt, StageRunner& run);

/// The same over a sub-step dt of a world step stepDt: the angular speed limit stays
/// def.maxRotation / stepDt. It is a limit per world step (WorldDef::maxRotation), which a
/// sub-stepping solver would otherwise raise by its sub-step count (as Box2D 3: B2_MAX_ROTATION
/// times the inverse of the whole step).
void IntegratePositions(Bodies& bodies, const WorldDef& def, Real dt, Real stepDt, StageRunner& run);

/// The same for bodies [begin, end), on the calling thread.
void IntegratePositionsRange(Bodies& bodies, const WorldDef& def, Real dt, int begin, int end);

/// The numerical guards of a position step (as in Box2D): the speed limited to maxSpeed
/// (maxSpeed2 its square) and the angular speed to maxAngularSpeed.
inline void LimitSpeeds(Vec2& v, Real& w, Real maxSpeed2, Real maxSpeed, Real maxAngularSpeed) {
  const Real speed2 = LengthSquared(v);
  if (speed2 > maxSpeed2) v = (maxSpeed / std::sqrt(speed2)) * v;
  w = std::clamp(w, -maxAngularSpeed, maxAngularSpeed);
}

/// Recomputes the origin transform of body i from its centre of mass and rotation.
inline void SyncTransform(Bodies& bodies, int i) {
  bodies.xf[i].p = bodies.center[i] - Rotate(bodies.xf[i].q, bodies.localCenter[i]);
}

}  // namespace quadrant
