// Quadrant: the task system interface. The world runs every parallel stage through it.
//
// Contract (what the engine relies on, and what a replacement must honour):
// - ParallelFor(count, fn) calls fn(begin, end, block) once for each non-empty block of a
//   static partition of [0, count) into WorkerCount() contiguous blocks, and returns when every
//   call has returned. Block boundaries are count * b / WorkerCount() (BlockBegin).
// - Which thread runs a block is not fixed: any thread of the pool, the caller included, may
//   claim any block, so no block waits for a thread the OS has not scheduled. The third
//   argument is the block index, never a thread identity: use it to pick a per-block output.
// - The partition depends only on count and WorkerCount(), so per-block outputs concatenated
//   in block order are the same sequence whatever the thread count: that is how the
//   deterministic scheme stays bit-identical from 1 to N threads.
// - If fn throws, blocks not yet started are skipped and the first exception is rethrown to
//   the caller once every started block has returned; the task system stays usable.
// - A ParallelFor called from inside a block runs inline on that thread, block by block.
#pragma once

#include <functional>
#include <memory>

namespace quadrant {

class TaskSystem {
 public:
  using RangeFn = std::function<void(int begin, int end, int block)>;
  virtual ~TaskSystem() = default;
  /// Threads that run blocks, the caller included (>= 1); also the number of blocks.
  virtual int WorkerCount() const = 0;
  virtual void ParallelFor(int count, const RangeFn& fn) = 0;
};

/// A pool of threadCount - 1 worker threads plus the caller, which claim blocks from a shared
/// counter. On a quiet machine waiting threads spin up to 1 ms, so back-to-back stages start
/// within microseconds; once a spinner is seen to be descheduled (another process wants the
/// cores) they wait on a futex instead, so the pool never takes a core from the thread it waits
/// for. threadCount 1 runs everything inline with no threading at all.
std::unique_ptr<TaskSystem> MakeThreadPool(int threadCount);

/// First index of block `worker` of `count` items over `workers` blocks (the block's end is
/// BlockBegin(count, workers, worker + 1)).
inline int BlockBegin(int count, int workers, int worker) {
  return static_cast<int>((static_cast<long long>(count) * worker) / workers);
}

}  // namespace quadrant
