// The soft step's bundles (soft_step.h): the rows of a sparse scene, or of a pile of small
// islands, run bundle by bundle.
//
// Contract: from 4 threads on, where the rows fall into many contact islands (connected through
// dynamic bodies; static, kinematic and sleeping bodies are only read), FindIslands deals the
// islands in contact order into bundles of about kBundlesPerWorker a thread, on another thread
// while the colouring's greedy pass runs (where the colouring is kept, so are the islands); a
// pile (more rows than half the bodies, so no free bodies to even the bundles out) only where its
// largest island fits in a bundle, as many_pyramids' 400 pyramids on their shelves do; then
// ApplyBundles orders each colour's rows by bundle (ConstraintGraph::SetBundles) and BuildRows
// lays each bundle's rows of a colour into groups of their own (LayOutBundleGroups: a group never
// mixes bundles). The sub-steps' regions run as one, bundle by bundle (RunRegionByBundle): a
// thread takes a bundle through every stage of every sub-step, its bodies' passes and its groups
// colour by colour, with no barrier between them; the free bodies' blocks are taken after the
// bundles. The passes after the sub-steps run bundle by bundle too, a region each. The bits are
// the ones colour by colour gives: a bundle shares no dynamic body with another, each body meets
// its rows in colour order and its integrations in pass order either way, and a row's lane never
// changes its arithmetic (soft_rows.h). Only where no row needs the whole world at once: no
// joints, no state exchange, no Box2D position pass or bounce, no overflow colour, no moving
// kinematic body (its state is integrated by one bundle and read by any other).
//
// Why: colour by colour a sparse scene's rows cost a barrier per colour and pass, and beside the
// free bodies (StageRunner::Beside) they ran on one thread: 64000 circles, 1274 contacts, the lone
// part took 1.05 ms of a 6.2 ms step, which capped the solve stage at about 1.9x at any thread
// count (tools/quadrant scaling: 3.29x predicted for the step at 8 threads, 3.98-4.38x with
// bundles; polygons 16000 2.63x -> 3.38-3.91x, 78 -> 30 barriers a step). The cost: a bundle's
// last group of each colour is padded, and the islands' union-find is a serial pass over the
// contacts (cache misses on the bodies' records: 71 us for 64000 circles' 1366 contacts, 121 us
// for 64000 polygons' 3079, prefetched; one core of a 2-core VM), beside the greedy colouring,
// itself such a pass, where the colouring is not kept, and not run where it is. Piles:
// many_pyramids 22000 (400 islands) 99 -> 13 barriers a step at 4-16 threads, the model's
// 16-thread speed-up 9.0x -> 12.7x (unmeasured on 16 cores); its one big island keeps the
// pyramid on the colour by colour path.
#include <algorithm>

#include "dynamics/soft_step.h"

