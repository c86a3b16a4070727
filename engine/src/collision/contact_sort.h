// The contacts of a step in pair-key order, from the narrow phase's per-worker lists: each
// list's (key, index) pairs sorted on its own worker, then the sorted key lists merged in
// parallel ranges of keys, each range gathering its contacts straight into the output.
#pragma once

#include <cstdint>
#include <vector>

#include "collision/contact_cache.h"
#include "quadrant/task_system.h"
#include "parallel/worker_lists.h"
#include "world/world_internal.h"

namespace quadrant {

class ContactSorter {
 public:
  /// Writes the contacts of all `workerContacts` lists into `contacts` in key order (a, b),
  /// with last step's impulses restored from `cache` (ContactCache::Restore) unless it is null.
  void Sort(StageRunner& run, int bodyCount, const WorkerLists<Contact>& workerContacts,
            std::vector<Contact>& contacts, const ContactCache* cache = nullptr);
  /// Whether the last Sort's output had strictly increasing keys (checked as it was written;
  /// the broad phase reports a pair once, so it has unless a compound body made several contacts
  /// with one body): ContactCache::Keep's condition.
  bool StrictlyIncreasing() const { return increasing_; }

 private:
  static constexpr int kMaxParts = 64;  // WorldDef::threadCount's limit
  // Counting sort on body a up to this many bodies (the counts, 256 KB, stay in L2) when it is
  // the cheaper; the radix sort of the key a*n+b otherwise. From 2^14: many_pyramids 22000's
  // sort took the counting sort, persistence 2.52 -> 1.91 ms a step at 1 thread, 1.32 -> 1.15 at
  // 2 (amd-epyc-2c, five interleaved pairs); the sparse 64000-body scenes within +-0.02 ms.
  static constexpr int kMaxBuckets = 1 << 16;
  struct SortKey {
    uint64_t key;
    uint32_t index;
  };
  // One per worker: the sort's buffers and the worker's (key, index) pairs in key order.
  // Alone on its cache lines: the workers sort their parts at once (worker_lists.h says why).
  struct alignas(kCacheLine) Part {
    std::vector<SortKey> keys, keyScratch;
    std::vector<uint32_t> radixCounts;
    bool increasing = true;  // keys strictly increase (no pair twice)
  };
  struct RadixDigits {
    int passes;
    int bits;
  };
  static RadixDigits RadixDigitsFor(uint64_t maxKey);
  static void SortPart(const std::vector<Contact>& in, int bodyCount, bool byBody, Part& part);
  static void RadixSort(const std::vector<Contact>& in, int bodyCount, Part& part);
  // Range r of `ranges`: merges the parts' keys in its key range and gathers (and restores)
  // their contacts into `contacts`.
  void MergeRange(int r, int ranges, const WorkerLists<Contact>& workerContacts,
                  std::vector<Contact>& contacts, const ContactCache* cache);

  std::vector<Part> parts_;
  std::vector<TaskSystem::StagePlan> plan_;
  std::vector<char> rangeIncreasing_;  // per merge range
  bool increasing_ = true;
};

}  // namespace quadrant
