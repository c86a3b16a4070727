// Runs the step's stages on the task system and measures their load balance.
//
// Every block of every parallel stage is timed. Per stage the runner adds up the total work
// and the critical path (the largest block of each parallel section, all of each serial one);
// work / critical path is the speed-up that the partition allows at this thread count, whatever
// the machine's core count. There are as many blocks as threads, but any thread may run any
// block (task_system.h), so the times are kept per block index, never per thread.
//
// Which clock: with more running threads than cores (TaskSystem::ThreadCount: the default pool
// starts no more threads than cores, oneTBB's arena does), the thread's own CPU clock, so a
// worker preempted in favour of another of the pool is not charged for the wait. That clock is
// a system call: 930 ns a read on the 2-core VMs (steady_clock, read in user space, 39 ns), and
// a step at 2 threads reads it about 190 times: 0.09 ms of a 1.3 ms step of 16000 circles on the
// critical path. With no more threads than cores no worker waits for another of the pool, so
// the wall clock measures the same work and is used. One worker needs no measurement: bound 1.
// A timed block also holds part of the two clock reads around it (for the thread clock about a
// microsecond, a small serial section's whole work): the runner measures a read once (the least
// of 32 back-to-back differences) and subtracts it from every block.
//
// With a StepTrace (step_trace.h, off unless a program asks) the runner also records every
// section it runs, in order, for the scaling model.
#pragma once

#include <time.h>

#include <algorithm>
#include <chrono>
#include <span>
#include <thread>
#include <vector>

#include "parallel/step_trace.h"
#include "quadrant/task_system.h"
#include "quadrant/types.h"

namespace quadrant {

class StageRunner {
 public:
  StageRunner(TaskSystem& tasks, int minParallelItems)
      : tasks_(tasks),
        minItems_(minParallelItems),
        workerMs_(tasks.WorkerCount(), 0.0),
        measure_(tasks.WorkerCount() > 1),
        threadClock_(static_cast<unsigned>(tasks.ThreadCount()) > std::max(1u, std::thread::hardware_concurrency())),
        readMs_(measure_ ? ClockReadMs() : 0.0) {}

  /// Blocks of this step's parallel sections: 1 for a step that runs alone (BeginStep).
  int Workers() const { return alone_ ? 1 : tasks_.WorkerCount(); }
  /// Called at the start of a step: a step whose jobs the task system would run on the caller
  /// alone (TaskSystem::RunsAlone, a busy machine) takes the one-thread path throughout. Running
  /// the two-thread partition serially cost 6 % more time than one thread on 16000 circles and
  /// 3 % on the base-100 pyramid (both pinned to one core, thread_pool.cpp).
  /// Otherwise the task system is told that a step begins (TaskSystem::Prepare: wake the workers).
  ///
  /// A step whose last step's work (every section's, on all threads; Reset) was too small to pay
  /// for the hand-overs and barriers runs alone too: below minParallelItems items at 50 ns (0.1
  /// ms at the default 2048). On the lent 16-core VM 1000 circles (0.08 ms a step) stepped at
  /// 0.85x on 2 threads and 0.78x on 4, while 1000 polygons (0.22 ms) gained 1.25x and 1.13x;
  /// 2000 circles (0.15 ms) gave 1.00x and 0.90x, so the limit does not grow with the threads. A
  /// small step stays alone until its work passes 1.5 times the limit. Tests that lower
  /// minParallelItems to exercise threading on small scenes, and recordings (StepTrace), keep
  /// the partition.
  void BeginStep() {
    const int workers = tasks_.WorkerCount();
    small_ = workers > 1 && trace_ == nullptr && lastWorkMs_ >= 0 &&
             lastWorkMs_ < (small_ ? 1.5 : 1.0) * SmallStepMs();
    alone_ = workers > 1 && (small_ || tasks_.RunsAlone());
    if (!alone_ && workers > 1) tasks_.Prepare();
    begun_ = true;
  }
  /// Whether this step runs alone (BeginStep), and whether because the last one was small.
  bool Alone() const { return alone_; }
  bool SmallStep() const { return small_; }
  /// Sections with fewer items run inline (WorldDef::minParallelItems).
  int MinItems() const { return minItems_; }
  /// The grain for items that cost about ten times a body update (a pair's manifold, a
  /// constraint's preparation, a contact's cache lookup): an eighth of MinItems, so a few
  /// hundred of them already pay for a parallel-for instead of staying on one thread.
  int MinHeavyItems() const { return std::max(1, minItems_ / 8); }

