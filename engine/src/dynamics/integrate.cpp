// Symplectic Euler integration at a fixed step.
#include "dynamics/integrate.h"

#include <algorithm>

namespace quadrant {

namespace {

// kSleep: a sleeping body has type dynamic but `dynamic` 0 (islands.cpp) and gets no gravity.
// The test is a template parameter so a world without sleep runs exactly the code it ran before.
template <bool kSleep>
bool GetsForces(const Bodies& bodies, int i) {
  if constexpr (kSleep) return bodies.dynamic[i] != 0;
  return bodies.type[i] == BodyType::kDynamic;
}

template <bool kSleep>
void IntegrateVelocitiesImpl(Bodies& bodies, const WorldDef& def, Real dt, StageRunner& run) {
  const Effects& fx = def.effects;
  run.For(Stage::kIntegrate, bodies.Count(), run.MinItems(), [&](int begin, int end, int) {
    if (fx.gravity) {
      const Vec2 dv = dt * def.gravity;
      for (int i = begin; i < end; ++i) {
        if (GetsForces<kSleep>(bodies, i)) bodies.vel[i].v += dv;
      }
    }
    if (fx.damping) {
      // The implicit form 1 / (1 + dt c) stays stable for any c, unlike 1 - dt c.
      for (int i = begin; i < end; ++i) {
        if (!GetsForces<kSleep>(bodies, i)) continue;
        bodies.vel[i].v = (Real(1) / (Real(1) + dt * bodies.linearDamping[i])) * bodies.vel[i].v;
        bodies.vel[i].w *= Real(1) / (Real(1) + dt * bodies.angularDamping[i]);
      }
    }
  });
}

template <bool kSleep>
void IntegratePositionsImpl(Bodies& bodies, const WorldDef& def, Real dt, Real stepDt, int begin, int end) {
  const Real maxSpeed2 = def.maxLinearSpeed * def.maxLinearSpeed;
  const Real maxAngularSpeed = def.maxRotation / stepDt;
  const bool rotation = def.effects.rotation;
  for (int i = begin; i < end; ++i) {
    if constexpr (kSleep) {
      if (bodies.awake[i] == 0) continue;  // static or sleeping: not integrated
    } else {
      if (bodies.type[i] == BodyType::kStatic) continue;
    }
    BodyVelocity& bv = bodies.vel[i];
    LimitSpeeds(bv.v, bv.w, maxSpeed2, def.maxLinearSpeed, maxAngularSpeed);
    bodies.center[i] += dt * bv.v;
    // Most bodies of frictionless scenes never spin: skip the renormalisation for them.
    if (rotation && bv.w != 0) bodies.xf[i].q = IntegrateRot(bodies.xf[i].q, dt * bv.w);
    SyncTransform(bodies, i);
  }
}

}  // namespace

void IntegrateVelocities(Bodies& bodies, const WorldDef& def, Real dt, StageRunner& run) {
  const Effects& fx = def.effects;
  if (!fx.gravity && !fx.damping) return;  // nothing to do: not even a pass over the bodies
  if (fx.sleep) {
    IntegrateVelocitiesImpl<true>(bodies, def, dt, run);
  } else {
    IntegrateVelocitiesImpl<false>(bodies, def, dt, run);
  }
}

void IntegratePositions(Bodies& bodies, const WorldDef& def, Real dt, StageRunner& run) {
  IntegratePositions(bodies, def, dt, dt, run);
}

void IntegratePositions(Bodies& bodies, const WorldDef& def, Real dt, Real stepDt, StageRunner& run) {
  run.For(Stage::kIntegrate, bodies.Count(), run.MinItems(), [&](int begin, int end, int) {
    if (def.effects.sleep) {
      IntegratePositionsImpl<true>(bodies, def, dt, stepDt, begin, end);
    } else {
      IntegratePositionsImpl<false>(bodies, def, dt, stepDt, begin, end);
    }
  });
}

void IntegratePositionsRange(Bodies& bodies, const WorldDef& def, Real dt, int begin, int end) {
  if (def.effects.sleep) {
    IntegratePositionsImpl<true>(bodies, def, dt, dt, begin, end);
  } else {
    IntegratePositionsImpl<false>(bodies, def, dt, dt, begin, end);
  }
}

}  // namespace quadrant
