// The constraint graph: the contacts coloured so that no two of one colour share a dynamic body,
// and the passes that walk them colour by colour. Held by the solvers that solve contacts in
// parallel (pgs, soft_step) beside their contact constraints (contact_constraints.h).
//
// Parallelism: constraints are coloured greedily (in contact order) so that no two of one
// colour share a dynamic body, and solved colour by colour. Within a colour the constraints
// are independent, so splitting a colour across threads gives exactly the serial result: the
// solve is bit-identical for any thread count. Static and kinematic bodies are read, never
// written, so they do not constrain the colouring (as in Box2D 3's constraint graph).
#pragma once

#include <algorithm>
#include <cstdint>
#include <functional>
#include <span>
#include <utility>
#include <vector>

#include "dynamics/solver.h"
#include "parallel/stage_runner.h"

namespace quadrant {

class ConstraintGraph {
 public:
  // Colours beyond this share one overflow group solved on one thread (rare: a body would
  // need 64 simultaneous contacts).
  static constexpr int kColors = 64;

  // Chunks of kColorGrain constraints (a few microseconds) are what ForEachColor's threads
  // claim dynamically.
  static constexpr int kColorGrain = 64;

  // Greedy colouring in contact order (deterministic): each constraint takes the lowest colour
  // that neither of its dynamic bodies has yet. Then the constraints' order is grouped by colour:
  // the k-th constraint in colour order is contact ContactOf(k).
  //
  // The greedy pass is inherently serial (a constraint's colour depends on every earlier one
  // that shares a body), so everything else is moved out of it: the contacts' dynamic ends are
  // gathered in parallel first (the serial loop then reads 8 bytes per contact, in order, not
  // the contact and both bodies' masses), and the body masks are cleared in parallel after.
  // clearLater: the caller clears the body masks (ClearColors) in a pass of its own over the
  // bodies before the next step, instead of a pass here.
  void Color(StageRunner& run, const StepContext& ctx, bool clearLater = false) {
    Color(run, ctx, clearLater, [](int, int) {});
  }
  // The same, calling onEnds(a, b) for every contact from the parallel gather of its dynamic ends
  // (a body index, or -1 for an end that is static, kinematic or asleep), on any worker, in no
  // particular order: a solver marks its per-body flags there instead of in a pass of its own.
  //
  // The colouring is a function of the sequence of dynamic ends alone, so where that sequence is
  // last step's (a pile at rest keeps its contacts, in key order), last step's colouring is this
  // step's, bit for bit, and the serial pass is skipped. The gather compares as it goes (each
  // block counts its changed entries; ends_ keeps last step's until overwritten here).
  //
  // beside (optional): work that needs only the gathered ends (Ends), run on another thread
  // while the greedy pass runs on this one (or after it, where the colouring is kept or there is
  // one worker): the soft step's islands, so their serial pass costs the step nothing more.
  template <class OnEnds>
  void Color(StageRunner& run, const StepContext& ctx, bool clearLater, OnEnds&& onEnds,
             const std::function<void()>* beside = nullptr) {
    const Bodies& bodies = *ctx.bodies;
    const int m = static_cast<int>(ctx.contacts.size());
    Prepare(run, bodies.Count(), m);
    const bool comparable = comparable_;
    run.For(Stage::kSolve, m, run.MinHeavyItems(), [&](int begin, int end, int worker) {
      int changed = 0;
      for (int c = begin; c < end; ++c) {
        const int a = ctx.contacts[c].a, b = ctx.contacts[c].b;
        const std::pair<int, int> e{bodies.inv[a].invMass > 0 ? a : -1, bodies.inv[b].invMass > 0 ? b : -1};
        changed += comparable && e != ends_[c] ? 1 : 0;
        ends_[c] = e;
        onEnds(e.first, e.second);
      }
      changed_[size_t(worker)] += changed;
    });
    Finish(run, bodies.Count(), m, clearLater, beside);
  }

  // Bodies [begin, end)'s colour masks back to zero (Color's clearLater). Bodies made since the
  // last colouring have no mask yet (Finish adds theirs as zeros): the part of the range below
  // them is cleared all the same, or a mask left set would colour the next step otherwise, and
  // differently by how the range was split into chunks.
  void ClearColors(int begin, int end) {
    end = std::min(end, static_cast<int>(bodyColors_.size()));
    if (begin < end) std::fill(bodyColors_.begin() + begin, bodyColors_.begin() + end, uint64_t(0));
  }

  // Contact `contact`'s dynamic ends this step (Color's gather): body indices, -1 for an end
  // that is static, kinematic or asleep.
  std::pair<int, int> Ends(int contact) const { return ends_[size_t(contact)]; }
  // Whether any constraint fell into the overflow colour (kColors) this step.
  bool Overflowed() const { return colorStart_[kColors + 1] > colorStart_[kColors]; }

