// The greedy colouring of the constraint graph (constraint_graph.h says what and why).
#include "dynamics/constraint_graph.h"

#include <algorithm>
#include <bit>

namespace quadrant {

void ConstraintGraph::Prepare(StageRunner& run, int bodyCount, int m) {
  bodyColors_.resize(bodyCount, 0);  // all zero between steps
  ends_.resize(m);
  colorOf_.resize(m);
  comparable_ = m == lastCount_ && m > 0;
  changed_.assign(size_t(run.Workers()), 0);
}

void ConstraintGraph::Finish(StageRunner& run, int bodyCount, int m, bool clearLater, const std::function<void()>* beside) {
  lastCount_ = m;
  bool same = comparable_;
  for (int changed : changed_) same = same && changed == 0;
  ++colorings_;
  kept_ = same;
  if (same) {
    ++reused_;
    if (beside != nullptr) run.Serial(Stage::kSolve, *beside);
    return;  // order_ and colorStart_ are last step's; the body masks were cleared after it
  }
  auto greedy = [&] {
    int counts[kColors + 1] = {};
    // The ends' masks a few contacts ahead: a sparse scene's contacts join bodies far apart, and
    // each mask is a cache miss otherwise (polygons 64000, 3100 contacts: about 60 ns a contact).
    constexpr int kAhead = 16;
    for (int c = 0; c < m; ++c) {
      if (c + kAhead < m) {
        const auto [pa, pb] = ends_[c + kAhead];
        if (pa >= 0) __builtin_prefetch(&bodyColors_[pa], 1);
        if (pb >= 0) __builtin_prefetch(&bodyColors_[pb], 1);
      }
      const auto [a, b] = ends_[c];
      const uint64_t used = (a >= 0 ? bodyColors_[a] : 0) | (b >= 0 ? bodyColors_[b] : 0);
      const int color = used == ~uint64_t(0) ? kColors : std::countr_one(used);
      colorOf_[c] = color;
      ++counts[color];
      if (color < kColors) {
        if (a >= 0) bodyColors_[a] |= uint64_t(1) << color;
        if (b >= 0) bodyColors_[b] |= uint64_t(1) << color;
      }
    }
    colorStart_.assign(kColors + 2, 0);
    for (int k = 0; k <= kColors; ++k) colorStart_[k + 1] = colorStart_[k] + counts[k];
    order_.resize(m);
    fill_.assign(colorStart_.begin(), colorStart_.end() - 1);
    for (int c = 0; c < m; ++c) order_[fill_[colorOf_[c]]++] = c;
  };
  if (beside == nullptr) {
    run.Serial(Stage::kSolve, greedy);
  } else {  // two items, one a claim: the greedy pass and `beside` on two threads where there are two
    const TaskSystem::StagePlan plan[1] = {{2, 1, false}};
    run.Stages(Stage::kSolve, plan, 2, [&](int, int b, int e) {
      for (int item = b; item < e; ++item) item == 0 ? greedy() : (*beside)();
    });
  }
  if (m > 0 && !clearLater) {  // leave the masks zeroed for the next step
    run.For(Stage::kSolve, bodyCount, run.MinItems(), [&](int begin, int end, int) {
      std::fill(bodyColors_.begin() + begin, bodyColors_.begin() + end, uint64_t(0));
    });
  }
}

void ConstraintGraph::SetBundles(std::span<const int> bundleOfContact, int bundles) {
  bundles_ = bundles;
  const size_t stride = size_t(bundles) + 1;
  bundleStart_.assign(size_t(kColors) * stride, 0);
  bundleFill_.resize(size_t(bundles));
  bundleScratch_.resize(order_.size());
  for (int color = 0; color < kColors; ++color) {
    const int begin = colorStart_[color], end = colorStart_[color + 1];
    int* start = &bundleStart_[size_t(color) * stride];
    // A counting sort of the colour's constraints by bundle, stable.
    for (int i = begin; i < end; ++i) ++start[bundleOfContact[size_t(order_[i])] + 1];
    start[0] = begin;
    for (int k = 0; k < bundles; ++k) start[k + 1] += start[k];
    if (end - begin < 2) continue;
    std::copy(start, start + bundles, bundleFill_.begin());
    for (int i = begin; i < end; ++i) bundleScratch_[size_t(bundleFill_[size_t(bundleOfContact[size_t(order_[i])])]++)] = order_[i];
    std::copy(bundleScratch_.begin() + begin, bundleScratch_.begin() + end, order_.begin() + begin);
  }
}

}  // namespace quadrant
