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
#include <bit>
#include <cmath>
#include <limits>

#include "collision/broad_phase.h"
#include "parallel/worker_lists.h"

#if defined(__SSE2__) && !defined(QUADRANT_DOUBLE)
#include <emmintrin.h>
#define QUADRANT_GRID_SIMD 1
#else
#define QUADRANT_GRID_SIMD 0
#endif

namespace quadrant {
namespace {

class UniformGrid final : public BroadPhase {
 public:
  const char* Name() const override { return "uniform_grid"; }

  void FindPairs(std::span<const AABB> aabbs, std::span<const uint8_t> movable,
                 std::vector<CandidatePair>& out, StageRunner& run) override {
    out.clear();
    if (aabbs.size() < 2) return;
    Build(aabbs, movable, run, true);
    if (!ready_) return;
    Interleave(out);
  }

  // The narrow phase cuts the pairs into equal blocks, one per worker. An oversized body's pair
  // (a box on a long ground) costs about 2.5 times an ordinary one, and appended after the others
  // they all fell in the last block: many_pyramids 22000 (4000 of 44000 pairs on its grounds),
  // model at 4 threads, the last block 815 us against 580-615 for the others. So both lists are
  // cut into kPieces pieces laid alternately, and any split into up to kPieces / 4 blocks gets its
  // share of each kind. The order depends on the two counts only (not on the block count), and
  // nothing after the broad phase depends on it (contacts are solved in key order).
  void Interleave(std::vector<CandidatePair>& out) const {
    struct Cursor {
      const WorkerLists<CandidatePair>& lists;
      int block = 0;
      size_t at = 0;
      void CopyTo(size_t m, std::vector<CandidatePair>& to) {
        while (m > 0 && block < lists.Count()) {
          const std::vector<CandidatePair>& v = lists[block];
          const size_t take = std::min(m, v.size() - at);
          to.insert(to.end(), v.begin() + ptrdiff_t(at), v.begin() + ptrdiff_t(at + take));
          at += take;
          m -= take;
          if (at == v.size()) ++block, at = 0;
        }
      }
    };
    const size_t scanCount = scanPairs_.TotalSize(), largeCount = largePairs_.TotalSize();
    out.reserve(scanCount + largeCount);
    Cursor scan{scanPairs_}, large{largePairs_};
    const size_t pieces = largeCount == 0 || scanCount == 0 ? 1 : kPieces;
    for (size_t p = 0; p < pieces; ++p) {
      scan.CopyTo((scanCount * (p + 1)) / pieces - (scanCount * p) / pieces, out);
      large.CopyTo((largeCount * (p + 1)) / pieces - (largeCount * p) / pieces, out);
    }
  }

  // The update runs in Extents, chunk by chunk, just before the chunk's boxes are read: one
  // region for the whole broad phase instead of a parallel-for and then the region. Circle
  // stress 16000 at 2 threads, 2-core VM: the broad phase -2.7 %, the step -1.1 % (near the
  // noise there); 1 thread +0.33 % instructions on circle stress 1000 (icount).
  void UpdateAndFindPairs(std::span<const AABB> aabbs, std::span<const uint8_t> movable,
                          std::vector<CandidatePair>& out, StageRunner& run, BoxUpdate update) override {
    if (aabbs.size() < 2) {  // no region to run it in
      run.Serial(Stage::kBroadPhase, [&] { update(0, static_cast<int>(aabbs.size())); });
      out.clear();
      return;
    }
    update_ = update;
    try {
      FindPairs(aabbs, movable, out, run);
    } catch (...) {
      update_ = {};
      throw;
    }
    update_ = {};
  }

  void BuildForQueries(std::span<const AABB> aabbs, StageRunner& run) override {
    // Every body counts as movable, so the region holds them all and no static is left out.
    all_.assign(aabbs.size(), 1);
    ready_ = false;
    if (!aabbs.empty()) Build(aabbs, all_, run, false);
    queryReady_ = ready_;
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
    for (int y = y0; y <= y1; ++y) {
      for (int l = RowFirst(y, x0), last = y * stride_ + x1; sortedKey_[l] <= last; ++l) {
        if (Overlaps(box, SortedBox(l))) out.push_back(sortedIndex_[l]);
      }
    }
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
      for (int l = RowFirst(y, x0), last = y * stride_ + x1; sortedKey_[l] <= last; ++l) {
        if (SegmentTouchesBox(p1, p2, SortedBox(l))) out.push_back(sortedIndex_[l]);
      }
    }
  }

