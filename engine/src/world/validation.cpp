// Validation of world and body definitions (validation.h).
#include "world/validation.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <span>
#include <string>
#include <vector>

namespace quadrant {

void ValidateWorldDef(const WorldDef& d) {
  Require(IsFinite(d.gravity), "WorldDef.gravity is not finite");
  Require(d.solver == SolverType::kThesis || d.solver == SolverType::kPgs || d.solver == SolverType::kSoftStep ||
              d.solver == SolverType::kJacobi,
          "WorldDef.solver is unknown");
  Require(d.softSubSteps >= 1, "WorldDef.softSubSteps must be >= 1");
  Require(d.softSubSteps <= kMaxIterations, "WorldDef.softSubSteps must be <= 1000");
  Require(IsFinite(d.contactHertz) && d.contactHertz > 0, "WorldDef.contactHertz must be > 0");
  Require(IsFinite(d.contactDampingRatio) && d.contactDampingRatio >= 0, "WorldDef.contactDampingRatio must be >= 0");
  Require(IsFinite(d.jointHertz) && d.jointHertz > 0, "WorldDef.jointHertz must be > 0");
  Require(IsFinite(d.jointDampingRatio) && d.jointDampingRatio >= 0, "WorldDef.jointDampingRatio must be >= 0");
  Require(IsFinite(d.contactPushMaxVelocity) && d.contactPushMaxVelocity > 0,
          "WorldDef.contactPushMaxVelocity must be > 0");
  Require(IsFinite(d.contactPushMaxDepth) && d.contactPushMaxDepth > 0, "WorldDef.contactPushMaxDepth must be > 0");
  Require(d.softRelaxIterations >= 1 && d.softRelaxIterations <= kMaxIterations,
          "WorldDef.softRelaxIterations must be in [1, 1000]");
  Require(IsFinite(d.softMassRatioLimit) && (d.softMassRatioLimit == 0 || d.softMassRatioLimit >= 1),
          "WorldDef.softMassRatioLimit must be 0 (off) or >= 1");
  Require(d.broadPhase == BroadPhaseType::kQuadTree || d.broadPhase == BroadPhaseType::kUniformGrid,
          "WorldDef.broadPhase is unknown");
  Require(d.velocityIterations >= 1, "WorldDef.velocityIterations must be >= 1");
  Require(d.velocityIterations <= kMaxIterations, "WorldDef.velocityIterations must be <= 1000");
  Require(d.positionIterations >= 0, "WorldDef.positionIterations must be >= 0");
  Require(d.positionIterations <= kMaxIterations, "WorldDef.positionIterations must be <= 1000");
  Require(d.thesisPasses >= 1, "WorldDef.thesisPasses must be >= 1");
  Require(d.thesisPasses <= kMaxIterations, "WorldDef.thesisPasses must be <= 1000");
  Require(d.restitutionIterations >= 1, "WorldDef.restitutionIterations must be >= 1");
  Require(d.restitutionIterations <= kMaxIterations, "WorldDef.restitutionIterations must be <= 1000");
  Require(IsFinite(d.linearSlop) && d.linearSlop >= 0, "WorldDef.linearSlop must be finite and >= 0");
  Require(IsFinite(d.baumgarte) && d.baumgarte >= 0 && d.baumgarte <= 1, "WorldDef.baumgarte must be in [0, 1]");
  Require(IsFinite(d.maxLinearCorrection) && d.maxLinearCorrection > 0, "WorldDef.maxLinearCorrection must be > 0");
  Require(IsFinite(d.speculativeDistance) && d.speculativeDistance >= 0,
          "WorldDef.speculativeDistance must be finite and >= 0");
  Require(IsFinite(d.contactRecycleDistance) && d.contactRecycleDistance >= 0,
          "WorldDef.contactRecycleDistance must be finite and >= 0");
  Require(IsFinite(d.restitutionThreshold) && d.restitutionThreshold >= 0,
          "WorldDef.restitutionThreshold must be finite and >= 0");
  Require(IsFinite(d.hitEventThreshold) && d.hitEventThreshold >= 0,
          "WorldDef.hitEventThreshold must be finite and >= 0");
  // The quadrants scheme solves inside its own step: the velocities before the solve are not seen.
  Require(!(d.hitEvents && d.scheme == ParallelScheme::kQuadrants),
          "WorldDef.hitEvents is not supported with ParallelScheme::kQuadrants (use kDeterministic)");
  Require(d.restitution == RestitutionPolicy::kCollisions || d.restitution == RestitutionPolicy::kBox2d,
          "WorldDef.restitution is unknown");
  Require(d.restitution == RestitutionPolicy::kCollisions || d.solver != SolverType::kThesis,
          "WorldDef.restitution = kBox2d needs SolverType::kPgs or kSoftStep");
  // Box2D 2.4.1's position pass geometry reads the bodies' shapes, which the quadrants scheme's
  // private copies do not carry; jacobi has no such pass (its split impulses replace it).
  Require(!d.box2dPositionSolve || d.solver == SolverType::kPgs || d.solver == SolverType::kSoftStep ||
              (d.solver == SolverType::kThesis && d.thesisPositionPass),
          "WorldDef.box2dPositionSolve needs SolverType::kPgs or kSoftStep, or kThesis with thesisPositionPass");
  Require(!d.box2dPositionSolve || d.scheme == ParallelScheme::kDeterministic,
          "WorldDef.box2dPositionSolve is not supported with ParallelScheme::kQuadrants (use kDeterministic)");
  Require(!d.thesisBlockImpulse ||
              (d.solver == SolverType::kThesis && d.thesisPointImpulses && d.thesisAccumulatedImpulse),
          "WorldDef.thesisBlockImpulse needs SolverType::kThesis with thesisPointImpulses and thesisAccumulatedImpulse");
  Require(IsFinite(d.polygonSkin) && d.polygonSkin >= 0 && 2 * d.polygonSkin <= d.speculativeDistance,
          "WorldDef.polygonSkin must be in [0, speculativeDistance / 2]");
  // The quadrants scheme solves private copies of its bodies without their shapes (quadrants_scheme.cpp).
  Require(d.polygonSkin == 0 || d.scheme == ParallelScheme::kDeterministic,
          "WorldDef.polygonSkin > 0 is not supported with ParallelScheme::kQuadrants (use kDeterministic)");
  Require(IsFinite(d.maxLinearSpeed) && d.maxLinearSpeed > 0, "WorldDef.maxLinearSpeed must be > 0");
  Require(IsFinite(d.maxRotation) && d.maxRotation > 0, "WorldDef.maxRotation must be > 0");
  Require(d.threadCount >= 1 && d.threadCount <= kMaxThreads, "WorldDef.threadCount must be in [1, 64]");
  Require(d.quadTreeMaxDepth >= 1 && d.quadTreeMaxDepth <= 12, "WorldDef.quadTreeMaxDepth must be in [1, 12]");
  Require(d.minParallelItems >= 1, "WorldDef.minParallelItems must be >= 1");
  Require(d.scheme == ParallelScheme::kDeterministic || d.scheme == ParallelScheme::kQuadrants,
          "WorldDef.scheme is unknown");
  // The quadrants scheme runs the thesis or pgs kernels on its private body copies.
  Require(d.solver != SolverType::kJacobi || d.scheme == ParallelScheme::kDeterministic,
          "WorldDef.solver = kJacobi is not supported with ParallelScheme::kQuadrants (use kDeterministic)");
  Require(IsFinite(d.linearSleepTolerance) && d.linearSleepTolerance >= 0,
          "WorldDef.linearSleepTolerance must be finite and >= 0");
  Require(IsFinite(d.angularSleepTolerance) && d.angularSleepTolerance >= 0,
          "WorldDef.angularSleepTolerance must be finite and >= 0");
  Require(IsFinite(d.timeToSleep) && d.timeToSleep > 0, "WorldDef.timeToSleep must be finite and > 0");
  // The quadrants scheme solves private copies of its regions' bodies (quadrants_scheme.cpp)
  // that carry no sleep state, and its results depend on the thread count anyway; sleeping is
  // refused there rather than half supported.
  Require(!(d.effects.sleep && d.scheme == ParallelScheme::kQuadrants),
          "WorldDef.effects.sleep is not supported with ParallelScheme::kQuadrants (use kDeterministic)");
}

// std::to_string prints 1e-40 as 0.000000; %g keeps the exponent.
std::string DensityText(Real density) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", double(density));
  return buffer;
}

