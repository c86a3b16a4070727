// The default task system: a small purpose-built pool.
//
// Why not the compiler's OpenMP or oneTBB: benchmarks/task_overhead.cpp measures the cost of
// one parallel-for over 2 threads for this pool and for OpenMP (see the README's table); and
// GCC's libgomp is not instrumented for ThreadSanitizer, so the tsan preset would report its
// internal synchronisation as races, while this pool uses only std::mutex,
// std::condition_variable and std::atomic, which TSan understands.
#include <atomic>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

#include "quadrant/task_system.h"

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
  explicit ThreadPool(int threads) : workers_(threads) {
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
    for (int spin = 0; spin < kSpins; ++spin) {
      if (remaining_.load(std::memory_order_acquire) == 0) return;
      std::this_thread::yield();
    }
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [this] { return remaining_.load(std::memory_order_acquire) == 0; });
  }

 private:
  // Yielding spins before sleeping: about 10-50 us on these machines, longer than the gap
  // between two stages of a step, and a yield hands the core to a runnable worker when the
  // pool has more threads than cores.
  static constexpr int kSpins = 2000;

  void RunBlock(int w) {
    const int begin = BlockBegin(count_, workers_, w);
    const int end = BlockBegin(count_, workers_, w + 1);
    if (begin < end) (*fn_)(begin, end, w);
  }

  void WorkerLoop(int w) {
    uint64_t seen = 0;
    for (;;) {
      uint64_t now = generation_.load(std::memory_order_acquire);
      for (int spin = 0; now == seen && spin < kSpins; ++spin) {
        std::this_thread::yield();
        now = generation_.load(std::memory_order_acquire);
      }
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
