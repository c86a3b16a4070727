// Box2D 3's "joint_grid", "junkyard" and "smash" benchmark scenes (its shared/benchmarks.c, 800 and 300 steps
// there) in the scene API, at its sizes by default; the code is this project's. Box2D 3 builds
// its static ground as one body of many boxes, here each box is a static body of its own (the
// same surfaces; Quadrant bodies carry one shape). Box2D 3 moves junkyard's pusher with
// b2Body_SetTargetTransform, which sets the velocity that reaches the target in one step; the
// scene's driver does the same through Adapter::SetVelocity.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "adapter.h"
#include "quadrant/error.h"
#include "scenes.h"

namespace quadrant::scene {
namespace {

constexpr int kJunkyardColumns = 200;
constexpr int kSmashRows = 80;

// Box2D 3's benchmark worlds sleep (b2DefaultWorldDef); these two scenes need it (smash's wall
// is created asleep).
Scene Box2d3Base(const char* name) {
  Scene s = Box2d3BenchmarkBase(name);
  s.effects.sleep = true;
  return s;
}

BodyDesc StaticBox(Vec2 centre, Real hx, Real hy) { return MakeBoxBody(centre, hx, hy, /*dynamic=*/false); }

}  // namespace

Scene MakeJunkyard(int count) {
  if (count < kJunkyardColumns || count > 200000) {
    throw Error("junkyard: count must be in [" + std::to_string(kJunkyardColumns) + ", 200000] pentagons, got " +
                std::to_string(count));
  }
  Scene s = Box2d3Base("junkyard");
  // The pusher first (body 0, the driver's): a 4 x 8 m kinematic box, its centre 4 m up.
  BodyDesc pusher = MakeBoxBody({0, 4}, 2, 4, /*dynamic=*/false);
  pusher.kinematic = true;
  s.bodies.push_back(pusher);
  // The ground: 161 boxes 1.1 x 1 m along y = 0 from x = -80, and two walls of 50 boxes 1 x 1.1 m
  // up from y = 1 at x = -80 and x = 80.
  for (int i = 0; i < 161; ++i) s.bodies.push_back(StaticBox({Real(-80 + i), 0}, Real(0.55), Real(0.5)));
  for (int side : {-80, 80}) {
    for (int i = 0; i < 50; ++i) s.bodies.push_back(StaticBox({Real(side), Real(1 + i)}, Real(0.5), Real(0.55)));
  }
  // Pentagons of circumradius 0.25: five points of a Fibonacci spiral on the circle, as their
  // convex hull (counter-clockwise, by angle).
  const double radius = 0.25, phi = std::numbers::pi * (std::sqrt(5.0) - 1.0);
  std::vector<std::pair<double, Vec2>> byAngle;
  for (int i = 0; i < 5; ++i) {
    const double theta = std::remainder(phi * i, 2 * std::numbers::pi);
    byAngle.push_back({theta, Vec2{Real(radius * std::cos(phi * i)), Real(radius * std::sin(phi * i))}});
  }
  std::sort(byAngle.begin(), byAngle.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<Vec2> pentagon;
  for (const auto& p : byAngle) pentagon.push_back(p.second);
  const int rows = count / kJunkyardColumns;
  double side = -0.1;
  for (int i = 0; i < kJunkyardColumns; ++i) {
    const double x = 1.5 * (2.0 * i - kJunkyardColumns) * radius;
    for (int j = 0; j < rows; ++j) {
      BodyDesc b;
      b.shape = ShapeKind::kPolygon;
      b.vertices = pentagon;
      b.position = {Real(x + side), Real(4.0 * j * radius + 15.0)};
      side = -side;
      s.bodies.push_back(b);
    }
  }
  s.bounds = {{-81, -1}, {81, Real(15 + rows + 1)}};
  // Target x = 60 sin(0.2 t) at the end of each step: the velocity that gets there in one step.
  const Real dt = s.timeStep;
  s.driver = [dt](int step, Adapter& adapter) {
    const double from = 60.0 * std::sin(0.2 * double(step) * dt), to = 60.0 * std::sin(0.2 * double(step + 1) * dt);
    adapter.SetVelocity(0, {Real((to - from) / dt), 0}, 0);
  };
  return s;
}

Scene MakeSmash(int count) {
  if (count < kSmashRows || count > 1000000) {
    throw Error("smash: count must be in [" + std::to_string(kSmashRows) + ", 1000000] boxes, got " + std::to_string(count));
  }
  Scene s = Box2d3Base("smash");
  s.gravity = {0, 0};
  s.effects.gravity = false;
  // An 8 m box of density 8 at 40 m/s (body 0) into a wall of touching 0.4 m boxes created asleep,
  // 80 rows high: count / 80 columns from x = 30.
  BodyDesc ram = MakeBoxBody({-20, 0}, 4, 4);
  ram.density = 8;
  ram.velocity = {40, 0};
  s.bodies.push_back(ram);
  const double d = 0.4;
  const int columns = count / kSmashRows;
  for (int i = 0; i < columns; ++i) {
    for (int j = 0; j < kSmashRows; ++j) {
      BodyDesc b = MakeBoxBody({Real(i * d + 30.0), Real((j - kSmashRows / 2.0) * d)}, Real(0.5 * d), Real(0.5 * d));
      b.awake = false;
      s.bodies.push_back(b);
    }
  }
  s.bounds = {{-25, Real(-0.5 * kSmashRows * d - 1)}, {Real(30 + columns * d + 1), Real(0.5 * kSmashRows * d + 1)}};
  return s;
}

Scene MakeJointGrid(int count) {
  if (count < 57 || count > 1000000) {
    throw Error("joint_grid: count must be in [57, 1000000] dynamic bodies, got " + std::to_string(count));
  }
  // The smallest N x N grid with at least `count` dynamic bodies (seven are static): built again
  // from its own dynamic count, the same grid.
  int n = int(std::sqrt(double(count + 7)));
  while (n * n - 7 < count) ++n;
  Scene s = Box2d3BenchmarkBase("joint_grid");
  // Columns k (x = k) of rows i (y = -i), column by column as Box2D 3 builds them; the top row's
  // seven middle bodies are static. Circles of radius 0.4, 1 m apart, filtered never to collide
  // (category 2, mask everything but 2), each joined to the one above and the one to its left.
  for (int k = 0; k < n; ++k) {
    for (int i = 0; i < n; ++i) {
      const bool fixed = i == 0 && k >= n / 2 - 3 && k <= n / 2 + 3;
      BodyDesc b = MakeCircleBody({Real(k), Real(-i)}, Real(0.4), !fixed);
      b.categoryBits = 2;
      b.maskBits = ~2u;
      const int index = int(s.bodies.size());
      s.bodies.push_back(b);
      if (i > 0) s.joints.push_back(JointDesc{index - 1, index, {Real(k), Real(-i) + Real(0.5)}});
      if (k > 0) s.joints.push_back(JointDesc{index - n, index, {Real(k) - Real(0.5), Real(-i)}});
    }
  }
  s.bounds = AABB{{-Real(n), -Real(2 * n)}, {Real(2 * n), Real(n)}};
  return s;
}

}  // namespace quadrant::scene