// One shape's materials and geometry; `prefix` starts every message ("" for BodyDef::shape, whose
// messages name ShapeDef alone, as before compound bodies).
ShapeDef ValidateShape(const ShapeDef& in, const std::string& prefix) {
  ShapeDef shape = in;
  Require(IsFinite(shape.density) && shape.density >= 0, prefix + "ShapeDef.density must be finite and >= 0");
  Require(IsFinite(shape.friction) && shape.friction >= 0, prefix + "ShapeDef.friction must be finite and >= 0");
  Require(IsFinite(shape.restitution) && shape.restitution >= 0 && shape.restitution <= 1,
          prefix + "ShapeDef.restitution must be in [0, 1]");
  try {
    if (shape.type == ShapeType::kCircle) {
      ValidateCircle(shape.circle);
    } else if (shape.type == ShapeType::kPolygon) {
      const int count = shape.polygon.count;
      Require(count >= 3 && count <= kMaxPolygonVertices,
              "polygon vertex count must be in [3, 8], got " + std::to_string(count));
      shape.polygon = MakePolygon(std::span<const Vec2>(shape.polygon.vertices.data(), size_t(count)));
    } else if (shape.type == ShapeType::kCapsule) {
      ValidateCapsule(shape.capsule);
    } else if (shape.type == ShapeType::kSegment) {
      ValidateSegment(shape.segment);
    } else if (shape.type == ShapeType::kChainSegment) {
      ValidateChainSegment(shape.chainSegment);
    } else {
      throw Error("ShapeDef.type is unknown");
    }
  } catch (const Error& e) {
    if (prefix.empty()) throw;
    throw Error(prefix + e.what());
  }
  return shape;
}

