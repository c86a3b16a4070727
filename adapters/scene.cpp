// Scene validation and mass properties, shared by every adapter.
#include "scene.h"

#include <limits>
#include <string>

#include "quadrant/error.h"
#include "quadrant/shapes.h"

namespace quadrant::scene {
namespace {

[[noreturn]] void Fail(int body, const std::string& what) {
  throw Error("scene body " + std::to_string(body) + ": " + what);
}

void RequireFinite(bool ok, const char* field) {
  if (!ok) throw Error(std::string("scene ") + field + " is not finite");
}

// Checks that the given vertex order is the convex hull's own counter-clockwise order, so a
// clockwise, self-intersecting or non-convex list is refused with a message saying which.
void ValidatePolygonOrder(const BodyDesc& b, int index) {
  Polygon hull;
  try {
    hull = MakePolygon(b.vertices, /*requireConvex=*/true);
  } catch (const Error& e) {
    Fail(index, e.what());
  }
  const int n = static_cast<int>(b.vertices.size());
  int start = -1;
  for (int i = 0; i < n; ++i) {
    if (b.vertices[i] == hull.vertices[0]) start = i;
  }
  bool ccw = true;
  bool cw = true;
  for (int i = 0; i < n; ++i) {
    ccw = ccw && b.vertices[(start + i) % n] == hull.vertices[i];
    cw = cw && b.vertices[(start - i + n) % n] == hull.vertices[i];
  }
  if (ccw) return;
  if (cw) Fail(index, "polygon vertices are clockwise; the scene API takes counter-clockwise");
  Fail(index, "polygon vertices are not in convex order (self-intersecting outline)");
}

}  // namespace

BodyDesc MakeCircleBody(Vec2 position, Real radius, bool dynamic) {
  BodyDesc b;
  b.dynamic = dynamic;
  b.shape = ShapeKind::kCircle;
  b.radius = radius;
  b.position = position;
  return b;
}

BodyDesc MakeBoxBody(Vec2 position, Real hx, Real hy, bool dynamic) {
  BodyDesc b;
  b.dynamic = dynamic;
  b.shape = ShapeKind::kPolygon;
  b.vertices = {{-hx, -hy}, {hx, -hy}, {hx, hy}, {-hx, hy}};
  b.position = position;
  return b;
}

MassProperties ComputeMassProperties(const BodyDesc& body) {
  MassData md = body.shape == ShapeKind::kCircle
                    ? ComputeMass(Circle{{0, 0}, body.radius}, body.density)
                    : ComputeMass(MakePolygon(body.vertices), body.density);
  return {md.mass, md.rotationalInertia, md.center};
}

void ValidateScene(const Scene& scene) {
  RequireFinite(IsFinite(scene.gravity), "gravity");
  RequireFinite(IsFinite(scene.timeStep), "time step");
  RequireFinite(IsFinite(scene.restitutionThreshold), "restitution threshold");
  if (scene.timeStep <= 0) throw Error("scene time step must be > 0");
  if (scene.timeStep > kMaxTimeStep) throw Error("scene time step must be <= 1 s");
  if (scene.pipelineRepeats < 1) throw Error("scene pipelineRepeats must be >= 1");
  if (scene.pipelineRepeats > kMaxIterations) throw Error("scene pipelineRepeats must be <= 1000");
  if (scene.velocityIterations > kMaxIterations) throw Error("scene velocity iterations must be <= 1000");
  if (scene.positionIterations > kMaxIterations) throw Error("scene position iterations must be <= 1000");
  if (scene.velocityIterations < 1) throw Error("scene velocity iterations must be >= 1");
  if (scene.positionIterations < 0) throw Error("scene position iterations must be >= 0");
  if (scene.restitutionThreshold < 0) throw Error("scene restitution threshold must be >= 0");
  for (int i = 0; i < static_cast<int>(scene.bodies.size()); ++i) {
    const BodyDesc& b = scene.bodies[i];
    if (!IsFinite(b.position) || !IsFinite(b.angle)) Fail(i, "position or angle is not finite");
    if (!IsFinite(b.velocity) || !IsFinite(b.angularVelocity)) Fail(i, "velocity is not finite");
    if (std::abs(b.position.x) > kMaxCoordinate || std::abs(b.position.y) > kMaxCoordinate) {
      Fail(i, "position is beyond the coordinate limit of 1e6 m");
    }
    if (!IsFinite(b.density) || (b.dynamic && b.density <= 0)) Fail(i, "density must be > 0");
    if (b.dynamic && b.kinematic) Fail(i, "a body is either dynamic or kinematic, not both");
    if (!IsFinite(b.friction) || b.friction < 0) Fail(i, "friction must be >= 0");
    if (!IsFinite(b.linearDamping) || b.linearDamping < 0 || !IsFinite(b.angularDamping) || b.angularDamping < 0) {
      Fail(i, "damping must be finite and >= 0");
    }
    if (!IsFinite(b.restitution) || b.restitution < 0 || b.restitution > 1) {
      Fail(i, "restitution must be in [0, 1]");
    }
    if (std::abs(b.velocity.x) > kMaxInputSpeed || std::abs(b.velocity.y) > kMaxInputSpeed ||
        std::abs(b.angularVelocity) > kMaxInputSpeed) {
      Fail(i, "velocity is beyond the limit of 1e6 m/s (rad/s)");
    }
    if (b.shape == ShapeKind::kCircle) {
      try {
        ValidateCircle(Circle{{0, 0}, b.radius});
      } catch (const Error& e) {
        Fail(i, e.what());
      }
    } else {
      ValidatePolygonOrder(b, i);
    }
    if (b.dynamic) {
      const MassProperties mp = ComputeMassProperties(b);
      constexpr Real kSmallest = std::numeric_limits<Real>::min();  // subnormals count as underflow
      if (!IsFinite(mp.mass) || mp.mass < kSmallest || !IsFinite(mp.inertia) || mp.inertia < kSmallest ||
          !IsFinite(Real(1) / mp.mass) || !IsFinite(Real(1) / mp.inertia)) {
        Fail(i, "mass or rotational inertia is not a positive finite number (density too large or too small)");
      }
    }
  }
}

}  // namespace quadrant::scene