 private:
  // A query's coordinates can lie anywhere (a box of 1e30 m): clamped to the region before the
  // conversion to int, which would overflow.
  int QueryCellX(double v) const { return CellX(std::clamp(v, double(region_.lower.x), double(region_.upper.x))); }
  int QueryCellY(double v) const { return CellY(std::clamp(v, double(region_.lower.y), double(region_.upper.y))); }

  // The first sorted body whose cell is (x, y) or later: the bodies of cells x..x1 of row y
  // follow it up to the first key above y * stride_ + x1 (the sentinel ends every such walk).
  int RowFirst(int y, int x) const {
    const int placed = static_cast<int>(sortedIndex_.size());
    return static_cast<int>(std::lower_bound(sortedKey_.begin(), sortedKey_.begin() + placed, y * stride_ + x) -
                            sortedKey_.begin());
  }

  AABB SortedBox(int l) const { return {{lowerX_[l], lowerY_[l]}, {upperX_[l], upperY_[l]}}; }

  static double Extent(const AABB& b) { return std::max(b.upper.x - b.lower.x, b.upper.y - b.lower.y); }

  // Per-chunk partial results of the layout pass. Chunks have a fixed size, so combining them
  // in chunk order gives the same bits for any thread count.
  struct Partial {
    AABB box{};
    double extentSum = 0;
    double movingMax = 0;  // the largest extent of a movable body
    int moving = 0;
    int fixed = 0;  // bodies that are not movable
  };
  static constexpr int kChunk = 1024;
  static constexpr size_t kPieces = 64;  // Interleave's pieces of each pair list
  // Radix digits of at most this many bits: a block's histogram (4 KiB) stays in L1.
  static constexpr int kMaxDigitBits = 10;
  static constexpr int kPad = 4;  // sentinel keys (and empty boxes) after the sorted bodies

  // The step as one region of stages (StageRunner::Stages): layout, the sort of the bodies by
  // cell, the pair scans. A parallel-for per phase (seven a step) would cost a hand-over to the
  // workers and a join each; a region costs one hand-over, and a stage boundary only a wait for
  // the stage's last chunk. One-item stages are the serial steps between them. With the radix
  // sort and the four-wide scan below, against seven parallel-fors and a counting sort, 2-core
  // VM, 1 thread: the broad phase 0.817 -> 0.543 ms a step on circle stress 16000, 1.071 ->
  // 0.797 ms on polygon stress 16000.
  enum class Op : uint8_t {
    kExtents, kReduce, kCellMax, kGrid, kKeys, kHistogram, kOffsets, kScatter, kSplit, kRangeSort, kScan, kLarge, kGather
  };
  struct Step {
    Op op;
    int pass;
  };

