// The thesis's region quad-tree (section 4.2.2.1): a body lives in the smallest node whose
// region contains its AABB; a pair can only overlap if one body's node is the other's node
// or an ancestor of it.
//
// Built from scratch each step without heap allocation once warm: the tree is complete to a
// fixed depth and stored flat (level L starts at (4^L - 1) / 3), a body's node follows from
// integer cell coordinates at the finest level (the node is the deepest level at which both
// corners of the AABB fall in the same cell), and bodies are bucketed by a counting sort.
//
// The thesis enumerates, for each body, its node's bodies and all ancestors' bodies. Here the
// same pair set is enumerated from the ancestor's side: each body is tested against its own
// node's later bodies and against the bodies of descendant nodes whose region overlaps its
// AABB. Bodies straddling a root boundary (the thesis's weakness: they are compared with every
// body) then cost a walk down the few nodes they touch, not a pass over the whole world.
#include <algorithm>
#include <bit>

#include "collision/broad_phase.h"

namespace quadrant {
namespace {

constexpr int NodesUpTo(int level) { return ((1 << (2 * (level + 1))) - 1) / 3; }  // levels 0..level
constexpr int LevelOffset(int level) { return ((1 << (2 * level)) - 1) / 3; }

class QuadTree final : public BroadPhase {
 public:
  explicit QuadTree(int maxDepth) : maxDepth_(maxDepth) {}
  const char* Name() const override { return "quad_tree"; }

  void FindPairs(std::span<const AABB> aabbs, std::span<const uint8_t> movable,
                 std::vector<CandidatePair>& out, StageRunner& run) override {
    out.clear();
    const int n = static_cast<int>(aabbs.size());
    if (n < 2) return;
    run.Serial(Stage::kBroadPhase, [&] {
      ChooseRegion(aabbs);
      AssignNodes(aabbs);
      Bucket(n);
    });
    perWorker_.Reset(run.Workers());
    stacks_.Reset(run.Workers());
    // Blocks of bodies in node order: each body pairs with its node's later bodies and with
    // the bodies below it, so blocks are independent.
    run.For(Stage::kBroadPhase, n, run.MinItems(), [&](int begin, int end, int worker) {
      std::vector<CandidatePair>& part = perWorker_[worker];
      int node = 0;
      for (int k = begin; k < end; ++k) {
        while (start_[node + 1] <= k) ++node;
        const int i = items_[k];
        for (int l = k + 1; l < start_[node + 1]; ++l) TestPair(i, items_[l], aabbs, movable, part);
        if (node < firstLeaf_) QueryDescendants(node, i, aabbs, movable, part, stacks_[worker]);
      }
    });
    MergePairs(perWorker_, out);
  }

  void BuildForQueries(std::span<const AABB> aabbs, StageRunner&) override {
    const int n = static_cast<int>(aabbs.size());
    queryReady_ = n > 0;
    if (!queryReady_) return;
    ChooseRegion(aabbs);
    AssignNodes(aabbs);
    Bucket(n);
    root_ = aabbs[0];
    for (const AABB& b : aabbs) root_ = Union(root_, b);
  }

  // The walk from the root: a node's bodies are tested when its region may hold a hit, and its
  // children only then too (a body lies inside its node's region).
  void QueryBox(const AABB& box, std::span<const AABB> aabbs, std::vector<int>& out) const override {
    if (!queryReady_ || !Overlaps(box, root_)) return;
    // Cell ranges are monotone in the coordinates, so a body overlapping the box lies in a node
    // whose cell range overlaps the box's. Clipped to the bodies' box first: a query's
    // coordinates can be huge, the cell's int not.
    const AABB c{Max(box.lower, root_.lower), Min(box.upper, root_.upper)};
    const CellRange r{CellOf(c.lower.x, originX_), CellOf(c.lower.y, originY_), CellOf(c.upper.x, originX_),
                      CellOf(c.upper.y, originY_)};
    Walk([&](int level, int cx, int cy) {
      const int shift = depth_ - level;
      return !((cx << shift) > r.x1 || (((cx + 1) << shift) - 1) < r.x0 || (cy << shift) > r.y1 ||
               (((cy + 1) << shift) - 1) < r.y0);
    }, [&](int i) {
      if (Overlaps(aabbs[i], box)) out.push_back(i);
    });
  }

