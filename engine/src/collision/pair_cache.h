// Pair cache: the broad phase's pairs of a resting scene reused from step to step.
//
// The broad phase rebuilds its structure from every box each step, for pairs that do not change
// while a pile rests (base-100 pyramid, one thread: the grid's scan 6.8 % of the step, the box
// update 2.5 %, perf). The cache keeps a fat box for every body (its box grown by kMargin on
// every side) and every pair whose fat boxes overlap (found by the broad phase itself, over the
// fat boxes). While every box stays inside its fat box, filtering those pairs by the boxes gives
// exactly the broad phase's pair set (in another order, on which nothing after the broad phase
// depends: contacts are sorted by their bodies). When a box leaves its fat box, or a body's
// movable flag or the body count changes, fat boxes and pairs are rebuilt. Box2D does the same
// with its fat tree proxies (b2_aabbMargin); here the reuse is all or nothing, which keeps it a
// wrapper around any broad phase. Same state hashes with and without it.
//
// Base-100 pyramid on the 2-core VM: the broad phase 0.256 -> 0.154 ms a step at 1 thread,
// 0.149 -> 0.105 ms at 2; at kMargin 0.1 m a settling body leaves its fat box about once in 7
// steps. Scenes in motion would rebuild every step: after a rebuild that served fewer than
// kMinReuse steps the cache stands aside for 2, 4, ... up to 64 steps (the plain broad phase
// runs), and for 64 at once when more than one body in a hundred left its fat box.
// docs/notes/pair_cache.md has the instruction counts.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "collision/broad_phase.h"
#include "parallel/stage_runner.h"
#include "parallel/worker_lists.h"

namespace quadrant {

class PairCache {
 public:
  /// The broad phase's UpdateAndFindPairs, served from the cache where it can be: `out` gets the
  /// same set of pairs as `broadPhase.UpdateAndFindPairs(aabbs, movable, out, run, update)`.
  /// True when the kept pairs served (no broad phase ran).
  bool UpdateAndFindPairs(BroadPhase& broadPhase, std::span<const AABB> aabbs, std::span<const uint8_t> movable,
                          std::vector<CandidatePair>& out, StageRunner& run, BroadPhase::BoxUpdate update);
  /// Forget the fat boxes (the next call rebuilds or stands aside).
  void Invalidate() { valid_ = false; }
  /// Steps served from the cache since the world began (for tests and the profile).
  int64_t Reused() const { return reused_; }
  int64_t Rebuilt() const { return rebuilt_; }

  /// How far a fat box reaches past the body's box (m), as Box2D's b2_aabbMargin.
  static constexpr Real kMargin = Real(0.1);

 private:
  void Rebuild(BroadPhase& broadPhase, std::span<const AABB> aabbs, std::span<const uint8_t> movable,
               StageRunner& run);
  void Filter(std::span<const AABB> aabbs, std::span<const uint8_t> movable, std::vector<CandidatePair>& out,
              StageRunner& run);

  static constexpr int kMinReuse = 2;
  static constexpr int kMaxBackoff = 6;  // stand aside at most 2^6 = 64 steps
  std::vector<AABB> fat_;
  std::vector<uint8_t> movable_;  // the flags the fat pairs were found with
  std::vector<CandidatePair> fatPairs_;
  WorkerLists<CandidatePair> lists_;
  std::vector<int> escaped_;  // per block of the check: bodies out of their fat boxes
  bool valid_ = false;
  int servedSinceRebuild_ = 0;
  int backoff_ = 0;
  int standAside_ = 0;  // plain steps left before the next try
  int64_t reused_ = 0, rebuilt_ = 0;
};

}  // namespace quadrant
