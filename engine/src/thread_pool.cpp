// The default task system: a small purpose-built pool whose blocks are claimed dynamically.
//
// Why it was rewritten (issue 14). The first pool bound block w of every parallel-for to
// thread w and made the caller wait, spinning for up to 1 ms, for every block. Beside one other
// busy process that collapses. Measured on this 2-core VM with one shell busy loop (the VM also
// carried other users' niced builds, load average 6.5), 60 + 10 steps per run: 16000 circles
// took 3.49 ms per step on 1 thread and 161 ms on 2; the base-100 pyramid 18.1 and 139 ms.
// Timing each parallel-for inside the pool showed where the time went. For the circles, 70
// steps ran 3443 parallel-fors (49 per step); the caller's own blocks took 0.10 s in all and
// its waits for the worker's block 10.0 s, 3211 of the waits longer than 1 ms, the longest
// 9.3 ms. The pyramid: 5667 parallel-fors, own blocks 0.52 s, waits 9.7 s, 2997 over 1 ms.
// (Again at load average 14: circles 4.55 / 5.22 ms, pyramid 15.9 / 143 ms, its waits 8.5 s
// against 0.71 s of own blocks.) So a step waited, dozens of times, for a worker that the
// scheduler was not running: the waits are time slices of other processes, not work. The
// spinning made it worse: a worker spinning 1 ms between sections uses up its fair share of
// the core (CFS charges the spin like work), so when a block arrives it is the thread the
// scheduler preempts, mid-block; and a caller spinning on its core keeps the scheduler from
// moving the waiting worker there.
//
// With this pool, interleaved with the first one and with oneTBB (README) in one run, one busy
// loop, load average 10-19 (first pool / this pool, ms per step at 1, 2, 3, 4 threads):
// circles 16000 3.92 / 4.17, 234 / 4.91, 113 / 3.32, 73.0 / 2.67; pyramid 23.0 / 24.9,
// 681 / 9.49, 445 / 42.9, 34.4 / 9.67. (Under that much foreign load the figures are noisy;
// the busy-machine table of speedup.md is the measurement on an otherwise quiet machine.)
//
// What this pool does instead:
// - Any thread takes any block. Blocks are claimed from one atomic counter (tagged with the job
//   number, so a late worker cannot claim a block of the next job); the caller claims too. A
//   worker that the scheduler has not run simply takes no block: the caller does its share.
//   The block boundaries and the `worker` argument (the block index) stay what they were, so
//   per-block outputs concatenated in block order are unchanged (determinism).
// - Waiting adapts to contention. A spinning thread reads the clock every few pause
//   instructions; a jump of more than kPreemptedMicros between two reads means the scheduler
//   took its core for something else, and a caller whose wait for the other blocks outlasts
//   twice its own blocks plus kMaxSpinMicros means a worker holding one was not running. Either
//   marks the pool contended for kContendedMillis: then no thread spins for long. The caller
//   spins at most as long as its own blocks took, then waits on a futex; a worker between jobs
//   naps kPollMicros at a time and looks for a job (so starting a job costs the caller no
//   system call), and after kPollMillis without one waits on a futex. No spinner takes the core
//   from the thread it waits for, and a napping
//   thread keeps its scheduler credit for the moment it has work. On a quiet machine nothing
//   is ever preempted and waiting is what it was: up to kMaxSpinMicros of pause spinning,
//   because a sleeping worker takes about 100 us to wake on these VMs and a step's serial gaps
//   are of that order (2000 circles at 2 threads: 0.65 ms per step with a 100 us spin, 0.24 ms
//   with 1 ms; 1 thread 0.22, measured with the first pool).
// - An exception thrown by a block is caught, the blocks not yet started are skipped, and the
//   first exception is rethrown to the caller once every started block has finished; the pool
//   stays usable.
// - A ParallelFor called from inside a block runs inline on that thread, block by block (the
//   same partition), instead of deadlocking.
//
// Why not the compiler's OpenMP or oneTBB: benchmarks/task_overhead.cpp measures the cost of
// one parallel-for over 2 threads for this pool and for OpenMP (see the README's table); GCC's
// libgomp is not instrumented for ThreadSanitizer, so the tsan preset would report its internal
// synchronisation as races, while this pool uses only std::atomic and std::mutex.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <exception>
#include <climits>
#include <cstdint>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

