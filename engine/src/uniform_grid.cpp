// A uniform grid broad phase, the alternative to the quad-tree behind the same interface.
//
// Rebuilt each step. Each ordinary body is put in exactly one cell, the one holding the lower
// corner of its AABB, and cells are at least as large as any ordinary body. Two overlapping
// AABBs then have lower corners less than one cell apart on each axis, so a body only needs the
// bodies of its own cell and of the 3x3 block around it; scanning half of that block (own cell,
// right, and the three cells above) reports every pair exactly once, with no duplicate check.
//
// Oversized bodies (longer than a few mean body sizes: walls, ground, a huge obstacle) would
// force huge cells, so they are kept out of the grid and instead query the cells their AABB
// covers, and are tested against each other directly.
#include <algorithm>
#include <cmath>

#include "broad_phase.h"

namespace quadrant {
namespace {

class UniformGrid final : public BroadPhase {
 public:
  const char* Name() const override { return "uniform_grid"; }

  void FindPairs(std::span<const AABB> aabbs, std::span<const uint8_t> movable,
                 std::vector<CandidatePair>& out, StageRunner& run) override {
    out.clear();
    if (aabbs.size() < 2) return;
    if (!Layout(aabbs, movable, run)) return;
    Bucket(aabbs, run);
    perWorker_.resize(run.Workers());
    for (auto& part : perWorker_) part.clear();
    run.For(Stage::kBroadPhase, static_cast<int>(sortedIndex_.size()), run.MinItems(),
            [&](int begin, int end, int worker) { ScanCells(begin, end, movable, perWorker_[worker]); });
    MergePairs(perWorker_, out);
    // The oversized bodies (a stress scene's four walls, each along a few hundred cells) are
    // split across the threads too when the grid is large; blocks of them in order, appended
    // in order, give the serial result.
    for (auto& part : perWorker_) part.clear();
    const int large = static_cast<int>(large_.size());
    run.For(Stage::kBroadPhase, large, aabbs.size() >= size_t(run.MinItems()) ? 2 : large + 1,
            [&](int begin, int end, int worker) { ScanLarge(begin, end, aabbs, movable, perWorker_[worker]); });
    for (const auto& part : perWorker_) out.insert(out.end(), part.begin(), part.end());
  }

  void BuildForQueries(std::span<const AABB> aabbs, StageRunner& run) override {
    // Every body counts as movable, so the region holds them all and no static is left out.
    all_.assign(aabbs.size(), 1);
    queryReady_ = !aabbs.empty() && Layout(aabbs, all_, run);
    if (queryReady_) Bucket(aabbs, run);
  }

  void QueryBox(const AABB& box, std::span<const AABB> aabbs, std::vector<int>& out) const override {
    if (!queryReady_) return;
    for (int i : large_) {
      if (Overlaps(aabbs[i], box)) out.push_back(i);
    }
    if (!Overlaps(box, region_)) return;
    // A body is filed by its lower corner, at most one cell below or left of any point it covers.
    const double cell = 1.0 / inv_;
    const int x0 = QueryCellX(box.lower.x - cell), x1 = QueryCellX(box.upper.x);
    const int y0 = QueryCellY(box.lower.y - cell), y1 = QueryCellY(box.upper.y);
    for (int y = y0; y <= y1; ++y) ScanRowFor(y * cols_ + x0, y * cols_ + x1, box, out);
  }

  // Row by row: in row y lie the bodies whose lower corner is in that row, so they reach at most
  // into row y + 1; the part of the segment inside that band of two rows gives the row's cells
  // (again one more to the left). Each cell is read once, so each body is reported once, and a
  // long diagonal ray reads about two cells per row instead of its whole bounding box.
  void QuerySegment(Vec2 p1, Vec2 p2, std::span<const AABB> aabbs, std::vector<int>& out) const override {
    if (!queryReady_) return;
    for (int i : large_) {
      if (SegmentTouchesBox(p1, p2, aabbs[i])) out.push_back(i);
    }
    const AABB bounds{Min(p1, p2), Max(p1, p2)};
    if (!Overlaps(bounds, region_)) return;
    const double cell = 1.0 / inv_;
    const double dx = double(p2.x) - p1.x, dy = double(p2.y) - p1.y;
    const double slack = 1e-6 * cell;  // rows are only chosen here; exact tests come later
    const int y0 = QueryCellY(bounds.lower.y - cell), y1 = QueryCellY(bounds.upper.y);
    for (int y = y0; y <= y1; ++y) {
      const double lo = originY_ + y * cell - slack, hi = originY_ + (y + 2) * cell + slack;
      double t0 = 0, t1 = 1;
      if (dy == 0) {
        if (p1.y < lo || p1.y > hi) continue;
      } else {
        double a = (lo - p1.y) / dy, b = (hi - p1.y) / dy;
        if (a > b) std::swap(a, b);
        t0 = std::max(t0, a);
        t1 = std::min(t1, b);
        if (t0 > t1) continue;
      }
      const double xa = p1.x + t0 * dx, xb = p1.x + t1 * dx;
      const int x0 = QueryCellX(std::min(xa, xb) - cell - slack), x1 = QueryCellX(std::max(xa, xb) + slack);
      for (int l = cellStart_[y * cols_ + x0]; l < cellStart_[y * cols_ + x1 + 1]; ++l) {
        if (SegmentTouchesBox(p1, p2, sortedBox_[l])) out.push_back(sortedIndex_[l]);
      }
    }
  }

