// Contact sort and merge (contact_sort.h).
#include "collision/contact_sort.h"

#include <algorithm>

#include "parallel/stage_runner.h"

namespace quadrant {

// Contacts are solved in pair-key order, not broad-phase order, so the result does not depend
// on which broad phase found them or on how threads split the work. Keys are unique (the
// broad phase reports a pair once), except a compound body's several contacts with one body,
// which one worker emits together in shape order and every sort below keeps in that order
// (all are stable, and a key's contacts are never in two parts); so the order is the same
// whichever way it is reached:
// every worker sorts its own contacts' (key, index) pairs, then each worker merges one range
// of keys of all parts and gathers those contacts into the output, restoring last step's
// impulses as it goes. Both stages are one parallel region (one hand-over, one barrier), and
// each contact is moved once at any thread count: the parts used to gather their own sorted
// contacts, which a merge then copied again (all 760 KB of the pyramid's), in a second
// parallel-for, and a third restored them; at 2 threads the stage took as long as at 1.
void ContactSorter::Sort(StageRunner& run, int bodyCount, const WorkerLists<Contact>& workerContacts,
                         std::vector<Contact>& contacts, const ContactCache* cache) {
  const int parts = workerContacts.Count();
  parts_.resize(parts);
  const size_t total = workerContacts.TotalSize();
  contacts.resize(total);
  increasing_ = true;
  if (total == 0) return;
  // Few contacts: one thread does it all (a parallel region would cost more than it saves).
  const bool parallel = total >= size_t(run.MinHeavyItems());
  const int ranges = parallel ? run.Workers() : 1;
  // The counting sort's fixed cost is a pass over n buckets, the radix sort's one over 2^10 to
  // 2^13 buckets a digit; a contact costs about 3 steps in the one (count, scatter, check) and
  // 2 a digit plus 1 in the other. The cheaper by that estimate is taken, for all parts alike
  // (their keys are merged). Circle stress 16000 (n = 16004, few contacts) cost 1.2 % more
  // instructions a step by counting sort; circle stress 1000 1.5 % less, the pyramid less.
  const size_t perPart = total / size_t(parts) + 1;
  const uint64_t n = uint64_t(bodyCount);
  const RadixDigits digits = RadixDigitsFor(n * n);
  const bool byBody = bodyCount <= kMaxBuckets &&
                      n + 3 * perPart <= size_t(digits.passes) * ((size_t(1) << digits.bits) + 2 * perPart) + perPart;
  plan_.assign({TaskSystem::StagePlan{parts, 1}, TaskSystem::StagePlan{ranges, 1}});
  rangeIncreasing_.assign(size_t(ranges), 1);
  run.Stages(Stage::kPersistence, plan_, parallel ? 1 : parts + ranges + 1, [&](int stage, int begin, int end) {
    for (int i = begin; i < end; ++i) {
      if (stage == 0) SortPart(workerContacts[i], bodyCount, byBody, parts_[i]);
      else MergeRange(i, ranges, workerContacts, contacts, cache);
    }
  });
  // Ranges hold disjoint key intervals in order, so the whole increases if each range does.
  for (char ok : rangeIncreasing_) increasing_ = increasing_ && ok != 0;
}

// Up to kMaxBuckets bodies, one counting pass on body a (a < n) puts the contacts in a-order,
// each a's contacts in input order; then each bucket is put in b-order. A bucket holds the
// pairs whose lower body is a: a handful (a box of the pyramid has at most 4), so an insertion
// sort, which the broad phase's near-sorted order makes a compare or two, does it. One scatter
// pass instead of the radix sort's two: callgrind on the base-100 pyramid (5051 bodies, 10 000
// contacts), SortPart 822 000 instructions a step with two 13-bit radix passes, 325 000 so.
// Keys are unique, so every way of sorting gives the same order.
void ContactSorter::SortPart(const std::vector<Contact>& in, int bodyCount, bool byBody, Part& part) {
  const size_t count = in.size();
  std::vector<SortKey>& keys = part.keys;
  std::vector<SortKey>& keyScratch = part.keyScratch;
  keys.resize(count);
  keyScratch.resize(count);
  part.increasing = true;
  if (count == 0) return;
  std::vector<uint32_t>& radixCounts = part.radixCounts;
  if (byBody) {
    const size_t buckets = size_t(bodyCount);
    radixCounts.assign(buckets + 1, 0u);
    for (size_t i = 0; i < count; ++i) ++radixCounts[size_t(in[i].a) + 1];
    for (size_t b = 0; b < buckets; ++b) radixCounts[b + 1] += radixCounts[b];
    for (size_t i = 0; i < count; ++i) keys[radixCounts[size_t(in[i].a)]++] = {in[i].Key(), uint32_t(i)};
    // In a-order now, each a's contacts in input order. One insertion pass over the keys puts
    // every bucket in b-order (a key moves back only past larger keys, all of its own bucket:
    // earlier buckets' keys are smaller). Walking the buckets instead cost a few instructions
    // for every body, most of them with no contact in the sparse stress scenes (circle stress
    // 1000: SortPart +41 % over the radix sort). A bucket far out of order (a ground body's
    // contacts reversed) would make it quadratic: past a budget of moves, std::sort does the rest.
    const size_t budget = 8 * count + 64;
    size_t moves = 0;
    for (size_t i = 1; i < count; ++i) {
      if (keys[i].key > keys[i - 1].key) continue;
      if (keys[i].key == keys[i - 1].key) part.increasing = false;
      const SortKey k = keys[i];
      size_t j = i;
      for (; j > 0 && keys[j - 1].key > k.key; --j) keys[j] = keys[j - 1];
      keys[j] = k;
      // A key moved back next to an equal one repeats too (a compound body's contacts).
      if (j > 0 && keys[j - 1].key == k.key) part.increasing = false;
      moves += i - j;
      if (moves > budget) {
        // Equal keys (a compound body's contacts with one body) stay in input order, which is
        // the narrow phase's shape order: the order must not depend on the part's other contacts.
        std::stable_sort(keys.begin(), keys.end(), [](const SortKey& x, const SortKey& y) { return x.key < y.key; });
        for (size_t m = 1; m < count; ++m) part.increasing = part.increasing && keys[m - 1].key < keys[m].key;
        break;
      }
    }
  } else {
    RadixSort(in, bodyCount, part);
    for (size_t i = 1; i < count; ++i) part.increasing = part.increasing && keys[i - 1].key < keys[i].key;
  }
}

// As few passes as digits of at most 13 bits allow, the key's bits shared evenly between them
// (the counts, 32 KB at 13 bits, stay in L1). Any digit width gives the same order (the keys are
// unique).
ContactSorter::RadixDigits ContactSorter::RadixDigitsFor(uint64_t maxKey) {
  constexpr int kMaxDigitBits = 13;
  int keyBits = 0;
  while (keyBits < 64 && (maxKey >> keyBits) != 0) ++keyBits;
  const int passes = (keyBits + kMaxDigitBits - 1) / kMaxDigitBits;
  return {passes, passes > 0 ? (keyBits + passes - 1) / passes : 1};
}

// More bodies than kMaxBuckets, or few contacts for many bodies: the key a*n+b (32 bits for up
// to 65536 bodies) LSD radix-sorted as (key, index).
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
  const RadixDigits digits = RadixDigitsFor(maxKey);
  const int passes = digits.passes, digitBits = digits.bits;
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

// The key space is cut into `ranges` ranges holding equal numbers of contacts: range r starts
// at the least key with r/ranges of all contacts below it, found by bisecting the key (each
// probe a binary search in every part; keys are unique, so the count below a key grows by at
// most one a key and hits the target exactly). The parts are not samples of the same keys:
// the narrow phase's blocks are runs of the broad phase's spatial order, so on the pyramid one
// worker's part held the low keys and the other's the high ones, and cutting at the largest
// part's median (as before) gave one range a quarter of the contacts and the other three
// quarters. Range r finds its start in every part by binary search, its place in the output
// by adding those starts, merges its share and gathers the contacts, restoring each chunk of 64
// (4.9 KB) while it is in L1 (a separate pass read and wrote the pyramid's 760 KB again).
void ContactSorter::MergeRange(int r, int ranges, const WorkerLists<Contact>& workerContacts,
                               std::vector<Contact>& contacts, const ContactCache* cache) {
  const int parts = static_cast<int>(parts_.size());
  auto lowerBound = [](const std::vector<SortKey>& v, uint64_t key) -> size_t {
    return size_t(std::partition_point(v.begin(), v.end(), [&](const SortKey& k) { return k.key < key; }) - v.begin());
  };
  size_t total = 0;
  uint64_t maxKey = 0;
  for (int p = 0; p < parts; ++p) {
    total += parts_[p].keys.size();
    if (!parts_[p].keys.empty()) maxKey = std::max(maxKey, parts_[p].keys.back().key);
  }
  auto split = [&](int at) -> uint64_t {  // the first key of range `at`
    if (at <= 0) return 0;
    if (at >= ranges) return ~uint64_t(0);
    const size_t target = total * size_t(at) / size_t(ranges);
    uint64_t lo = 0, hi = maxKey + 1;  // count below lo < target... or lo == 0; count below hi = total
    while (lo < hi) {
      const uint64_t mid = lo + (hi - lo) / 2;
      size_t below = 0;
      for (int p = 0; p < parts; ++p) below += lowerBound(parts_[p].keys, mid);
      if (below >= target) hi = mid;
      else lo = mid + 1;
    }
    return lo;
  };
  auto bound = [&](const std::vector<SortKey>& v, uint64_t key) -> size_t {
    return key == ~uint64_t(0) ? v.size() : lowerBound(v, key);
  };
  const uint64_t lo = split(r), hi = split(r + 1);
  size_t head[kMaxParts], end[kMaxParts];
  size_t out = 0;
  int live = 0, last = 0;
  for (int p = 0; p < parts; ++p) {
    const std::vector<SortKey>& v = parts_[p].keys;
    head[p] = bound(v, lo);
    end[p] = bound(v, hi);
    out += head[p];
    if (head[p] < end[p]) {
      ++live;
      last = p;
    }
  }
  ContactCache::Cursor cursor;
  constexpr size_t kChunk = 64;
  const size_t first = out;
  uint64_t previous = 0;
  bool increasing = true;
  while (live > 0) {
    const size_t chunkBegin = out;
    if (live == 1) {  // one part left in the range (always so on one thread): a straight gather
      const std::vector<SortKey>& keys = parts_[last].keys;
      const std::vector<Contact>& in = workerContacts[last];
      const size_t n = std::min(kChunk, end[last] - head[last]);
      // Within the part the keys increase (Part::increasing); only the first can repeat the
      // previous part's last. (Checking every key here cost 10 instructions a contact.)
      if (n > 0) {
        increasing = increasing && (out == first || keys[head[last]].key > previous) && parts_[last].increasing;
        previous = keys[head[last] + n - 1].key;
      }
      for (size_t i = 0; i < n; ++i) contacts[out++] = in[keys[head[last]++].index];
      if (head[last] == end[last]) live = 0;
    } else {
      for (size_t i = 0; i < kChunk && live > 1; ++i) {
        int best = -1;
        uint64_t bestKey = 0;
        for (int p = 0; p < parts; ++p) {
          if (head[p] == end[p]) continue;
          const uint64_t key = parts_[p].keys[head[p]].key;
          if (best < 0 || key < bestKey) {
            best = p;
            bestKey = key;
          }
        }
        increasing = increasing && (out == first || bestKey > previous);
        previous = bestKey;
        contacts[out++] = workerContacts[best][parts_[best].keys[head[best]++].index];
        if (head[best] == end[best]) {
          --live;
          if (live == 1) {
            for (int p = 0; p < parts; ++p) {
              if (head[p] < end[p]) last = p;
            }
          }
        }
      }
    }
    if (cache != nullptr) cache->Restore(std::span<Contact>(contacts).subspan(chunkBegin, out - chunkBegin), cursor);
  }
  rangeIncreasing_[size_t(r)] = increasing ? 1 : 0;
}

}  // namespace quadrant