  void Build(std::span<const AABB> aabbs, std::span<const uint8_t> movable, StageRunner& run, bool scan) {
    const int n = static_cast<int>(aabbs.size());
    // Split from a quarter of MinItems: a body costs the grid about 60 ns (tumbler 2025: 0.126 ms
    // a step), several times a body update, and below MinItems (2048) the tumbler, pyramid and
    // stress scenes of 1000-2000 bodies ran the grid serially at 2 threads. Against the split at
    // MinItems, 2 threads, amd-epyc-2c, ms a step: tumbler 2025 0.722 -> 0.659, circles 2000
    // 0.116 -> 0.098, polygons 2000 0.211 -> 0.183; 1 thread within 1.6 %
    // (docs/notes/uniform_grid.md has the rest).
    const bool parallel = n >= std::max(2, run.MinItems() / 4) && run.Workers() > 1;
    // Blocks of the sort and the scans: four per worker, so a thread that starts late leaves
    // little to wait on. The sorted order and the pairs do not depend on the block count.
    blocks_ = parallel ? 4 * run.Workers() : 1;
    ranges_ = parallel ? run.Workers() : 0;
    chunks_ = (n + kChunk - 1) / kChunk;
    // The sort's passes, fixed before the grid is known: keys stay below rows * (cols + 1),
    // at most about twice the grid's cell budget (Grid), so this many digits always suffice
    // (more would only make the histograms larger, never the sort wrong).
    const long long keyBound = 4 * (4LL * n + 64);
    const int boundBits = std::bit_width(static_cast<unsigned long long>(keyBound));
    passes_ = (boundBits + kMaxDigitBits - 1) / kMaxDigitBits;
    ready_ = false;
    steps_.clear();
    plan_.clear();
    auto add = [&](Op op, int count, int pass = 0) {
      steps_.push_back({op, pass});
      plan_.push_back({count, 1});
    };
    add(Op::kExtents, chunks_);
    add(Op::kReduce, 1);
    add(Op::kCellMax, chunks_);
    add(Op::kGrid, 1);
    add(Op::kKeys, blocks_);
    if (ranges_ > 0) {
      add(Op::kSplit, 1);
      add(Op::kRangeSort, ranges_);
    } else {
      for (int p = 0; p < passes_; ++p) {
        if (p > 0) add(Op::kHistogram, blocks_, p);
        add(Op::kOffsets, 1, p);
        add(Op::kScatter, blocks_, p);
      }
      add(Op::kGather, blocks_);
    }
    if (scan) {
      add(Op::kScan, blocks_);
      add(Op::kLarge, blocks_);
      scanPairs_.Reset(blocks_);
      largePairs_.Reset(blocks_);
    }
    extent_.resize(n);
    partial_.resize(chunks_);
    cellMax_.resize(chunks_);
    keyOf_.resize(n);
    largePart_.Reset(blocks_);
    const int minParallel = parallel ? 2 : std::numeric_limits<int>::max();
    run.Stages(Stage::kBroadPhase, plan_, minParallel, [&](int s, int begin, int end) {
      const Step step = steps_[s];
      if (step.op != Op::kExtents && step.op != Op::kReduce && !ready_) return;
      for (int item = begin; item < end; ++item) {
        switch (step.op) {
          case Op::kExtents: Extents(aabbs, movable, item); break;
          case Op::kReduce: Reduce(); break;
          case Op::kCellMax: CellMax(aabbs, movable, item); break;
          case Op::kGrid: Grid(n); break;
          case Op::kKeys: Keys(aabbs, item); break;
          case Op::kHistogram: Histogram(step.pass, item); break;
          case Op::kOffsets: Offsets(step.pass); break;
          case Op::kScatter: Scatter(step.pass, item, n); break;
          case Op::kGather: Gather(aabbs, BlockBegin(placed_, blocks_, item), BlockBegin(placed_, blocks_, item + 1)); break;
          case Op::kSplit: Split(); break;
          case Op::kRangeSort: RangeSort(aabbs, item, n); break;
          case Op::kScan: ScanCells(item, movable); break;
          case Op::kLarge: ScanLarge(item, aabbs, movable); break;
        }
      }
    });
  }

  // Layout, part 1 (per chunk of bodies): extents, the box of the movable bodies, their mean
  // extent and largest extent.
  void Extents(std::span<const AABB> aabbs, std::span<const uint8_t> movable, int c) {
    const int n = static_cast<int>(aabbs.size());
    if (update_.fn) update_(c * kChunk, std::min(n, (c + 1) * kChunk));
    Partial p;
    for (int i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) {
      extent_[i] = Real(Extent(aabbs[i]));
      if (!movable[i]) {
        ++p.fixed;
        continue;
      }
      p.box = p.moving == 0 ? aabbs[i] : Union(p.box, aabbs[i]);
      p.extentSum += extent_[i];
      p.movingMax = std::max<double>(p.movingMax, extent_[i]);
      ++p.moving;
    }
    partial_[c] = p;
  }

  // Layout, part 2 (serial): the region of the movable bodies and the threshold between
  // ordinary and oversized bodies.
  void Reduce() {
    double meanExtent = 0;
    int moving = 0;
    AABB box{};
    for (const Partial& p : partial_) {
      if (p.moving == 0) continue;
      box = moving == 0 ? p.box : Union(box, p.box);
      meanExtent += p.extentSum;
      moving += p.moving;
    }
    ready_ = false;
    if (moving == 0) return;
    // A non-finite box would make the cell arithmetic meaningless; the world's input checks
    // keep states finite, so this only guards against misuse of the broad phase on its own.
    if (!IsFinite(box.lower) || !IsFinite(box.upper) || !std::isfinite(meanExtent)) return;
    meanExtent /= moving;
    largeThreshold_ = 4.0 * meanExtent;
    movingBox_ = box;
    ready_ = true;
  }