 private:
  // A query's coordinates can lie anywhere (a box of 1e30 m): clamped to the region before the
  // conversion to int, which would overflow.
  int QueryCellX(double v) const { return CellX(std::clamp(v, double(region_.lower.x), double(region_.upper.x))); }
  int QueryCellY(double v) const { return CellY(std::clamp(v, double(region_.lower.y), double(region_.upper.y))); }

  void ScanRowFor(int first, int last, const AABB& box, std::vector<int>& out) const {
    for (int l = cellStart_[first]; l < cellStart_[last + 1]; ++l) {
      if (Overlaps(box, sortedBox_[l])) out.push_back(sortedIndex_[l]);
    }
  }

  static double Extent(const AABB& b) { return std::max(b.upper.x - b.lower.x, b.upper.y - b.lower.y); }

  // Per-chunk partial results of the layout pass. Chunks have a fixed size, so combining them
  // in chunk order gives the same bits for any thread count.
  struct Partial {
    AABB box{};
    double extentSum = 0;
    int moving = 0;
  };
  static constexpr int kChunk = 1024;

  // Chooses the grid: the region of the movable bodies (grown by one cell), the threshold
  // between ordinary and oversized bodies, and the cell size.
  bool Layout(std::span<const AABB> aabbs, std::span<const uint8_t> movable, StageRunner& run) {
    const int n = static_cast<int>(aabbs.size());
    extent_.resize(n);
    const int chunks = (n + kChunk - 1) / kChunk;
    // In parallel only from MinItems bodies, as every other per-body pass.
    const int minChunks = n >= run.MinItems() ? 2 : chunks + 1;
    partial_.assign(chunks, Partial{});
    run.For(Stage::kBroadPhase, chunks, minChunks, [&](int c0, int c1, int) {
      for (int c = c0; c < c1; ++c) {
        Partial& p = partial_[c];
        for (int i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) {
          extent_[i] = Real(Extent(aabbs[i]));
          if (!movable[i]) continue;
          p.box = p.moving == 0 ? aabbs[i] : Union(p.box, aabbs[i]);
          p.extentSum += extent_[i];
          ++p.moving;
        }
      }
    });
    double meanExtent = 0;
    int moving = 0;
    AABB box{};
    for (const Partial& p : partial_) {
      if (p.moving == 0) continue;
      box = moving == 0 ? p.box : Union(box, p.box);
      meanExtent += p.extentSum;
      moving += p.moving;
    }
    if (moving == 0) return false;
    // A non-finite box would make the cell arithmetic meaningless; the world's input checks
    // keep states finite, so this only guards against misuse of the broad phase on its own.
    if (!IsFinite(box.lower) || !IsFinite(box.upper) || !std::isfinite(meanExtent)) return false;
    meanExtent /= moving;
    largeThreshold_ = 4.0 * meanExtent;
    // The cell must hold the largest ordinary body that can meet a movable one (max is exact
    // in any order, so per-chunk maxima combine deterministically).
    cellMax_.assign(chunks, 1e-3);
    run.For(Stage::kBroadPhase, chunks, minChunks, [&](int c0, int c1, int) {
      for (int c = c0; c < c1; ++c) {
        double cell = 1e-3;
        for (int i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) {
          const double e = extent_[i];
          if (e <= largeThreshold_ && (movable[i] || Overlaps(aabbs[i], box))) cell = std::max(cell, e);
        }
        cellMax_[c] = cell;
      }
    });
    double cell = 1e-3;
    for (double c : cellMax_) cell = std::max(cell, c);
    const double w = std::max<double>(box.upper.x - box.lower.x, 1e-6);
    const double h = std::max<double>(box.upper.y - box.lower.y, 1e-6);
    // A few cells per body at most, so a sparse scene does not allocate a huge grid.
    const double maxCells = 4.0 * double(n) + 64.0;
    while ((w / cell + 3) * (h / cell + 3) > maxCells) cell *= 1.5;
    inv_ = 1.0 / cell;
    originX_ = box.lower.x - cell;
    originY_ = box.lower.y - cell;
    cols_ = int(w * inv_) + 3;
    rows_ = int(h * inv_) + 3;
    region_ = {{Real(originX_), Real(originY_)}, {Real(originX_ + cols_ * cell), Real(originY_ + rows_ * cell)}};
    return true;
  }

