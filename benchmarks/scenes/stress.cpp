// The thesis's circle and polygon stress scenes (its Figures 14 and 15).
#include <cmath>
#include <numbers>
#include <string>

#include "quadrant/error.h"
#include "quadrant/shapes.h"
#include "scenes.h"

namespace quadrant::scene {
namespace {

void Check(bool ok, const std::string& message) {
  if (!ok) throw Error("stress scene: " + message);
}


}  // namespace

// A random convex polygon: 3..8 vertices at sorted random angles on a circle, with each gap
// between consecutive angles at least a fifth of the even spacing so no edge degenerates.
std::vector<Vec2> RandomConvexPolygon(Random& rng, Real circumradius) {
  const int n = rng.UniformInt(3, 8);
  const double even = 2 * std::numbers::pi / n;
  const double minGap = 0.2 * even;
  double angles[8];
  double slack = 2 * std::numbers::pi - n * minGap;
  double cuts[8];
  for (int i = 0; i < n; ++i) cuts[i] = rng.Uniform(0, 1);
  double sum = 0;
  for (int i = 0; i < n; ++i) sum += cuts[i];
  const double start = rng.Uniform(0, 2 * std::numbers::pi);
  double a = start;
  for (int i = 0; i < n; ++i) {
    angles[i] = a;
    a += minGap + slack * cuts[i] / sum;
  }
  std::vector<Vec2> v(n);
  for (int i = 0; i < n; ++i) {
    v[i] = {Real(circumradius * std::cos(angles[i])), Real(circumradius * std::sin(angles[i]))};
  }
  // Centre on the centroid so the body origin is its centre of mass in every engine.
  Polygon hull = MakePolygon(v);
  std::vector<Vec2> out(hull.count);
  for (int i = 0; i < hull.count; ++i) out[i] = hull.vertices[i] - hull.centroid;
  return out;
}

Scene MakeStressScene(const StressParams& p) {
  Check(p.count > 0, "body count must be > 0, got " + std::to_string(p.count));
  Check(p.count <= 1000000, "body count must be <= 1e6");
  Check(std::isfinite(p.radius) && p.radius > 0, "radius must be > 0");
  Check(std::isfinite(p.minCircumradius) && std::isfinite(p.maxCircumradius) && p.minCircumradius > 0 &&
            p.minCircumradius <= p.maxCircumradius,
        "circumradii must satisfy 0 < min <= max");
  Check(std::isfinite(p.areaFraction) && p.areaFraction > 0 && p.areaFraction < Real(0.9),
        "area fraction must be in (0, 0.9)");
  Check(std::isfinite(p.minSpeed) && std::isfinite(p.maxSpeed) && p.minSpeed >= 0 && p.minSpeed <= p.maxSpeed,
        "speeds must satisfy 0 <= min <= max");

  Random rng(p.seed);
  const bool circles = p.shape == ShapeKind::kCircle;
  Scene scene;
  scene.name = circles ? "circle_stress" : "polygon_stress";
  scene.seed = p.seed;
  scene.gravity = {0, 0};
  scene.timeStep = Real(1.0 / 60.0);
  scene.restitutionThreshold = 0;  // every collision is elastic, however slow
  scene.effects.gravity = false;
  scene.effects.friction = false;
  scene.effects.sleep = false;

  // Shapes first: the box is sized from the bodies' real total area.
  std::vector<BodyDesc> bodies(p.count);
  double area = 0;
  double maxExtent = 0;
  for (BodyDesc& b : bodies) {
    b.dynamic = true;
    b.density = 1;
    b.friction = 0;
    b.restitution = 1;
    if (circles) {
      b.shape = ShapeKind::kCircle;
      b.radius = p.radius;
      area += std::numbers::pi * p.radius * p.radius;
      maxExtent = std::max(maxExtent, 2.0 * p.radius);
    } else {
      b.shape = ShapeKind::kPolygon;
      const Real r = Real(rng.Uniform(p.minCircumradius, p.maxCircumradius));
      b.vertices = RandomConvexPolygon(rng, r);
      area += ComputeArea(MakePolygon(b.vertices));
      maxExtent = std::max(maxExtent, 2.0 * r);
    }
  }
  // The clumped variant puts every body in the lower-left quadrant of a box twice as wide, at
  // the same area fraction there: the quadrant looks like the uniform scene, the rest is empty
  // (the load-imbalance case of the thesis's quadrant scheme).
  const double side = std::sqrt(area / p.areaFraction) * (p.clumped ? 2.0 : 1.0);
  const double half = 0.5 * side;

  // Place on a jittered grid so no two bodies start overlapping.
  const double region = p.clumped ? half : side;
  const int perRow = static_cast<int>(std::ceil(std::sqrt(double(p.count))));
  const double cell = region / perRow;
  Check(cell > maxExtent, "bodies do not fit: lower the area fraction or unclump");
  const double jitter = 0.5 * (cell - maxExtent);
  for (int i = 0; i < p.count; ++i) {
    BodyDesc& b = bodies[i];
    const double cx = -half + (i % perRow + 0.5) * cell;
    const double cy = -half + (i / perRow + 0.5) * cell;
    b.position = {Real(cx + rng.Uniform(-jitter, jitter)), Real(cy + rng.Uniform(-jitter, jitter))};
    b.angle = Real(rng.Uniform(-std::numbers::pi, std::numbers::pi));
    const double speed = rng.Uniform(p.minSpeed, p.maxSpeed);
    const double dir = rng.Uniform(0, 2 * std::numbers::pi);
    b.velocity = {Real(speed * std::cos(dir)), Real(speed * std::sin(dir))};
  }

  // Four static walls, 1 m thick, outside the box.
  const Real t = 1;
  auto wall = [&](double cx, double cy, double hx, double hy) {
    BodyDesc w;
    w.dynamic = false;
    w.shape = ShapeKind::kPolygon;
    w.position = {Real(cx), Real(cy)};
    w.vertices = {{Real(-hx), Real(-hy)}, {Real(hx), Real(-hy)}, {Real(hx), Real(hy)}, {Real(-hx), Real(hy)}};
    w.friction = 0;
    w.restitution = 1;
    bodies.push_back(w);
  };
  wall(0, -half - 0.5 * t, half + t, 0.5 * t);
  wall(0, half + 0.5 * t, half + t, 0.5 * t);
  wall(-half - 0.5 * t, 0, 0.5 * t, half);
  wall(half + 0.5 * t, 0, 0.5 * t, half);

  scene.bodies = std::move(bodies);
  scene.bounds = {{Real(-half), Real(-half)}, {Real(half), Real(half)}};
  return scene;
}

}  // namespace quadrant::scene
