// Contact persistence by pair key and feature id.
#include "contact_cache.h"

#include <algorithm>

namespace quadrant {
namespace {

// Fibonacci hashing spreads the (a << 32 | b) keys, whose low bits are the body index b.
inline size_t Slot(uint64_t key, size_t mask) { return size_t((key * 0x9E3779B97F4A7C15ull) >> 20) & mask; }

}  // namespace

void ContactCache::Clear() { table_.clear(); }

void ContactCache::Store(std::span<const Contact> contacts) {
  // Only contacts that carry something to the next step are stored: in sparse scenes most
  // speculative contacts end the step with zero impulses.
  auto carries = [](const Contact& c) {
    for (int k = 0; k < c.manifold.pointCount; ++k) {
      const ManifoldPoint& p = c.manifold.points[k];
      if (p.normalImpulse != 0 || p.tangentImpulse != 0) return true;
    }
    return false;
  };
  size_t stored = 0;
  for (const Contact& c : contacts) stored += carries(c) ? 1 : 0;
  size_t capacity = 16;
  while (capacity < 2 * stored) capacity <<= 1;
  // Re-use the buffer: assign only re-allocates when the capacity grows.
  table_.assign(capacity, Entry{kEmpty, 0, {0, 0}, {0, 0}, {0, 0}});
  const size_t mask = capacity - 1;
  for (const Contact& c : contacts) {
    if (!carries(c)) continue;
    const Manifold& m = c.manifold;
    Entry e{c.Key(), m.pointCount, {0, 0}, {0, 0}, {0, 0}};
    for (int k = 0; k < m.pointCount; ++k) {
      e.ids[k] = m.points[k].id;
      e.normalImpulse[k] = m.points[k].normalImpulse;
      e.tangentImpulse[k] = m.points[k].tangentImpulse;
    }
    size_t s = Slot(e.key, mask);
    while (table_[s].key != kEmpty) s = (s + 1) & mask;
    table_[s] = e;
  }
}

const ContactCache::Entry* ContactCache::Find(uint64_t key) const {
  if (table_.empty()) return nullptr;
  const size_t mask = table_.size() - 1;
  for (size_t s = Slot(key, mask);; s = (s + 1) & mask) {
    if (table_[s].key == key) return &table_[s];
    if (table_[s].key == kEmpty) return nullptr;
  }
}

int ContactCache::Restore(std::span<Contact> contacts) const {
  int matched = 0;
  for (Contact& c : contacts) {
    const Entry* e = Find(c.Key());
    if (e == nullptr) continue;
    for (int k = 0; k < c.manifold.pointCount; ++k) {
      ManifoldPoint& p = c.manifold.points[k];
      for (int j = 0; j < e->pointCount; ++j) {
        if (e->ids[j] == p.id) {
          p.normalImpulse = e->normalImpulse[j];
          p.tangentImpulse = e->tangentImpulse[j];
          ++matched;
          break;
        }
      }
    }
  }
  return matched;
}

}  // namespace quadrant