  // Truncation instead of floor: it differs only below the origin, where the clamp to 0 makes
  // both agree.
  int CellX(double v) const { return std::clamp(int((v - originX_) * inv_), 0, cols_ - 1); }
  int CellY(double v) const { return std::clamp(int((v - originY_) * inv_), 0, rows_ - 1); }

  // Counting sort of ordinary bodies by cell, in parallel by ranges of cells: each worker owns
  // a contiguous range of cells, reads every body's cell and counts, places and copies only the
  // bodies of its own range, walking the bodies in index order. Within a cell, bodies are in
  // index order whatever the ranges, so the sorted arrays are the same for any thread count.
  // AABBs are copied in cell order so the pair scan reads memory sequentially.
  //
  // Why ranges of cells rather than blocks of bodies with per-worker counts: the grid has about
  // 2.6 cells per body (16000 circles: 41000 cells), so per-worker count arrays meant zeroing and
  // twice reading workers x cells counters per step, which grew with the thread count and moved
  // between the cores' caches; reading the bodies' cell numbers (4 bytes each) once per range is
  // cheaper (circle stress, N = 16000, 2 threads: the bucket passes went from about 19 % to
  // about 12 % of perf's samples of the step).
  // Inlined by force: with two callers (FindPairs, BuildForQueries) GCC 12 stopped inlining it
  // into FindPairs, which cost 0.16 % more instructions on circle stress (icount, 1000 bodies).
  [[gnu::always_inline]] inline void Bucket(std::span<const AABB> aabbs, StageRunner& run) {
    const int n = static_cast<int>(aabbs.size());
    const int cells = cols_ * rows_;
    cellOf_.resize(n);
    largePart_.resize(run.Workers());
    for (std::vector<int>& part : largePart_) part.clear();  // a worker may get no block
    run.For(Stage::kBroadPhase, n, run.MinItems(), [&](int begin, int end, int worker) {
      std::vector<int>& large = largePart_[worker];
      for (int i = begin; i < end; ++i) {
        const AABB& b = aabbs[i];
        if (extent_[i] > largeThreshold_) {
          cellOf_[i] = -1;  // oversized: queried separately
          large.push_back(i);
        } else if (!Overlaps(b, region_)) {
          cellOf_[i] = -2;  // cannot touch any movable body
        } else {
          cellOf_[i] = CellY(b.lower.y) * cols_ + CellX(b.lower.x);
        }
      }
    });
    // One range of cells per worker when the bodies are many enough to split; one otherwise.
    const int ranges = n >= run.MinItems() ? run.Workers() : 1;
    cellCount_.resize(size_t(cells) + 1);
    rangeTotal_.assign(ranges + 1, 0);
    run.For(Stage::kBroadPhase, ranges, 1, [&](int r0, int r1, int) {
      for (int r = r0; r < r1; ++r) {
        const int c0 = BlockBegin(cells, ranges, r), c1 = BlockBegin(cells, ranges, r + 1);
        std::fill(cellCount_.begin() + c0, cellCount_.begin() + c1, 0);
        for (int i = 0; i < n; ++i) {
          const int c = cellOf_[i];
          if (c >= c0 && c < c1) ++cellCount_[c];
        }
        int total = 0;  // the count becomes the cell's first slot, relative to the range
        for (int c = c0; c < c1; ++c) {
          const int k = cellCount_[c];
          cellCount_[c] = total;
          total += k;
        }
        rangeTotal_[r + 1] = total;
      }
    });
    run.Serial(Stage::kBroadPhase, [&] {
      large_.clear();  // blocks are in index order, so the oversized bodies are too
      for (const std::vector<int>& part : largePart_) large_.insert(large_.end(), part.begin(), part.end());
      for (int r = 0; r < ranges; ++r) rangeTotal_[r + 1] += rangeTotal_[r];
      const int placed = rangeTotal_[ranges];
      cellStart_.resize(size_t(cells) + 1);
      cellStart_[cells] = placed;
      sortedIndex_.resize(placed);
      sortedBox_.resize(placed);
      sortedCell_.resize(placed);
    });
    run.For(Stage::kBroadPhase, ranges, 1, [&](int r0, int r1, int) {
      for (int r = r0; r < r1; ++r) {
        const int c0 = BlockBegin(cells, ranges, r), c1 = BlockBegin(cells, ranges, r + 1);
        const int offset = rangeTotal_[r];
        for (int c = c0; c < c1; ++c) cellStart_[c] = cellCount_[c] += offset;
        for (int i = 0; i < n; ++i) {
          const int c = cellOf_[i];
          if (c < c0 || c >= c1) continue;
          const int k = cellCount_[c]++;
          sortedIndex_[k] = i;
          sortedBox_[k] = aabbs[i];
          sortedCell_[k] = c;
        }
      }
    });
  }

