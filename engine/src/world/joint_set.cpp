#include "world/joint_set.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "world/validation.h"

namespace quadrant {
namespace {

constexpr Real kPi = std::numbers::pi_v<Real>;
constexpr Real kMinLength = Real(0.005);  // the linear slop: below it a distance joint's axis is undefined

bool FiniteAnchor(Vec2 p) { return IsFinite(p) && std::abs(p.x) <= kMaxCoordinate && std::abs(p.y) <= kMaxCoordinate; }

template <class Def>
Joint Common(const Def& def, JointType type, const std::string& call) {
  Require(!def.bodyA.IsNull() && !def.bodyB.IsNull(), call + ": bodyA and bodyB must be set");
  Require(!(def.bodyA == def.bodyB), call + ": bodyA and bodyB are the same body");
  Vec2 anchorA{};
  if constexpr (requires { def.localAnchorA; }) anchorA = def.localAnchorA;  // a mouse joint has none
  Require(FiniteAnchor(anchorA), call + ": localAnchorA must be finite and within 1e6 m");
  Require(FiniteAnchor(def.localAnchorB), call + ": localAnchorB must be finite and within 1e6 m");
  Joint j;
  j.type = type;
  j.idA = def.bodyA;
  j.idB = def.bodyB;
  j.localAnchorA = anchorA;
  j.localAnchorB = def.localAnchorB;
  j.collideConnected = def.collideConnected;
  return j;
}

void RequireSpring(Real hertz, Real damping, const std::string& what) {
  Require(IsFinite(hertz) && hertz >= 0, what + "hertz must be finite and >= 0");
  Require(IsFinite(damping) && damping >= 0, what + "dampingRatio must be finite and >= 0");
}

}  // namespace

Joint MakeJoint(const RevoluteJointDef& def) {
  const std::string call = "CreateRevoluteJoint";
  Joint j = Common(def, JointType::kRevolute, call);
  Require(IsFinite(def.referenceAngle) && std::abs(def.referenceAngle) <= kPi,
          call + ": referenceAngle must be finite and within [-pi, pi]");
  Require(IsFinite(def.lowerAngle) && IsFinite(def.upperAngle) && def.lowerAngle >= -kPi && def.upperAngle <= kPi,
          call + ": lowerAngle and upperAngle must be finite and within [-pi, pi]");
  Require(def.lowerAngle <= def.upperAngle, call + ": lowerAngle must be <= upperAngle");
  Require(IsFinite(def.motorSpeed), call + ": motorSpeed must be finite");
  Require(IsFinite(def.maxMotorTorque) && def.maxMotorTorque >= 0, call + ": maxMotorTorque must be finite and >= 0");
  RequireSpring(def.hertz, def.dampingRatio, call + ": ");
  j.referenceAngle = def.referenceAngle;
  j.enableLimit = def.enableLimit;
  j.lower = def.lowerAngle;
  j.upper = def.upperAngle;
  j.enableMotor = def.enableMotor;
  j.motorSpeed = def.motorSpeed;
  j.maxMotorTorque = def.maxMotorTorque;
  j.enableSpring = def.enableSpring;
  j.hertz = def.hertz;
  j.dampingRatio = def.dampingRatio;
  return j;
}

Joint MakeJoint(const DistanceJointDef& def) {
  const std::string call = "CreateDistanceJoint";
  Joint j = Common(def, JointType::kDistance, call);
  Require(IsFinite(def.length) && def.length >= kMinLength && def.length <= kMaxCoordinate,
          call + ": length must be finite and within [0.005, 1e6] m");
  Require(IsFinite(def.minLength) && IsFinite(def.maxLength) && def.minLength >= kMinLength && def.maxLength <= kMaxCoordinate,
          call + ": minLength and maxLength must be finite and within [0.005, 1e6] m");
  Require(def.minLength <= def.maxLength, call + ": minLength must be <= maxLength");
  RequireSpring(def.hertz, def.dampingRatio, call + ": ");
  j.length = def.length;
  j.enableSpring = def.enableSpring;
  j.hertz = def.hertz;
  j.dampingRatio = def.dampingRatio;
  j.enableLimit = def.enableLimit;
  j.lower = def.minLength;
  j.upper = def.maxLength;
  return j;
}

Joint MakeJoint(const WeldJointDef& def) {
  const std::string call = "CreateWeldJoint";
  Joint j = Common(def, JointType::kWeld, call);
  Require(IsFinite(def.referenceAngle) && std::abs(def.referenceAngle) <= kPi,
          call + ": referenceAngle must be finite and within [-pi, pi]");
  RequireSpring(def.linearHertz, def.linearDampingRatio, call + ": linear");
  RequireSpring(def.angularHertz, def.angularDampingRatio, call + ": angular");
  j.referenceAngle = def.referenceAngle;
  j.hertz = def.linearHertz;
  j.dampingRatio = def.linearDampingRatio;
  j.angularHertz = def.angularHertz;
  j.angularDampingRatio = def.angularDampingRatio;
  return j;
}

namespace {

Vec2 UnitAxis(Vec2 axis, const std::string& call) {
  Require(IsFinite(axis) && std::abs(axis.x) <= kMaxCoordinate && std::abs(axis.y) <= kMaxCoordinate,
          call + ": localAxisA must be finite");
  const Real length = Length(axis);
  Require(length > Real(1e-6), call + ": localAxisA must not be zero");
  return (Real(1) / length) * axis;
}

void RequireTranslations(Real lower, Real upper, const std::string& call) {
  Require(IsFinite(lower) && IsFinite(upper) && std::abs(lower) <= kMaxCoordinate && std::abs(upper) <= kMaxCoordinate,
          call + ": lowerTranslation and upperTranslation must be finite and within 1e6 m");
  Require(lower <= upper, call + ": lowerTranslation must be <= upperTranslation");
}

}  // namespace

Joint MakeJoint(const PrismaticJointDef& def) {
  const std::string call = "CreatePrismaticJoint";
  Joint j = Common(def, JointType::kPrismatic, call);
  j.localAxisA = UnitAxis(def.localAxisA, call);
  Require(IsFinite(def.referenceAngle) && std::abs(def.referenceAngle) <= kPi,
          call + ": referenceAngle must be finite and within [-pi, pi]");
  RequireTranslations(def.lowerTranslation, def.upperTranslation, call);
  Require(IsFinite(def.motorSpeed), call + ": motorSpeed must be finite");
  Require(IsFinite(def.maxMotorForce) && def.maxMotorForce >= 0, call + ": maxMotorForce must be finite and >= 0");
  RequireSpring(def.hertz, def.dampingRatio, call + ": ");
  j.referenceAngle = def.referenceAngle;
  j.enableLimit = def.enableLimit;
  j.lower = def.lowerTranslation;
  j.upper = def.upperTranslation;
  j.enableMotor = def.enableMotor;
  j.motorSpeed = def.motorSpeed;
  j.maxForce = def.maxMotorForce;
  j.enableSpring = def.enableSpring;
  j.hertz = def.hertz;
  j.dampingRatio = def.dampingRatio;
  return j;
}

Joint MakeJoint(const WheelJointDef& def) {
  const std::string call = "CreateWheelJoint";
  Joint j = Common(def, JointType::kWheel, call);
  j.localAxisA = UnitAxis(def.localAxisA, call);
  RequireTranslations(def.lowerTranslation, def.upperTranslation, call);
  Require(IsFinite(def.motorSpeed), call + ": motorSpeed must be finite");
  Require(IsFinite(def.maxMotorTorque) && def.maxMotorTorque >= 0, call + ": maxMotorTorque must be finite and >= 0");
  RequireSpring(def.hertz, def.dampingRatio, call + ": ");
  j.enableSpring = def.enableSpring;
  j.hertz = def.hertz;
  j.dampingRatio = def.dampingRatio;
  j.enableLimit = def.enableLimit;
  j.lower = def.lowerTranslation;
  j.upper = def.upperTranslation;
  j.enableMotor = def.enableMotor;
  j.motorSpeed = def.motorSpeed;
  j.maxMotorTorque = def.maxMotorTorque;
  return j;
}

Joint MakeJoint(const MotorJointDef& def) {
  const std::string call = "CreateMotorJoint";
  Joint j = Common(def, JointType::kMotor, call);
  Require(IsFinite(def.referenceAngle) && std::abs(def.referenceAngle) <= kPi,
          call + ": referenceAngle must be finite and within [-pi, pi]");
  Require(IsFinite(def.maxForce) && def.maxForce >= 0, call + ": maxForce must be finite and >= 0");
  Require(IsFinite(def.maxTorque) && def.maxTorque >= 0, call + ": maxTorque must be finite and >= 0");
  Require(IsFinite(def.correctionFactor) && def.correctionFactor >= 0 && def.correctionFactor <= 1,
          call + ": correctionFactor must be within [0, 1]");
  j.referenceAngle = def.referenceAngle;
  j.maxForce = def.maxForce;
  j.maxMotorTorque = def.maxTorque;
  j.correctionFactor = def.correctionFactor;
  return j;
}

Joint MakeJoint(const MouseJointDef& def) {
  const std::string call = "CreateMouseJoint";
  Joint j = Common(def, JointType::kMouse, call);
  Require(FiniteAnchor(def.target), call + ": target must be finite and within 1e6 m");
  Require(IsFinite(def.hertz) && def.hertz > 0, call + ": hertz must be finite and > 0");
  Require(IsFinite(def.dampingRatio) && def.dampingRatio >= 0, call + ": dampingRatio must be finite and >= 0");
  Require(IsFinite(def.maxForce) && def.maxForce >= 0, call + ": maxForce must be finite and >= 0");
  j.target = def.target;
  j.hertz = def.hertz;
  j.dampingRatio = def.dampingRatio;
  j.maxForce = def.maxForce;
  return j;
}

JointId JointSet::Add(const Joint& joint) {
  uint32_t slot;
  if (!freeSlots_.empty()) {
    slot = freeSlots_.back();
    freeSlots_.pop_back();
  } else {
    slot = static_cast<uint32_t>(generation_.size());
    generation_.push_back(1);
    denseOf_.push_back(-1);
  }
  Joint j = joint;
  j.slot = slot;
  denseOf_[slot] = static_cast<int32_t>(joints_.size());
  joints_.push_back(j);
  noCollide_ += j.collideConnected ? 0 : 1;
  stale_ = true;
  ++version_;
  return JointId{slot, generation_[slot]};
}

int JointSet::Dense(JointId id) const {
  if (!IsValid(id)) {
    throw Error("stale or invalid JointId (index " + std::to_string(id.index) + ", generation " +
                std::to_string(id.generation) + ")");
  }
  return denseOf_[id.index];
}

bool JointSet::IsValid(JointId id) const {
  return id.generation != 0 && id.index < generation_.size() && generation_[id.index] == id.generation &&
         denseOf_[id.index] >= 0;
}

void JointSet::RemoveAt(int j) {
  const uint32_t slot = joints_[size_t(j)].slot;
  noCollide_ -= joints_[size_t(j)].collideConnected ? 0 : 1;
  joints_[size_t(j)] = joints_.back();
  joints_.pop_back();
  if (size_t(j) < joints_.size()) denseOf_[joints_[size_t(j)].slot] = j;
  denseOf_[slot] = -1;
  generation_[slot] = generation_[slot] + 1 == 0 ? 1 : generation_[slot] + 1;  // 0 is the null id
  freeSlots_.push_back(slot);
  stale_ = true;
  ++version_;
}

std::vector<int> JointSet::OnBody(uint32_t slot) const {
  std::vector<int> out;
  for (int j = 0; j < Count(); ++j) {
    if (joints_[size_t(j)].idA.index == slot || joints_[size_t(j)].idB.index == slot) out.push_back(j);
  }
  return out;
}

void JointSet::Prepare(const std::vector<int32_t>& denseOf, int bodyCount) {
  for (Joint& j : joints_) {
    j.a = denseOf[j.idA.index];
    j.b = denseOf[j.idB.index];
  }
  if (!stale_) return;
  stale_ = false;
  pairs_.clear();
  joined_.assign(size_t(bodyCount), 0);
  for (const Joint& j : joints_) {
    if (j.collideConnected) continue;
    const uint32_t lo = uint32_t(std::min(j.a, j.b)), hi = uint32_t(std::max(j.a, j.b));
    pairs_.insert((uint64_t(lo) << 32) | hi);
    joined_[lo] = joined_[hi] = 1;
  }
}

void JointSet::FilterPairs(std::vector<CandidatePair>& pairs) const {
  const uint8_t* joined = joined_.data();
  pairs.erase(std::remove_if(pairs.begin(), pairs.end(),
                             [&](const CandidatePair& p) {
                               if (!joined[p.a] || !joined[p.b]) return false;
                               const uint32_t lo = uint32_t(std::min(p.a, p.b)), hi = uint32_t(std::max(p.a, p.b));
                               return pairs_.count((uint64_t(lo) << 32) | hi) != 0;
                             }),
              pairs.end());
}

}  // namespace quadrant
