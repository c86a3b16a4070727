// A joint as the world keeps it and the soft step solves it: the validated definition in one flat
// record (the fields of every joint type; a type reads its own), the bodies by id and, for the
// step, by dense index, and the impulses accumulated over the last step for the warm start.
// Joints live in World::Impl in creation order (a removal moves the last one into the gap), and
// the solver walks them in that order: the same order, the same bits, for any thread count.
#pragma once

#include <cstdint>

#include "quadrant/joints.h"

namespace quadrant {

struct Joint {
  JointType type = JointType::kRevolute;
  uint32_t slot = 0;    // the JointId's index
  BodyId idA, idB;
  int a = -1, b = -1;   // dense body indices, refreshed before each step
  Vec2 localAnchorA, localAnchorB;  // relative to each body's origin
  Real referenceAngle = 0;
  // Revolute: limit, motor, spring. Distance: length, spring, limit. Weld: two springs.
  // Prismatic and wheel: lower and upper are translations. Motor joint: maxMotorTorque is its
  // maxTorque. Mouse: hertz and dampingRatio its spring.
  bool enableLimit = false, enableMotor = false, enableSpring = false;
  bool collideConnected = false;
  Real lower = 0, upper = 0;          // revolute angles; distance lengths
  Real motorSpeed = 0, maxMotorTorque = 0;
  Real hertz = 0, dampingRatio = 0;   // revolute and distance spring; weld linear spring
  Real angularHertz = 0, angularDampingRatio = 0;  // weld
  Real length = 0;                    // distance
  Vec2 localAxisA;                    // prismatic, wheel: unit, in bodyA's frame
  Real maxForce = 0, correctionFactor = 0;  // prismatic motor (N), motor and mouse force; motor joint
  Vec2 target;                        // mouse: the world point bodyB's anchor is pulled to
  // Accumulated impulses, kept from step to step (warm start).
  Vec2 linearImpulse;                 // revolute and weld point
  Real angularImpulse = 0;            // weld angle; distance rod or spring
  Real springImpulse = 0, motorImpulse = 0, lowerImpulse = 0, upperImpulse = 0;
  Real perpImpulse = 0;               // prismatic and wheel: across the axis
};

}  // namespace quadrant
