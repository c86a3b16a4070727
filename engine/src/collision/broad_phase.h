// Broad phase: the pairs of bodies whose AABBs overlap.
//
// The interface is rebuild-per-step: the suite's stress scenes move every body every step,
// so incremental structures buy nothing there. Implementations keep their buffers between
// steps, so a warm world does no heap allocation here.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "quadrant/math.h"
#include "quadrant/types.h"
#include "parallel/stage_runner.h"
#include "parallel/worker_lists.h"

namespace quadrant {

/// Two bodies (dense indices into the world's arrays), a < b.
struct CandidatePair {
  int32_t a;
  int32_t b;
};

class BroadPhase {
 public:
  virtual ~BroadPhase() = default;
  /// Writes every pair (a < b) whose AABBs overlap (touching counts) and of which at least
  /// one body has movable[i] != 0, each pair exactly once, into `out` (cleared first). The
  /// order is deterministic for a given input and the same for any thread count of `run`
  /// (parallel sections write per-worker buffers that are concatenated in worker order).
  virtual void FindPairs(std::span<const AABB> aabbs, std::span<const uint8_t> movable,
                         std::vector<CandidatePair>& out, StageRunner& run) = 0;
  /// The caller's update of the boxes, by reference: update(begin, end) brings aabbs[begin, end)
  /// up to date (no other element).
  struct BoxUpdate {
    void (*fn)(const void* ctx, int begin, int end) = nullptr;
    const void* ctx = nullptr;
    void operator()(int begin, int end) const { fn(ctx, begin, end); }
  };
  /// FindPairs after update(begin, end) over every index (each once, before the broad phase
  /// reads those boxes). This default runs the update as a parallel-for of its own; the grid
  /// does it in its first stage, which saves the step a hand-over to the workers and a join.
  virtual void UpdateAndFindPairs(std::span<const AABB> aabbs, std::span<const uint8_t> movable,
                                  std::vector<CandidatePair>& out, StageRunner& run, BoxUpdate update);
  virtual const char* Name() const = 0;

  // Queries (World::QueryAABB, RayCastClosest, RayCastAll). A separate instance of the same
  // structure serves them: the step's instance is built from swept, fattened boxes of the
  // moving bodies only (the grid leaves out statics far from them), so the world builds this
  // one from every body's current box when a query comes after a change (world.cpp).

  /// Builds the structure over every box of `aabbs`, none left out.
  virtual void BuildForQueries(std::span<const AABB> aabbs, StageRunner& run) = 0;
  /// Appends to `out` every body whose box overlaps `box` (touching counts), each once, in no
  /// particular order. Needs BuildForQueries with the same `aabbs` first.
  virtual void QueryBox(const AABB& box, std::span<const AABB> aabbs, std::vector<int>& out) const = 0;
  /// Appends to `out` every body whose box the segment from p1 to p2 touches, each once (it may
  /// append a few more; the caller tests shapes exactly), in no particular order.
  virtual void QuerySegment(Vec2 p1, Vec2 p2, std::span<const AABB> aabbs, std::vector<int>& out) const = 0;
};

/// Whether the segment p1-p2 touches `box` (slab test, done in double so a segment grazing
/// an edge is not lost to float rounding).
bool SegmentTouchesBox(Vec2 p1, Vec2 p2, const AABB& box);

/// Concatenates per-worker pair buffers in worker order.
void MergePairs(const WorkerLists<CandidatePair>& perWorker, std::vector<CandidatePair>& out);

std::unique_ptr<BroadPhase> MakeQuadTree(int maxDepth);
std::unique_ptr<BroadPhase> MakeUniformGrid();
std::unique_ptr<BroadPhase> MakeBroadPhase(BroadPhaseType type, int quadTreeMaxDepth);

}  // namespace quadrant