  // Layout, part 3 (per chunk): the largest ordinary body that can meet a movable one (max is
  // exact in any order, so per-chunk maxima combine deterministically). A chunk of movable
  // bodies none of which is oversized has it from part 1: only chunks holding static bodies
  // (a stress scene's walls, a pyramid's ground) or an oversized one are read again.
  void CellMax(std::span<const AABB> aabbs, std::span<const uint8_t> movable, int c) {
    const Partial& p = partial_[c];
    if (p.fixed == 0 && p.movingMax <= largeThreshold_) {
      cellMax_[c] = std::max(1e-3, p.movingMax);
      return;
    }
    const int n = static_cast<int>(aabbs.size());
    double cell = 1e-3;
    for (int i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) {
      const double e = extent_[i];
      if (e <= largeThreshold_ && (movable[i] || Overlaps(aabbs[i], movingBox_))) cell = std::max(cell, e);
    }
    cellMax_[c] = cell;
  }

  // Layout, part 4 (serial): the grid.
  void Grid(int n) {
    double cell = 1e-3;
    for (double c : cellMax_) cell = std::max(cell, c);
    const AABB& box = movingBox_;
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
    // A body's key is y * stride_ + x: row-major cell order, with one empty column after each
    // row, so the right neighbour of the last column and the upper-left one of the first are
    // that empty column, and the pair scan needs no edge tests.
    stride_ = cols_ + 1;
    region_ = {{Real(originX_), Real(originY_)}, {Real(originX_ + cols_ * cell), Real(originY_ + rows_ * cell)}};
    const int keyBits = std::max(1, int(std::bit_width(static_cast<unsigned>(rows_ * stride_ - 1))));
    digitBits_ = (keyBits + passes_ - 1) / passes_;
    // The parallel path's histogram counts the keys' top kCoarseBits bits (Split); the serial
    // one the first radix digit.
    keyShift_ = ranges_ > 0 ? std::max(0, keyBits - kCoarseBits) : 0;
    keyBits_ = ranges_ > 0 ? std::min(keyBits, kCoarseBits) : digitBits_;
    histogram_.resize(size_t(blocks_) << keyBits_);
  }

  // Truncation instead of floor: it differs only below the origin, where the clamp to 0 makes
  // both agree.
  int CellX(double v) const { return std::clamp(int((v - originX_) * inv_), 0, cols_ - 1); }
  int CellY(double v) const { return std::clamp(int((v - originY_) * inv_), 0, rows_ - 1); }

  // Each ordinary body goes in exactly one cell, that of its lower corner; the bodies are sorted
  // by cell with a least-significant-digit radix sort, which is stable, so within a cell they
  // stay in index order: the same order for any block count. AABBs are copied in cell order so
  // the pair scan reads memory sequentially.
  //
  // Why a radix sort and no per-cell array: the grid has about 2.6 cells per body (16000
  // circles: 41000 cells), so the counting sort by cell it replaces zeroed, counted, summed and
  // wrote per-cell arrays each step, and split across threads only by ranges of cells, each of
  // which read every body's cell (the work did not shrink with more threads). Two passes of
  // 8-bit digits touch only the bodies and a 256-entry histogram per block.
  void Keys(std::span<const AABB> aabbs, int block) {
    const int n = static_cast<int>(aabbs.size());
    const int mask = (1 << keyBits_) - 1, shift = keyShift_;
    int* hist = histogram_.data() + (size_t(block) << keyBits_);
    std::fill(hist, hist + mask + 1, 0);
    std::vector<int>& large = largePart_[block];
    large.clear();
    for (int i = BlockBegin(n, blocks_, block), end = BlockBegin(n, blocks_, block + 1); i < end; ++i) {
      const AABB& b = aabbs[i];
      int key = -1;
      if (extent_[i] > largeThreshold_) {
        large.push_back(i);  // oversized: queried separately
      } else if (Overlaps(b, region_)) {  // otherwise it cannot touch any movable body
        key = CellY(b.lower.y) * stride_ + CellX(b.lower.x);
        ++hist[(key >> shift) & mask];
      }
      keyOf_[i] = key;
    }
  }