  /// Runs fn(begin, end, block) over [0, count) in parallel when count >= minParallel,
  /// otherwise inline on the caller as one block (block 0). `block` indexes per-block outputs
  /// (Workers() of them); it says nothing about which thread runs the block. Both give the
  /// same results for work whose blocks are independent.
  template <class Fn>
  void For(Stage stage, int count, int minParallel, Fn&& fn) {
    if (count <= 0) return;
    if (nested_) {  // inside Beside's lone part: one block, not timed on its own
      fn(0, count, 0);
      return;
    }
    if (Workers() == 1 || count < std::max(2, minParallel)) {  // one item cannot be split
      Serial(stage, [&] { fn(0, count, 0); });
      return;
    }
    std::fill(workerMs_.begin(), workerMs_.end(), 0.0);
    const double traceMs = trace_ ? StepTrace::Now() : 0.0;
    tasks_.ParallelFor(count, [&](int begin, int end, int block) {
      const double t0 = NowMs();
      fn(begin, end, block);
      workerMs_[block] += Elapsed(t0);
    });
    double sum = 0, largest = 0;
    for (double ms : workerMs_) {
      sum += ms;
      largest = std::max(largest, ms);
    }
    Add(stage, sum, largest);
    if (trace_) [[unlikely]] trace_->AddFor(stage, traceMs, StepTrace::Now(), workerMs_);
  }

  /// Runs the stages of `plan` in order as one region (TaskSystem::ParallelStages): fn(stage,
  /// begin, end) over each stage's items, which must be independent of each other within a
  /// stage. A region of fewer than minParallel items in all runs inline on the caller. The
  /// load-balance bound counts per stage the larger of its largest chunk (or run of chunks that
  /// one thread claimed together, timed as one) and its work shared evenly (chunks are claimed
  /// dynamically, so no thread's share is fixed in advance). A pool that runs a region on the
  /// caller alone (a busy machine) still calls it chunk by chunk.
  template <class Fn>
  void Stages(Stage stage, std::span<const TaskSystem::StagePlan> plan, int minParallel, Fn&& fn) {
    if (nested_) {
      for (int s = 0; s < static_cast<int>(plan.size()); ++s) {
        if (plan[s].count > 0) fn(s, 0, plan[s].count);
      }
      return;
    }
    // `splittable`: the items of the stages that split into two chunks or more. A region whose
    // stages are each one chunk (a sub-step of 1000 circles: 8 stages of a few groups or a few
    // dozen bodies each) gives the other threads nothing to do but wait at every stage's end, so
    // it runs inline like a small one. Measured on circle stress N = 1000 at 2 threads: 3 such
    // regions a step (24 stages, 334 items in all), each a hand-over and 8 barriers.
    long long total = 0, splittable = 0;
    for (const TaskSystem::StagePlan& p : plan) {
      total += p.count;
      if (StageChunks(p.count, p.grain, Workers()) > 1) splittable += p.count;
    }
    if (total <= 0) return;
    const int stages = static_cast<int>(plan.size());
    if (Workers() == 1 || total < std::max<long long>(2, minParallel) || splittable < minParallel) {
      Serial(stage, [&] {
        for (int s = 0; s < stages; ++s) {
          if (plan[s].count > 0) fn(s, 0, plan[s].count);
        }
      });
      return;
    }
    if (!measure_) {
      tasks_.ParallelStages(stages, plan.data(), [&](int s, int b, int e, int) { fn(s, b, e); });
      return;
    }
    chunkOffset_.resize(stages + 1);
    chunkOffset_[0] = 0;
    for (int s = 0; s < stages; ++s) {
      chunkOffset_[s + 1] = chunkOffset_[s] + std::max(1, StageChunks(plan[s].count, plan[s].grain, Workers()));
    }
    chunkMs_.assign(chunkOffset_[stages], 0.0);
    const double traceMs = trace_ ? StepTrace::Now() : 0.0;
    tasks_.ParallelStages(stages, plan.data(), [&](int s, int b, int e, int chunk) {
      const double t0 = NowMs();
      fn(s, b, e);
      // (A task system that calls a whole stage at once passes chunk 0.)
      chunkMs_[chunkOffset_[s] + std::min(chunk, chunkOffset_[s + 1] - chunkOffset_[s] - 1)] += Elapsed(t0);
    });
    double work = 0, critical = 0;
    for (int s = 0; s < stages; ++s) {
      double sum = 0, largest = 0;
      for (int c = chunkOffset_[s]; c < chunkOffset_[s + 1]; ++c) {
        sum += chunkMs_[c];
        largest = std::max(largest, chunkMs_[c]);
      }
      work += sum;
      critical += std::max(largest, sum / Workers());
    }
    Add(stage, work, critical);
    if (trace_) [[unlikely]] trace_->AddRegion(stage, traceMs, StepTrace::Now(), plan, chunkMs_, chunkOffset_);
  }

