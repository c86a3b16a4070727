// Broad phase selection.
#include "collision/broad_phase.h"

#include <algorithm>

namespace quadrant {

void MergePairs(const WorkerLists<CandidatePair>& perWorker, std::vector<CandidatePair>& out) {
  out.clear();
  for (int w = 0; w < perWorker.Count(); ++w) out.insert(out.end(), perWorker[w].begin(), perWorker[w].end());
}

void BroadPhase::UpdateAndFindPairs(std::span<const AABB> aabbs, std::span<const uint8_t> movable,
                                    std::vector<CandidatePair>& out, StageRunner& run, BoxUpdate update) {
  const int n = static_cast<int>(aabbs.size());
  run.For(Stage::kBroadPhase, n, run.MinItems(), [&](int begin, int end, int) { update(begin, end); });
  FindPairs(aabbs, movable, out, run);
}

bool SegmentTouchesBox(Vec2 p1, Vec2 p2, const AABB& box) {
  double t0 = 0, t1 = 1;
  const double p[2] = {p1.x, p1.y}, d[2] = {double(p2.x) - p1.x, double(p2.y) - p1.y};
  const double lo[2] = {box.lower.x, box.lower.y}, hi[2] = {box.upper.x, box.upper.y};
  for (int k = 0; k < 2; ++k) {
    if (d[k] == 0) {
      if (p[k] < lo[k] || p[k] > hi[k]) return false;
      continue;
    }
    double a = (lo[k] - p[k]) / d[k], b = (hi[k] - p[k]) / d[k];
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
    if (t0 > t1) return false;
  }
  return true;
}

std::unique_ptr<BroadPhase> MakeBroadPhase(BroadPhaseType type, int quadTreeMaxDepth) {
  switch (type) {
    case BroadPhaseType::kQuadTree: return MakeQuadTree(quadTreeMaxDepth);
    case BroadPhaseType::kUniformGrid: return MakeUniformGrid();
  }
  return MakeUniformGrid();
}

}  // namespace quadrant
