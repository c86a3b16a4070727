// Contact persistence by pair key and feature id.
//
// The store is an array sorted by key rather than a hash table: the world's contacts arrive in
// key order, so storing is a parallel filtered copy (count per worker block, prefix, copy)
// and a lookup walks forward from the previous one (galloping), which is as cheap as a hash
// probe for sorted input and still correct for any order.
#include "collision/contact_cache.h"

#include <algorithm>

namespace quadrant {
namespace {

// Only contacts that carry something to the next step are stored: in sparse scenes most
// speculative contacts end the step with zero impulses.
bool Carries(const Contact& c) {
  for (int k = 0; k < c.manifold.pointCount; ++k) {
    const ManifoldPoint& p = c.manifold.points[k];
    if (p.normalImpulse != 0 || p.tangentImpulse != 0) return true;
  }
  return false;
}

}  // namespace

void ContactCache::Clear() {
  entries_.clear();
  last_.clear();
  kept_ = false;
  repeated_ = false;
}

// Last step's contacts themselves instead of a copy of their impulses: Store read every
// contact and wrote a 40-byte entry for each (352 000 instructions a step on the base-100
// pyramid, and a parallel-for of its own after the solve).
void ContactCache::Keep(std::vector<Contact>& contacts, bool strictlyIncreasing) {
  if (!strictlyIncreasing) {
    Store(contacts);
    return;
  }
  last_.swap(contacts);
  entries_.clear();
  kept_ = true;
  repeated_ = false;
}

ContactCache::Entry ContactCache::MakeEntry(const Contact& c) {
  const Manifold& m = c.manifold;
  Entry e{c.Key(), m.pointCount, {0, 0}, {0, 0}, {0, 0}};
  for (int k = 0; k < m.pointCount; ++k) {
    e.ids[k] = m.points[k].id;
    e.normalImpulse[k] = m.points[k].normalImpulse;
    e.tangentImpulse[k] = m.points[k].tangentImpulse;
  }
  return e;
}

// Contacts in strictly increasing key order (the world's always are) get one entry each, in
// one pass: a contact that carries nothing gets an entry of no points, which matches nothing,
// exactly as if it were absent. That saves the pass that counted the carrying contacts to
// place them (and the check of the order afterwards): callgrind on the base-100 pyramid, Store
// and Finish 607 000 instructions a step, StoreEach 352 000. Any other order
// (repeated keys: the first carrying entry of a key must be the one found) takes the filtered
// store.
bool ContactCache::StoreEach(std::span<const Contact> contacts, int begin, int end) {
  if (begin >= end) return true;
  // Straight-line (both point slots copied; Restore reads only the first pointCount, and a
  // contact that carries nothing gets pointCount 0): the loops of Carries and MakeEntry cost
  // 46 instructions a contact on the pyramid.
  auto put = [&](const Contact& c, uint64_t key) {
    const Manifold& m = c.manifold;
    const ManifoldPoint& p0 = m.points[0];
    const ManifoldPoint& p1 = m.points[1];
    const bool carries0 = m.pointCount > 0 && (p0.normalImpulse != 0 || p0.tangentImpulse != 0);
    const bool carries1 = m.pointCount > 1 && (p1.normalImpulse != 0 || p1.tangentImpulse != 0);
    entries_[size_t(&c - contacts.data())] = Entry{key,
                                                   carries0 || carries1 ? m.pointCount : 0,
                                                   {p0.id, p1.id},
                                                   {p0.normalImpulse, p1.normalImpulse},
                                                   {p0.tangentImpulse, p1.tangentImpulse}};
  };
  // The first contact of the list has nothing before it; a block's first is checked against
  // the contact before the block.
  uint64_t previous = contacts[size_t(begin)].Key();
  bool increasing = begin == 0 || contacts[size_t(begin) - 1].Key() < previous;
  put(contacts[size_t(begin)], previous);
  for (int i = begin + 1; i < end; ++i) {
    const Contact& c = contacts[size_t(i)];
    const uint64_t key = c.Key();
    increasing = increasing && previous < key;
    previous = key;
    put(c, key);
  }
  return increasing;
}

void ContactCache::StoreFiltered(std::span<const Contact> contacts) {
  entries_.clear();
  for (const Contact& c : contacts) {
    if (Carries(c)) entries_.push_back(MakeEntry(c));
  }
  Finish();
  repeated_ = std::adjacent_find(entries_.begin(), entries_.end(),
                                 [](const Entry& x, const Entry& y) { return x.key == y.key; }) != entries_.end();
}

void ContactCache::Store(std::span<const Contact> contacts) {
  kept_ = false;
  repeated_ = false;
  entries_.resize(contacts.size());
  if (!StoreEach(contacts, 0, static_cast<int>(contacts.size()))) StoreFiltered(contacts);
}

void ContactCache::Store(std::span<const Contact> contacts, StageRunner& run) {
  const int count = static_cast<int>(contacts.size());
  kept_ = false;
  repeated_ = false;
  entries_.resize(size_t(count));
  increasing_.assign(size_t(run.Workers()), 1);
  run.For(Stage::kPersistence, count, run.MinHeavyItems(), [&](int begin, int end, int worker) {
    if (!StoreEach(contacts, begin, end)) increasing_[size_t(worker)] = 0;
  });
  for (char ok : increasing_) {
    if (!ok) {
      run.Serial(Stage::kPersistence, [&] { StoreFiltered(contacts); });
      return;
    }
  }
}

void ContactCache::Finish() {
  auto byKey = [](const Entry& x, const Entry& y) { return x.key < y.key; };
  if (!std::is_sorted(entries_.begin(), entries_.end(), byKey)) {
    std::stable_sort(entries_.begin(), entries_.end(), byKey);
  }
}

int ContactCache::Restore(std::span<Contact> contacts) const {
  Cursor cursor;
  return Restore(contacts, cursor);
}

namespace {

// What Restore reads of a stored entry or of a kept contact of last step. A kept contact that
// carries nothing has no points, exactly as the store leaves it out.
uint64_t KeyOf(const ContactCache::Entry& e) { return e.key; }
int PointsOf(const ContactCache::Entry& e) { return e.pointCount; }
uint32_t IdOf(const ContactCache::Entry& e, int j) { return e.ids[j]; }
Real NormalOf(const ContactCache::Entry& e, int j) { return e.normalImpulse[j]; }
Real TangentOf(const ContactCache::Entry& e, int j) { return e.tangentImpulse[j]; }
uint64_t KeyOf(const Contact& c) { return c.Key(); }
int PointsOf(const Contact& c) { return Carries(c) ? c.manifold.pointCount : 0; }
uint32_t IdOf(const Contact& c, int j) { return c.manifold.points[j].id; }
Real NormalOf(const Contact& c, int j) { return c.manifold.points[j].normalImpulse; }
Real TangentOf(const Contact& c, int j) { return c.manifold.points[j].tangentImpulse; }

}  // namespace

int ContactCache::Restore(std::span<Contact> contacts, Cursor& cursor) const {
  if (kept_) return RestoreFrom<Contact, false>(last_.data(), last_.size(), contacts, cursor);
  if (repeated_) [[unlikely]] return RestoreFrom<Entry, true>(entries_.data(), entries_.size(), contacts, cursor);
  return RestoreFrom<Entry, false>(entries_.data(), entries_.size(), contacts, cursor);
}

template <class Source, bool kRepeated>
int ContactCache::RestoreFrom(const Source* entries, size_t size, std::span<Contact> contacts, Cursor& cursor) {
  int matched = 0;
  size_t at = cursor.at;
  uint64_t previous = cursor.previous;
  for (Contact& c : contacts) {
    const uint64_t key = c.Key();
    if (key < previous) at = 0;  // out of order: search from the start
    previous = key;
    // Entries before `at` have smaller keys. In key order the entry sought is almost always the
    // one at `at` (a repeated key) or the next (or there is none and that one is larger): one
    // or two compares. Otherwise gallop from there, then binary search the bracket. (Galloping
    // from `at` itself took 84 % of the pyramid's lookups into the search: `at` is last
    // contact's entry.)
    if (at < size && KeyOf(entries[at]) < key && ++at < size && KeyOf(entries[at]) < key) {
      size_t lo = at + 1, hi = at + 1, step = 1;
      while (hi < size && KeyOf(entries[hi]) < key) {
        lo = hi + 1;
        hi += step;
        step *= 2;
      }
      hi = std::min(hi, size);
      at = size_t(std::partition_point(entries + lo, entries + hi, [&](const Source& x) { return KeyOf(x) < key; }) -
                  entries);
    }
    if (at == size || KeyOf(entries[at]) != key) continue;
    if constexpr (kRepeated) {
      // Each point takes the first point of the key's entries with its feature id (a compound
      // contact's ids name its pair of shapes; `at` stays on the key's first entry for the next
      // contact of the same key).
      for (int k = 0; k < c.manifold.pointCount; ++k) {
        ManifoldPoint& p = c.manifold.points[k];
        bool found = false;
        for (size_t x = at; x < size && KeyOf(entries[x]) == key && !found; ++x) {
          for (int j = 0; j < PointsOf(entries[x]); ++j) {
            if (IdOf(entries[x], j) == p.id) {
              p.normalImpulse = NormalOf(entries[x], j);
              p.tangentImpulse = TangentOf(entries[x], j);
              ++matched;
              found = true;
              break;
            }
          }
        }
      }
      continue;
    }
    const Source& e = entries[at];
    const int stored = PointsOf(e);
    ManifoldPoint* points = c.manifold.points;
    const int count = c.manifold.pointCount;
    // Mostly the same two features in the same places: both copied at once. (The first
    // matching entry point is taken for each point, as the loop below does: the second point
    // takes entry point 1 only if entry point 0 does not match it.)
    if (count == 2 && stored == 2 && IdOf(e, 0) == points[0].id && IdOf(e, 1) == points[1].id &&
        IdOf(e, 0) != points[1].id) {
      points[0].normalImpulse = NormalOf(e, 0);
      points[0].tangentImpulse = TangentOf(e, 0);
      points[1].normalImpulse = NormalOf(e, 1);
      points[1].tangentImpulse = TangentOf(e, 1);
      matched += 2;
      continue;
    }
    for (int k = 0; k < count; ++k) {
      ManifoldPoint& p = points[k];
      for (int j = 0; j < stored; ++j) {
        if (IdOf(e, j) == p.id) {
          p.normalImpulse = NormalOf(e, j);
          p.tangentImpulse = TangentOf(e, j);
          ++matched;
          break;
        }
      }
    }
  }
  cursor.at = at;
  cursor.previous = previous;
  return matched;
}

}  // namespace quadrant
