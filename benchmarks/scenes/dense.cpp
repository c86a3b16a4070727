// The dense, solver-bound benchmark scenes beside `pyramid` (issue #13 item 6): Box2D 3's
// "many pyramids" and "tumbler" benchmarks (its shared/benchmarks.c) in the scene API. Sizes and
// counts follow Box2D 3's; the code is this project's. Unlike the stress scenes, most bodies
// touch several others at every step, so the contact solver does most of the work.
#include <cmath>
#include <numbers>
#include <string>

#include "adapter.h"
#include "quadrant/error.h"
#include "scenes.h"

namespace quadrant::scene {
namespace {

constexpr int kPyramidBase = 10;                                    // Box2D 3: base 10, 55 boxes
constexpr int kPyramidBoxes = kPyramidBase * (kPyramidBase + 1) / 2;
constexpr int kTumblerMaxGrid = 46;  // 46 x 46 boxes at 0.4 m pitch still fit inside the walls


BodyDesc Box(Vec2 position, Real hx, Real hy, bool dynamic) {
  BodyDesc b = MakeBoxBody(position, hx, hy, dynamic);
  b.density = dynamic ? 1 : 0;
  b.friction = Real(0.6);
  b.restitution = 0;
  return b;
}

}  // namespace

Scene Box2d3BenchmarkBase(const char* name) {
  Scene s;
  s.name = name;
  s.gravity = {0, Real(-10)};
  s.timeStep = Real(1.0 / 60.0);
  s.pipelineRepeats = 1;
  s.velocityIterations = 8;  // the default budget of every engine
  s.positionIterations = 3;
  s.restitutionThreshold = 1;
  s.effects.gravity = true;
  s.effects.friction = true;
  s.effects.restitution = false;  // restitution 0 on every body
  s.effects.rotation = true;
  s.effects.warmStarting = true;
  s.effects.sleep = false;  // a benchmark must simulate every body every step (Box2D 3 too)
  s.effects.continuous = false;
  s.effects.damping = false;
  return s;
}

Scene MakeManyPyramids(int count) {
  if (count < kPyramidBoxes || count > 1000000) {
    throw Error("many_pyramids: count must be in [" + std::to_string(kPyramidBoxes) + ", 1000000] boxes, got " +
                std::to_string(count));
  }
  Scene s = Box2d3BenchmarkBase("many_pyramids");
  const int pyramids = count / kPyramidBoxes;
  const int columns = int(std::ceil(std::sqrt(double(pyramids))));
  const int rows = (pyramids + columns - 1) / columns;
  // Each pyramid in a cell base + 1 m wide; each row of pyramids on its own thin static shelf,
  // base + 1 m above the one below (Box2D 3 stacks its rows the same way, 20 x 20 at 22000).
  const double cell = kPyramidBase + 1.0, width = columns * cell, shelf = 0.2;
  for (int r = 0; r < rows; ++r) {
    const double groundY = r * cell;
    s.bodies.push_back(Box({0, Real(groundY - 0.5 * shelf)}, Real(0.5 * width), Real(0.5 * shelf), false));
  }
  for (int p = 0; p < pyramids; ++p) {
    const double groundY = (p / columns) * cell;
    const double left = -0.5 * width + (p % columns) * cell + 0.5;
    // Rows of touching 1 m boxes, each row half a box in from the one below.
    for (int row = 0; row < kPyramidBase; ++row) {
      for (int j = 0; j < kPyramidBase - row; ++j) {
        const double x = left + 0.5 * row + j + 0.5;
        const double y = groundY + 0.5 + row;
        s.bodies.push_back(Box({Real(x), Real(y)}, Real(0.5), Real(0.5), true));
      }
    }
  }
  s.bounds = {{Real(-0.5 * width), Real(-shelf)}, {Real(0.5 * width), Real(rows * cell)}};
  return s;
}

Scene MakeTumbler(int count) {
  const int grid = int(std::ceil(std::sqrt(double(count))));
  if (count < 1 || grid > kTumblerMaxGrid) {
    throw Error("tumbler: count must be in [1, " + std::to_string(kTumblerMaxGrid * kTumblerMaxGrid) +
                "] boxes, got " + std::to_string(count));
  }
  Scene s = Box2d3BenchmarkBase("tumbler");
  // Box2D 3's tumbler: a 20 m square of 1 m thick walls centred 10 m up, turning at 25 degrees
  // per second, with small boxes (0.25 m) tumbling inside. Box2D 3 turns one body of four
  // shapes with a motor joint; the scene API has one shape per body and no joints, so here four
  // kinematic walls follow the same rigid rotation (the driver below).
  const Vec2 pivot{0, 10};
  const double omega = 25.0 * std::numbers::pi / 180.0, dt = double(s.timeStep);
  const Vec2 offsets[4] = {{10, 0}, {-10, 0}, {0, 10}, {0, -10}};
  auto wallPosition = [=](int k, int step) {
    const double a = omega * dt * step, c = std::cos(a), sn = std::sin(a);
    const double x = offsets[k].x, y = offsets[k].y;
    return Vec2{Real(pivot.x + c * x - sn * y), Real(pivot.y + sn * x + c * y)};
  };
  // Each step a wall moves along the chord from where the rotation puts it now to where it puts
  // it next: engines integrate a kinematic body exactly (x += v dt), so the walls stay on the
  // circle instead of spiralling out as tangent velocities would.
  auto chord = [=](int k, int step) {
    const Vec2 a = wallPosition(k, step), b = wallPosition(k, step + 1);
    return Vec2{Real((double(b.x) - a.x) / dt), Real((double(b.y) - a.y) / dt)};
  };
  for (int k = 0; k < 4; ++k) {
    const bool vertical = k < 2;
    BodyDesc wall = Box(wallPosition(k, 0), vertical ? Real(0.5) : Real(10), vertical ? Real(10) : Real(0.5), false);
    wall.kinematic = true;
    wall.velocity = chord(k, 0);
    wall.angularVelocity = Real(omega);
    s.bodies.push_back(wall);
  }
  s.driver = [=](int step, Adapter& adapter) {
    for (int k = 0; k < 4; ++k) adapter.SetVelocity(k, chord(k, step), Real(omega));
  };
  const double pitch = 0.4, start = -0.2 * grid;
  for (int i = 0; i < count; ++i) {
    const double x = pivot.x + start + pitch * (i % grid), y = pivot.y + start + pitch * (i / grid);
    s.bodies.push_back(Box({Real(x), Real(y)}, Real(0.125), Real(0.125), true));
  }
  s.bounds = {{Real(pivot.x - 15), Real(pivot.y - 15)}, {Real(pivot.x + 15), Real(pivot.y + 15)}};
  return s;
}

}  // namespace quadrant::scene