  void Emit(int i, int j, std::span<const uint8_t> movable, std::vector<CandidatePair>& out) const {
    if (!(movable[i] | movable[j])) return;
    out.push_back(i < j ? CandidatePair{i, j} : CandidatePair{j, i});
  }

  void ScanCells(int begin, int end, std::span<const uint8_t> movable, std::vector<CandidatePair>& out) const {
    // Own cell (later bodies only), then right, upper-left, up, upper-right. Walking the bodies
    // in cell order (not the cells) skips the many empty cells of a sparse scene.
    const int placed = static_cast<int>(sortedIndex_.size());
    for (int k = begin; k < end; ++k) {
      const AABB& a = sortedBox_[k];
      const int i = sortedIndex_[k];
      const int cell = sortedCell_[k];
      for (int l = k + 1; l < placed && sortedCell_[l] == cell; ++l) {
        if (Overlaps(a, sortedBox_[l])) Emit(i, sortedIndex_[l], movable, out);
      }
      const int x = cell % cols_;
      const int y = cell / cols_;
      const int right = x + 1 < cols_ ? cell + 1 : -1;
      if (right >= 0) ScanCell(right, a, i, movable, out);
      if (y + 1 < rows_) {
        const int up = cell + cols_;
        ScanRow(x > 0 ? up - 1 : up, x + 1 < cols_ ? up + 1 : up, a, i, movable, out);
      }
    }
  }

  void ScanCell(int cell, const AABB& a, int i, std::span<const uint8_t> movable, std::vector<CandidatePair>& out) const {
    for (int l = cellStart_[cell]; l < cellStart_[cell + 1]; ++l) {
      if (Overlaps(a, sortedBox_[l])) Emit(i, sortedIndex_[l], movable, out);
    }
  }

  // Cells first..last of one row are contiguous in cell order, so their bodies are too.
  void ScanRow(int first, int last, const AABB& a, int i, std::span<const uint8_t> movable,
               std::vector<CandidatePair>& out) const {
    for (int l = cellStart_[first]; l < cellStart_[last + 1]; ++l) {
      if (Overlaps(a, sortedBox_[l])) Emit(i, sortedIndex_[l], movable, out);
    }
  }

  // The pairs of the oversized bodies large_[begin, end) with later oversized ones and with the
  // ordinary bodies.
  void ScanLarge(int begin, int end, std::span<const AABB> aabbs, std::span<const uint8_t> movable,
                 std::vector<CandidatePair>& out) const {
    for (int k = begin; k < end; ++k) {
      const int i = large_[k];
      const AABB& a = aabbs[i];
      for (size_t l = size_t(k) + 1; l < large_.size(); ++l) {
        if (Overlaps(a, aabbs[large_[l]])) Emit(i, large_[l], movable, out);
      }
      if (!Overlaps(a, region_)) continue;
      // Ordinary bodies are filed by their lower corner, which lies at most one cell below
      // or left of any point they cover.
      const int x0 = CellX(a.lower.x - 1.0 / inv_), x1 = CellX(a.upper.x);
      const int y0 = CellY(a.lower.y - 1.0 / inv_), y1 = CellY(a.upper.y);
      for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) {
          const int cell = y * cols_ + x;
          for (int l = cellStart_[cell]; l < cellStart_[cell + 1]; ++l) {
            if (Overlaps(a, sortedBox_[l])) Emit(i, sortedIndex_[l], movable, out);
          }
        }
      }
    }
  }

  std::vector<uint8_t> all_;  // BuildForQueries: every body counts as movable
  bool queryReady_ = false;
  double originX_ = 0, originY_ = 0, inv_ = 1, largeThreshold_ = 0;
  int cols_ = 0, rows_ = 0;
  AABB region_{};
  std::vector<int> cellOf_, cellStart_, sortedIndex_, sortedCell_, large_;
  std::vector<AABB> sortedBox_;
  std::vector<Real> extent_;
  std::vector<Partial> partial_;
  std::vector<double> cellMax_;
  std::vector<int> cellCount_, rangeTotal_;
  std::vector<std::vector<int>> largePart_;
  std::vector<std::vector<CandidatePair>> perWorker_;
};

}  // namespace

std::unique_ptr<BroadPhase> MakeUniformGrid() { return std::make_unique<UniformGrid>(); }

}  // namespace quadrant
