// pair_cache.h says what the cache does and why.
#include "collision/pair_cache.h"

#include <algorithm>

namespace quadrant {

bool PairCache::UpdateAndFindPairs(BroadPhase& broadPhase, std::span<const AABB> aabbs,
                                   std::span<const uint8_t> movable, std::vector<CandidatePair>& out,
                                   StageRunner& run, BroadPhase::BoxUpdate update) {
  const int n = static_cast<int>(aabbs.size());
  if (standAside_ > 0) {
    --standAside_;
    valid_ = false;
    broadPhase.UpdateAndFindPairs(aabbs, movable, out, run, update);
    return false;
  }
  // The boxes brought up to date and checked against the fat boxes in one pass.
  const bool check = valid_ && static_cast<int>(fat_.size()) == n;
  escaped_.assign(static_cast<size_t>(std::max(1, run.Workers())), 0);
  run.For(Stage::kBroadPhase, n, run.MinItems(), [&](int begin, int end, int block) {
    update(begin, end);
    if (!check) return;
    int out = 0;
    for (int i = begin; i < end; ++i) {
      out += !Contains(fat_[i], aabbs[i]) || movable[i] != movable_[i];
    }
    escaped_[block] = out;
  });
  int64_t escaped = 0;
  for (int e : escaped_) escaped += e;
  const bool reuse = check && escaped == 0;
  if (reuse) {
    ++servedSinceRebuild_;
    ++reused_;
    Filter(aabbs, movable, out, run);
    return true;
  }
  if (valid_) {
    // The last rebuild served too few steps: the scene moves too much for fat boxes to pay.
    if (servedSinceRebuild_ < kMinReuse) {
      // More than one body in a hundred out at once: a scene in motion, not a pile settling.
      backoff_ = escaped * 100 > n ? kMaxBackoff : std::min(backoff_ + 1, kMaxBackoff);
      standAside_ = (1 << backoff_) - 1;  // this step rebuilds; then the plain broad phase
      valid_ = false;
      broadPhase.FindPairs(aabbs, movable, out, run);
      return false;
    }
    backoff_ = 0;
  }
  Rebuild(broadPhase, aabbs, movable, run);
  Filter(aabbs, movable, out, run);
  return false;
}

void PairCache::Rebuild(BroadPhase& broadPhase, std::span<const AABB> aabbs, std::span<const uint8_t> movable,
                        StageRunner& run) {
  const int n = static_cast<int>(aabbs.size());
  fat_.resize(static_cast<size_t>(n));
  const Vec2 grow{kMargin, kMargin};
  run.For(Stage::kBroadPhase, n, run.MinItems(), [&](int begin, int end, int) {
    for (int i = begin; i < end; ++i) fat_[i] = {aabbs[i].lower - grow, aabbs[i].upper + grow};
  });
  movable_.assign(movable.begin(), movable.end());
  broadPhase.FindPairs(fat_, movable_, fatPairs_, run);
  valid_ = true;
  servedSinceRebuild_ = 0;
  ++rebuilt_;
}

// The fat pairs whose boxes overlap (touching counts, as the broad phases' test), in the fat
// pairs' order: blocks are consecutive ranges, concatenated in block order.
void PairCache::Filter(std::span<const AABB> aabbs, std::span<const uint8_t> movable,
                       std::vector<CandidatePair>& out, StageRunner& run) {
  const int count = static_cast<int>(fatPairs_.size());
  lists_.Reset(std::max(1, run.Workers()));
  run.For(Stage::kBroadPhase, count, run.MinItems(), [&](int begin, int end, int block) {
    std::vector<CandidatePair>& list = lists_[block];
    for (int k = begin; k < end; ++k) {
      const CandidatePair p = fatPairs_[k];
      if ((movable[p.a] | movable[p.b]) && Overlaps(aabbs[p.a], aabbs[p.b])) list.push_back(p);
    }
  });
  MergePairs(lists_, out);
}

}  // namespace quadrant