  // Pass p's histogram, per block of the previous pass's output.
  void Histogram(int p, int block) {
    const int mask = (1 << digitBits_) - 1, shift = p * digitBits_;
    int* hist = histogram_.data() + (size_t(block) << digitBits_);
    std::fill(hist, hist + mask + 1, 0);
    const std::vector<int>& key = tempKey_[(p - 1) & 1];
    for (int l = BlockBegin(placed_, blocks_, block), end = BlockBegin(placed_, blocks_, block + 1); l < end; ++l) {
      ++hist[(key[l] >> shift) & mask];
    }
  }

  // Serial: the histogram becomes each (block, digit)'s first slot, digit-major, so the blocks
  // of equal digits follow each other in block order (the stability of the sort).
  void Offsets(int p) {
    if (p == 0) {
      large_.clear();  // blocks are in index order, so the oversized bodies are too
      for (int b = 0; b < largePart_.Count(); ++b) large_.insert(large_.end(), largePart_[b].begin(), largePart_[b].end());
    }
    const int digits = 1 << keyBits_;
    int total = 0;
    for (int d = 0; d < digits; ++d) {
      for (int b = 0; b < blocks_; ++b) {
        int& slot = histogram_[(size_t(b) << digitBits_) + d];
        const int k = slot;
        slot = total;
        total += k;
      }
    }
    if (p > 0) return;
    placed_ = total;
    Resize();
  }

  // The sort's outputs for placed_ bodies.
  void Resize() {
    for (auto& v : tempKey_) v.resize(placed_);
    for (auto& v : tempIndex_) v.resize(placed_);
    // kPad sentinels end every walk (the scan reads four keys and boxes at a time).
    sortedKey_.resize(size_t(placed_) + kPad);
    std::fill(sortedKey_.begin() + placed_, sortedKey_.end(), std::numeric_limits<int>::max());
    sortedIndex_.resize(placed_);
    for (std::vector<Real>* v : {&lowerX_, &lowerY_, &upperX_, &upperY_}) {
      v->resize(size_t(placed_) + kPad);
      std::fill(v->begin() + placed_, v->end(), Real(0));
    }
  }

  void Scatter(int p, int block, int n) {
    const int mask = (1 << digitBits_) - 1, shift = p * digitBits_;
    int* slot = histogram_.data() + (size_t(block) << digitBits_);
    const bool last = p == passes_ - 1;
    int* outKey = last ? sortedKey_.data() : tempKey_[p & 1].data();
    int* outIndex = last ? sortedIndex_.data() : tempIndex_[p & 1].data();
    auto put = [&](int key, int i) {
      const int k = slot[(key >> shift) & mask]++;
      outKey[k] = key;
      outIndex[k] = i;
    };
    if (p == 0) {
      for (int i = BlockBegin(n, blocks_, block), end = BlockBegin(n, blocks_, block + 1); i < end; ++i) {
        if (keyOf_[i] >= 0) put(keyOf_[i], i);
      }
      return;
    }
    const int* inKey = tempKey_[(p - 1) & 1].data();
    const int* inIndex = tempIndex_[(p - 1) & 1].data();
    for (int l = BlockBegin(placed_, blocks_, block), end = BlockBegin(placed_, blocks_, block + 1); l < end; ++l) {
      put(inKey[l], inIndex[l]);
    }
  }

