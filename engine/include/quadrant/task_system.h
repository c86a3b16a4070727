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
// - ParallelStages(stages, plan, fn) runs stage 0, then stage 1, ... in order (every call of a
//   stage returns before any call of the next begins), each stage's [0, plan[s].count) cut into
//   StageChunks(plan[s].count, plan[s].grain, WorkerCount()) contiguous chunks, fn(stage, begin,
//   end, chunk) once per run of consecutive chunks (a run may be one chunk or several; `chunk`
//   is its first, [begin, end) all of its items; one chunk where StagePlan::runs is false),
//   every chunk in exactly one run. It is for stages whose items are independent of each other
//   (a solver colour's constraints, a body range): which thread runs a chunk is never fixed, and
//   a pool may run a whole region on the caller alone, so fn's results must not depend on who
//   runs it. One region costs one hand-over to the workers, however many stages it has.
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
  /// Threads that actually run blocks, the caller included: at most WorkerCount(), fewer when a
  /// pool starts no more threads than the process has cores.
  virtual int ThreadCount() const { return WorkerCount(); }
  virtual void ParallelFor(int count, const RangeFn& fn) = 0;

  /// One stage of a ParallelStages region: `count` items, at least `grain` of them a chunk
  /// (grain >= count keeps the stage on one thread).
  struct StagePlan {
    int count = 0;
    int grain = 1;
    /// Whether a thread may take several of the stage's chunks in one claim (one call over their
    /// items; a pool may ignore it). False where the chunks' costs differ by design and each must
    /// go to whichever thread is free (StageRunner::Beside: one chunk is the lone part).
    bool runs = true;
  };
  using StageFn = std::function<void(int stage, int begin, int end, int chunk)>;
  /// Runs `stages` stages in order (see the contract above). The default runs one ParallelFor
  /// over each stage's chunks; the thread pool runs the whole region as one job.
  virtual void ParallelStages(int stages, const StagePlan* plan, const StageFn& fn);

  /// Whether the jobs that the calling thread starts next would all run on it alone (a pool that
  /// found the machine busy, or that could start no worker). The engine asks once per step and
  /// then takes its one-thread path for the whole step, which gives the same results (see the
  /// contract above) without the per-block bookkeeping of the partition. Default: false. The
  /// default pool never runs alone with QUADRANT_POOL_ALONE=0 in the environment (tests that
  /// must exercise the partition on a busy machine set it).
  virtual bool RunsAlone() { return false; }

  /// A step that will run jobs in parallel is about to start (the engine calls it once a step,
  /// after RunsAlone said no). A pool may wake its sleeping workers here, so that they are running
  /// by the step's first job instead of paying their wake-up latency inside it (a game loop steps
  /// and then sleeps to the next frame, longer than any spin). A hint: it changes no result.
  /// Default: nothing.
  virtual void Prepare() {}
};

/// A pool of threadCount blocks run by the caller and up to threadCount - 1 worker threads (no
/// more threads than the process has cores), which claim blocks and chunks from a shared word.
/// On a quiet machine waiting threads spin up to 1 ms, then sleep on a futex. When the caller
/// finds itself waiting on preempted workers (another process wants the cores), it runs the
/// jobs alone for a while (thread_pool.cpp). threadCount 1 runs everything inline with no
/// threading at all; more than 16383 throws std::invalid_argument.
std::unique_ptr<TaskSystem> MakeThreadPool(int threadCount);

/// The chunks ParallelStages cuts a stage of `count` items into: one per `grain` items (at
/// least one), at most four per worker, so that a thread that starts late or is preempted
/// leaves little for the others to wait on, and a claim (one atomic operation) stays cheap
/// against the chunk's work.
inline int StageChunks(int count, int grain, int workers) {
  if (count <= 0) return 0;
  const long long byGrain = (static_cast<long long>(count) + (grain > 1 ? grain : 1) - 1) / (grain > 1 ? grain : 1);
  const long long most = 4LL * (workers > 1 ? workers : 1);
  return static_cast<int>(byGrain < most ? byGrain : most);
}

/// First index of block `worker` of `count` items over `workers` blocks (the block's end is
/// BlockBegin(count, workers, worker + 1)).
inline int BlockBegin(int count, int workers, int worker) {
  return static_cast<int>((static_cast<long long>(count) * worker) / workers);
}

}  // namespace quadrant
