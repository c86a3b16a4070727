// Box2D 3's "joint_grid", "junkyard", "smash", "compounds" and "washer" benchmark scenes (its
// shared/benchmarks.c; 500, 800, 300, 500 and 500 steps there) in the scene API, at its sizes by
// default; the code is this project's. Box2D 3 builds its static ground as one body of many boxes,
// here each box is a static body of its own (the same surfaces, and more than the 64 shapes a
// Quadrant body carries); compounds' bodies of two triangles and washer's drum of 40 polygons are
// compound bodies (BodyDesc::extraShapes), as in Box2D 3. Box2D 3 moves junkyard's pusher with
// b2Body_SetTargetTransform, which sets the velocity that reaches the target in one step; the
// scene's driver does the same through Adapter::SetVelocity.
#include <algorithm>
#include <cmath>
#include <initializer_list>
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
constexpr int kCompoundColumns = 20;
constexpr int kSmashRows = 80;

// Box2D 3's benchmark worlds sleep (b2DefaultWorldDef); these two scenes need it (smash's wall
// is created asleep).
Scene Box2d3Base(const char* name) {
  Scene s = Box2d3BenchmarkBase(name);
  s.effects.sleep = true;
  return s;
}

BodyDesc StaticBox(Vec2 centre, Real hx, Real hy) { return MakeBoxBody(centre, hx, hy, /*dynamic=*/false); }

// The convex hull of `points`, counter-clockwise (the scene API's order), as MakePolygon makes it.
std::vector<Vec2> Hull(std::initializer_list<Vec2> points) {
  const std::vector<Vec2> in(points);
  const Polygon hull = MakePolygon(in);
  return std::vector<Vec2>(hull.vertices.begin(), hull.vertices.begin() + hull.count);
}

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

Scene MakeCompounds(int count) {
  if (count < kCompoundColumns || count > 200000) {
    throw Error("compounds: count must be in [" + std::to_string(kCompoundColumns) + ", 200000] bodies, got " +
                std::to_string(count));
  }
  Scene s = Box2d3BenchmarkBase("compounds");
  // The ground: 81 boxes 1.1 x 1 m along y = 0 from x = -40, two walls of 100 boxes 1 x 1.1 m up
  // from y = 1 at x = -40 and x = 40, and a segment 80 m below from x = -800 to 800.
  for (int i = 0; i < 81; ++i) s.bodies.push_back(StaticBox({Real(-40 + i), 0}, Real(0.55), Real(0.5)));
  for (int side : {-40, 40}) {
    for (int i = 0; i < 100; ++i) s.bodies.push_back(StaticBox({Real(side), Real(1 + i)}, Real(0.5), Real(0.55)));
  }
  s.bodies.push_back(MakeSegmentBody({0, 0}, {-800, -80}, {800, -80}));
  // count / 20 rows of 20 columns of bodies made of two triangles (density 1, friction 0.5), 2 m
  // apart in x and 2.25 m in y from y = 5.575, each shifted 0.25 m left or right in turn.
  const int rows = count / kCompoundColumns;
  BodyDesc body;
  body.shape = ShapeKind::kPolygon;
  body.vertices = Hull({{-1, 0}, {Real(0.5), 1}, {0, 2}});
  body.friction = Real(0.5);
  ShapeDesc right;
  right.vertices = Hull({{1, 0}, {Real(-0.5), 1}, {0, 2}});
  right.friction = Real(0.5);
  body.extraShapes.push_back(right);
  double side = 0.25;
  const double centerX = 2.0 * kCompoundColumns / 2 - 1;
  for (int i = 0; i < kCompoundColumns; ++i) {
    for (int j = 0; j < rows; ++j) {
      body.position = {Real(i * 2.0 - centerX + side), Real(j * 2.25 + 1.15 / 2 + 5)};
      side = -side;
      s.bodies.push_back(body);
    }
  }
  s.bounds = {{-801, -81}, {801, Real(rows * 2.25 + 10)}};
  return s;
}

Scene MakeWasher(int count) {
  if (count < 4 || count > 40000) {
    throw Error("washer: count must be in [4, 40000] boxes (Box2D 3's 90 x 90 = 8100), got " + std::to_string(count));
  }
  int grid = int(std::sqrt(double(count)));  // the largest square grid within count
  while ((grid + 1) * (grid + 1) <= count) ++grid;
  while (grid * grid > count) --grid;
  Scene s = Box2d3BenchmarkBase("washer");
  // The drum (body 0): one kinematic body at (0, 10) turning at 25 deg/s and drifting at (0.001,
  // -0.002) m/s as Box2D 3's does, of 36 quadrilaterals between radii 16 and 18, each over its 10
  // degrees and 1 degree more at each end, and 4 fins between radii 14 and 16 over the 10 degrees
  // from 0, 90, 180 and 270 degrees: 40 polygons.
  BodyDesc drum;
  drum.dynamic = false;
  drum.kinematic = true;
  drum.position = {0, 10};
  drum.angularVelocity = Real(std::numbers::pi / 180 * 25);
  drum.velocity = {Real(0.001), Real(-0.002)};
  const double step = std::numbers::pi / 18;
  auto at = [](double radius, double angle) { return Vec2{Real(radius * std::cos(angle)), Real(radius * std::sin(angle))}; };
  for (int i = 0; i < 36; ++i) {
    const double a1 = i * step - 0.1 * step, a2 = (i + 1) * step + 0.1 * step;
    std::vector<Vec2> outer = Hull({at(16, a1), at(18, a1), at(16, a2), at(18, a2)});
    if (i == 0) {
      drum.shape = ShapeKind::kPolygon;
      drum.vertices = outer;
    } else {
      ShapeDesc piece;
      piece.vertices = outer;
      drum.extraShapes.push_back(piece);
    }
    if (i % 9 == 0) {
      ShapeDesc fin;
      fin.vertices = Hull({at(14, i * step), at(16, i * step), at(14, (i + 1) * step), at(16, (i + 1) * step)});
      drum.extraShapes.push_back(fin);
    }
  }
  s.bodies.push_back(drum);
  // grid x grid boxes 0.2 m wide, 0.21 m apart, from (-0.11 grid, 10 - 0.11 grid).
  const double a = 0.1;
  for (int i = 0; i < grid; ++i) {
    for (int j = 0; j < grid; ++j) {
      s.bodies.push_back(MakeBoxBody({Real(-1.1 * a * grid + j * 2.1 * a), Real(-1.1 * a * grid + 10 + i * 2.1 * a)}, Real(a), Real(a)));
    }
  }
  s.bounds = {{-20, -10}, {20, 30}};
  return s;
}

}  // namespace quadrant::scene