#include "quadrant/task_system.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif
#if defined(__linux__)
#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

namespace quadrant {
namespace {

using Clock = std::chrono::steady_clock;

class InlineTaskSystem final : public TaskSystem {
 public:
  int WorkerCount() const override { return 1; }
  void ParallelFor(int count, const RangeFn& fn) override {
    if (count > 0) fn(0, count, 0);
  }
};

// Longest spin on a quiet machine (see the head comment for the measurement behind 1 ms).
constexpr int kMaxSpinMicros = 1000;
// Spin before a futex wait when the pool is contended: about one futex system call.
constexpr int kContendedSpinMicros = 5;
// A gap this long between two clock reads of a spin loop means the spinner was descheduled for
// another thread. The loop reads the clock every 32 pause instructions (1-5 us on x86-64); a
// scheduler time slice is 0.75 ms or more, while interrupts and a VM's short steals are tens of
// microseconds and must not count.
constexpr int kPreemptedMicros = 200;
// How long one sign of contention keeps the pool in futex-waiting mode.
constexpr int kContendedMillis = 200;
// A contended worker between jobs sleeps this long at a time and then looks for a job (plus the
// timer slack, 50 us by default), for up to kPollMillis before it waits on the futex; see Poll.
constexpr int kPollMicros = 50;
constexpr int kPollMillis = 20;

// Sleeps while *word == expected (or returns at once if it differs). Linux: the futex system
// call itself, because libstdc++'s std::atomic::wait first calls sched_yield four times, and a
// yield hands the core to a competing process for its time slice (measured with the first
// pool, which yielded while spinning: 16000 circles at 2 threads beside a nice -n 19 build took
// 5.8 ms per step, 1.2 ms without yields). Elsewhere std::atomic::wait. Callers re-check the word after waking: wake-ups may be spurious.
void WaitWhileEqual(std::atomic<uint32_t>& word, uint32_t expected) {
#if defined(__linux__)
  static_assert(sizeof(std::atomic<uint32_t>) == sizeof(uint32_t));
  syscall(SYS_futex, reinterpret_cast<uint32_t*>(&word), FUTEX_WAIT_PRIVATE, expected, nullptr, nullptr, 0);
#else
  word.wait(expected, std::memory_order_seq_cst);
#endif
}
void WakeAll(std::atomic<uint32_t>& word) {
#if defined(__linux__)
  syscall(SYS_futex, reinterpret_cast<uint32_t*>(&word), FUTEX_WAKE_PRIVATE, INT32_MAX, nullptr, nullptr, 0);
#else
  word.notify_all();
#endif
}

// The pool thread (or caller) that is running a block of some pool right now, for nesting.
thread_local const TaskSystem* tRunning = nullptr;

class ThreadPool final : public TaskSystem {
 public:
  explicit ThreadPool(int threads)
      : workers_(threads),
        oversubscribed_(static_cast<unsigned>(threads) > std::max(1u, std::thread::hardware_concurrency())) {
    threads_.reserve(threads - 1);
    for (int w = 1; w < threads; ++w) threads_.emplace_back([this] { WorkerLoop(); });
  }

  ~ThreadPool() override {
    stop_.store(true, std::memory_order_seq_cst);
    jobWord_.fetch_add(1, std::memory_order_seq_cst);
    WakeAll(jobWord_);
    for (std::thread& t : threads_) t.join();
  }

  int WorkerCount() const override { return workers_; }

