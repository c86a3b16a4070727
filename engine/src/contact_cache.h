// Contact persistence: last step's manifold points, found by body pair and feature id, so the
// solver can start from the impulses that held the bodies last step (warm starting).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "world_internal.h"

namespace quadrant {

class ContactCache {
 public:
  /// Copies last step's impulses into the points of `contacts` whose pair and feature id match.
  /// Returns the number of points matched.
  int Restore(std::span<Contact> contacts) const;
  /// Remembers the impulses of `contacts` for the next step (replacing what was stored).
  void Store(std::span<const Contact> contacts);
  void Clear();

 private:
  struct Entry {
    uint64_t key;
    int pointCount;
    uint32_t ids[2];
    Real normalImpulse[2];
    Real tangentImpulse[2];
  };
  static constexpr uint64_t kEmpty = ~uint64_t(0);
  const Entry* Find(uint64_t key) const;

  std::vector<Entry> table_;  // open addressing, linear probing, power-of-two size
};

}  // namespace quadrant
