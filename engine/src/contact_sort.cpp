// Contact sort and merge (contact_sort.h).
#include "contact_sort.h"

#include <algorithm>

#include "stage_runner.h"

namespace quadrant {

// Contacts are solved in pair-key order, not broad-phase order, so the result does not depend
// on which broad phase found them or on how threads split the work. Keys are unique (the
// broad phase reports a pair once), so the order is the same whichever way it is reached:
// every worker sorts its own contacts (in parallel), then the sorted parts are merged in
// parallel, each worker producing one range of keys.
void ContactSorter::Sort(StageRunner& run, int bodyCount, const WorkerLists<Contact>& workerContacts,
                         std::vector<Contact>& contacts) {
  const int parts = workerContacts.Count();
  parts_.resize(parts);
  const size_t total = workerContacts.TotalSize();
  // Few contacts: one thread does it all (a parallel-for would cost more than it saves).
  const bool parallel = total >= size_t(run.MinHeavyItems());
  run.For(Stage::kPersistence, parts, parallel ? 1 : parts + 1, [&](int begin, int end, int) {
    for (int p = begin; p < end; ++p) SortPart(workerContacts[p], bodyCount, parts_[p]);
  });
  Merge(run, parallel ? run.Workers() : 1, contacts);
}

// The key a*n+b fits 32 bits for up to 65536 bodies; an LSD radix sort of (key, index) in
// 11-bit digits, then one gather of the contacts, keeps it linear and moves each contact once.
void ContactSorter::SortPart(const std::vector<Contact>& in, int bodyCount, Part& part) {
  const size_t count = in.size();
  part.sorted.resize(count);
  if (count < 2) {
    std::copy(in.begin(), in.end(), part.sorted.begin());
    return;
  }
  const uint64_t n = uint64_t(bodyCount);
  std::vector<SortKey>& keys = part.keys;
  std::vector<SortKey>& keyScratch = part.keyScratch;
  keys.resize(count);
  keyScratch.resize(count);
  uint64_t maxKey = 0;
  for (size_t i = 0; i < count; ++i) {
    const uint64_t key = uint64_t(in[i].a) * n + uint64_t(in[i].b);
    keys[i] = {key, uint32_t(i)};
    maxKey = std::max(maxKey, key);
  }
  // As few passes as digits of at most 13 bits allow, the key's bits shared evenly between them
  // (the counts, 32 KB at 13 bits, stay in L1): the base-100 pyramid's keys (25 bits) take two
  // passes of 13 bits instead of three of 11. Any digit width gives the same order (the keys are
  // unique).
  constexpr int kMaxDigitBits = 13;
  int keyBits = 0;
  while (keyBits < 64 && (maxKey >> keyBits) != 0) ++keyBits;
  const int passes = (keyBits + kMaxDigitBits - 1) / kMaxDigitBits;
  const int digitBits = passes > 0 ? (keyBits + passes - 1) / passes : 1;
  const size_t buckets = size_t(1) << digitBits;
  const uint64_t mask = buckets - 1;
  std::vector<uint32_t>& radixCounts = part.radixCounts;
  radixCounts.resize(buckets + 1);
  for (int pass = 0, shift = 0; pass < passes; ++pass, shift += digitBits) {
    std::fill(radixCounts.begin(), radixCounts.end(), 0u);
    for (const SortKey& k : keys) ++radixCounts[((k.key >> shift) & mask) + 1];
    for (size_t b = 0; b < buckets; ++b) radixCounts[b + 1] += radixCounts[b];
    for (const SortKey& k : keys) keyScratch[radixCounts[(k.key >> shift) & mask]++] = k;
    keys.swap(keyScratch);
  }
  for (size_t i = 0; i < count; ++i) part.sorted[i] = in[keys[i].index];
}

// Merges the sorted parts into `contacts`. The key space is cut into `ranges` ranges at evenly
// spaced keys of the largest part (the parts are samples of the same scene, so the ranges hold
// similar numbers of contacts); each range finds its start in every part by binary search, its
// place in the output by adding those starts, and merges its share on its own.
void ContactSorter::Merge(StageRunner& run, int ranges, std::vector<Contact>& contacts) {
  int live = 0, largest = -1;
  size_t total = 0;
  for (int p = 0; p < static_cast<int>(parts_.size()); ++p) {
    const size_t size = parts_[p].sorted.size();
    total += size;
    if (size == 0) continue;
    ++live;
    if (largest < 0 || size > parts_[largest].sorted.size()) largest = p;
  }
  if (live <= 1) {  // one thread's case: the sorted part is the result
    if (live == 0) contacts.clear();
    else contacts.swap(parts_[largest].sorted);
    return;
  }
  contacts.resize(total);
  const std::vector<Contact>& sample = parts_[largest].sorted;
  auto split = [&](int r) -> uint64_t {  // the first key of range r
    if (r <= 0) return 0;
    if (r >= ranges) return ~uint64_t(0);
    return sample[sample.size() * size_t(r) / size_t(ranges)].Key();
  };
  auto lowerBound = [](const std::vector<Contact>& v, uint64_t key) -> size_t {
    if (key == ~uint64_t(0)) return v.size();
    return size_t(std::partition_point(v.begin(), v.end(), [&](const Contact& c) { return c.Key() < key; }) - v.begin());
  };
  const int parts = static_cast<int>(parts_.size());
  run.For(Stage::kPersistence, ranges, ranges > 1 ? 1 : 2, [&](int r0, int r1, int) {
    size_t head[kMaxParts], end[kMaxParts];
    for (int r = r0; r < r1; ++r) {
      const uint64_t lo = split(r), hi = split(r + 1);
      size_t out = 0;
      for (int p = 0; p < parts; ++p) {
        const std::vector<Contact>& v = parts_[p].sorted;
        head[p] = lowerBound(v, lo);
        end[p] = lowerBound(v, hi);
        out += head[p];
      }
      for (;;) {
        int best = -1;
        uint64_t bestKey = 0;
        for (int p = 0; p < parts; ++p) {
          if (head[p] == end[p]) continue;
          const uint64_t key = parts_[p].sorted[head[p]].Key();
          if (best < 0 || key < bestKey) {
            best = p;
            bestKey = key;
          }
        }
        if (best < 0) break;
        contacts[out++] = parts_[best].sorted[head[best]++];
      }
    }
  });
}

}  // namespace quadrant