ShapeDef ValidateBodyDef(const BodyDef& def, std::vector<ShapeDef>* shapes) {
  Require(def.type == BodyType::kStatic || def.type == BodyType::kKinematic || def.type == BodyType::kDynamic,
          "BodyDef.type is unknown");
  Require(IsFinite(def.position) && IsFinite(def.angle), "BodyDef position or angle is not finite");
  Require(std::abs(def.position.x) <= kMaxCoordinate && std::abs(def.position.y) <= kMaxCoordinate,
          "BodyDef.position is beyond the coordinate limit of 1e6 m");
  Require(IsFinite(def.linearVelocity) && IsFinite(def.angularVelocity), "BodyDef velocity is not finite");
  Require(std::abs(def.linearVelocity.x) <= kMaxInputSpeed && std::abs(def.linearVelocity.y) <= kMaxInputSpeed &&
              std::abs(def.angularVelocity) <= kMaxInputSpeed,
          "BodyDef velocity is beyond the limit of 1e6 m/s (rad/s)");
  Require(IsFinite(def.linearDamping) && def.linearDamping >= 0, "BodyDef.linearDamping must be finite and >= 0");
  Require(IsFinite(def.angularDamping) && def.angularDamping >= 0, "BodyDef.angularDamping must be finite and >= 0");
  Require(GravityScaleOk(def.gravityScale), "BodyDef.gravityScale must be finite and in [-1e6, 1e6]");
  Require(!def.fixedRotation || def.angularVelocity == 0, "BodyDef.angularVelocity must be 0 with fixedRotation");
  const bool dynamic = def.type == BodyType::kDynamic;
  if (def.extraShapes.empty()) {
    Require(IsFinite(def.shape.density) && def.shape.density >= 0, "ShapeDef.density must be finite and >= 0");
    Require(!dynamic || def.shape.density > 0, "a dynamic body needs ShapeDef.density > 0");
    const ShapeDef shape = ValidateShape(def.shape, "");
    if (dynamic) RequireDynamicMass(shape, "");
    if (shapes != nullptr) shapes->clear();
    return shape;
  }
  // A compound body: every shape checked, then the total mass.
  Require(def.extraShapes.size() < size_t(kMaxBodyShapes),
          "BodyDef.extraShapes has " + std::to_string(def.extraShapes.size()) + " shapes; a body carries at most " +
              std::to_string(kMaxBodyShapes) + " (shape and extraShapes together)");
  std::vector<ShapeDef> all;
  all.reserve(def.extraShapes.size() + 1);
  for (size_t k = 0; k <= def.extraShapes.size(); ++k) {
    const std::string prefix = k == 0 ? std::string("BodyDef.shape: ") : "BodyDef.extraShapes[" + std::to_string(k - 1) + "]: ";
    const ShapeDef& in = k == 0 ? def.shape : def.extraShapes[k - 1];
    all.push_back(ValidateShape(in, prefix));
    Require(!in.isSensor, prefix + "a compound body's shapes cannot be sensors (give the sensor a body of its own)");
    Require(!dynamic || !IsSegmentType(in.type),
            prefix + "a segment has no area (mass 0): only a static or kinematic body may carry it");
  }
  if (dynamic) RequireDynamicMass(std::span<const ShapeDef>(all), "");
  if (shapes != nullptr) *shapes = std::move(all);
  return shapes != nullptr ? (*shapes)[0] : ValidateShape(def.shape, "BodyDef.shape: ");
}

