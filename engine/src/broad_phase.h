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
#include "quadrant/world.h"
#include "stage_runner.h"

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
  virtual const char* Name() const = 0;
};

/// Concatenates per-worker pair buffers in worker order.
void MergePairs(std::vector<std::vector<CandidatePair>>& perWorker, std::vector<CandidatePair>& out);

std::unique_ptr<BroadPhase> MakeQuadTree(int maxDepth);
std::unique_ptr<BroadPhase> MakeUniformGrid();
std::unique_ptr<BroadPhase> MakeBroadPhase(BroadPhaseType type, int quadTreeMaxDepth);

}  // namespace quadrant