  // Bundles: disjoint sets of constraints, no dynamic body in two of them (SoftStepSolver's
  // bundles of contact islands). SetBundles orders each colour's constraints by bundle (stably;
  // within a colour the order changes no bit, as no two share a dynamic body), so a bundle's
  // constraints of one colour are [BundleBegin(color, k), BundleBegin(color, k + 1)), and
  // ForEachColor then runs bundle by bundle. Not with an overflow colour (its constraints may
  // share bodies and are solved in order). Until ClearBundles, which every step that does not
  // bundle calls; the order stays (a kept colouring reuses it).
  void SetBundles(std::span<const int> bundleOfContact, int bundles);
  void ClearBundles() { bundles_ = 0; }
  int Bundles() const { return bundles_; }
  int BundleBegin(int color, int k) const { return bundleStart_[size_t(color) * size_t(bundles_ + 1) + size_t(k)]; }

  // The number of constraints coloured, and the contact of the k-th in colour order.
  int Count() const { return static_cast<int>(order_.size()); }
  // Whether this step's colouring is last step's (the ends' sequence unchanged): set before
  // Color's `beside` runs, so it may keep what it derived from the same ends last step.
  bool Kept() const { return kept_; }
  int ContactOf(int k) const { return order_[k]; }
  // Colour `color`'s constraints are [ColorBegin(color), ColorBegin(color + 1)) in colour
  // order; colour kColors is the overflow group, ColorBegin(kColors + 1) == Count().
  int ColorBegin(int color) const { return colorStart_[color]; }

  // fn(begin, end) over every colour's constraints (positions in colour order), colour by
  // colour, `repeat` times over, as one region of stages (StageRunner::Stages): the threads go
  // from colour to colour inside one job instead of being handed one job per colour (a
  // hand-over and a join each, for colours of a few microseconds' work): with pgs's 8 velocity
  // iterations in one region too, the base-100 pyramid went from 71 jobs per step to 26. Chunks
  // of kColorGrain constraints are claimed dynamically. The overflow colour is one chunk (its
  // rows may share bodies: in order, on one thread).
  //
  // With bundles (SetBundles) the colours run bundle by bundle instead: a thread takes a bundle
  // and walks its constraints through every colour (and repeat) alone, with no barrier between
  // colours. The same bits: a bundle's constraints share no dynamic body with another's, and
  // each body meets its constraints in colour order either way.
  template <class Fn>
  void ForEachColor(StageRunner& run, Fn&& fn, int repeat = 1) {
    if (bundles_ > 0) {
      const TaskSystem::StagePlan plan[1] = {{bundles_, 1, false}};  // a bundle a claim
      run.Stages(Stage::kSolve, plan, 2, [&](int, int kb, int ke) {
        for (int k = kb; k < ke; ++k) {
          for (int r = 0; r < repeat; ++r) {
            for (int color = 0; color < kColors; ++color) {
              const int b = BundleBegin(color, k), e = BundleBegin(color, k + 1);
              if (b < e) fn(b, e);
            }
          }
        }
      });
      return;
    }
    stagePlan_.clear();
    stageFirst_.clear();
    const int overflowBegin = colorStart_[kColors], overflow = colorStart_[kColors + 1] - overflowBegin;
    for (int r = 0; r < repeat; ++r) {
      for (int color = 0; color < kColors; ++color) {
        const int count = colorStart_[color + 1] - colorStart_[color];
        if (count == 0) continue;
        stagePlan_.push_back({count, kColorGrain});
        stageFirst_.push_back(colorStart_[color]);
      }
      if (overflow > 0) {
        stagePlan_.push_back({overflow, overflow});
        stageFirst_.push_back(overflowBegin);
      }
    }
    run.Stages(Stage::kSolve, stagePlan_, run.MinHeavyItems() * repeat,
               [&](int s, int b, int e) { fn(stageFirst_[s] + b, stageFirst_[s] + e); });
  }

 private:
  std::vector<uint64_t> bodyColors_;  // per body: the colours its constraints hold (zero between steps)
  std::vector<int> colorOf_, colorStart_, order_, fill_;
  std::vector<TaskSystem::StagePlan> stagePlan_;  // ForEachColor's region: a stage per colour
  std::vector<int> stageFirst_;                   // the first item of each stage
  std::vector<std::pair<int, int>> ends_;         // per contact: its dynamic bodies, -1 for others
  std::vector<int> changed_;                      // per worker: ends that differ from last step's
  int bundles_ = 0;                               // SetBundles; 0: none
  std::vector<int> bundleStart_;                  // per colour (below kColors), per bundle, and one past
  std::vector<int> bundleFill_, bundleScratch_;
  int lastCount_ = -1;                            // the contacts coloured last step (-1: none yet)
  bool comparable_ = false;                       // this step has as many contacts as the last
  bool kept_ = false;                             // this step kept last step's colouring

  void Prepare(StageRunner& run, int bodyCount, int m);
  // After the gather: last step's colouring kept, or the greedy pass; then the masks cleared
  // (unless clearLater).
  void Finish(StageRunner& run, int bodyCount, int m, bool clearLater, const std::function<void()>* beside);

 public:
  // How many colourings were asked for and how many reused last step's (for the tests).
  int64_t colorings_ = 0, reused_ = 0;
};

}  // namespace quadrant
