// Symplectic Euler integration at a fixed step.
#include "integrate.h"

#include <algorithm>

namespace quadrant {

void IntegrateVelocities(Bodies& bodies, const WorldDef& def, Real dt, StageRunner& run) {
  const Effects& fx = def.effects;
  if (!fx.gravity && !fx.damping) return;  // nothing to do: not even a pass over the bodies
  run.For(Stage::kIntegrate, bodies.Count(), run.MinItems(), [&](int begin, int end, int) {
    if (fx.gravity) {
      const Vec2 dv = dt * def.gravity;
      for (int i = begin; i < end; ++i) {
        if (bodies.type[i] == BodyType::kDynamic) bodies.vel[i].v += dv;
      }
    }
    if (fx.damping) {
      // The implicit form 1 / (1 + dt c) stays stable for any c, unlike 1 - dt c.
      for (int i = begin; i < end; ++i) {
        if (bodies.type[i] != BodyType::kDynamic) continue;
        bodies.vel[i].v = (Real(1) / (Real(1) + dt * bodies.linearDamping[i])) * bodies.vel[i].v;
        bodies.vel[i].w *= Real(1) / (Real(1) + dt * bodies.angularDamping[i]);
      }
    }
  });
}

void IntegratePositions(Bodies& bodies, const WorldDef& def, Real dt, StageRunner& run) {
  run.For(Stage::kIntegrate, bodies.Count(), run.MinItems(),
          [&](int begin, int end, int) { IntegratePositionsRange(bodies, def, dt, begin, end); });
}

void IntegratePositionsRange(Bodies& bodies, const WorldDef& def, Real dt, int begin, int end) {
  const Real maxSpeed2 = def.maxLinearSpeed * def.maxLinearSpeed;
  const Real maxAngularSpeed = def.maxRotation / dt;
  const bool rotation = def.effects.rotation;
  for (int i = begin; i < end; ++i) {
    if (bodies.type[i] == BodyType::kStatic) continue;
    BodyVelocity& bv = bodies.vel[i];
    const Real speed2 = LengthSquared(bv.v);
    if (speed2 > maxSpeed2) bv.v = (def.maxLinearSpeed / std::sqrt(speed2)) * bv.v;
    bv.w = std::clamp(bv.w, -maxAngularSpeed, maxAngularSpeed);
    bodies.center[i] += dt * bv.v;
    // Most bodies of frictionless scenes never spin: skip the renormalisation for them.
    if (rotation && bv.w != 0) bodies.xf[i].q = IntegrateRot(bodies.xf[i].q, dt * bv.w);
    SyncTransform(bodies, i);
  }
}

}  // namespace quadrant