MassData ShapeMass(const ShapeDef& shape) {
  switch (shape.type) {
    case ShapeType::kCircle: return ComputeMass(shape.circle, shape.density);
    case ShapeType::kCapsule: return ComputeMass(shape.capsule, shape.density);
    case ShapeType::kSegment: return ComputeMass(shape.segment);
    case ShapeType::kChainSegment: return ComputeMass(shape.chainSegment.segment);
    case ShapeType::kPolygon: break;
  }
  return ComputeMass(shape.polygon, shape.density);
}

void RequireDynamicMass(const ShapeDef& shape, const std::string& prefix) {
  // Density times area can overflow (or underflow) float: a mass or inertia that is not a
  // positive finite number would poison the solver, so the body is refused.
  // Subnormal values count as underflow: they lose precision and make 1/m overflow.
  // Box2D's rule: a shape of no area gives no mass, so a segment rides static and kinematic bodies.
  Require(!IsSegmentType(shape.type), prefix + "a segment has no area (mass 0): only a static or kinematic body may carry it");
  const MassData md = ShapeMass(shape);
  constexpr Real kSmallest = std::numeric_limits<Real>::min();
  Require(IsFinite(md.mass) && md.mass >= kSmallest && IsFinite(md.rotationalInertia) &&
              md.rotationalInertia >= kSmallest && IsFinite(Real(1) / md.mass) &&
              IsFinite(Real(1) / md.rotationalInertia),
          prefix + "the body's mass or rotational inertia is not a positive finite number (density " +
              DensityText(shape.density) + ")");
}

// Exact: each shape's mass and centre at its density, the inertias moved to the common centre by
// the parallel-axis theorem, summed in double (a float sum of 40 shapes loses the last bits).
MassData CompoundMass(std::span<const ShapeDef> shapes) {
  double mass = 0, cx = 0, cy = 0, mx = 0, my = 0;
  for (const ShapeDef& s : shapes) {
    const MassData md = ShapeMass(s);
    mass += double(md.mass);
    mx += double(md.mass) * double(md.center.x);
    my += double(md.mass) * double(md.center.y);
    cx += double(md.center.x);
    cy += double(md.center.y);
  }
  // No mass (a static body of segments): the shapes' mean centre, which nothing weighs.
  const double n = double(shapes.size());
  const double x = mass > 0 ? mx / mass : cx / n, y = mass > 0 ? my / mass : cy / n;
  double inertia = 0;
  for (const ShapeDef& s : shapes) {
    const MassData md = ShapeMass(s);
    const double dx = double(md.center.x) - x, dy = double(md.center.y) - y;
    inertia += double(md.rotationalInertia) + double(md.mass) * (dx * dx + dy * dy);
  }
  MassData out;
  out.mass = Real(mass);
  out.center = Vec2{Real(x), Real(y)};
  out.rotationalInertia = Real(inertia);
  return out;
}

void RequireDynamicMass(std::span<const ShapeDef> shapes, const std::string& prefix) {
  const MassData md = CompoundMass(shapes);
  constexpr Real kSmallest = std::numeric_limits<Real>::min();
  Require(IsFinite(md.mass) && md.mass >= kSmallest && IsFinite(md.rotationalInertia) &&
              md.rotationalInertia >= kSmallest && IsFinite(Real(1) / md.mass) &&
              IsFinite(Real(1) / md.rotationalInertia),
          prefix + "a dynamic compound body's total mass or rotational inertia is not a positive finite number (" +
              std::to_string(shapes.size()) + " shapes; every one of density 0?)");
}

void CheckBodyDef(const BodyDef& def) { (void)ValidateBodyDef(def); }

MassData ComputeBodyMass(std::span<const ShapeDef> shapes) {
  Require(!shapes.empty(), "ComputeBodyMass: no shapes");
  return CompoundMass(shapes);
}

}  // namespace quadrant
