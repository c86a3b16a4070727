// Quadrant: the task system interface. The world runs every parallel stage through it.
//
// Contract (what the engine relies on, and what a replacement must honour):
// - ParallelFor(count, fn) calls fn(begin, end, worker) for the blocks of a static partition of
//   [0, count) into WorkerCount() contiguous blocks, block w on worker index w, and returns
//   when every call has returned. Block boundaries are count * w / WorkerCount().
// - Worker 0 is the calling thread. Calls never nest.
// - The partition depends only on count and WorkerCount(), so per-worker outputs concatenated
//   in worker order are the same sequence whatever the thread count: that is how the
//   deterministic scheme stays bit-identical from 1 to N threads.
#pragma once

#include <functional>
#include <memory>

namespace quadrant {

class TaskSystem {
 public:
  using RangeFn = std::function<void(int begin, int end, int worker)>;
  virtual ~TaskSystem() = default;
  /// Threads that run blocks, the caller included (>= 1).
  virtual int WorkerCount() const = 0;
  virtual void ParallelFor(int count, const RangeFn& fn) = 0;
};

/// A pool of threadCount - 1 worker threads plus the caller. Workers spin (yielding) for a
/// short while after each block and then sleep on a condition variable, so back-to-back
/// stages start within microseconds while an idle or oversubscribed pool costs no CPU.
/// threadCount 1 runs everything inline with no threading at all.
std::unique_ptr<TaskSystem> MakeThreadPool(int threadCount);

/// First and one-past-last index of block `worker` of `count` items over `workers` blocks.
inline int BlockBegin(int count, int workers, int worker) {
  return static_cast<int>((static_cast<long long>(count) * worker) / workers);
}

}  // namespace quadrant