  /// fn(begin, end) over [0, count) as one stage of Stages: chunks of at least `grain` items that
  /// the threads claim as they go, for a pass whose items write nothing another item reads and
  /// that needs no per-block output. Why: For's static blocks (one a worker) finish apart by
  /// whatever their items, or their cores, differ in speed, and on these shared VMs one core often
  /// runs slower for a while. The soft step's per-body passes (base-100 pyramid, 2 threads, 2-core
  /// VM, rdtsc; BuildRows' region the same in both): 107-153 us a step with static blocks,
  /// 108-129 us claimed dynamically: the gain where a core ran slow, the quietest case equal.
  template <class Fn>
  void Dynamic(Stage stage, int count, int minParallel, int grain, Fn&& fn) {
    const TaskSystem::StagePlan plan[1] = {{count, grain}};
    Stages(stage, plan, minParallel, [&](int, int begin, int end) { fn(begin, end); });
  }

  /// Runs `alone()` once, on one thread, beside fn(begin, end) over [0, count) in blocks that
  /// the other threads (and that one, once it is done) take: one region of one stage, so the
  /// two parts cost one hand-over and one join together. alone() may call this runner again
  /// (For, Stages, Serial): there every call runs inline on its thread, as one block, and is
  /// timed as part of alone(). alone() and fn must not touch the same data. Under
  /// minParallel items, or on one worker, both run on the caller, alone() first (and alone()'s
  /// own calls then split as they would anywhere else).
  ///
  /// Why: a part of the step too small to split well (a few hundred contact rows) gains nothing
  /// from the threads, and each of its passes split across them costs a barrier; beside an
  /// independent pass over many bodies it runs on one thread while the others do that pass.
  template <class Alone, class Fn>
  void Beside(Stage stage, Alone&& alone, int count, int minParallel, Fn&& fn) {
    if (Workers() == 1 || nested_ || count < std::max(2, minParallel)) {
      alone();  // its own calls of this runner split and time themselves
      if (count > 0) Serial(stage, [&] { fn(0, count); });
      return;
    }
    // Item 0 is alone(), items 1.. the blocks: one item a chunk (StageChunks' most, 4 a worker).
    // The caller claims from the front (thread_pool.cpp), so it takes alone() unless a worker
    // is there first.
    const int items = 4 * Workers(), blocks = items - 1;
    // One item a claim (runs = false): in a run of two the thread that took alone() would also
    // hold a block the others could have run meanwhile (circle stress 16000, 2 threads, 2-core VM:
    // the solve stage 0.138 ms a step, 0.155 ms with runs).
    const TaskSystem::StagePlan plan{items, 1, false};  // one stage: no list to allocate every step
    chunkMs_.assign(items, 0.0);
    const double traceMs = trace_ ? StepTrace::Now() : 0.0;
    tasks_.ParallelStages(1, &plan, [&](int, int b, int e, int) {
      for (int item = b; item < e; ++item) {
        const double t0 = measure_ ? NowMs() : 0.0;
        if (item == 0) {
          nested_ = true;  // only the thread running alone() reads it until the join
          try {
            alone();
          } catch (...) {
            nested_ = false;
            throw;
          }
          nested_ = false;
        } else {
          const int begin = BlockBegin(count, blocks, item - 1), end = BlockBegin(count, blocks, item);
          if (begin < end) fn(begin, end);
        }
        if (measure_) chunkMs_[item] = Elapsed(t0);
      }
    });
    if (!measure_) return;
    double sum = 0, largest = 0;
    for (double ms : chunkMs_) {
      sum += ms;
      largest = std::max(largest, ms);
    }
    Add(stage, sum, std::max(largest, sum / Workers()));
    if (trace_) [[unlikely]] trace_->AddRegion(stage, traceMs, StepTrace::Now(), {&plan, 1}, chunkMs_, std::array{0, items});
  }