  void ParallelFor(int count, const RangeFn& fn) override {
    if (count <= 0) return;
    if (tRunning == this) {  // called from one of this pool's blocks: run inline
      for (int b = 0; b < workers_; ++b) {
        const int begin = BlockBegin(count, workers_, b), end = BlockBegin(count, workers_, b + 1);
        if (begin < end) fn(begin, end, b);
      }
      return;
    }
    // Publish the job: its fields first, then the claim word (release), then the wake word.
    fn_ = &fn;
    count_ = count;
    failed_.store(false, std::memory_order_relaxed);
    remaining_.store(static_cast<uint32_t>(workers_), std::memory_order_relaxed);
    const uint32_t job = ++job_;
    claim_.store(uint64_t(job) << 32, std::memory_order_seq_cst);
    jobWord_.store(job, std::memory_order_seq_cst);
    if (sleepers_.load(std::memory_order_seq_cst) > 0) WakeAll(jobWord_);

    const Clock::time_point start = Clock::now();
    RunBlocks();
    WaitForBlocks(Clock::now() - start);
    fn_ = nullptr;
    if (error_) {
      std::exception_ptr error = std::exchange(error_, nullptr);
      std::rethrow_exception(error);
    }
  }

 private:
  bool Contended(Clock::time_point now) const {
    return oversubscribed_ || now.time_since_epoch().count() < contendedUntil_.load(std::memory_order_relaxed);
  }
  void MarkContended(Clock::time_point now) {
    const auto until = now + std::chrono::milliseconds(kContendedMillis);
    contendedUntil_.store(until.time_since_epoch().count(), std::memory_order_relaxed);
  }

  // Spins until done() or the budget runs out; true if done() became true. Marks the pool
  // contended if the spinner was descheduled while spinning.
  template <class Done>
  bool Spin(Done done, Clock::duration contendedBudget = std::chrono::microseconds(kContendedSpinMicros)) {
    Clock::time_point last = Clock::now();
    const Clock::time_point end = last + (Contended(last) ? contendedBudget : std::chrono::microseconds(kMaxSpinMicros));
    for (;;) {
      for (int k = 0; k < 4; ++k) {
        if (done()) return true;
#if defined(__x86_64__) || defined(__i386__)
        for (int p = 0; p < 8; ++p) _mm_pause();
#else
        std::this_thread::yield();
#endif
      }
      const Clock::time_point now = Clock::now();
      if (now - last > std::chrono::microseconds(kPreemptedMicros)) {
        MarkContended(now);
        return done();
      }
      if (now >= end) return done();
      last = now;
    }
  }

  // Claims and runs blocks of the current job until none is left.
  void RunBlocks() {
    const TaskSystem* outer = std::exchange(tRunning, this);
    uint64_t c = claim_.load(std::memory_order_acquire);
    for (;;) {
      const uint32_t block = static_cast<uint32_t>(c);
      if (block >= static_cast<uint32_t>(workers_)) break;
      // The tag in the high half keeps a worker that read an old job's word from claiming a
      // block of a newer one with the old job's index.
      if (!claim_.compare_exchange_weak(c, c + 1, std::memory_order_acq_rel, std::memory_order_acquire)) continue;
      RunBlock(static_cast<int>(block));
      if (remaining_.fetch_sub(1, std::memory_order_seq_cst) == 1 &&
          callerSleeping_.load(std::memory_order_seq_cst)) {
        WakeAll(remaining_);
      }
      c = claim_.load(std::memory_order_acquire);
    }
    tRunning = outer;
  }

  void RunBlock(int b) {
    if (failed_.load(std::memory_order_relaxed)) return;  // an earlier block threw: skip
    const int begin = BlockBegin(count_, workers_, b), end = BlockBegin(count_, workers_, b + 1);
    if (begin >= end) return;
    try {
      (*fn_)(begin, end, b);
    } catch (...) {
      std::lock_guard<std::mutex> lock(errorMutex_);
      if (!error_) error_ = std::current_exception();
      failed_.store(true, std::memory_order_relaxed);
    }
  }

