// Broad phase selection.
#include "broad_phase.h"

namespace quadrant {

void MergePairs(std::vector<std::vector<CandidatePair>>& perWorker, std::vector<CandidatePair>& out) {
  out.clear();
  for (const auto& part : perWorker) out.insert(out.end(), part.begin(), part.end());
}

std::unique_ptr<BroadPhase> MakeBroadPhase(BroadPhaseType type, int quadTreeMaxDepth) {
  switch (type) {
    case BroadPhaseType::kQuadTree: return MakeQuadTree(quadTreeMaxDepth);
    case BroadPhaseType::kUniformGrid: return MakeUniformGrid();
  }
  return MakeUniformGrid();
}

}  // namespace quadrant
