// Seeded random input through every validating entry point: MakePolygon, ValidateCircle,
// World::CreateBody and scene::ValidateScene, 100000 inputs in all (40000 + 20000 + 25000 +
// 15000). Values are drawn from the cases that break validators: NaN, infinities, -0, denormals,
// float's largest values, the 1e6 m coordinate limit and just past it, the 0.005 m feature size
// and just under it, duplicates, collinear and sliver polygons, clockwise and non-convex orders,
// 0 to 10 vertices. Every call must either succeed with a valid result or throw quadrant::Error
// (and then leave a world exactly as it was); anything else (another exception type, a crash, an
// accepted input that yields a non-finite or degenerate result) fails. Under 10 s in a release
// build; CI also runs it under ASan and UBSan.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <limits>
#include <string>
#include <vector>

#include "quadrant/error.h"
#include "quadrant/shapes.h"
#include "quadrant/world.h"
#include "scene.h"
#include "scenes.h"

namespace quadrant {
namespace {

using scene::Random;

constexpr Real kNaN = std::numeric_limits<Real>::quiet_NaN();
constexpr Real kInf = std::numeric_limits<Real>::infinity();

/// Collects failures with a few examples, so one broken rule gives one readable report.
struct Failures {
  int count = 0;
  std::string examples;
  void Add(const std::string& what) {
    if (++count <= 8) examples += "\n  " + what;
  }
};

std::string Text(Real v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.9g", double(v));
  return buffer;
}
std::string Text(Vec2 v) { return "(" + Text(v.x) + ", " + Text(v.y) + ")"; }
std::string Text(const std::vector<Vec2>& vs) {
  std::string out = "[";
  for (Vec2 v : vs) out += Text(v) + " ";
  return out + "]";
}

// A value from the classes validators get wrong, or an ordinary one.
Real Value(Random& rng, double typical) {
  switch (rng.UniformInt(0, 19)) {
    case 0: return kNaN;
    case 1: return rng.UniformInt(0, 1) ? kInf : -kInf;
    case 2: return Real(-0.0);
    case 3: return std::numeric_limits<Real>::denorm_min() * Real(rng.UniformInt(1, 1000));
    case 4: return (rng.UniformInt(0, 1) ? 1 : -1) * std::numeric_limits<Real>::max() * Real(rng.Uniform(0.1, 1));
    case 5: return (rng.UniformInt(0, 1) ? 1 : -1) * kMaxCoordinate * Real(rng.UniformInt(0, 1) ? 1 : 1.0000002);
    case 6: return Real(rng.Uniform(-2e7, 2e7));
    case 7: return kMinFeatureSize * Real(rng.Uniform(0.5, 1.5));
    case 8: return 0;
    default: return Real(rng.Uniform(-typical, typical));
  }
}

Vec2 Point(Random& rng, double typical) { return {Value(rng, typical), Value(rng, typical)}; }

// 0..10 points, built to hit one of the polygon rules (or none).
std::vector<Vec2> Points(Random& rng) {
  const int n = rng.UniformInt(0, 10);
  std::vector<Vec2> p;
  const double scale = rng.UniformInt(0, 3) == 0 ? rng.Uniform(1e-3, 1e-2) : rng.Uniform(0.1, 5);
  const Vec2 shift{Real(rng.Uniform(-1, 1) * (rng.UniformInt(0, 4) == 0 ? 1e6 : 10)), Real(rng.Uniform(-10, 10))};
  switch (rng.UniformInt(0, 6)) {
    case 0:  // arbitrary points, some of them absurd
      for (int i = 0; i < n; ++i) p.push_back(Point(rng, scale));
      break;
    case 1:  // collinear
      for (int i = 0; i < n; ++i) {
        const Real t = Real(rng.Uniform(-scale, scale));
        p.push_back({shift.x + t, shift.y + 2 * t});
      }
      break;
    default: {  // a convex n-gon, then maybe spoiled
      const double start = rng.Uniform(0, 6.283);
      for (int i = 0; i < n; ++i) {
        const double a = start + 6.283185307 * i / std::max(n, 1) + rng.Uniform(0, 0.3);
        p.push_back({shift.x + Real(scale * std::cos(a)), shift.y + Real(scale * std::sin(a))});
      }
      const int spoil = rng.UniformInt(0, 6);
      if (spoil == 0 && n > 1) p[size_t(rng.UniformInt(1, n - 1))] = p[0];                       // duplicate
      if (spoil == 1) std::reverse(p.begin(), p.end());                                      // clockwise
      if (spoil == 2 && n > 2) p[size_t(rng.UniformInt(0, n - 1))] = shift;                   // interior point
      if (spoil == 3 && n > 0) p[size_t(rng.UniformInt(0, n - 1))] = Point(rng, scale);      // one bad coordinate
      if (spoil == 4 && n > 3) std::swap(p[1], p[2]);                                        // self-intersecting order
      if (spoil == 5 && n > 0) p[size_t(rng.UniformInt(0, n - 1))].y += Real(1e-4);          // near-duplicate
      break;
    }
  }
  return p;
}

// What a successful MakePolygon must return: 3..8 finite vertices within the limit, strictly
// convex and counter-clockwise, positive area, unit outward normals, every vertex an input point,
// all input points when convexity was required.
std::string CheckPolygon(const Polygon& poly, const std::vector<Vec2>& input, bool requireConvex) {
  if (poly.count < 3 || poly.count > kMaxPolygonVertices) return "count " + std::to_string(poly.count);
  if (requireConvex && poly.count != int(input.size())) return "dropped points although convexity was required";
  for (int i = 0; i < poly.count; ++i) {
    const Vec2 v = poly.vertices[i];
    if (!IsFinite(v) || std::abs(v.x) > kMaxCoordinate || std::abs(v.y) > kMaxCoordinate) return "vertex " + Text(v);
    bool fromInput = false;
    for (Vec2 q : input) fromInput = fromInput || (q == v);
    if (!fromInput) return "vertex " + Text(v) + " is not an input point";
    const Vec2 e1 = poly.vertices[(i + 1) % poly.count] - v;
    const Vec2 e2 = poly.vertices[(i + 2) % poly.count] - poly.vertices[(i + 1) % poly.count];
    if (!(Cross(e1, e2) > 0)) return "not strictly convex and counter-clockwise at vertex " + std::to_string(i);
    const Vec2 n = poly.normals[i];
    if (!(std::abs(Length(n) - 1) < 1e-3) || !(std::abs(Dot(n, e1)) < 1e-3 * Length(e1)) || !(Cross(e1, n) < 0)) {
      return "normal " + std::to_string(i) + " " + Text(n) + " is not the unit outward normal";
    }
  }
  const Real area = ComputeArea(poly);
  if (!(area > 0) || !IsFinite(area)) return "area " + Text(area);
  if (!IsFinite(poly.centroid)) return "centroid " + Text(poly.centroid);
  return "";
}

TEST(FuzzValidation, MakePolygon) {
  Random rng(20240501);
  Failures fail;
  int accepted = 0;
  for (int i = 0; i < 40000; ++i) {
    const std::vector<Vec2> points = Points(rng);
    const bool requireConvex = rng.UniformInt(0, 3) != 0;
    try {
      const Polygon poly = MakePolygon(points, requireConvex);
      ++accepted;
      const std::string bad = CheckPolygon(poly, points, requireConvex);
      if (!bad.empty()) fail.Add("accepted " + Text(points) + ": " + bad);
    } catch (const Error&) {
      // refused with a message: fine
    } catch (const std::exception& e) {
      fail.Add(std::string("non-Error exception '") + e.what() + "' for " + Text(points));
    }
  }
  EXPECT_EQ(fail.count, 0) << fail.examples;
  EXPECT_GT(accepted, 4000) << "the generator should produce valid polygons too";
}

TEST(FuzzValidation, ValidateCircle) {
  Random rng(77);
  Failures fail;
  for (int i = 0; i < 20000; ++i) {
    const Circle c{Point(rng, 5), Value(rng, 3)};
    // The documented rule is an oracle: accepted exactly when finite, within the coordinate
    // limit and at least the smallest feature size.
    const bool valid = IsFinite(c.center) && IsFinite(c.radius) && c.radius >= kMinFeatureSize &&
                       c.radius <= kMaxCoordinate && std::abs(c.center.x) <= kMaxCoordinate &&
                       std::abs(c.center.y) <= kMaxCoordinate;
    try {
      ValidateCircle(c);
      if (!valid) fail.Add("accepted circle at " + Text(c.center) + " r " + Text(c.radius));
    } catch (const Error&) {
      if (valid) fail.Add("refused valid circle at " + Text(c.center) + " r " + Text(c.radius));
    } catch (const std::exception& e) {
      fail.Add(std::string("non-Error exception '") + e.what() + "'");
    }
  }
  EXPECT_EQ(fail.count, 0) << fail.examples;
}

TEST(FuzzValidation, CreateBody) {
  Random rng(4242);
  Failures fail;
  World world;
  BodyDef ground;
  ground.shape = ShapeDef::Box(20, Real(0.5));
  world.CreateBody(ground);
  BodyDef ball;
  ball.type = BodyType::kDynamic;
  ball.position = {0, 2};
  ball.shape = ShapeDef::MakeCircle(Real(0.5));
  world.CreateBody(ball);
  for (int i = 0; i < 5; ++i) world.Step(Real(1.0 / 60.0));
  int accepted = 0;
  for (int i = 0; i < 25000; ++i) {
    // One field (or none) drawn from the hard classes, the others ordinary: a body with every
    // field absurd would only ever test the first check.
    const int spoil = rng.UniformInt(0, 12);
    auto pick = [&](int field, double typical, Real ordinary) {
      return spoil == field ? Value(rng, typical) : ordinary;
    };
    BodyDef def;
    def.type = spoil == 0 ? static_cast<BodyType>(rng.UniformInt(0, 3)) : (rng.UniformInt(0, 3) ? BodyType::kDynamic : BodyType::kStatic);
    def.position = {pick(1, 1e6, Real(rng.Uniform(-50, 50))), pick(1, 1e6, Real(rng.Uniform(-50, 50)))};
    def.angle = pick(2, 4, Real(rng.Uniform(-4, 4)));
    def.linearVelocity = {pick(3, 10, Real(rng.Uniform(-10, 10))), pick(3, 10, Real(rng.Uniform(-10, 10)))};
    def.angularVelocity = pick(4, 10, Real(rng.Uniform(-10, 10)));
    def.linearDamping = pick(5, 1, Real(rng.Uniform(0, 1)));
    def.angularDamping = pick(5, 1, Real(rng.Uniform(0, 1)));
    if (rng.UniformInt(0, 1) == 0) {
      def.shape.type = ShapeType::kCircle;
      def.shape.circle = {spoil == 6 ? Point(rng, 1) : Vec2{}, pick(7, 2, Real(rng.Uniform(0.01, 3)))};
    } else {
      def.shape.type = ShapeType::kPolygon;
      const std::vector<Vec2> points = Points(rng);  // spoiled or not by its own draw
      def.shape.polygon.count = spoil == 8 ? rng.UniformInt(-2, 12) : int(points.size());
      for (size_t k = 0; k < points.size() && k < size_t(kMaxPolygonVertices); ++k) def.shape.polygon.vertices[k] = points[k];
    }
    if (spoil == 9) def.shape.type = static_cast<ShapeType>(rng.UniformInt(0, 3));  // 2 and 3 are not ShapeTypes
    def.shape.density = pick(10, 5, Real(rng.Uniform(0.1, 10)));
    def.shape.friction = pick(11, 1, Real(rng.Uniform(0, 1)));
    def.shape.restitution = pick(12, 1, Real(rng.Uniform(0, 1)));

    const uint64_t hash = world.StateHash();
    const int count = world.GetBodyCount();
    try {
      const BodyId id = world.CreateBody(def);
      ++accepted;
      std::string bad;
      const bool dynamic = world.GetType(id) == BodyType::kDynamic;
      const AABB box = world.GetAABB(id);
      if (!IsFinite(world.GetPosition(id)) || !IsFinite(world.GetLinearVelocity(id))) bad = "non-finite state";
      // The solver works with inverses: a denormal mass is as bad as zero (1 / m overflows).
      const Real mass = world.GetMass(id), inertia = world.GetRotationalInertia(id);
      if (dynamic && !(std::isfinite(mass) && mass > 0 && std::isfinite(Real(1) / mass))) bad = "mass " + Text(mass);
      if (dynamic && !(std::isfinite(inertia) && inertia > 0 && std::isfinite(Real(1) / inertia))) {
        bad = "rotational inertia " + Text(inertia);
      }
      if (!IsFinite(box.lower) || !IsFinite(box.upper)) bad = "AABB " + Text(box.lower) + " " + Text(box.upper);
      if (!bad.empty()) {
        const std::string shape = def.shape.type == ShapeType::kCircle
                                      ? "circle r " + Text(def.shape.circle.radius)
                                      : std::to_string(def.shape.polygon.count) + "-gon";
        fail.Add("accepted body (density " + Text(def.shape.density) + ", " + shape + "): " + bad);
      }
      world.DestroyBody(id);
      if (world.StateHash() != hash) fail.Add("create + destroy changed the state hash");
    } catch (const Error&) {
      if (world.StateHash() != hash || world.GetBodyCount() != count) fail.Add("a refused CreateBody changed the world");
    } catch (const std::exception& e) {
      fail.Add(std::string("non-Error exception '") + e.what() + "'");
    }
  }
  EXPECT_EQ(fail.count, 0) << fail.examples;
  EXPECT_GT(accepted, 500) << "the generator should produce valid bodies too";
  // The world still steps to a finite state after everything it was fed.
  for (int i = 0; i < 10; ++i) world.Step(Real(1.0 / 60.0));
  for (BodyId id : world.GetBodyIds()) EXPECT_TRUE(IsFinite(world.GetPosition(id)));
}

TEST(FuzzValidation, ValidateScene) {
  Random rng(9001);
  Failures fail;
  int accepted = 0;
  for (int i = 0; i < 15000; ++i) {
    scene::Scene s;
    s.name = "fuzz";
    const int knob = rng.UniformInt(0, 9);  // which world setting to spoil, if any
    s.gravity = knob == 0 ? Point(rng, 20) : Vec2{0, -10};
    s.timeStep = knob == 1 ? Value(rng, 0.1) : Real(1.0 / 60.0);
    s.pipelineRepeats = knob == 2 ? rng.UniformInt(-3, 3) : 1;
    s.velocityIterations = knob == 3 ? rng.UniformInt(-3, 10) : 8;
    s.positionIterations = knob == 4 ? rng.UniformInt(-3, 10) : 3;
    s.restitutionThreshold = knob == 5 ? Value(rng, 2) : 1;
    const int bodies = rng.UniformInt(0, 4);
    for (int b = 0; b < bodies; ++b) {
      scene::BodyDesc d;
      d.dynamic = rng.UniformInt(0, 3) != 0;
      d.shape = rng.UniformInt(0, 1) ? scene::ShapeKind::kCircle : scene::ShapeKind::kPolygon;
      d.radius = Value(rng, 2);
      d.vertices = Points(rng);
      d.position = Point(rng, 50);
      d.angle = Value(rng, 4);
      d.velocity = Point(rng, 10);
      d.angularVelocity = Value(rng, 10);
      d.density = Value(rng, 5);
      d.friction = Value(rng, 1);
      d.restitution = Value(rng, 1);
      s.bodies.push_back(d);
    }
    try {
      scene::ValidateScene(s);
      ++accepted;
      // Accepted means loadable: every dynamic body has a finite, positive mass and inertia whose
      // inverses (what the solver uses) are finite too.
      for (size_t b = 0; b < s.bodies.size(); ++b) {
        if (!s.bodies[b].dynamic) continue;
        const scene::MassProperties mp = scene::ComputeMassProperties(s.bodies[b]);
        if (!(std::isfinite(mp.mass) && mp.mass > 0 && std::isfinite(Real(1) / mp.mass) && std::isfinite(mp.inertia) &&
              mp.inertia > 0 && std::isfinite(Real(1) / mp.inertia))) {
          const std::string shape = s.bodies[b].shape == scene::ShapeKind::kCircle
                                        ? "circle r " + Text(s.bodies[b].radius)
                                        : std::to_string(s.bodies[b].vertices.size()) + "-gon";
          fail.Add("accepted body " + std::to_string(b) + " (density " + Text(s.bodies[b].density) + ", " + shape +
                   "): mass " + Text(mp.mass) + ", inertia " + Text(mp.inertia));
        }
      }
      if (!(s.timeStep > 0) || s.pipelineRepeats < 1 || s.velocityIterations < 1 || !IsFinite(s.gravity)) {
        fail.Add("accepted a scene with bad world settings");
      }
    } catch (const Error&) {
    } catch (const std::exception& e) {
      fail.Add(std::string("non-Error exception '") + e.what() + "'");
    }
  }
  EXPECT_EQ(fail.count, 0) << fail.examples;
  EXPECT_GT(accepted, 1000) << "the generator should produce valid scenes too";
}

}  // namespace
}  // namespace quadrant