  // The parallel sort. The passes of the radix sort above, split across threads by blocks of
  // their input, write each digit's slots from every block: on two threads nearly every cache
  // line of their outputs was written by both cores (16000 bodies, 256 digits, 8 blocks: runs
  // of about 8 slots), and the scan then read half its sorted arrays from the other core.
  // Circle stress 16000, work summed over the threads, ms a step, 1 -> 2 threads: the scatter
  // passes 0.088 -> 0.163 (with their histogram and offsets 0.10 -> 0.18), the scan 0.234 ->
  // 0.299. Instead the keys are split into one range per worker, of about equal counts (from the
  // keys' top bits counted in Keys), and each range is sorted on its own: its bodies gathered in
  // index order from all the keys, then two radix passes of its own, into its own part of the
  // sorted arrays. Every range is sorted stably and the ranges follow each other, so the order
  // is the serial sort's. At 2 threads, the same work summed, ms a step: sort 0.148-0.184 ->
  // 0.124-0.134, scan 0.257-0.295 -> 0.245-0.253, the grid's region 0.310-0.365 -> 0.290-0.314
  // (the gather reads every key once per range; one thread keeps the serial sort).
  void Split() {
    large_.clear();  // blocks are in index order, so the oversized bodies are too
    for (int b = 0; b < largePart_.Count(); ++b) large_.insert(large_.end(), largePart_[b].begin(), largePart_[b].end());
    const int digits = 1 << keyBits_;
    rangeKey_.assign(ranges_ + 1, std::numeric_limits<int>::max());
    rangeBegin_.assign(ranges_ + 1, 0);
    rangeKey_[0] = 0;
    long long total = 0;
    for (int b = 0; b < blocks_; ++b) {
      for (int d = 0; d < digits; ++d) total += histogram_[(size_t(b) << keyBits_) + d];
    }
    placed_ = static_cast<int>(total);
    // Range r starts at the first top-bits digit before which at least r / ranges_ of the bodies lie.
    int r = 1, before = 0;
    for (int d = 0; d < digits && r < ranges_; ++d) {
      while (r < ranges_ && (long long)before * ranges_ >= total * r) {
        rangeKey_[r] = d << keyShift_;
        rangeBegin_[r] = before;
        ++r;
      }
      for (int b = 0; b < blocks_; ++b) before += histogram_[(size_t(b) << keyBits_) + d];
    }
    for (; r <= ranges_; ++r) rangeBegin_[r] = placed_;  // rangeKey_ stays past every key
    rangeHist_.resize(ranges_);
    Resize();
  }

  void RangeSort(std::span<const AABB> aabbs, int r, int n) {
    const int begin = rangeBegin_[r], count = rangeBegin_[r + 1] - begin;
    if (count == 0) return;
    const int lo = rangeKey_[r], hi = rangeKey_[r + 1];
    const int span = std::min(hi, rows_ * stride_) - lo;  // every key of the range is below lo + span
    const int bits = std::max(1, int(std::bit_width(static_cast<unsigned>(span - 1))));
    const int lowBits = (bits + 1) / 2, lowMask = (1 << lowBits) - 1;
    std::vector<int>& hist = rangeHist_[r];
    hist.assign((size_t(1) << lowBits) + (size_t(1) << (bits - lowBits)), 0);
    int* low = hist.data();
    int* high = hist.data() + (size_t(1) << lowBits);
    int* key0 = tempKey_[0].data() + begin;
    int* index0 = tempIndex_[0].data() + begin;
    int m = 0;
    for (int i = 0; i < n; ++i) {
      const int key = keyOf_[i];
      if (key < lo || key >= hi) continue;  // unplaced bodies (-1) are below every range
      key0[m] = key;
      index0[m] = i;
      ++m;
      ++low[(key - lo) & lowMask];
      ++high[(key - lo) >> lowBits];
    }
    auto exclusive = [](int* h, size_t size) {
      int total = 0;
      for (size_t d = 0; d < size; ++d) {
        const int k = h[d];
        h[d] = total;
        total += k;
      }
    };
    exclusive(low, size_t(1) << lowBits);
    exclusive(high, size_t(1) << (bits - lowBits));
    int* key1 = tempKey_[1].data() + begin;
    int* index1 = tempIndex_[1].data() + begin;
    for (int l = 0; l < m; ++l) {
      const int k = low[(key0[l] - lo) & lowMask]++;
      key1[k] = key0[l];
      index1[k] = index0[l];
    }
    for (int l = 0; l < m; ++l) {
      const int k = begin + high[(key1[l] - lo) >> lowBits]++;
      sortedKey_[k] = key1[l];
      sortedIndex_[k] = index1[l];
    }
    Gather(aabbs, begin, begin + m);
  }

  // The sorted bodies' boxes into the scan's arrays, in sorted order: written in sequence, read
  // where the bodies lie. Written by the last radix pass itself, each box went to the slot of one
  // of 1024 digits in four arrays, about 4000 lines written at once. Circle stress 64000, 1
  // thread, 2-core VM: the scatter passes 1.55 ms a step -> 0.35 and this pass 0.10 (the
  // grid's own timers, 400 steps); broad phase -13 %, five interleaved pairs; the same bits.
  void Gather(std::span<const AABB> aabbs, int begin, int end) {
    for (int k = begin; k < end; ++k) {
      const AABB& b = aabbs[size_t(sortedIndex_[k])];
      lowerX_[k] = b.lower.x;
      lowerY_[k] = b.lower.y;
      upperX_[k] = b.upper.x;
      upperY_[k] = b.upper.y;
    }
  }