namespace quadrant {
namespace {

// Bundles per thread: enough for the threads to even out islands of different sizes, few enough
// that the padding of each bundle's last group per colour stays small.
constexpr int kBundlesPerWorker = 3;
// Blocks of the free bodies' pass per thread, beside the first region's bundles; with the bundles
// at most 4 a thread (StageChunks), so each chunk is one bundle or one block.
constexpr int kFreeBlocksPerWorker = 1;
// From this many threads: on 2 (a 2-core VM, seven interleaved pairs each) the bundles cost more
// than the lone part beside the free bodies (solve stage, 64000 circles 1.18 -> 1.29 ms a step,
// 16000 circles 0.215 -> 0.277, polygons 64000 1.77 -> 2.08, the free bodies' pass moved into
// it): finding the islands is a serial 0.1-0.15 ms there, and two threads gain little from the
// barriers saved. The scaling model's gain is from 4 threads on (the head of this file).
constexpr int kMinBundleWorkers = 4;
// The fewest rows worth a bundle of their own (a few microseconds of sub-steps).
constexpr int kMinBundleRows = 32;

}  // namespace

bool SoftStepSolver::MayBundle(const StageRunner& run, const StepContext& ctx, bool box2dRestitution) const {
  const WorldDef& def = *ctx.def;
  const int64_t m = static_cast<int64_t>(ctx.contacts.size());
  return run.Workers() >= kMinBundleWorkers && m >= 2 * kMinBundleRows && !exchange_ && ctx.joints.empty() &&
         !def.box2dPositionSolve && !box2dRestitution && !kinematicInRows_.flag.load(std::memory_order_relaxed);
}

// Only Color's gather has run: the contacts' dynamic ends (ConstraintGraph::Ends) are all it reads,
// while the greedy pass writes the colour order beside it.
void SoftStepSolver::FindIslands(const StepContext& ctx, int workers) {
  const int m = static_cast<int>(ctx.contacts.size());
  // The islands are a function of the ends' sequence and the threads: where the colouring kept
  // last step's (the same ends) and last step found them for as many threads, they are its.
  islandsKept_ = graph_.Kept() && islandsFor_ == workers;
  if (islandsKept_) return;
  islandsFor_ = workers;
  int bundles = 0;
  bundleNodes_.resize(size_t(ctx.bodies->Count()));  // parent and island -1 between steps
  BundleNode* node = bundleNodes_.data();
  auto find = [node](int x) {
    while (node[x].parent != x) {
      node[x].parent = node[node[x].parent].parent;  // path halving
      x = node[x].parent;
    }
    return x;
  };
  // The ends' records a few contacts ahead: the bodies of a sparse scene's contacts lie far
  // apart, and each record is a cache miss otherwise. Inlined by force: GCC 12 finds a lambda
  // that only prefetches free of side effects and deletes its calls (no prefetch was emitted).
  constexpr int kAhead = 16;
  auto prefetch = [&](int c) __attribute__((always_inline)) {
    if (c >= m) return;
    const auto [a, b] = graph_.Ends(c);
    if (a >= 0) __builtin_prefetch(&node[a], 1);
    if (b >= 0) __builtin_prefetch(&node[b], 1);
  };
  for (int c = 0; c < m; ++c) {
    prefetch(c + kAhead);
    const auto [a, b] = graph_.Ends(c);
    if (a >= 0 && node[a].parent < 0) node[a].parent = a;
    if (b >= 0 && node[b].parent < 0) node[b].parent = b;
    if (a >= 0 && b >= 0) {
      const int ra = find(a), rb = find(b);
      if (ra != rb) node[std::max(ra, rb)].parent = std::min(ra, rb);
    }
  }
  // Islands numbered in contact order; a contact with no dynamic end writes nothing and may go
  // anywhere (bundle 0).
  islandRows_.clear();
  bundleOfContact_.resize(size_t(m));
  for (int c = 0; c < m; ++c) {
    prefetch(c + kAhead);
    const auto [a, b] = graph_.Ends(c);
    const int x = a >= 0 ? a : b;
    if (x < 0) {
      bundleOfContact_[size_t(c)] = -1;
      continue;
    }
    int& island = node[find(x)].island;
    if (island < 0) {
      island = static_cast<int>(islandRows_.size());
      islandRows_.push_back(0);
    }
    ++islandRows_[size_t(island)];
    bundleOfContact_[size_t(c)] = island;
  }
  // Islands dealt in order into bundles of at least `target` rows.
  const int target = std::max(kMinBundleRows, (m + kBundlesPerWorker * workers - 1) / (kBundlesPerWorker * workers));
  // A pile (more rows than half the bodies) only where every island fits in a bundle: it has no
  // free bodies to even out a bundle that holds more than a thread's share.
  const bool uneven = 2 * int64_t(m) > ctx.bodies->Count() && !islandRows_.empty() &&
                     *std::max_element(islandRows_.begin(), islandRows_.end()) > target;
  bundleOfIsland_.resize(islandRows_.size());
  int rows = 0;
  for (size_t i = 0; i < islandRows_.size(); ++i) {
    bundleOfIsland_[i] = bundles;
    rows += islandRows_[i];
    if (rows >= target) {
      ++bundles;
      rows = 0;
    }
  }
  bundles += rows > 0 ? 1 : 0;
  // Each contact's and each body's bundle; the union-find back to -1 for the next step (every
  // root is an end of some contact).
  for (int c = 0; c < m; ++c) {
    prefetch(c + kAhead);
    int& bundle = bundleOfContact_[size_t(c)];
    bundle = bundle < 0 ? 0 : bundleOfIsland_[size_t(bundle)];
    const auto [a, b] = graph_.Ends(c);
    for (const int x : {a, b}) {
      if (x >= 0) node[x] = BundleNode{-1, -1, bundle};
    }
  }
  islandBundles_ = uneven ? 0 : bundles;
}

void SoftStepSolver::ApplyBundles(StageRunner& run) {
  bundles_ = 0;
  const bool appliedLast = bundlesApplied_;
  bundlesApplied_ = bundlesKept_ = false;
  if (islandBundles_ < 2 || graph_.Overflowed()) {
    graph_.ClearBundles();
    return;
  }
  // Where the colouring and the islands are last step's and last step applied them, the colour
  // order, its bundles' ranges and the rows' layout are last step's too: a pile at rest (on
  // many_pyramids 22000 the two serial passes took 0.2 and 0.1 ms a step on a 2-core VM).
  bundlesKept_ = islandsKept_ && appliedLast && graph_.Bundles() == islandBundles_;
  if (!bundlesKept_) run.Serial(Stage::kSolve, [&] { graph_.SetBundles(bundleOfContact_, islandBundles_); });
  bundles_ = islandBundles_;
  bundlesApplied_ = true;
}

// BuildRows' layout with bundles: colour by colour as without, and within a colour bundle by
// bundle, each bundle's rows in groups of their own (its last one padded).
void SoftStepSolver::LayOutBundleGroups() {
  if (bundlesKept_) return;  // last step's (ApplyBundles)
  constexpr int kColors = ConstraintGraph::kColors;
  const size_t stride = size_t(bundles_) + 1;
  groupStart_.assign(kColors + 2, 0);
  bundleGroupStart_.assign(size_t(kColors) * stride, 0);
  groupRowBegin_.clear();
  groupRowEnd_.clear();
  int g = 0;
  for (int color = 0; color < kColors; ++color) {
    groupStart_[size_t(color)] = g;
    int* start = &bundleGroupStart_[size_t(color) * stride];
    for (int k = 0; k < bundles_; ++k) {
      start[k] = g;
      const int end = graph_.BundleBegin(color, k + 1);
      for (int r = graph_.BundleBegin(color, k); r < end; r += kGroupRows, ++g) {
        groupRowBegin_.push_back(r);
        groupRowEnd_.push_back(std::min(r + kGroupRows, end));
      }
    }
    start[bundles_] = g;
  }
  groupStart_[kColors] = groupStart_[kColors + 1] = g;  // no overflow colour (ApplyBundles)
}

// The queued region (BeginRegion .. EndRegion) bundle by bundle: each stage's items that belong
// to the bundle, in stage order. A stage over groups may span several colours (PlanPassStages
// joins small ones): the bundle's groups of each, in colour order.
void SoftStepSolver::RunRegionByBundle(StageRunner& run) {
  constexpr int kColors = ConstraintGraph::kColors;
  const int stages = static_cast<int>(regionPlan_.size());
  if (stages == 0) return;
  const size_t stride = size_t(bundles_) + 1;
  // The free bodies' blocks after the bundles: the caller claims from the front, and the bundles
  // (uneven) are better started first.
  const int freeBlocks = freeCount_ > 0 ? std::min(kFreeBlocksPerWorker * run.Workers(), (freeCount_ + kBodyGrain - 1) / kBodyGrain) : 0;
  // One item a claim (runs = false), as StageRunner::Beside: a thread that took several bundles
  // at once held work the others could have run meanwhile.
  const TaskSystem::StagePlan plan[1] = {{bundles_ + freeBlocks, 1, false}};
  run.Stages(Stage::kSolve, plan, 2, [&](int, int kb, int ke) {
    for (int k = kb; k < ke; ++k) {
      if (k >= bundles_) {
        const int b = BlockBegin(freeCount_, freeBlocks, k - bundles_), e = BlockBegin(freeCount_, freeBlocks, k - bundles_ + 1);
        if (b < e) MoveFreeBodies(*freePass_.bodies, *freePass_.def, freePass_.dt, b, e);
        continue;
      }
      for (int s = 0; s < stages; ++s) {
        const int first = regionFirst_[size_t(s)], end = first + regionPlan_[size_t(s)].count;
        const std::function<void(int, int)>& fn = regionFns_[size_t(regionPass_[size_t(s)])];
        if (regionOnBodies_[size_t(s)] != 0) {
          const int lo = std::max(first, bundleBodyStart_[size_t(k)]), hi = std::min(end, bundleBodyStart_[size_t(k) + 1]);
          if (lo < hi) fn(lo, hi);
          continue;
        }
        int color = static_cast<int>(std::upper_bound(groupStart_.begin(), groupStart_.begin() + kColors + 1, first) -
                                     groupStart_.begin()) - 1;
        for (; color < kColors && groupStart_[size_t(color)] < end; ++color) {
          const int* start = &bundleGroupStart_[size_t(color) * stride];
          const int gb = std::max(first, start[k]), ge = std::min(end, start[k + 1]);
          if (gb < ge) fn(gb, ge);
        }
      }
    }
  });
  freeCount_ = 0;  // run once
}

}  // namespace quadrant
