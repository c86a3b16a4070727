// The default task system: a small purpose-built pool.
//
// Why not the compiler's OpenMP or oneTBB: benchmarks/task_overhead.cpp measures the cost of
// one parallel-for over 2 threads for this pool and for OpenMP (see the README's table); and
// GCC's libgomp is not instrumented for ThreadSanitizer, so the tsan preset would report its
// internal synchronisation as races, while this pool uses only std::mutex,
// std::condition_variable and std::atomic, which TSan understands.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

#include "quadrant/task_system.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace quadrant {
namespace {

class InlineTaskSystem final : public TaskSystem {
 public:
  int WorkerCount() const override { return 1; }
  void ParallelFor(int count, const RangeFn& fn) override {
    if (count > 0) fn(0, count, 0);
  }
};

class ThreadPool final : public TaskSystem {
 public:
  explicit ThreadPool(int threads)
      : workers_(threads),
        oversubscribed_(static_cast<unsigned>(threads) > std::max(1u, std::thread::hardware_concurrency())) {
    threads_.reserve(threads - 1);
    for (int w = 1; w < threads; ++w) threads_.emplace_back([this, w] { WorkerLoop(w); });
  }

  ~ThreadPool() override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
      generation_.fetch_add(1, std::memory_order_release);
    }
    wake_.notify_all();
    for (std::thread& t : threads_) t.join();
  }

  int WorkerCount() const override { return workers_; }

  void ParallelFor(int count, const RangeFn& fn) override {
    if (count <= 0) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      fn_ = &fn;
      count_ = count;
      remaining_.store(workers_ - 1, std::memory_order_relaxed);
      generation_.fetch_add(1, std::memory_order_release);
    }
    wake_.notify_all();
    RunBlock(0);
    // Wait for the others: spin briefly (stages are short), then sleep.
    Waiter wait(oversubscribed_);
    while (remaining_.load(std::memory_order_acquire) != 0) {
      if (!wait.Spin()) break;
    }
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [this] { return remaining_.load(std::memory_order_acquire) == 0; });
  }

 private:
  // How a thread waits for the others (the caller for the workers' blocks, a worker for the
  // next job): it spins for a while, then sleeps on a condition variable.
  //
  // With no more threads than cores it spins with the pause instruction, keeping its core,
  // for up to kPauseMicros, then sleeps. It never yields: a yield is a system call that hands
  // the core to any other runnable process, even a niced one, for a whole time slice (with
  // yields, a step of 16000 circles at 2 threads took 5.8 ms beside a nice -n 19 build instead
  // of 1.2 ms, measured). The spin is long because a sleeping worker takes about 100 us to wake
  // on these VMs, and a small step has serial gaps of that order between its parallel
  // sections: 2000 circles at 2 threads took 0.65 ms per step with a 100 us spin and 0.24 ms
  // with 1 ms (one thread: 0.22). A worker left spinning after a step burns at most 1 ms.
  //
  // With more threads than cores the partner a spinner waits for is usually a preempted worker
  // of the pool, so there it yields (kYields times, about 10-50 us) and then sleeps.
  static constexpr int kYields = 2000;
  static constexpr int kPauseMicros = 1000;

  class Waiter {
   public:
    explicit Waiter(bool oversubscribed) : oversubscribed_(oversubscribed), start_(Clock::now()) {}
    // One spin; false once the spin budget is spent (time to sleep).
    bool Spin() {
      if (oversubscribed_) {
        std::this_thread::yield();
        return ++spins_ < kYields;
      }
#if defined(__x86_64__) || defined(__i386__)
      for (int k = 0; k < 8; ++k) _mm_pause();
#else
      std::this_thread::yield();
#endif
      // The clock is read every 16th spin only (a read costs about as much as 8 pauses).
      return ++spins_ % 16 != 0 || Clock::now() - start_ < std::chrono::microseconds(kPauseMicros);
    }

   private:
    using Clock = std::chrono::steady_clock;
    bool oversubscribed_;
    Clock::time_point start_;
    int spins_ = 0;
  };

  void RunBlock(int w) {
    const int begin = BlockBegin(count_, workers_, w);
    const int end = BlockBegin(count_, workers_, w + 1);
    if (begin < end) (*fn_)(begin, end, w);
  }

  void WorkerLoop(int w) {
    uint64_t seen = 0;
    for (;;) {
      uint64_t now = generation_.load(std::memory_order_acquire);
      Waiter wait(oversubscribed_);
      while (now == seen && wait.Spin()) now = generation_.load(std::memory_order_acquire);
      if (now == seen) {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [&] { return generation_.load(std::memory_order_acquire) != seen; });
        now = generation_.load(std::memory_order_acquire);
      }
      seen = now;
      {
        // The job fields were written under the mutex before the generation moved; taking
        // it here orders this worker's reads after those writes (and tells TSan so).
        std::lock_guard<std::mutex> lock(mutex_);
        if (stop_) return;
      }
      RunBlock(w);
      if (remaining_.fetch_sub(1, std::memory_order_acq_rel) == 1) {
        std::lock_guard<std::mutex> lock(mutex_);
        done_.notify_one();
      }
    }
  }

  const int workers_;
  const bool oversubscribed_;
  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable done_;
  std::atomic<uint64_t> generation_{0};
  std::atomic<int> remaining_{0};
  const RangeFn* fn_ = nullptr;
  int count_ = 0;
  bool stop_ = false;
};

}  // namespace

std::unique_ptr<TaskSystem> MakeThreadPool(int threadCount) {
  if (threadCount <= 1) return std::make_unique<InlineTaskSystem>();
  return std::make_unique<ThreadPool>(threadCount);
}

}  // namespace quadrant
