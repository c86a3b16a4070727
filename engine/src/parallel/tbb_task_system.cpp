// A task system on oneTBB (Debian's libtbb-dev), built only with -DQUADRANT_TBB=ON: the
// candidate measured against the purpose-built pool (thread_pool.cpp) under the same load.
//
// The partition is the pool's: tbb::parallel_for runs over block indices 0..threads-1 (grain 1,
// simple_partitioner, so every block is one task) and each block covers the same range
// BlockBegin gives, so per-block outputs and hence state hashes are identical to the pool's.
// TBB's workers steal blocks (no block is bound to a thread) and its arena is limited to
// `threads` threads, the caller included. TBB propagates an exception thrown by a block to the
// caller, and a nested ParallelFor is allowed.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>
#include <tbb/task_arena.h>

#include "quadrant/task_system.h"

namespace quadrant {
namespace {

class TbbTaskSystem final : public TaskSystem {
 public:
  explicit TbbTaskSystem(int threads) : workers_(threads), arena_(threads) {}
  int WorkerCount() const override { return workers_; }
  void ParallelFor(int count, const RangeFn& fn) override {
    if (count <= 0) return;
    arena_.execute([&] {
      tbb::parallel_for(
          tbb::blocked_range<int>(0, workers_, 1),
          [&](const tbb::blocked_range<int>& r) {
            for (int b = r.begin(); b < r.end(); ++b) {
              const int begin = BlockBegin(count, workers_, b), end = BlockBegin(count, workers_, b + 1);
              if (begin < end) fn(begin, end, b);
            }
          },
          tbb::simple_partitioner());
    });
  }

 private:
  int workers_;
  tbb::task_arena arena_;
};

}  // namespace

std::unique_ptr<TaskSystem> MakeTbbTaskSystem(int threadCount) { return std::make_unique<TbbTaskSystem>(threadCount); }

}  // namespace quadrant
