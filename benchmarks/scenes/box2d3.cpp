// Box2D 3's "joint_grid", "junkyard", "smash", "spinner", "rain", "compounds" and "washer" benchmark
// scenes (its shared/benchmarks.c and shared/human.c; 500, 800, 300, 500, 1000, 500 and 500 steps there)
// in the scene API, at its sizes by default; the code is this project's. Box2D 3 builds its static
// ground as one body of many boxes, here each box is a static body of its own (the same surfaces, and
// more than the 64 shapes a Quadrant body carries); compounds' bodies of two triangles and washer's
// drum of 40 polygons are compound bodies (BodyDesc::extraShapes), as in Box2D 3. Box2D 3 moves junkyard's pusher with
// b2Body_SetTargetTransform, which sets the velocity that reaches the target in one step; the
// scene's driver does the same through Adapter::SetVelocity.
#include <algorithm>
#include <cmath>
#include <limits>
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

namespace {

constexpr int kSpinnerPoints = 360;
constexpr int kSpinnerMaxBodies = 10000;  // 109 rows of 92: the top row still well inside the loop

// Rain: each storey is a floor of 501 static 0.5 m boxes with 40 columns of ragdoll groups
// spawned 40 m above it; a group is five ragdolls of 11 bodies.
constexpr int kRainColumns = 40;
constexpr int kRainGroupSize = 5;
constexpr int kRainBones = 11;
constexpr int kRainBodiesPerStorey = kRainColumns * kRainGroupSize * kRainBones;  // 2200
constexpr int kRainMaxStoreys = 20;
constexpr int kRainGridCount = 500;
constexpr double kRainGridSize = 0.5;
constexpr double kRainStoreyHeight = 45.0;
constexpr int kRainSpawnEvery = 8;  // steps (Box2D 3: stepCount & 7 == 0)

// One ragdoll (Box2D 3's shared/human.c at scale 1, joint friction 0.05 N m, springs of 5 Hz and
// damping ratio 0.5) standing with its feet at `base`, appended to `group`. Bodies in Box2D 3's
// bone order: hip, torso, head, upper and lower left leg, upper and lower right leg, upper and
// lower left arm, upper and lower right arm; each joint joins a bone to its parent (bodyA).
// Box2D 3's lower leg also carries a foot polygon: bodies here carry one shape, so the foot is
// left out. Box2D 3 keeps a ragdoll's own bones apart with a negative group index shared by the
// `slot`-th ragdoll of every group; the scene API has categories and masks only, which give the
// same pairs: ragdoll slot k is category 2 << k and collides with the ground (1) and the other
// slots.
void AddRagdoll(BodyGroup& group, Vec2 base, int slot) {
  const int first = int(group.bodies.size());
  const uint32_t category = 2u << slot;
  const uint32_t mask = 1u | (0x3Eu & ~category);
  const double pi = std::numbers::pi;
  struct Bone {
    int parent;          // index within the ragdoll, -1 for the hip
    double y;            // body origin above the feet
    double c1, c2, r;    // capsule centres (0, c1) and (0, c2), radius
    double damping;      // linear damping, 1/s
    double frictionScale;
    double pivotY, lower, upper, reference;  // the joint to the parent (angles / pi)
  };
  const Bone bones[kRainBones] = {
      {-1, 0.95, -0.02, 0.02, 0.095, 0.0, 1.0, 0, 0, 0, 0},             // hip
      {0, 1.2, -0.135, 0.135, 0.09, 0.0, 0.5, 1.0, -0.25, 0.0, 0},      // torso
      {1, 1.475, -0.038, 0.039, 0.075, 0.1, 0.25, 1.4, -0.3, 0.1, 0},   // head
      {0, 0.775, -0.125, 0.125, 0.06, 0.0, 1.0, 0.9, -0.05, 0.4, 0},    // upper left leg
      {3, 0.475, -0.155, 0.125, 0.045, 0.0, 0.5, 0.625, -0.5, -0.02, 0},// lower left leg
      {0, 0.775, -0.125, 0.125, 0.06, 0.0, 1.0, 0.9, -0.05, 0.4, 0},    // upper right leg
      {5, 0.475, -0.155, 0.125, 0.045, 0.0, 0.5, 0.625, -0.5, -0.02, 0},// lower right leg
      {1, 1.225, -0.125, 0.125, 0.035, 0.0, 0.5, 1.35, -0.1, 0.8, 0},   // upper left arm
      {7, 0.975, -0.125, 0.125, 0.03, 0.1, 0.1, 1.1, -0.2, 0.3, 0.25},  // lower left arm
      {1, 1.225, -0.125, 0.125, 0.035, 0.0, 0.5, 1.35, -0.1, 0.8, 0},   // upper right arm
      {9, 0.975, -0.125, 0.125, 0.03, 0.1, 0.1, 1.1, -0.2, 0.3, 0.25},  // lower right arm
  };
  constexpr double kFrictionTorque = 0.05, kHertz = 5, kDampingRatio = 0.5;
  for (const Bone& b : bones) {
    BodyDesc d;
    d.shape = ShapeKind::kCapsule;
    d.vertices = {{0, Real(b.c1)}, {0, Real(b.c2)}};
    d.radius = Real(b.r);
    d.position = {base.x, Real(double(base.y) + b.y)};
    d.friction = Real(0.2);
    d.linearDamping = Real(b.damping);
    d.categoryBits = category;
    d.maskBits = mask;
    group.bodies.push_back(d);
    if (b.parent < 0) continue;
    // The joint: limit, spring and joint friction (a motor of speed 0 and a small torque).
    JointDesc j;
    j.bodyA = first + b.parent;
    j.bodyB = int(group.bodies.size()) - 1;
    j.anchor = {base.x, Real(double(base.y) + b.pivotY)};
    j.enableLimit = true;
    j.lowerAngle = Real(b.lower * pi);
    j.upperAngle = Real(b.upper * pi);
    // Box2D 3 turns the forearm joints' frame on the upper arm by pi/4: their zero angle is the
    // elbow bent by pi/4.
    j.referenceAngle = Real(b.reference * pi);
    j.enableMotor = true;
    j.motorSpeed = 0;
    j.maxMotorTorque = Real(b.frictionScale * kFrictionTorque);
    j.enableSpring = true;
    j.hertz = Real(kHertz);
    j.dampingRatio = Real(kDampingRatio);
    group.joints.push_back(j);
  }
}

// Box2D 3's rain group: five ragdolls 0.5 m apart from the column's x, on storey `storey`.
BodyGroup RainGroup(int storey, int column) {
  const double span = kRainGridCount * kRainGridSize, spacing = span / kRainColumns;
  const double x = -0.5 * span + spacing * (column + 0.5), y = 40.0 + kRainStoreyHeight * storey;
  BodyGroup g;
  for (int k = 0; k < kRainGroupSize; ++k) AddRagdoll(g, {Real(x + 0.5 * k), Real(y)}, k);
  return g;
}

}  // namespace

