// Broad phase selection.
#include "broad_phase.h"

namespace quadrant {

std::unique_ptr<BroadPhase> MakeBroadPhase(BroadPhaseType type, int quadTreeMaxDepth) {
  switch (type) {
    case BroadPhaseType::kQuadTree: return MakeQuadTree(quadTreeMaxDepth);
    case BroadPhaseType::kUniformGrid: return MakeUniformGrid();
  }
  return MakeUniformGrid();
}

}  // namespace quadrant
