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
  kRevolute,   ///< a shared point; free rotation with an optional limit, motor and spring
  kDistance,   ///< a rod (or spring, or rope between limits) between two anchors
  kWeld,       ///< a shared point and a fixed relative angle, rigid or soft
  kPrismatic,  ///< sliding along an axis fixed in bodyA, no relative turn; limit, motor, spring
  kWheel,      ///< sliding along an axis on a spring (suspension), free turn with a motor
  kMotor,      ///< drives bodyB to an offset and angle relative to bodyA with bounded force and torque
  kMouse,      ///< pulls bodyB's anchor to a world target by a bounded soft spring
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

/// bodyB slides relative to bodyA along localAxisA (in bodyA's frame, any non-zero length: it is
/// normalised) through the anchors, without turning relative to it (referenceAngle). The
/// translation is measured along the axis from where the anchors coincide. Refused besides the
/// common rules: a zero or non-finite axis, lowerTranslation > upperTranslation, a negative
/// maxMotorForce, hertz or dampingRatio.
struct PrismaticJointDef {
  BodyId bodyA, bodyB;
  Vec2 localAnchorA, localAnchorB;
  Vec2 localAxisA{1, 0};
  Real referenceAngle = 0;
  bool enableLimit = false;
  Real lowerTranslation = 0, upperTranslation = 0;  ///< m
  bool enableMotor = false;
  Real motorSpeed = 0, maxMotorForce = 0;  ///< m/s, N
  bool enableSpring = false;
  Real hertz = 0, dampingRatio = 0;  ///< a spring towards translation 0
  bool collideConnected = false;
};

/// A wheel on bodyB (its anchor the hub) riding on bodyA along localAxisA (the suspension): held
/// on the axis's line, a spring of hertz and dampingRatio along it (enableSpring; the default, as
/// Box2D's), optional limits on the travel, and a motor on bodyB's turn relative to bodyA.
struct WheelJointDef {
  BodyId bodyA, bodyB;
  Vec2 localAnchorA, localAnchorB;
  Vec2 localAxisA{0, 1};
  bool enableSpring = true;
  Real hertz = 1, dampingRatio = Real(0.7);
  bool enableLimit = false;
  Real lowerTranslation = 0, upperTranslation = 0;
  bool enableMotor = false;
  Real motorSpeed = 0, maxMotorTorque = 0;  ///< rad/s, N m
  bool collideConnected = false;
};

/// Drives bodyB's anchor towards bodyA's anchor and bodyB's angle towards bodyA's plus
/// referenceAngle with at most maxForce and maxTorque, aiming to close correctionFactor (in [0, 1])
/// of the remaining offset per sub-step (Box2D's motor joint: a character's or a platform's
/// controller). Refused: negative or non-finite maxForce, maxTorque; correctionFactor outside [0, 1].
struct MotorJointDef {
  BodyId bodyA, bodyB;
  Vec2 localAnchorA, localAnchorB;  ///< the offset to reach: bodyB's anchor onto bodyA's
  Real referenceAngle = 0;
  Real maxForce = 1, maxTorque = 1;  ///< N, N m, >= 0
  Real correctionFactor = Real(0.3);
  bool collideConnected = false;
};

/// Pulls bodyB's anchor (localAnchorB) towards `target` (a world point; World::SetJointTarget moves
/// it) by a spring of hertz and dampingRatio, with at most maxForce. bodyA is only a reference
/// (a static ground body, as in Box2D); localAnchorA is unused.
struct MouseJointDef {
  BodyId bodyA, bodyB;
  Vec2 localAnchorB;
  Vec2 target;
  Real hertz = 5, dampingRatio = Real(0.7);
  Real maxForce = 1000;  ///< N, >= 0
  bool collideConnected = true;
};

}  // namespace quadrant
