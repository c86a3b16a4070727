// The contacts of a step in pair-key order, from the narrow phase's per-worker lists: each list
// radix-sorted on its own worker, then the sorted lists merged in parallel ranges of keys.
#pragma once

#include <cstdint>
#include <vector>

#include "contact_cache.h"
#include "world_internal.h"

namespace quadrant {

class ContactSorter {
 public:
  /// Writes the contacts of all `workerContacts` lists into `contacts` in key order (a, b),
  /// with last step's impulses restored from `cache` (ContactCache::Restore) unless it is null.
  void Sort(StageRunner& run, int bodyCount, const std::vector<std::vector<Contact>>& workerContacts,
            std::vector<Contact>& contacts, const ContactCache* cache = nullptr);

 private:
  static constexpr int kMaxParts = 64;  // WorldDef::threadCount's limit
  struct SortKey {
    uint64_t key;
    uint32_t index;
  };
  // One per worker: the radix sort's buffers and the worker's contacts in key order.
  struct Part {
    std::vector<SortKey> keys, keyScratch;
    std::vector<uint32_t> radixCounts;
    std::vector<Contact> sorted;
  };
  // Counting sort on body a up to this many bodies (the counts, 64 KB, stay in L2); the radix
  // sort of the key a*n+b above it.
  static constexpr int kMaxBuckets = 1 << 14;
  static constexpr size_t kInsertionBucket = 16;  // larger buckets: std::sort
  static void SortPart(const std::vector<Contact>& in, int bodyCount, Part& part, const ContactCache* cache);
  static void RadixSort(const std::vector<Contact>& in, int bodyCount, Part& part);
  void Merge(StageRunner& run, int ranges, std::vector<Contact>& contacts);

  std::vector<Part> parts_;
};

}  // namespace quadrant
