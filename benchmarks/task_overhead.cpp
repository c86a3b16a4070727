// The per-call overhead of a parallel-for: Quadrant's thread pool against the compiler's
// OpenMP, the measurement behind the task system's default (see thread_pool.cpp and README).
//
// Each iteration runs one parallel-for over `items` items doing a little work each (a few
// nanoseconds, like an integration step), so the time is mostly dispatch and join. A step of
// the engine runs a few dozen such sections.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <cmath>
#include <thread>
#include <vector>

#include "gbench_main.h"
#include "quadrant/task_system.h"

namespace {

void Work(std::vector<float>& data, int begin, int end) {
  for (int i = begin; i < end; ++i) data[i] = data[i] * 0.999f + 0.001f;
}

void BM_ThreadPool(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const int items = static_cast<int>(state.range(1));
  std::vector<float> data(items, 1.0f);
  auto pool = quadrant::MakeThreadPool(threads);
  const quadrant::TaskSystem::RangeFn fn = [&](int b, int e, int) { Work(data, b, e); };
  for (auto _ : state) {
    pool->ParallelFor(items, fn);
    benchmark::ClobberMemory();
  }
}

void BM_OpenMP(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const int items = static_cast<int>(state.range(1));
  std::vector<float> data(items, 1.0f);
  for (auto _ : state) {
#pragma omp parallel num_threads(threads)
    {
      const int w = omp_get_thread_num(), t = omp_get_num_threads();
      Work(data, quadrant::BlockBegin(items, t, w), quadrant::BlockBegin(items, t, w + 1));
    }
    benchmark::ClobberMemory();
  }
}

// A solver pass over eight colours: eight dependent sections, as eight parallel-fors (a
// hand-over and a join each) or as one region of eight stages (TaskSystem::ParallelStages: one
// hand-over, the threads go from stage to stage through the claim word). Chunks of 512 items
// here (about half a microsecond of this work; the solver's chunks of 64 constraints are a few
// microseconds).
void BM_ThreadPoolEightFors(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const int items = static_cast<int>(state.range(1));
  std::vector<float> data(items, 1.0f);
  auto pool = quadrant::MakeThreadPool(threads);
  const quadrant::TaskSystem::RangeFn fn = [&](int b, int e, int) { Work(data, b, e); };
  for (auto _ : state) {
    for (int stage = 0; stage < 8; ++stage) pool->ParallelFor(items, fn);
    benchmark::ClobberMemory();
  }
}

void BM_ThreadPoolEightStages(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const int items = static_cast<int>(state.range(1));
  std::vector<float> data(items, 1.0f);
  auto pool = quadrant::MakeThreadPool(threads);
  std::vector<quadrant::TaskSystem::StagePlan> plan(8, {items, 512});
  const quadrant::TaskSystem::StageFn fn = [&](int, int b, int e, int) { Work(data, b, e); };
  for (auto _ : state) {
    pool->ParallelStages(8, plan.data(), fn);
    benchmark::ClobberMemory();
  }
}

// 1, 2 and 4 threads anywhere (4 oversubscribed on a 2-core machine), 8 and 16 where the machine
// has the cores (a lent 16-core machine: the cost of a stage at 16 threads, issue #25).
void Args(benchmark::internal::Benchmark* b) {
  const int cores = static_cast<int>(std::thread::hardware_concurrency());
  for (int threads : {1, 2, 4, 8, 16}) {
    if (threads > 4 && threads > cores) continue;
    for (int items : {1024, 16384}) b->Args({threads, items});
  }
  b->UseRealTime()->MinTime(0.2);
}

BENCHMARK(BM_ThreadPool)->Apply(Args);
BENCHMARK(BM_OpenMP)->Apply(Args);
BENCHMARK(BM_ThreadPoolEightFors)->Apply(Args);
BENCHMARK(BM_ThreadPoolEightStages)->Apply(Args);

}  // namespace

int main(int argc, char** argv) {
  return quadrant::cli::GoogleBenchmarkMain(
      "quadrant_task_overhead",
      "The per-call overhead of a parallel-for: Quadrant's thread pool against OpenMP. No options of its own.", argc,
      argv);
}
