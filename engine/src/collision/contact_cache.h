// Contact persistence: last step's manifold points, found by body pair and feature id, so the
// solver can start from the impulses that held the bodies last step (warm starting).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "parallel/stage_runner.h"
#include "world/world_internal.h"

namespace quadrant {

class ContactCache {
 public:
  /// Copies last step's impulses into the points of `contacts` whose pair and feature id match.
  /// Returns the number of points matched. Fastest when `contacts` are in key order.
  int Restore(std::span<Contact> contacts) const;
  /// Where a walk of Restore calls over contacts in key order has got to: consecutive chunks of
  /// one sorted list restored with the same cursor walk the store once, as one call would.
  struct Cursor {
    size_t at = 0;
    uint64_t previous = 0;
  };
  /// Restore, continuing from `cursor` (same result as Restore for any cursor state).
  int Restore(std::span<Contact> contacts, Cursor& cursor) const;
  /// Remembers the impulses of `contacts` for the next step (replacing what was stored), on
  /// the calling thread.
  void Store(std::span<const Contact> contacts);
  /// The same, in parallel over `run`'s workers (timed as kPersistence).
  void Store(std::span<const Contact> contacts, StageRunner& run);
  /// Remembers the impulses of `contacts` for the next Restore by taking the vector itself
  /// (swapping it with the cache's previous one, so `contacts` is left with stale contacts to
  /// overwrite), if the caller has checked that their keys strictly increase (ContactSorter::
  /// StrictlyIncreasing); otherwise stores them (Store) and leaves `contacts` as it was.
  void Keep(std::vector<Contact>& contacts, bool strictlyIncreasing);
  void Clear();
  /// Last step's contacts as Keep took them (strictly increasing keys), or null when they were
  /// stored as entries instead (or cleared).
  const std::vector<Contact>* Kept() const { return kept_ ? &last_ : nullptr; }

  struct Entry {
    uint64_t key;
    int pointCount;
    uint32_t ids[2];
    Real normalImpulse[2];
    Real tangentImpulse[2];
  };

 private:
  template <class Source, bool kRepeated>
  static int RestoreFrom(const Source* entries, size_t size, std::span<Contact> contacts, Cursor& cursor);
  static Entry MakeEntry(const Contact& c);
  bool StoreEach(std::span<const Contact> contacts, int begin, int end);
  void StoreFiltered(std::span<const Contact> contacts);
  void Finish();

  // Sorted by key: one entry per contact for contacts in strictly increasing key order (an
  // entry of no points for one that carries nothing), else only the carrying ones, stably
  // sorted, so among equal keys the first stored is found, as before.
  std::vector<Entry> entries_;
  std::vector<char> increasing_;  // per block of the parallel store
  // Or (kept_) last step's contacts themselves, in strictly increasing key order (Keep).
  std::vector<Contact> last_;
  bool kept_ = false;
  // entries_ holds keys more than once (a compound body's several contacts with one body): Restore
  // then searches all entries of a key for a point's feature id, not only the first.
  bool repeated_ = false;
};

}  // namespace quadrant
