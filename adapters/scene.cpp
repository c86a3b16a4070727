// Scene validation and mass properties, shared by every adapter.
#include "scene.h"

#include <algorithm>
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
void ValidatePolygonOrder(const std::vector<Vec2>& vertices, int index) {
  Polygon hull;
  try {
    hull = MakePolygon(vertices, /*requireConvex=*/true);
  } catch (const Error& e) {
    Fail(index, e.what());
  }
  const int n = static_cast<int>(vertices.size());
  int start = -1;
  for (int i = 0; i < n; ++i) {
    if (vertices[i] == hull.vertices[0]) start = i;
  }
  bool ccw = true;
  bool cw = true;
  for (int i = 0; i < n; ++i) {
    ccw = ccw && vertices[(start + i) % n] == hull.vertices[i];
    cw = cw && vertices[(start - i + n) % n] == hull.vertices[i];
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

BodyDesc MakeCapsuleBody(Vec2 position, Real halfLength, Real radius, bool dynamic) {
  BodyDesc b;
  b.dynamic = dynamic;
  b.shape = ShapeKind::kCapsule;
  b.vertices = {{-halfLength, 0}, {halfLength, 0}};
  b.radius = radius;
  b.position = position;
  return b;
}

BodyDesc MakeSegmentBody(Vec2 position, Vec2 p1, Vec2 p2, bool kinematic) {
  BodyDesc b;
  b.dynamic = false;
  b.kinematic = kinematic;
  b.shape = ShapeKind::kSegment;
  b.vertices = {p1, p2};
  b.position = position;
  return b;
}

std::vector<BodyDesc> MakeChainBodyDescs(const std::vector<Vec2>& points, bool isLoop, Real friction) {
  ChainDef def;
  def.points = points;
  def.isLoop = isLoop;
  def.friction = friction;
  std::vector<BodyDesc> out;
  for (const BodyDef& body : MakeChainBodies(def)) {  // the engine's rules, once
    const ChainSegment& c = body.shape.chainSegment;
    BodyDesc b;
    b.dynamic = false;
    b.shape = ShapeKind::kChainSegment;
    b.vertices = {c.ghost1, c.segment.point1, c.segment.point2, c.ghost2};
    b.friction = friction;
    out.push_back(b);
  }
  return out;
}

std::vector<ShapeDesc> ShapesOf(const BodyDesc& b) {
  std::vector<ShapeDesc> shapes;
  shapes.reserve(1 + b.extraShapes.size());
  shapes.push_back(ShapeDesc{b.shape, b.radius, Vec2{}, b.vertices, b.density, b.friction, b.restitution});
  shapes.insert(shapes.end(), b.extraShapes.begin(), b.extraShapes.end());
  return shapes;
}

namespace {

ShapeDef ToShapeDef(const ShapeDesc& b) {
  ShapeDef shape;
  if (b.shape == ShapeKind::kCircle) {
    shape.type = ShapeType::kCircle;
    shape.circle = Circle{b.center, b.radius};
  } else if (b.shape == ShapeKind::kCapsule) {
    if (b.vertices.size() != 2) throw Error("a capsule has 2 centres, got " + std::to_string(b.vertices.size()));
    shape.type = ShapeType::kCapsule;
    shape.capsule = Capsule{b.vertices[0], b.vertices[1], b.radius};
  } else if (b.shape == ShapeKind::kSegment) {
    if (b.vertices.size() != 2) throw Error("a segment has 2 points, got " + std::to_string(b.vertices.size()));
    shape.type = ShapeType::kSegment;
    shape.segment = Segment{b.vertices[0], b.vertices[1]};
  } else if (b.shape == ShapeKind::kChainSegment) {
    if (b.vertices.size() != 4) {
      throw Error("a chain segment has 4 vertices (ghost1, point1, point2, ghost2), got " + std::to_string(b.vertices.size()));
    }
    shape.type = ShapeType::kChainSegment;
    shape.chainSegment = ChainSegment{b.vertices[0], Segment{b.vertices[1], b.vertices[2]}, b.vertices[3]};
  } else {
    if (b.vertices.size() > size_t(kMaxPolygonVertices)) {
      throw Error("a polygon has at most 8 vertices, got " + std::to_string(b.vertices.size()));
    }
    shape.type = ShapeType::kPolygon;
    std::copy(b.vertices.begin(), b.vertices.end(), shape.polygon.vertices.begin());
    shape.polygon.count = static_cast<int>(b.vertices.size());
  }
  shape.density = b.density;
  shape.friction = b.friction;
  shape.restitution = b.restitution;
  return shape;
}

}  // namespace

BodyDef ToBodyDef(const BodyDesc& b) {
  BodyDef bd;
  bd.type = b.dynamic ? BodyType::kDynamic : b.kinematic ? BodyType::kKinematic : BodyType::kStatic;
  bd.position = b.position;
  bd.angle = b.angle;
  bd.linearVelocity = b.velocity;
  bd.angularVelocity = b.angularVelocity;
  bd.isAwake = b.awake;
  bd.linearDamping = b.linearDamping;  // the engine applies them only with effects.damping
  bd.angularDamping = b.angularDamping;
  const std::vector<ShapeDesc> shapes = ShapesOf(b);
  bd.shape = ToShapeDef(shapes[0]);
  for (size_t k = 1; k < shapes.size(); ++k) {
    try {
      bd.extraShapes.push_back(ToShapeDef(shapes[k]));
    } catch (const Error& e) {
      throw Error("extra shape " + std::to_string(k - 1) + ": " + e.what());
    }
  }
  bd.filter.categoryBits = b.categoryBits;
  bd.filter.maskBits = b.maskBits;
  return bd;
}

MassProperties ComputeMassProperties(const BodyDesc& body) {
  if (!body.extraShapes.empty()) {  // a compound body: the engine's exact sum over its shapes
    const BodyDef def = ToBodyDef(body);
    std::vector<ShapeDef> shapes{def.shape};
    shapes.insert(shapes.end(), def.extraShapes.begin(), def.extraShapes.end());
    for (ShapeDef& s : shapes) {
      if (s.type == ShapeType::kPolygon) s.polygon = MakePolygon(std::span<const Vec2>(s.polygon.vertices.data(), size_t(s.polygon.count)));
    }
    const MassData md = ComputeBodyMass(shapes);
    return {md.mass, md.rotationalInertia, md.center};
  }
  if (body.shape == ShapeKind::kSegment || body.shape == ShapeKind::kChainSegment) return {};  // no area: no mass
  MassData md = body.shape == ShapeKind::kCircle    ? ComputeMass(Circle{{0, 0}, body.radius}, body.density)
                : body.shape == ShapeKind::kCapsule ? ComputeMass(ToBodyDef(body).shape.capsule, body.density)
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
  if (scene.groupBodies < 0) throw Error("scene groupBodies must be >= 0");
  for (int i = 0; i < static_cast<int>(scene.bodies.size()); ++i) {
    const BodyDesc& b = scene.bodies[i];
    if (b.dynamic && b.kinematic) Fail(i, "a body is either dynamic or kinematic, not both");
    if (!b.awake && !(b.dynamic && scene.effects.sleep)) {
      Fail(i, "a body created asleep (awake = false) must be dynamic, in a scene with the sleep effect");
    }
    if (b.shape == ShapeKind::kPolygon && (b.vertices.size() < 3 || b.vertices.size() > size_t(kMaxPolygonVertices))) {
      // MakePolygon's own messages for both (ToBodyDef cannot hold more than 8).
      try {
        (void)MakePolygon(b.vertices);
      } catch (const Error& e) {
        Fail(i, e.what());
      }
    }
    try {
      CheckBodyDef(ToBodyDef(b));
    } catch (const Error& e) {
      Fail(i, e.what());
    }
    if (b.shape == ShapeKind::kPolygon) ValidatePolygonOrder(b.vertices, i);
    for (const ShapeDesc& extra : b.extraShapes) {
      if (extra.shape == ShapeKind::kPolygon) ValidatePolygonOrder(extra.vertices, i);
    }
  }
  const int n = static_cast<int>(scene.bodies.size());
  for (int j = 0; j < static_cast<int>(scene.joints.size()); ++j) {
    const JointDesc& d = scene.joints[size_t(j)];
    auto fail = [j](const std::string& what) { throw Error("scene joint " + std::to_string(j) + ": " + what); };
    if (d.bodyA < 0 || d.bodyA >= n || d.bodyB < 0 || d.bodyB >= n) fail("body index out of range");
    if (d.bodyA == d.bodyB) fail("bodyA and bodyB are the same body");
    if (!IsFinite(d.anchor) || !IsFinite(d.lowerAngle) || !IsFinite(d.upperAngle) || !IsFinite(d.motorSpeed) ||
        !IsFinite(d.maxMotorTorque) || !IsFinite(d.hertz) || !IsFinite(d.dampingRatio) || !IsFinite(d.axis) ||
        !IsFinite(d.lowerTranslation) || !IsFinite(d.upperTranslation) || !IsFinite(d.maxMotorForce) ||
        !IsFinite(d.anchorB) || !IsFinite(d.length) || !IsFinite(d.minLength) || !IsFinite(d.maxLength) ||
        !IsFinite(d.angularHertz) || !IsFinite(d.angularDampingRatio) || !IsFinite(d.referenceAngle)) {
      fail("a value is not finite");
    }
    if (d.kind != JointKind::kRevolute && d.kind != JointKind::kPrismatic && d.kind != JointKind::kDistance &&
        d.kind != JointKind::kWeld && d.kind != JointKind::kWheel) {
      fail("the joint kind is unknown");
    }
    if ((d.kind == JointKind::kPrismatic || d.kind == JointKind::kWheel) && Length(d.axis) < Real(1e-6)) {
      fail("the axis must not be zero");
    }
    if (d.lowerTranslation > d.upperTranslation) fail("lowerTranslation must be <= upperTranslation");
    if (d.kind == JointKind::kDistance && d.length != 0 && d.length < Real(0.005)) fail("length must be 0 (at load) or >= 0.005 m");
    if (d.minLength > d.maxLength) fail("minLength must be <= maxLength");
    if (d.maxMotorForce < 0 || d.angularHertz < 0 || d.angularDampingRatio < 0) {
      fail("maxMotorForce, angularHertz and angularDampingRatio must be >= 0");
    }
    const Real pi = Real(3.14159265358979323846);
    if (d.lowerAngle > d.upperAngle || d.lowerAngle < -pi || d.upperAngle > pi) {
      fail("lowerAngle <= upperAngle within [-pi, pi] required");
    }
    if (d.maxMotorTorque < 0 || d.hertz < 0 || d.dampingRatio < 0) fail("maxMotorTorque, hertz and dampingRatio must be >= 0");
  }
}

void ValidateGroup(const Scene& scene, const BodyGroup& group) {
  if (group.bodies.empty()) throw Error("group: a group needs at least one body");
  // The scene's rules on a scene of the group alone (settings copied, not the scene's bodies),
  // with the messages renamed: "scene body 3: ..." -> "group body 3: ...".
  Scene alone;
  alone.gravity = scene.gravity;
  alone.timeStep = scene.timeStep;
  alone.pipelineRepeats = scene.pipelineRepeats;
  alone.velocityIterations = scene.velocityIterations;
  alone.positionIterations = scene.positionIterations;
  alone.restitutionThreshold = scene.restitutionThreshold;
  alone.effects = scene.effects;
  alone.bodies = group.bodies;
  alone.joints = group.joints;
  try {
    ValidateScene(alone);
  } catch (const Error& e) {
    std::string what = e.what();
    if (what.starts_with("scene ")) what.replace(0, 6, "group ");
    throw Error(what);
  }
}

}  // namespace quadrant::scene
