// The README's "engine in 30 lines" as a complete program: a ball and a capsule dropped on a static
// box come to rest on it, and a ball pinned to it by a revolute joint hangs still. Built by CI against an installed Quadrant twice (examples/CMakeLists.txt with
// find_package, and g++ with pkg-config; .ci/package_test.sh), and run: it exits 1 if either is
// not resting on the ground.
#include <cmath>
#include <cstdio>

#include "quadrant/world.h"
using namespace quadrant;

int main() {
  WorldDef def;                                   // gravity (0,-10); soft_step: 4 sub-steps, 2 relax passes
  World world(def);
  BodyDef ground;                                 // static by default
  ground.shape = ShapeDef::Box(20, 0.5f);
  BodyId groundId = world.CreateBody(ground);
  BodyDef ball;
  ball.type = BodyType::kDynamic;
  ball.position = {0, 4};
  ball.shape = ShapeDef::MakeCircle(0.5f);
  BodyId id = world.CreateBody(ball);
  BodyDef pill = ball;                            // a capsule: two centres and a radius
  pill.position = {3, 2};
  pill.shape = ShapeDef::MakeCapsule({-0.5f, 0}, {0.5f, 0}, 0.25f);
  BodyId pillId = world.CreateBody(pill);
  BodyDef bob = ball;                             // a pendulum: a revolute joint to the ground
  bob.position = {-3, 4};
  BodyId bobId = world.CreateBody(bob);
  RevoluteJointDef pin;
  pin.bodyA = groundId;
  pin.bodyB = bobId;
  pin.localAnchorA = world.GetLocalPoint(groundId, {-3, 6});  // the pin, 2 m above the bob
  pin.localAnchorB = world.GetLocalPoint(bobId, {-3, 6});
  world.CreateRevoluteJoint(pin);
  for (int i = 0; i < 60; ++i) world.Step(1.0f / 60.0f);
  Vec2 p = world.GetPosition(id);                  // resting on the ground: y = 1.0
  Vec2 q = world.GetPosition(pillId);             // lying on its side: y = 0.75
  Vec2 r = world.GetPosition(bobId);              // hanging 2 m below the pin: y = 4.0

  std::printf("ball at x = %.3f m, y = %.3f m; capsule at y = %.3f m; pendulum at (%.3f, %.3f) m\n",
              static_cast<double>(p.x), static_cast<double>(p.y), static_cast<double>(q.y), static_cast<double>(r.x),
              static_cast<double>(r.y));
  // The ground's top is at y = 0.5 and the radius 0.5: resting means y = 1.0 within the
  // linear slop (0.005 m by default) and a little speculative margin.
  // The capsule lies on its side: its radius, 0.25, above the ground. The pendulum hangs 2 m
  // below its pin at (-3, 6), within the joint's softness.
  const bool pendulum = std::fabs(r.x + 3.0f) < 0.01f && std::fabs(r.y - 4.0f) < 0.01f;
  return std::fabs(p.y - 1.0f) < 0.02f && std::fabs(q.y - 0.75f) < 0.02f && pendulum ? 0 : 1;
}