  /// Runs fn on the calling thread; all of it is on the critical path.
  template <class Fn>
  void Serial(Stage stage, Fn&& fn) {
    if (nested_) {
      fn();
      return;
    }
    const double traceMs = trace_ ? StepTrace::Now() : 0.0;
    if (!measure_) {
      fn();
    } else {
      const double t0 = NowMs();
      fn();
      const double ms = Elapsed(t0);
      Add(stage, ms, ms);
    }
    if (trace_) [[unlikely]] trace_->AddSerial(stage, traceMs, StepTrace::Now());
  }

  /// Called before each step's BeginStep: keeps the finished step's work for it, then clears.
  void Reset() {
    double work = 0;
    for (const StageBalance& b : balance_) work += b.workMs;
    lastWorkMs_ = begun_ && measure_ ? work : -1.0;
    balance_ = {};
  }
  const std::array<StageBalance, kStageCount>& Balance() const { return balance_; }

 private:
  double NowMs() const {
    if (threadClock_) {
      timespec ts;
      clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
      return double(ts.tv_sec) * 1e3 + double(ts.tv_nsec) * 1e-6;
    }
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
  }
  // Milliseconds since t0, less the cost of one clock read.
  double Elapsed(double t0) const { return std::max(0.0, NowMs() - t0 - readMs_); }
  double ClockReadMs() const {
    double least = 1e9;
    for (int k = 0; k < 32; ++k) {
      const double a = NowMs();
      least = std::min(least, NowMs() - a);
    }
    return least;
  }

  double SmallStepMs() const {
    constexpr double kItemMs = 50e-6;
    return double(minItems_) * kItemMs;
  }

  void Add(Stage stage, double work, double critical) {
    balance_[size_t(stage)].workMs += work;
    balance_[size_t(stage)].criticalMs += critical;
  }

  TaskSystem& tasks_;
  int minItems_;
  std::vector<double> workerMs_;  // per block index
  std::vector<int> chunkOffset_;  // Stages: the first chunk slot of each stage
  std::vector<double> chunkMs_;   // Stages: per chunk
  bool alone_ = false;  // this step runs on the caller alone (BeginStep)
  bool small_ = false;  // ... because the last step's work was below SmallStepMs
  double lastWorkMs_ = -1;  // the last step's work (Reset); -1: none measured yet
  bool begun_ = false;      // a step has begun since the runner was made
  bool nested_ = false;  // inside Beside's alone(): every call runs inline, untimed
  bool measure_;      // more than one worker: a single one's bound is 1 by definition
  bool threadClock_;  // more workers than cores: time blocks by thread CPU time
  double readMs_;     // the cost of one clock read, subtracted from every timed block
  StepTrace* trace_ = stepTraceSink;  // where each section is recorded (step_trace.h); usually none
  std::array<StageBalance, kStageCount> balance_{};
};

}  // namespace quadrant
