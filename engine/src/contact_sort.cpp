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
void ContactSorter::Sort(StageRunner& run, int bodyCount, const std::vector<std::vector<Contact>>& workerContacts,
                         std::vector<Contact>& contacts, const ContactCache* cache) {
  const int parts = static_cast<int>(workerContacts.size());
  parts_.resize(parts);
  size_t total = 0;
  for (const std::vector<Contact>& part : workerContacts) total += part.size();
  // Few contacts: one thread does it all (a parallel-for would cost more than it saves).
  const bool parallel = total >= size_t(run.MinHeavyItems());
  run.For(Stage::kPersistence, parts, parallel ? 1 : parts + 1, [&](int begin, int end, int) {
    for (int p = begin; p < end; ++p) SortPart(workerContacts[p], bodyCount, parts_[p], cache);
  });
  Merge(run, parallel ? run.Workers() : 1, contacts);
}

// Up to kMaxBuckets bodies, one counting pass on body a (a < n) puts the contacts in a-order,
// each a's contacts in input order; then each bucket is put in b-order on its own. A bucket
// holds the pairs whose lower body is a: a handful (a box of the pyramid has at most 4), so an
// insertion sort, which the broad phase's near-sorted order makes a compare or two, does it;
// a large one (a ground body under many bodies) is sorted by std::sort instead (no quadratic
// worst case). One scatter pass instead of the radix sort's two (three above 8192 bodies):
// callgrind on the base-100 pyramid (5051 bodies, 10 000 contacts), SortPart 822 000
// instructions a step before (two 13-bit passes), see the commit for after.
// Keys are unique, so every way of sorting gives the same order.
void ContactSorter::SortPart(const std::vector<Contact>& in, int bodyCount, Part& part, const ContactCache* cache) {
  const size_t count = in.size();
  part.sorted.resize(count);
  if (count < 2) {
    std::copy(in.begin(), in.end(), part.sorted.begin());
    if (cache != nullptr) cache->Restore(part.sorted);
    return;
  }
  std::vector<SortKey>& keys = part.keys;
  std::vector<SortKey>& keyScratch = part.keyScratch;
  keys.resize(count);
  keyScratch.resize(count);
  std::vector<uint32_t>& radixCounts = part.radixCounts;
  if (bodyCount <= kMaxBuckets) {
    const size_t buckets = size_t(bodyCount);
    radixCounts.assign(buckets + 1, 0u);
    for (size_t i = 0; i < count; ++i) ++radixCounts[size_t(in[i].a) + 1];
    for (size_t b = 0; b < buckets; ++b) radixCounts[b + 1] += radixCounts[b];
    for (size_t i = 0; i < count; ++i) keys[radixCounts[size_t(in[i].a)]++] = {in[i].Key(), uint32_t(i)};
    // radixCounts[a] is now the end of bucket a (the start of a + 1).
    size_t begin = 0;
    for (size_t a = 0; a < buckets; ++a) {
      const size_t end = radixCounts[a];
      if (end - begin > kInsertionBucket) {
        std::sort(keys.begin() + ptrdiff_t(begin), keys.begin() + ptrdiff_t(end),
                  [](const SortKey& x, const SortKey& y) { return x.key < y.key; });
      } else {
        for (size_t i = begin + 1; i < end; ++i) {
          const SortKey k = keys[i];
          size_t j = i;
          for (; j > begin && keys[j - 1].key > k.key; --j) keys[j] = keys[j - 1];
          keys[j] = k;
        }
      }
      begin = end;
    }
  } else {
    RadixSort(in, bodyCount, part);
  }
  // The gather, and last step's impulses restored into each chunk of it while it is in L1 (a
  // separate pass read and wrote the 760 KB of the pyramid's contacts again, and cost a
  // parallel-for of its own). Merging restored parts gives the restored whole.
  if (cache == nullptr) {
    for (size_t i = 0; i < count; ++i) part.sorted[i] = in[keys[i].index];
    return;
  }
  ContactCache::Cursor cursor;
  constexpr size_t kChunk = 64;  // 64 contacts: 4.9 KB
  for (size_t begin = 0; begin < count; begin += kChunk) {
    const size_t end = std::min(count, begin + kChunk);
    for (size_t i = begin; i < end; ++i) part.sorted[i] = in[keys[i].index];
    cache->Restore(std::span<Contact>(part.sorted).subspan(begin, end - begin), cursor);
  }
}

// More bodies than kMaxBuckets: the key a*n+b (32 bits for up to 65536 bodies) LSD
// radix-sorted as (key, index).
void ContactSorter::RadixSort(const std::vector<Contact>& in, int bodyCount, Part& part) {
  const size_t count = in.size();
  const uint64_t n = uint64_t(bodyCount);
  std::vector<SortKey>& keys = part.keys;
  std::vector<SortKey>& keyScratch = part.keyScratch;
  uint64_t maxKey = 0;
  for (size_t i = 0; i < count; ++i) {
    const uint64_t key = uint64_t(in[i].a) * n + uint64_t(in[i].b);
    keys[i] = {key, uint32_t(i)};
    maxKey = std::max(maxKey, key);
  }
  // As few passes as digits of at most 13 bits allow, the key's bits shared evenly between them
  // (the counts, 32 KB at 13 bits, stay in L1). Any digit width gives the same order (the keys
  // are unique).
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
