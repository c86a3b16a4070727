// Sleeping: islands of dynamic bodies connected by contacts, per-body sleep timers, and the
// waking rules. Used only when WorldDef::effects.sleep is on; with it off the world never calls
// into this stage, so a world without sleep does no island bookkeeping at all.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "world/world_internal.h"

namespace quadrant {

class Islands {
 public:
  /// After the solve of a (sub-)step: advances the sleep timers, builds the islands from
  /// `contacts` and puts every island whose bodies have all been slow for def.timeToSleep to
  /// sleep. Serial and in contact order, so the result does not depend on the thread count.
  /// The bodies put to sleep are listed in Changed() (their AABBs need a refresh).
  /// Joined bodies (`joints`) are in one island as touching ones are.
  void Update(Bodies& bodies, std::span<const Contact> contacts, std::span<const Joint> joints, const WorldDef& def,
              Real dt);

  /// After the narrow phase: wakes the island of every sleeping body that has a contact with
  /// a simulated one. Returns the number of bodies woken; they are listed in Changed().
  int WakeTouched(Bodies& bodies, std::span<const Contact> contacts);

  /// Wakes the sleeping bodies whose AABB overlaps `box`, with their islands (a body created,
  /// destroyed or moved there). Returns the number woken.
  int WakeOverlapping(Bodies& bodies, const AABB& box);

  /// Wakes body i's island if the body is asleep.
  void WakeIslandOf(Bodies& bodies, int i);

  /// Body i (dynamic) to sleep alone, as SetAwake(false).
  static void Sleep(Bodies& bodies, int i, uint32_t island);
  static bool IsSleeping(const Bodies& bodies, int i) {
    return bodies.type[i] == BodyType::kDynamic && bodies.awake[i] == 0;
  }
  /// The inverse mass body i has when awake (a sleeping body's is 0 while it sleeps).
  static BodyInverseMass AwakeInverseMass(const Bodies& bodies, int i);

  const std::vector<int>& Changed() const { return changed_; }

 private:
  static void Wake(Bodies& bodies, int i);
  void Mark(uint32_t island);
  int WakeMarked(Bodies& bodies);
  int Find(int i);

  std::vector<int32_t> parent_;   // union-find over dense body indices
  std::vector<Real> islandTime_;  // per root: the smallest sleep time of the island
  std::vector<uint8_t> marked_;   // per island id: wake it
  std::vector<uint32_t> markedIds_;
  std::vector<int> changed_;
};

}  // namespace quadrant
