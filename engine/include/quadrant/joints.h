// Joints: the definitions World::CreateRevoluteJoint, CreateDistanceJoint and CreateWeldJoint take,
// and the joint handle. Value types only, every default documented here; world.h includes this.
//
// A joint ties two bodies at an anchor on each, given in that body's own frame (relative to the
// body origin, as BodyDef::position places it; World::GetLocalPoint turns a world point into one).
// Joints are solved by the soft_step solver (the default) in its sub-steps, before the contacts,
// coloured like them so the result is bit-identical for any thread count; the other solvers and
// the quadrants scheme refuse them. Softness: a rigid joint is held by a stiff spring of
// WorldDef::jointHertz and jointDampingRatio per sub-step (Box2D 3's scheme), so an over-loaded
// chain stretches a little rather than exploding.
#pragma once

#include <cstdint>

#include "quadrant/types.h"

namespace quadrant {

/// A joint handle: a slot index plus a generation, as BodyId. The default is the null id.
struct JointId {
  uint32_t index = 0;
  uint32_t generation = 0;
  constexpr bool IsNull() const { return generation == 0; }
  friend constexpr bool operator==(JointId a, JointId b) = default;
};

enum class JointType : uint8_t {
  kRevolute,  ///< a shared point; free rotation with an optional limit, motor and spring
  kDistance,  ///< a rod (or spring, or rope between limits) between two anchors
  kWeld,      ///< a shared point and a fixed relative angle, rigid or soft
};

/// Holds bodyA's and bodyB's anchors together; bodyB turns relative to bodyA by an angle measured
/// from referenceAngle (radians, counter-clockwise). Refused: a stale or null body, the same body
/// twice, non-finite values, a limit with lowerAngle > upperAngle or outside [-pi, pi], a negative
/// maxMotorTorque, hertz or dampingRatio.
struct RevoluteJointDef {
  BodyId bodyA, bodyB;
  Vec2 localAnchorA, localAnchorB;  ///< m, in each body's frame
  Real referenceAngle = 0;          ///< bodyB's angle minus bodyA's where the joint angle is 0
  bool enableLimit = false;
  Real lowerAngle = 0, upperAngle = 0;  ///< rad, the joint angle stays within them
  bool enableMotor = false;
  Real motorSpeed = 0;      ///< rad/s, the relative angular velocity the motor drives towards
  Real maxMotorTorque = 0;  ///< N m; a motor of speed 0 is joint friction of this torque
  bool enableSpring = false;
  Real hertz = 0, dampingRatio = 0;  ///< an angular spring towards joint angle 0
  bool collideConnected = false;     ///< whether the two bodies' shapes may still touch
};

/// Keeps the anchors `length` apart along the line between them. With enableSpring the length is
/// a spring of hertz and dampingRatio (hertz 0: no force) between the limits minLength and
/// maxLength when enableLimit (a rope: minLength 0). Refused besides the common rules: length, or a
/// limit, below 0.005 m (the axis is undefined at zero length) or non-finite, minLength > maxLength.
struct DistanceJointDef {
  BodyId bodyA, bodyB;
  Vec2 localAnchorA, localAnchorB;
  Real length = 1;  ///< m
  bool enableSpring = false;
  Real hertz = 0, dampingRatio = 0;
  bool enableLimit = false;
  Real minLength = Real(0.005), maxLength = 1e6f;  ///< m
  bool collideConnected = false;
};

/// Holds the anchors together and bodyB's angle at bodyA's plus referenceAngle. Rigid (held at
/// WorldDef::jointHertz) where linearHertz / angularHertz are 0, else a spring of that frequency.
struct WeldJointDef {
  BodyId bodyA, bodyB;
  Vec2 localAnchorA, localAnchorB;
  Real referenceAngle = 0;
  Real linearHertz = 0, linearDampingRatio = 0;
  Real angularHertz = 0, angularDampingRatio = 0;
  bool collideConnected = false;
};

}  // namespace quadrant
