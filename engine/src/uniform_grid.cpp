// A uniform grid broad phase, the alternative to the quad-tree behind the same interface.
//
// Rebuilt each step by a counting sort of bodies into every cell their AABB touches. A pair is
// reported only by the cell holding the lower corner of the two AABBs' intersection, so a pair
// sharing several cells is reported once without a hash set. The cell size follows the mean
// size of the movable bodies, and the grid covers only the region they occupy: static bodies
// outside it cannot touch them.
#include <algorithm>
#include <cmath>

#include "broad_phase.h"

namespace quadrant {
namespace {

class UniformGrid final : public BroadPhase {
 public:
  const char* Name() const override { return "uniform_grid"; }

  void FindPairs(std::span<const AABB> aabbs, std::span<const uint8_t> movable,
                 std::vector<CandidatePair>& out) override {
    out.clear();
    const int n = static_cast<int>(aabbs.size());
    if (n < 2 || !Layout(aabbs, movable)) return;

    cellStart_.assign(size_t(cols_) * rows_ + 1, 0);
    ranges_.resize(n);
    for (int i = 0; i < n; ++i) {
      Range r = RangeOf(aabbs[i]);
      ranges_[i] = r;
      if (r.x0 > r.x1 || r.y0 > r.y1) continue;  // entirely outside the movable region
      for (int y = r.y0; y <= r.y1; ++y) {
        for (int x = r.x0; x <= r.x1; ++x) ++cellStart_[size_t(y) * cols_ + x + 1];
      }
    }
    for (size_t c = 0; c + 1 < cellStart_.size(); ++c) cellStart_[c + 1] += cellStart_[c];
    fill_.assign(cellStart_.begin(), cellStart_.end() - 1);
    items_.resize(cellStart_.back());
    for (int i = 0; i < n; ++i) {
      const Range r = ranges_[i];
      for (int y = r.y0; y <= r.y1; ++y) {
        for (int x = r.x0; x <= r.x1; ++x) items_[fill_[size_t(y) * cols_ + x]++] = i;
      }
    }

    for (int y = 0; y < rows_; ++y) {
      for (int x = 0; x < cols_; ++x) {
        const size_t cell = size_t(y) * cols_ + x;
        const int end = cellStart_[cell + 1];
        for (int k = cellStart_[cell]; k < end; ++k) {
          const int i = items_[k];
          const AABB& a = aabbs[i];
          for (int l = k + 1; l < end; ++l) {
            const int j = items_[l];
            if (!(movable[i] | movable[j])) continue;
            const AABB& b = aabbs[j];
            if (!Overlaps(a, b)) continue;
            // Report only from the cell of the intersection's lower corner.
            if (Clamp(CellX(std::max(a.lower.x, b.lower.x))) != x) continue;
            if (Clamp(CellY(std::max(a.lower.y, b.lower.y)), rows_) != y) continue;
            out.push_back(i < j ? CandidatePair{i, j} : CandidatePair{j, i});
          }
        }
      }
    }
  }

 private:
  struct Range {
    int x0, y0, x1, y1;
  };

  bool Layout(std::span<const AABB> aabbs, std::span<const uint8_t> movable) {
    bool any = false;
    AABB box{};
    double extent = 0;
    int count = 0;
    for (size_t i = 0; i < aabbs.size(); ++i) {
      if (!movable[i]) continue;
      box = any ? Union(box, aabbs[i]) : aabbs[i];
      any = true;
      extent += std::max(aabbs[i].upper.x - aabbs[i].lower.x, aabbs[i].upper.y - aabbs[i].lower.y);
      ++count;
    }
    if (!any) return false;
    // Cells about twice the mean body size: most bodies then touch one to four cells and a
    // cell holds a handful of bodies at the stress scenes' density.
    double cell = std::max(2.0 * extent / count, 1e-3);
    const double w = std::max<double>(box.upper.x - box.lower.x, 1e-6);
    const double h = std::max<double>(box.upper.y - box.lower.y, 1e-6);
    // Bound the cell count by a few per body, so a sparse scene does not allocate a huge grid.
    const double maxCells = 4.0 * count + 64.0;
    while ((std::floor(w / cell) + 1) * (std::floor(h / cell) + 1) > maxCells) cell *= 1.5;
    inv_ = 1.0 / cell;
    originX_ = box.lower.x;
    originY_ = box.lower.y;
    cols_ = int(std::floor(w * inv_)) + 1;
    rows_ = int(std::floor(h * inv_)) + 1;
    return true;
  }

  int CellX(double v) const { return int(std::floor((v - originX_) * inv_)); }
  int CellY(double v) const { return int(std::floor((v - originY_) * inv_)); }
  int Clamp(int c) const { return std::clamp(c, 0, cols_ - 1); }
  int Clamp(int c, int limit) const { return std::clamp(c, 0, limit - 1); }

  Range RangeOf(const AABB& b) const {
    int x0 = CellX(b.lower.x), x1 = CellX(b.upper.x);
    int y0 = CellY(b.lower.y), y1 = CellY(b.upper.y);
    if (x1 < 0 || y1 < 0 || x0 >= cols_ || y0 >= rows_) return {0, 0, -1, -1};
    return {Clamp(x0), Clamp(y0, rows_), Clamp(x1), Clamp(y1, rows_)};
  }

  double originX_ = 0, originY_ = 0, inv_ = 1;
  int cols_ = 0, rows_ = 0;
  std::vector<int> cellStart_, fill_, items_;
  std::vector<Range> ranges_;
};

}  // namespace

std::unique_ptr<BroadPhase> MakeUniformGrid() { return std::make_unique<UniformGrid>(); }

}  // namespace quadrant
