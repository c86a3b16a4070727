// The contacts of a step in pair-key order, from the narrow phase's per-worker lists: each list
// radix-sorted on its own worker, then the sorted lists merged in parallel ranges of keys.
#pragma once

#include <cstdint>
#include <vector>

#include "worker_lists.h"
#include "world_internal.h"

namespace quadrant {

class ContactSorter {
 public:
  /// Writes the contacts of all `workerContacts` lists into `contacts` in key order (a, b).
  void Sort(StageRunner& run, int bodyCount, const WorkerLists<Contact>& workerContacts,
            std::vector<Contact>& contacts);

 private:
  static constexpr int kMaxParts = 64;  // WorldDef::threadCount's limit
  struct SortKey {
    uint64_t key;
    uint32_t index;
  };
  // One per worker: the radix sort's buffers and the worker's contacts in key order.
  // Alone on its cache lines: the workers sort their parts at once (worker_lists.h says why).
  struct alignas(kCacheLine) Part {
    std::vector<SortKey> keys, keyScratch;
    std::vector<uint32_t> radixCounts;
    std::vector<Contact> sorted;
  };
  static void SortPart(const std::vector<Contact>& in, int bodyCount, Part& part);
  void Merge(StageRunner& run, int ranges, std::vector<Contact>& contacts);

  std::vector<Part> parts_;
};

}  // namespace quadrant