  void Emit(int i, int j, std::span<const uint8_t> movable, std::vector<CandidatePair>& out) const {
    if (!(movable[i] | movable[j])) return;
    out.push_back(i < j ? CandidatePair{i, j} : CandidatePair{j, i});
  }

  // Each body against the later bodies of its own cell, then the cell to the right, then the
  // three cells above (upper-left, up, upper-right), in the sorted order: the same pairs in the
  // same order as reading those cells one by one. Own cell and right cell are the run of keys
  // up to key + 1 that follows the body; the three upper cells are the keys key + stride_ - 1 ..
  // key + stride_ + 1, whose first body only moves forward from body to body, so one pointer
  // walks it. No per-cell table, no division for the cell's column.
  void ScanCells(int block, std::span<const uint8_t> movable) {
    std::vector<CandidatePair>& out = scanPairs_[block];
    const int begin = BlockBegin(placed_, blocks_, block), end = BlockBegin(placed_, blocks_, block + 1);
    if (begin >= end) return;
    const int* key = sortedKey_.data();
    const int* index = sortedIndex_.data();
    const int s = stride_;
    int up = static_cast<int>(std::lower_bound(key, key + placed_, key[begin] + s - 1) - key);
    for (int k = begin; k < end; ++k) {
      const int c = key[k];
      const int i = index[k];
#if QUADRANT_GRID_SIMD
      // Four candidates at a time, without a branch per candidate: in a sparse scene a cell
      // holds 0.4 bodies on average, so the scalar loops' exits and overlap tests were
      // mispredicted about every body (ScanCells was 25 % of the step's cycles at 1 thread,
      // circle stress 16000, after the radix sort; callgrind's branch simulation: 367 000
      // mispredicted branches in 10 steps before, 102 000 after).
      const Probe a{_mm_set1_ps(lowerX_[k]), _mm_set1_ps(lowerY_[k]), _mm_set1_ps(upperX_[k]), _mm_set1_ps(upperY_[k])};
      Windows(k + 1, c + 1, a, i, movable, out);
      for (;;) {  // up to the first key >= c + s - 1: the keys below it are a prefix
        const unsigned below = unsigned(_mm_movemask_ps(_mm_castsi128_ps(
            _mm_cmplt_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(key + up)), _mm_set1_epi32(c + s - 1)))));
        up += std::countr_one(below);
        if (below != 0xF) break;
      }
      Windows(up, c + s + 1, a, i, movable, out);
#else
      const AABB a = SortedBox(k);
      for (int l = k + 1; key[l] <= c + 1; ++l) {
        if (Overlaps(a, SortedBox(l))) Emit(i, index[l], movable, out);
      }
      while (key[up] < c + s - 1) ++up;
      for (int l = up; key[l] <= c + s + 1; ++l) {
        if (Overlaps(a, SortedBox(l))) Emit(i, index[l], movable, out);
      }
#endif
    }
  }

#if QUADRANT_GRID_SIMD
  struct Probe {
    __m128 lowerX, lowerY, upperX, upperY;  // one box in every lane
  };

  // The sorted bodies from `first` on whose key is <= last, four at a time (the arrays carry
  // kPad sentinels past the end): each one whose box overlaps a's is emitted with body i, in
  // order. Overlaps() as one mask: any "greater" separates the boxes (NaN compares false there
  // and here).
  void Windows(int first, int last, const Probe& a, int i, std::span<const uint8_t> movable,
               std::vector<CandidatePair>& out) const {
    const __m128i lastKey = _mm_set1_epi32(last);
    for (;;) {
      const __m128i keys = _mm_loadu_si128(reinterpret_cast<const __m128i*>(sortedKey_.data() + first));
      const unsigned inRange = ~unsigned(_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpgt_epi32(keys, lastKey)))) & 0xFu;
      const __m128 separated =
          _mm_or_ps(_mm_or_ps(_mm_cmpgt_ps(_mm_loadu_ps(lowerX_.data() + first), a.upperX),
                              _mm_cmpgt_ps(_mm_loadu_ps(lowerY_.data() + first), a.upperY)),
                    _mm_or_ps(_mm_cmpgt_ps(a.lowerX, _mm_loadu_ps(upperX_.data() + first)),
                              _mm_cmpgt_ps(a.lowerY, _mm_loadu_ps(upperY_.data() + first))));
      unsigned hit = ~unsigned(_mm_movemask_ps(separated)) & inRange;
      while (hit != 0) {
        Emit(i, sortedIndex_[first + std::countr_zero(hit)], movable, out);
        hit &= hit - 1;
      }
      if (inRange != 0xF) return;
      first += 4;
    }
  }
