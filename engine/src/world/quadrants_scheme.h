// The thesis's data-partitioned step (its section 4.5.4), generalised to T threads.
//
// The region around all bodies is split into the 4^L cells of quad-tree level L (L = 1 for up
// to 4 threads: the root's four children, as in the thesis), dealt to the threads in Morton
// order. A body whose box fits in one cell belongs to that cell's thread; a body that straddles
// a cell boundary lives at the root and belongs to the master. Each thread is a small world:
// it finds the pairs of its bodies (and of master bodies reaching into its region), builds
// their contacts, and solves and integrates on a private copy of the bodies it touches. A
// contact with a foreign body is solved against a private "ghost" of that body whose changes
// are thrown away, and only the thread's own bodies are written back: each side of a boundary
// contact is resolved once, by its owner, from the same pre-solve state, with no locks. The
// master does the same for the root bodies after the threads. Bodies that cross into another
// cell change owner at the next step.
#pragma once

#include <memory>
#include <vector>

#include "collision/broad_phase.h"
#include "collision/contact_cache.h"
#include "dynamics/solver.h"
#include "world/world_internal.h"

namespace quadrant {

class QuadrantsScheme {
 public:
  QuadrantsScheme(const WorldDef& def, int threads);
  ~QuadrantsScheme();

  /// One (sub-)step of broad phase, narrow phase, persistence and solve. AABBs must be up to
  /// date. `contacts` receives every partition's contacts (boundary contacts appear twice, once
  /// per side) for read-back and counters; `pairs` the number of candidate pairs.
  void Step(Real dt, const WorldDef& def, Bodies& bodies, StageRunner& run, ContactCache& cache,
            std::vector<Contact>& contacts, int& pairs, Profile& profile);

  /// Owner of each body in the last step: thread index, or -1 for the master.
  const std::vector<int>& Owners() const { return owner_; }
  /// The partitioned region and its level (cells per side = 2^level).
  AABB Region() const { return region_; }
  int Level() const { return level_; }

 private:
  struct Partition;
  void AssignOwners(const Bodies& bodies);
  void Detect(Partition& part, const Bodies& bodies, const WorldDef& def, Real dt, bool master);
  void BuildLocal(Partition& part, const Bodies& bodies, ContactCache& cache, bool warm);
  void Solve(Partition& part, const WorldDef& def, Real dt);
  void WriteBack(Partition& part, Bodies& bodies) const;

  int threads_;
  int level_ = 1;
  AABB region_{};
  std::vector<int> owner_;
  std::vector<std::unique_ptr<Partition>> parts_;  // threads, then the master
};

}  // namespace quadrant