  void QuerySegment(Vec2 p1, Vec2 p2, std::span<const AABB> aabbs, std::vector<int>& out) const override {
    if (!queryReady_ || !SegmentTouchesBox(p1, p2, root_)) return;
    const double finest = 1.0 / scale_;  // side of a finest cell (m)
    // A node's region is taken a hundredth of a finest cell larger on every side: the cell of a
    // body corner was found with rounding, and exact tests come later.
    const double pad = 0.01 * finest;
    Walk([&](int level, int cx, int cy) {
      const int shift = depth_ - level;
      const AABB region{{Real(originX_ + double(cx << shift) * finest - pad), Real(originY_ + double(cy << shift) * finest - pad)},
                        {Real(originX_ + double((cx + 1) << shift) * finest + pad),
                         Real(originY_ + double((cy + 1) << shift) * finest + pad)}};
      return SegmentTouchesBox(p1, p2, region);
    }, [&](int i) {
      if (SegmentTouchesBox(p1, p2, aabbs[i])) out.push_back(i);
    });
  }

 private:
  // Depth-first over the nodes for which visitNode(level, cx, cy) holds, from the root (always
  // visited); visitBody(i) for each of their bodies. Empty subtrees are skipped.
  template <class NodeFn, class BodyFn>
  void Walk(NodeFn&& visitNode, BodyFn&& visitBody) const {
    std::vector<NodeRef>& stack = queryStack_;
    stack.clear();
    stack.push_back({0, 0, 0});
    while (!stack.empty()) {
      const NodeRef ref = stack.back();
      stack.pop_back();
      const int node = LevelOffset(ref.level) + (ref.cy << ref.level) + ref.cx;
      if (subtree_[node] == 0) continue;
      for (int k = start_[node]; k < start_[node + 1]; ++k) visitBody(items_[k]);
      if (ref.level == depth_) continue;
      for (int q = 0; q < 4; ++q) {
        const int cx = (ref.cx << 1) | (q & 1), cy = (ref.cy << 1) | (q >> 1);
        if (visitNode(ref.level + 1, cx, cy)) stack.push_back({ref.level + 1, cx, cy});
      }
    }
  }

  struct NodeRef {
    int level, cx, cy;
  };
  struct CellRange {
    int x0, y0, x1, y1;  // inclusive, at the finest level
  };

  // The root region: the square around all AABBs (so every body is contained), and the depth:
  // deep enough that leaves are about twice the mean body size, at most maxDepth_.
  void ChooseRegion(std::span<const AABB> aabbs) {
    AABB box = aabbs[0];
    double extent = 0;
    for (const AABB& b : aabbs) {
      box = Union(box, b);
      extent += std::max(b.upper.x - b.lower.x, b.upper.y - b.lower.y);
    }
    extent /= double(aabbs.size());
    const double side = std::max<double>(std::max(box.upper.x - box.lower.x, box.upper.y - box.lower.y), 1e-6);
    depth_ = 0;
    while (depth_ < maxDepth_ && side / double(1 << (depth_ + 1)) >= 2.0 * extent) ++depth_;
    originX_ = box.lower.x;
    originY_ = box.lower.y;
    const int cells = 1 << depth_;
    // Slightly more than cells/side so the upper edge maps to the last cell, not one past it.
    scale_ = double(cells) / (side * (1.0 + 1e-6));
    nodeCount_ = NodesUpTo(depth_);
    firstLeaf_ = LevelOffset(depth_);
  }

  int CellOf(double v, double origin) const {
    int c = static_cast<int>((v - origin) * scale_);
    return std::clamp(c, 0, (1 << depth_) - 1);
  }