Scene MakeSpinner(int count) {
  if (count < 1 || count > kSpinnerMaxBodies) {
    throw Error("spinner: count must be in [1, " + std::to_string(kSpinnerMaxBodies) + "] bodies, got " + std::to_string(count));
  }
  Scene s = Box2d3Base("spinner");
  s.effects.restitution = true;  // the small bodies' 0.1
  // Box2D 3's benchmark runs with continuous collision (its default), and this scene needs it:
  // the paddle's ends move at 100 m/s and, without it, knock bodies through the loop (over 100 of
  // 600 in a second, in Quadrant, Box2D 2.4.1 and Chipmunk alike).
  s.effects.continuous = true;
  // The loop: 360 points on a circle of radius 40 m about (0, 32), clockwise from (40, 32), so
  // that the chain's one side faces in.
  std::vector<Vec2> points;
  for (int i = 0; i < kSpinnerPoints; ++i) {
    const double a = -2.0 * std::numbers::pi * i / kSpinnerPoints;
    points.push_back({Real(40.0 * std::cos(a)), Real(40.0 * std::sin(a) + 32.0)});
  }
  s.bodies = MakeChainBodyDescs(points, /*isLoop=*/true, Real(0.1));
  // The paddle (body 360): Box2D 3's rounded box of half-widths 0.4 x 20 and radius 0.2, here
  // the octagon that cuts its rounded corners (polygons have no radius), friction 0, turned
  // about (0, 12) by a motor at 5 rad/s with no torque limit to speak of (Box2D 3: FLT_MAX).
  // Its joint's bodyA is the chain's first segment (Box2D 3: the chain's static body).
  BodyDesc paddle;
  paddle.shape = ShapeKind::kPolygon;
  paddle.vertices = {{Real(0.4), Real(-20.2)}, {Real(0.6), -20}, {Real(0.6), 20}, {Real(0.4), Real(20.2)},
                     {Real(-0.4), Real(20.2)}, {Real(-0.6), 20}, {Real(-0.6), -20}, {Real(-0.4), Real(-20.2)}};
  paddle.position = {0, 12};
  paddle.friction = 0;
  const int paddleIndex = int(s.bodies.size());
  s.bodies.push_back(paddle);
  JointDesc motor;
  motor.bodyA = 0;
  motor.bodyB = paddleIndex;
  motor.anchor = {0, 12};
  motor.enableMotor = true;
  motor.motorSpeed = 5;
  motor.maxMotorTorque = Real(std::numeric_limits<float>::max());
  s.joints.push_back(motor);
  // Capsules (0.25 m half-length, radius 0.25), circles (radius 0.35) and 0.7 m squares in turn,
  // 0.5 m apart in rows from (-23, 2) (they start overlapping, as in Box2D 3); density 0.25,
  // friction 0.1, restitution 0.1.
  double x = -23, y = 2;
  for (int i = 0; i < count; ++i) {
    BodyDesc b = i % 3 == 0   ? MakeCapsuleBody({Real(x), Real(y)}, Real(0.25), Real(0.25))
                 : i % 3 == 1 ? MakeCircleBody({Real(x), Real(y)}, Real(0.35))
                              : MakeBoxBody({Real(x), Real(y)}, Real(0.35), Real(0.35));
    b.density = Real(0.25);
    b.friction = Real(0.1);
    b.restitution = Real(0.1);
    s.bodies.push_back(b);
    x += 0.5;
    if (x >= 23) {
      x = -23;
      y += 0.5;
    }
  }
  s.bounds = {{-41, -9}, {41, 73}};
  return s;
}

