// The greedy colouring of the constraint graph (constraint_graph.h says what and why).
#include "constraint_graph.h"

#include <algorithm>
#include <bit>

namespace quadrant {

void ConstraintGraph::Color(StageRunner& run, const StepContext& ctx, bool clearLater) {
  const Bodies& bodies = *ctx.bodies;
  const int m = static_cast<int>(ctx.contacts.size());
  bodyColors_.resize(bodies.Count(), 0);  // all zero between steps
  ends_.resize(m);
  colorOf_.resize(m);
  // The colouring is a function of the sequence of dynamic ends alone, so where that sequence is
  // last step's (a pile at rest keeps its contacts, in key order), last step's colouring is this
  // step's, bit for bit, and the serial pass is skipped. The gather compares as it goes (each
  // block counts its changed entries; ends_ keeps last step's until overwritten here).
  const bool comparable = m == lastCount_ && m > 0;
  changed_.assign(size_t(run.Workers()), 0);
  run.For(Stage::kSolve, m, run.MinHeavyItems(), [&](int begin, int end, int worker) {
    int changed = 0;
    for (int c = begin; c < end; ++c) {
      const int a = ctx.contacts[c].a, b = ctx.contacts[c].b;
      const std::pair<int, int> e{bodies.inv[a].invMass > 0 ? a : -1, bodies.inv[b].invMass > 0 ? b : -1};
      changed += comparable && e != ends_[c] ? 1 : 0;
      ends_[c] = e;
    }
    changed_[size_t(worker)] += changed;
  });
  lastCount_ = m;
  bool same = comparable;
  for (int changed : changed_) same = same && changed == 0;
  ++colorings_;
  if (same) {
    ++reused_;
    return;  // order_ and colorStart_ are last step's; the body masks were cleared after it
  }
  run.Serial(Stage::kSolve, [&] {
    int counts[kColors + 1] = {};
    for (int c = 0; c < m; ++c) {
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
  });
  if (m > 0 && !clearLater) {  // leave the masks zeroed for the next step
    run.For(Stage::kSolve, bodies.Count(), run.MinItems(), [&](int begin, int end, int) {
      std::fill(bodyColors_.begin() + begin, bodyColors_.begin() + end, uint64_t(0));
    });
  }
}

}  // namespace quadrant