  void AssignNodes(std::span<const AABB> aabbs) {
    const int n = static_cast<int>(aabbs.size());
    node_.resize(n);
    range_.resize(n);
    for (int i = 0; i < n; ++i) {
      CellRange r{CellOf(aabbs[i].lower.x, originX_), CellOf(aabbs[i].lower.y, originY_),
                  CellOf(aabbs[i].upper.x, originX_), CellOf(aabbs[i].upper.y, originY_)};
      range_[i] = r;
      const unsigned differ = unsigned(r.x0 ^ r.x1) | unsigned(r.y0 ^ r.y1);
      const int up = std::bit_width(differ);  // levels to climb until both corners share a cell
      const int level = depth_ - up;
      const int cx = r.x0 >> up;
      const int cy = r.y0 >> up;
      node_[i] = LevelOffset(level) + (cy << level) + cx;
    }
  }

  void Bucket(int n) {
    start_.assign(nodeCount_ + 1, 0);
    for (int i = 0; i < n; ++i) ++start_[node_[i] + 1];
    // Bodies in a node's whole subtree, to skip empty subtrees during the downward walk.
    subtree_.assign(start_.begin() + 1, start_.end());
    for (int level = depth_; level > 0; --level) {
      const int side = 1 << level;
      for (int cy = 0; cy < side; ++cy) {
        for (int cx = 0; cx < side; ++cx) {
          const int parent = LevelOffset(level - 1) + ((cy >> 1) << (level - 1)) + (cx >> 1);
          subtree_[parent] += subtree_[LevelOffset(level) + cy * side + cx];
        }
      }
    }
    for (int k = 0; k < nodeCount_; ++k) start_[k + 1] += start_[k];
    fill_.assign(start_.begin(), start_.end() - 1);
    items_.resize(n);
    for (int i = 0; i < n; ++i) items_[fill_[node_[i]]++] = i;
  }

  void QueryDescendants(int node, int i, std::span<const AABB> aabbs, std::span<const uint8_t> movable,
                        std::vector<CandidatePair>& out, std::vector<NodeRef>& stack_) const {
    const CellRange r = range_[i];
    // Decode (level, cx, cy) of the starting node.
    int level = 0;
    while (level < depth_ && node >= LevelOffset(level + 1)) ++level;
    const int local = node - LevelOffset(level);
    stack_.clear();
    stack_.push_back({level, local & ((1 << level) - 1), local >> level});
    while (!stack_.empty()) {
      const NodeRef ref = stack_.back();
      stack_.pop_back();
      const int childLevel = ref.level + 1;
      const int shift = depth_ - childLevel;  // finest cells per child cell = 1 << shift
      for (int q = 0; q < 4; ++q) {
        const int cx = (ref.cx << 1) | (q & 1);
        const int cy = (ref.cy << 1) | (q >> 1);
        if ((cx << shift) > r.x1 || (((cx + 1) << shift) - 1) < r.x0) continue;
        if ((cy << shift) > r.y1 || (((cy + 1) << shift) - 1) < r.y0) continue;
        const int child = LevelOffset(childLevel) + (cy << childLevel) + cx;
        if (subtree_[child] == 0) continue;
        for (int k = start_[child]; k < start_[child + 1]; ++k) TestPair(i, items_[k], aabbs, movable, out);
        if (childLevel < depth_) stack_.push_back({childLevel, cx, cy});
      }
    }
  }

  static void TestPair(int i, int j, std::span<const AABB> aabbs, std::span<const uint8_t> movable,
                       std::vector<CandidatePair>& out) {
    if (!(movable[i] | movable[j])) return;
    if (!Overlaps(aabbs[i], aabbs[j])) return;
    out.push_back(i < j ? CandidatePair{i, j} : CandidatePair{j, i});
  }

  bool queryReady_ = false;
  AABB root_{};  // BuildForQueries: the box of every body
  mutable std::vector<NodeRef> queryStack_;  // queries are not run concurrently (world.h)
  int maxDepth_;
  int depth_ = 0;
  int nodeCount_ = 1;
  int firstLeaf_ = 0;
  double originX_ = 0, originY_ = 0, scale_ = 1;
  std::vector<int> node_;
  std::vector<CellRange> range_;
  std::vector<int> start_, fill_, subtree_, items_;
  WorkerLists<CandidatePair> perWorker_;  // per worker, apart (worker_lists.h)
  WorkerLists<NodeRef> stacks_;
};

}  // namespace

std::unique_ptr<BroadPhase> MakeQuadTree(int maxDepth) { return std::make_unique<QuadTree>(maxDepth); }

}  // namespace quadrant
