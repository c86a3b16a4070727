// Shared helpers for the engine unit tests: one-line construction of small worlds and a
// few comparison utilities. Header-only, included by several test files.
#pragma once

#include <gtest/gtest.h>

#include <stdlib.h>

#include <algorithm>
#include <functional>
#include <string>
#include <cmath>
#include <ostream>
#include <vector>

#include "quadrant/error.h"
#include "quadrant/math.h"
#include "quadrant/shapes.h"
#include "quadrant/world.h"

namespace quadrant::test {

// On a busy machine the default pool runs whole steps on the one-thread path (RunsAlone), and a
// determinism test would then compare one thread with one thread. QUADRANT_POOL_ALONE=0 keeps
// every step on the partitioned path (serially when the pool is serial); set before main, unless
// the environment already says otherwise.
[[maybe_unused]] inline const bool kPoolStepsSplit = (setenv("QUADRANT_POOL_ALONE", "0", 0), true);

inline constexpr Real kDt = Real(1) / Real(60);
inline constexpr double kPi = 3.14159265358979323846;

/// A world definition without gravity (for collision experiments).
inline WorldDef NoGravityDef(SolverType solver = SolverType::kPgs) {
  WorldDef def;
  def.gravity = {0, 0};
  def.solver = solver;
  return def;
}

/// A static ground box of half-widths hx, hy centred at `center` (top face at center.y + hy).
inline BodyId AddGround(World& world, Real hx = 20, Real hy = Real(0.5), Vec2 center = {0, 0}) {
  BodyDef def;
  def.type = BodyType::kStatic;
  def.position = center;
  def.shape = ShapeDef::Box(hx, hy);
  return world.CreateBody(def);
}

/// A dynamic box of half-widths hx, hy at `position`.
inline BodyId AddBox(World& world, Vec2 position, Real hx = Real(0.5), Real hy = Real(0.5),
                     Real density = 1, Real angle = 0, Vec2 velocity = {}) {
  BodyDef def;
  def.type = BodyType::kDynamic;
  def.position = position;
  def.angle = angle;
  def.linearVelocity = velocity;
  def.shape = ShapeDef::Box(hx, hy);
  def.shape.density = density;
  return world.CreateBody(def);
}

/// A dynamic circle of radius r at `position`.
inline BodyId AddCircle(World& world, Vec2 position, Real radius = Real(0.5), Vec2 velocity = {},
                        Real density = 1, Real friction = Real(0.6), Real restitution = 0) {
  BodyDef def;
  def.type = BodyType::kDynamic;
  def.position = position;
  def.linearVelocity = velocity;
  def.shape = ShapeDef::MakeCircle(radius);
  def.shape.density = density;
  def.shape.friction = friction;
  def.shape.restitution = restitution;
  return world.CreateBody(def);
}

/// Whether the last Step ran at least one section on more than one worker: a parallel section
/// adds every worker's time to a stage's work but only the largest share to its critical path,
/// so work exceeds critical path exactly when one ran (serial sections add the same to both).
inline bool ParallelSectionRan(const Profile& profile) {
  for (const StageBalance& b : profile.balance) {
    if (b.workMs > b.criticalMs) return true;
  }
  return false;
}

inline void StepN(World& world, int n, Real dt = kDt) {
  for (int i = 0; i < n; ++i) world.Step(dt);
}

/// Most negative separation over all contact points touching `body` (0 when none).
inline Real DeepestPenetration(const World& world, BodyId body) {
  Real deepest = 0;
  for (const ContactInfo& c : world.GetContacts()) {
    if (!(c.bodyA == body) && !(c.bodyB == body)) continue;
    for (int i = 0; i < c.pointCount; ++i) deepest = std::min(deepest, c.separations[i]);
  }
  return deepest;
}

inline ::testing::AssertionResult VecNear(Vec2 got, Vec2 want, double tol) {
  double dx = double(got.x) - double(want.x);
  double dy = double(got.y) - double(want.y);
  if (std::isfinite(dx) && std::isfinite(dy) && std::abs(dx) <= tol && std::abs(dy) <= tol) {
    return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure() << "got (" << got.x << ", " << got.y << "), want ("
                                       << want.x << ", " << want.y << ") within " << tol;
}

/// Expects `call` to throw quadrant::Error whose message contains `message` (`what` names the
/// case in the failure).
inline void ExpectError(const std::function<void()>& call, const std::string& message, const std::string& what) {
  SCOPED_TRACE(what);
  try {
    call();
    ADD_FAILURE() << "no quadrant::Error thrown; expected one containing '" << message << "'";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(message), std::string::npos)
        << "message '" << e.what() << "' lacks '" << message << "'";
  }
}

}  // namespace quadrant::test

namespace quadrant {
/// Readable names for parameterised tests' failure messages (found by ADL).
inline void PrintTo(SolverType s, std::ostream* os) { *os << (s == SolverType::kThesis ? "kThesis" : "kPgs"); }
}  // namespace quadrant
