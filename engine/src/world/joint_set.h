// The world's joints: their id slots, their validation, and the pair filter for joined bodies that
// must not collide. The world owns one; the solver reads the joints' span (StepContext::joints).
//
// Cost when unused: a world without joints never calls into here during a step. With joints the
// step pays one pass over them (dense body indices), and, while some joint has collideConnected
// false, a flag test per candidate pair and a hash lookup where both bodies are joined.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <unordered_set>
#include <vector>

#include "collision/broad_phase.h"
#include "dynamics/joint.h"

namespace quadrant {

// The definitions checked in full and turned into a Joint (bodies by id; dense indices are set by
// Prepare). Throws quadrant::Error naming the field; `call` prefixes the message.
Joint MakeJoint(const RevoluteJointDef& def);
Joint MakeJoint(const DistanceJointDef& def);
Joint MakeJoint(const WeldJointDef& def);
Joint MakeJoint(const PrismaticJointDef& def);
Joint MakeJoint(const WheelJointDef& def);
Joint MakeJoint(const MotorJointDef& def);
Joint MakeJoint(const MouseJointDef& def);

class JointSet {
 public:
  JointId Add(const Joint& joint);
  /// The joint's position in All(); throws quadrant::Error for a stale or null id.
  int Dense(JointId id) const;
  bool IsValid(JointId id) const;
  /// Removes the joint at dense position j (the last one moves into its place).
  void RemoveAt(int j);
  JointId IdOf(int j) const { return JointId{joints_[size_t(j)].slot, generation_[joints_[size_t(j)].slot]}; }
  int Count() const { return static_cast<int>(joints_.size()); }
  std::vector<Joint>& All() { return joints_; }
  const std::vector<Joint>& All() const { return joints_; }
  /// Dense positions of the joints on body slot `slot`, in dense order.
  std::vector<int> OnBody(uint32_t slot) const;

  /// Before a step: every joint's dense body indices from the world's slot map, and the set of
  /// joined pairs that must not collide, rebuilt if a joint or a body came or went since.
  void Prepare(const std::vector<int32_t>& denseOf, int bodyCount);
  /// Bodies or joints changed (dense indices moved): the pair set is rebuilt at the next Prepare.
  void MarkStale() {
    stale_ = true;
    ++version_;
  }
  /// Bumped by every change of the joints or of the bodies' dense indices (StepContext::jointsVersion).
  uint64_t Version() const { return version_; }
  /// Drops from `pairs` (keeping their order) every pair of bodies joined by a joint with
  /// collideConnected false. Nothing to do while no such joint exists.
  bool Filters() const { return noCollide_ > 0; }
  void FilterPairs(std::vector<CandidatePair>& pairs) const;

 private:
  std::vector<Joint> joints_;
  std::vector<uint32_t> generation_;  // per slot; bumped on removal
  std::vector<int32_t> denseOf_;      // per slot: position in joints_, -1 when free
  std::vector<uint32_t> freeSlots_;
  int noCollide_ = 0;                 // joints with collideConnected false
  bool stale_ = true;
  uint64_t version_ = 0;
  std::unordered_set<uint64_t> pairs_;  // (min, max) dense body indices of non-colliding joints
  std::vector<uint8_t> joined_;         // per dense body: in some non-colliding joint
};

}  // namespace quadrant
