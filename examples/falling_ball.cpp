// The README's "engine in 15 lines" as a complete program: a ball dropped on a static box comes to
// rest on it. Built by CI against an installed Quadrant twice (examples/CMakeLists.txt with
// find_package, and g++ with pkg-config; .ci/package_test.sh), and run: it exits 1 if the ball is
// not resting on the ground.
#include <cmath>
#include <cstdio>

#include "quadrant/world.h"
using namespace quadrant;

int main() {
  WorldDef def;                                   // gravity (0,-10), soft_step, 4 sub-steps
  World world(def);
  BodyDef ground;                                 // static by default
  ground.shape = ShapeDef::Box(20, 0.5f);
  world.CreateBody(ground);
  BodyDef ball;
  ball.type = BodyType::kDynamic;
  ball.position = {0, 4};
  ball.shape = ShapeDef::MakeCircle(0.5f);
  BodyId id = world.CreateBody(ball);
  for (int i = 0; i < 60; ++i) world.Step(1.0f / 60.0f);
  Vec2 p = world.GetPosition(id);                  // resting on the ground: y = 1.0

  std::printf("ball at x = %.3f m, y = %.3f m\n", static_cast<double>(p.x), static_cast<double>(p.y));
  // The ground's top is at y = 0.5 and the radius 0.5: resting means y = 1.0 within the
  // linear slop (0.005 m by default) and a little speculative margin.
  return std::fabs(p.y - 1.0f) < 0.02f ? 0 : 1;
}