#endif

  // The pairs of the oversized bodies of one block of large_ with later oversized ones and with
  // the ordinary bodies. (A stress scene's four walls each reach along a few hundred cells.)
  void ScanLarge(int block, std::span<const AABB> aabbs, std::span<const uint8_t> movable) {
    std::vector<CandidatePair>& out = largePairs_[block];
    const int count = static_cast<int>(large_.size());
    for (int k = BlockBegin(count, blocks_, block), end = BlockBegin(count, blocks_, block + 1); k < end; ++k) {
      const int i = large_[k];
      const AABB& a = aabbs[i];
      for (int l = k + 1; l < count; ++l) {
        if (Overlaps(a, aabbs[large_[l]])) Emit(i, large_[l], movable, out);
      }
      if (!Overlaps(a, region_)) continue;
      // Ordinary bodies are filed by their lower corner, which lies at most one cell below
      // or left of any point they cover.
      const int x0 = CellX(a.lower.x - 1.0 / inv_), x1 = CellX(a.upper.x);
      const int y0 = CellY(a.lower.y - 1.0 / inv_), y1 = CellY(a.upper.y);
      for (int y = y0; y <= y1; ++y) {
        for (int l = RowFirst(y, x0), last = y * stride_ + x1; sortedKey_[l] <= last; ++l) {
          if (Overlaps(a, SortedBox(l))) Emit(i, sortedIndex_[l], movable, out);
        }
      }
    }
  }

  BoxUpdate update_;           // UpdateAndFindPairs: the caller's box update, run in Extents
  std::vector<uint8_t> all_;  // BuildForQueries: every body counts as movable
  bool ready_ = false;        // this build has a grid (some movable body, finite boxes)
  bool queryReady_ = false;
  double originX_ = 0, originY_ = 0, inv_ = 1, largeThreshold_ = 0;
  int cols_ = 0, rows_ = 0, stride_ = 1;
  AABB region_{}, movingBox_{};
  int blocks_ = 1, chunks_ = 0, passes_ = 1, digitBits_ = 1, placed_ = 0;
  int ranges_ = 0;                 // the parallel sort's key ranges (0: the serial radix sort)
  int keyShift_ = 0, keyBits_ = 1;  // Keys counts (key >> keyShift_) & ((1 << keyBits_) - 1)
  static constexpr int kCoarseBits = 8;
  std::vector<int> rangeKey_, rangeBegin_;  // range r: keys from rangeKey_[r], slots from rangeBegin_[r]
  std::vector<std::vector<int>> rangeHist_;
  std::vector<Step> steps_;
  std::vector<TaskSystem::StagePlan> plan_;
  std::vector<int> keyOf_, large_, histogram_;
  std::vector<int> tempKey_[2], tempIndex_[2];
  std::vector<int> sortedKey_ = std::vector<int>(kPad, std::numeric_limits<int>::max()), sortedIndex_;
  // The sorted bodies' boxes, one array per bound, so the scan tests four at once.
  std::vector<Real> lowerX_, lowerY_, upperX_, upperY_;
  std::vector<Real> extent_;
  std::vector<Partial> partial_;
  std::vector<double> cellMax_;
  // Per block, each alone on its cache lines (worker_lists.h: blocks scanned at once by two
  // threads appended to neighbouring headers).
  WorkerLists<int> largePart_;
  WorkerLists<CandidatePair> scanPairs_, largePairs_;
};

}  // namespace

std::unique_ptr<BroadPhase> MakeUniformGrid() { return std::make_unique<UniformGrid>(); }

}  // namespace quadrant