  // A worker of a contended pool, between jobs: sleeps kPollMicros at a time and looks for a
  // job, for up to kPollMillis. The caller then starts a job with no system call: waking a
  // futex sleeper costs the waker 7.5 us here (measured: mean of 2000 wakes, loaded VM), and a
  // step of 16000 circles runs 49 parallel-fors in about 1.2 ms. A sleeping poller keeps its
  // scheduler credit, so when it finds a block it is not the thread preempted mid-block. True if
  // the job arrived; false when the pool is no longer contended or the polling time is up.
  template <class Done>
  bool Poll(Done arrived) {
    const Clock::time_point end = Clock::now() + std::chrono::milliseconds(kPollMillis);
    for (Clock::time_point now = Clock::now(); Contended(now) && now < end; now = Clock::now()) {
      std::this_thread::sleep_for(std::chrono::microseconds(kPollMicros));
      if (arrived()) return true;
    }
    return arrived();
  }

  // The caller, after its own blocks (which took `own`): waits until every claimed block has
  // finished.
  void WaitForBlocks(Clock::duration own) {
    auto done = [this] { return remaining_.load(std::memory_order_acquire) == 0; };
    const Clock::time_point start = Clock::now();
    // Contended, the caller still spins as long as its own blocks took (at most 1 ms): a worker
    // that is running finishes its block within about that, and a futex round trip costs the
    // caller a wake-up latency; one that is not running costs the caller at most that much.
    const Clock::duration budget =
        std::clamp<Clock::duration>(own, std::chrono::microseconds(kContendedSpinMicros), std::chrono::microseconds(kMaxSpinMicros));
    if (Spin(done, budget)) return;
    callerSleeping_.store(true, std::memory_order_seq_cst);
    for (uint32_t left; (left = remaining_.load(std::memory_order_seq_cst)) != 0;) WaitWhileEqual(remaining_, left);
    callerSleeping_.store(false, std::memory_order_relaxed);
    // Blocks are about equal, so a worker's block that ends much later than the caller's own
    // (twice as long, and a whole spin budget more) was one the scheduler was not running:
    // another process wants these cores.
    const Clock::time_point now = Clock::now();
    if (now - start > 2 * own + std::chrono::microseconds(kMaxSpinMicros)) MarkContended(now);
  }

  void WorkerLoop() {
    uint32_t seen = 0;
    for (;;) {
      auto arrived = [&] { return jobWord_.load(std::memory_order_acquire) != seen; };
      if (!Spin(arrived) && !Poll(arrived)) {
        sleepers_.fetch_add(1, std::memory_order_seq_cst);
        while (jobWord_.load(std::memory_order_seq_cst) == seen) WaitWhileEqual(jobWord_, seen);
        sleepers_.fetch_sub(1, std::memory_order_relaxed);
      }
      if (stop_.load(std::memory_order_acquire)) return;
      seen = jobWord_.load(std::memory_order_acquire);
      RunBlocks();
    }
  }

  const int workers_;
  const bool oversubscribed_;  // more threads than cores: the pool always waits on futexes
  std::vector<std::thread> threads_;

  // The current job: written by the caller before the claim word is published.
  const RangeFn* fn_ = nullptr;
  int count_ = 0;
  uint32_t job_ = 0;

  std::atomic<uint64_t> claim_{0};       // job number << 32 | next block to claim
  std::atomic<uint32_t> jobWord_{0};     // the job number, for workers to wait on
  std::atomic<uint32_t> remaining_{0};   // blocks of the current job not yet finished
  std::atomic<int> sleepers_{0};         // workers in a futex wait for the next job
  std::atomic<bool> callerSleeping_{false};
  std::atomic<bool> stop_{false};
  std::atomic<Clock::rep> contendedUntil_{0};

  std::mutex errorMutex_;
  std::exception_ptr error_;             // the first exception of the current job
  std::atomic<bool> failed_{false};
};

}  // namespace

#if defined(QUADRANT_TBB)
std::unique_ptr<TaskSystem> MakeTbbTaskSystem(int threadCount);  // tbb_task_system.cpp
#endif

std::unique_ptr<TaskSystem> MakeThreadPool(int threadCount) {
  if (threadCount <= 1) return std::make_unique<InlineTaskSystem>();
#if defined(QUADRANT_TBB)
  return MakeTbbTaskSystem(threadCount);
#else
  return std::make_unique<ThreadPool>(threadCount);
#endif
}

}  // namespace quadrant