Scene MakeRain(int count) {
  if (count < kRainBodiesPerStorey || count > kRainMaxStoreys * kRainBodiesPerStorey) {
    throw Error("rain: count must be in [" + std::to_string(kRainBodiesPerStorey) + ", " +
                std::to_string(kRainMaxStoreys * kRainBodiesPerStorey) + "] ragdoll bodies, got " + std::to_string(count));
  }
  const int storeys = count / kRainBodiesPerStorey;
  Scene s = Box2d3Base("rain");
  s.effects.damping = true;  // the ragdolls' heads and forearms: 0.1 1/s
  // The floors: storey k is 501 touching static 0.5 m boxes centred on y = 45 k from x = -125.
  const double span = kRainGridCount * kRainGridSize;
  for (int k = 0; k < storeys; ++k) {
    for (int j = 0; j <= kRainGridCount; ++j) {
      s.bodies.push_back(StaticBox({Real(-0.5 * span + j * kRainGridSize), Real(kRainStoreyHeight * k)},
                                   Real(0.5 * kRainGridSize), Real(0.5 * kRainGridSize)));
    }
  }
  s.groupSamples = {RainGroup(0, 0)};
  s.groupBodies = storeys * kRainBodiesPerStorey;
  s.bounds = {{Real(-0.5 * span - 1), -1}, {Real(0.5 * span + 1), Real(kRainStoreyHeight * storeys)}};
  // Every 8 steps from step 0: a new column of groups (one per storey) until there are 40, then
  // the oldest column's groups are removed and made again, Box2D 3's order.
  struct Rain {
    int storeys = 0;
    int columnCount = 0, columnIndex = 0;
    std::vector<int> ids;  // group id by storey * 40 + column
  };
  Rain state;
  state.storeys = storeys;
  state.ids.assign(size_t(storeys * kRainColumns), -1);
  s.driver = [state](int step, Adapter& adapter) mutable {
    if (step % kRainSpawnEvery != 0) return;
    if (state.columnCount < kRainColumns) {
      for (int k = 0; k < state.storeys; ++k) {
        state.ids[size_t(k * kRainColumns + state.columnCount)] = adapter.AddGroup(RainGroup(k, state.columnCount));
      }
      ++state.columnCount;
      return;
    }
    for (int k = 0; k < state.storeys; ++k) {
      int& id = state.ids[size_t(k * kRainColumns + state.columnIndex)];
      adapter.RemoveGroup(id);
      id = adapter.AddGroup(RainGroup(k, state.columnIndex));
    }
    state.columnIndex = (state.columnIndex + 1) % kRainColumns;
  };
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
