// Pair cache: the broad phase's pairs of a resting scene reused from step to step.
//
// The broad phase (uniform grid, quad tree) rebuilds its structure from every box each step; on
// the base-100 pyramid that is about a tenth of a one-thread step (perf: the grid's scan 6.8 %,
// the box update 2.5 %), for pairs that do not change while the pile rests. The cache keeps a
// fat box for every body (its box grown by kMargin on every side) and every pair whose fat boxes
// overlap (found by the broad phase itself, over the fat boxes). While every body's box stays
// inside its fat box, every pair whose boxes overlap is among those pairs, so a filter of them
// with the boxes gives exactly the broad phase's pairs: the same set (the pairs' order differs,
// and nothing after the broad phase depends on it: the contacts are sorted by their bodies).
// When a box leaves its fat box, or a body's movable flag or the body count changes, the fat
// boxes and pairs are rebuilt. Box2D does the same with its fat tree proxies (b2_aabbMargin);
// here the reuse is all or nothing, which keeps it a wrapper around any broad phase.
//
// Measured (issue #13): base-100 pyramid, one thread, 5 interleaved rounds of 60 steps against
// a524d1a (load 2.8 from a helper's builds): the broad phase 0.256 -> 0.154 ms a step; at two
// threads 0.149 -> 0.105 ms. With a margin of 0.1 m a body of the settling pyramid leaves its fat
// box about once in 7 steps over the first 300 (one rebuild each time). Instructions
// (tools/quadrant icount): pyramid_20_60 50.85M -> 47.99M, circle_stress_1000_60 37.66M -> 37.43M,
// polygon_stress_1000_60 69.77M -> 69.55M; the same state hashes.
//
// Scenes in motion (the stress scenes) would rebuild every step and pay for the fat boxes' extra
// pairs; after a rebuild that served fewer than kMinReuse steps the cache stands aside for 2, 4,
// ... up to 64 steps (the plain broad phase runs), and for 64 at once when more than one body in
// a hundred left its fat box, so such scenes pay for one try in 64 steps.
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
