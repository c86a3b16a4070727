// Tests for the task system (engine/src/parallel/thread_pool.cpp, include/quadrant/task_system.h): the
// block partition, that every index runs exactly once whichever thread claims it, nesting,
// empty ranges, exceptions, Prepare, a world stepped on more threads than there are free cores
// and one stepped with pauses between steps (a game loop).
// Nothing here is timed.
#include <gtest/gtest.h>

#include <chrono>

#if defined(__linux__)
#include <sched.h>

#include <filesystem>
#include <fstream>
#endif

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <memory>
#include <mutex>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "quadrant/task_system.h"
#include "quadrant/world.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

using namespace test;

struct Call {
  int begin, end, block;
  bool operator<(const Call& o) const { return std::tie(block, begin, end) < std::tie(o.block, o.begin, o.end); }
};

// Runs one ParallelFor and returns its calls (sorted by block) and how often each index ran.
std::vector<Call> RunOnce(TaskSystem& tasks, int count, std::vector<int>& hits) {
  std::mutex mutex;
  std::vector<Call> calls;
  hits.assign(size_t(std::max(count, 0)), 0);
  std::vector<std::atomic<int>> counter(hits.size());
  tasks.ParallelFor(count, [&](int begin, int end, int block) {
    for (int i = begin; i < end; ++i) counter[size_t(i)].fetch_add(1, std::memory_order_relaxed);
    std::lock_guard<std::mutex> lock(mutex);
    calls.push_back({begin, end, block});
  });
  for (size_t i = 0; i < hits.size(); ++i) hits[i] = counter[i].load();
  std::sort(calls.begin(), calls.end());
  return calls;
}

TEST(ThreadPoolTest, EveryIndexRunsOnceInTheStaticBlocks) {
  const int hardware = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  for (int threads : {1, 2, 3, 4, hardware + 3}) {
    auto tasks = MakeThreadPool(threads);
    ASSERT_EQ(tasks->WorkerCount(), threads);
    for (int count : {1, 2, 3, 5, 7, 64, 1000, 4099}) {
      SCOPED_TRACE(testing::Message() << threads << " threads, count " << count);
      std::vector<int> hits;
      const std::vector<Call> calls = RunOnce(*tasks, count, hits);
      EXPECT_TRUE(std::all_of(hits.begin(), hits.end(), [](int h) { return h == 1; }));
      // Exactly the non-empty blocks of the partition, each once, with its own index.
      std::vector<Call> want;
      for (int b = 0; b < threads; ++b) {
        const int begin = BlockBegin(count, threads, b), end = BlockBegin(count, threads, b + 1);
        if (begin < end) want.push_back({begin, end, b});
      }
      ASSERT_EQ(calls.size(), want.size());
      for (size_t k = 0; k < want.size(); ++k) {
        EXPECT_EQ(calls[k].block, want[k].block);
        EXPECT_EQ(calls[k].begin, want[k].begin);
        EXPECT_EQ(calls[k].end, want[k].end);
      }
    }
  }
}

TEST(ThreadPoolTest, TooManyThreadsIsAClearError) {
  try {
    MakeThreadPool(20000);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "MakeThreadPool: at most 16383 threads");
  }
}

TEST(ThreadPoolTest, ZeroAndNegativeCountsCallNothing) {
  for (int threads : {1, 2, 4}) {
    auto tasks = MakeThreadPool(threads);
    int calls = 0;
    tasks->ParallelFor(0, [&](int, int, int) { ++calls; });
    tasks->ParallelFor(-5, [&](int, int, int) { ++calls; });
    EXPECT_EQ(calls, 0) << threads << " threads";
  }
}

TEST(ThreadPoolTest, BackToBackJobsEachCoverTheirRange) {
  // Many short jobs in a row: a worker that wakes late must not run a block of the next job
  // with the previous job's function, nor twice.
  auto tasks = MakeThreadPool(3);
  std::vector<std::atomic<int>> sum(3);
  long long want = 0;
  for (int job = 0; job < 3000; ++job) {
    const int count = 1 + job % 17;
    want += count;
    tasks->ParallelFor(count, [&](int begin, int end, int block) {
      sum[size_t(block)].fetch_add(end - begin, std::memory_order_relaxed);
    });
  }
  EXPECT_EQ(sum[0].load() + sum[1].load() + sum[2].load(), want);
}

TEST(ThreadPoolTest, APoolDestroyedRightAfterAJobJoinsItsWorkers) {
  // A worker woken by a job's bump that is preempted after its stop check, while the caller runs
  // the job alone and destroys the pool, must still see the stop: it once took the destructor's
  // bump for its next wait and slept through it, and the join hung (a World destroyed under load,
  // a few times in thousands). The window is a few instructions wide, so this loop only rarely
  // reaches it on a quiet machine; a hang ends in ctest's timeout.
  for (int round = 0; round < 2000; ++round) {
    auto tasks = MakeThreadPool(2);
    std::atomic<int> items{0};
    if (round % 2 == 1) tasks->Prepare();
    tasks->ParallelFor(2, [&](int begin, int end, int) { items.fetch_add(end - begin, std::memory_order_relaxed); });
    ASSERT_EQ(items.load(), 2);
  }
}

TEST(ThreadPoolTest, PrepareBetweenJobsChangesNothing) {
  // Prepare (a step begins: wake the workers) may come at any time, with or without jobs after it,
  // and after the workers went to sleep (a game loop's pause between frames, longer than a spin).
  const int hardware = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  for (int threads : {1, 2, hardware + 1}) {
    auto tasks = MakeThreadPool(threads);
    std::vector<int> hits;
    for (int round = 0; round < 20; ++round) {
      tasks->Prepare();
      if (round % 3 == 0) tasks->Prepare();  // twice, no job between
      if (round % 5 == 4) std::this_thread::sleep_for(std::chrono::milliseconds(3));  // workers asleep
      const int count = 100 + 37 * round;
      const std::vector<Call> calls = RunOnce(*tasks, count, hits);
      EXPECT_EQ(calls.size(), size_t(std::min(count, threads)));
      for (int h : hits) ASSERT_EQ(h, 1);
    }
    tasks->Prepare();  // the pool is destroyed right after a wake
  }
}

TEST(ThreadPoolTest, NestedCallsRunInlineAndCoverTheirRange) {
  auto tasks = MakeThreadPool(2);
  std::vector<std::atomic<int>> hits(40 * 30);
  tasks->ParallelFor(40, [&](int begin, int end, int) {
    for (int i = begin; i < end; ++i) {
      tasks->ParallelFor(30, [&](int b, int e, int) {
        for (int j = b; j < e; ++j) hits[size_t(i * 30 + j)].fetch_add(1, std::memory_order_relaxed);
      });
    }
  });
  for (const auto& h : hits) EXPECT_EQ(h.load(), 1);
}

TEST(ThreadPoolTest, AnExceptionInABlockReachesTheCallerAndThePoolStaysUsable) {
  for (int threads : {1, 2, 4}) {
    SCOPED_TRACE(testing::Message() << threads << " threads");
    auto tasks = MakeThreadPool(threads);
    for (int round = 0; round < 20; ++round) {
      // The last block throws (on one thread: the only block).
      EXPECT_THROW(tasks->ParallelFor(1000,
                                      [&](int, int end, int) {
                                        if (end == 1000) throw std::runtime_error("block failed");
                                      }),
                   std::runtime_error);
      std::vector<int> hits;
      RunOnce(*tasks, 1000, hits);
      EXPECT_TRUE(std::all_of(hits.begin(), hits.end(), [](int h) { return h == 1; }));
    }
    // The message arrives intact.
    try {
      tasks->ParallelFor(10, [](int, int, int) { throw std::invalid_argument("bad item 7"); });
      ADD_FAILURE() << "no exception";
    } catch (const std::invalid_argument& e) {
      EXPECT_STREQ(e.what(), "bad item 7");
    }
  }
}

// Spinning threads that occupy every core while they live.
class BusyCores {
 public:
  explicit BusyCores(int n) {
    for (int k = 0; k < n; ++k) {
      threads_.emplace_back([this] {
        while (!stop_.load(std::memory_order_relaxed)) {
        }
      });
    }
  }
  ~BusyCores() {
    stop_.store(true);
    for (auto& t : threads_) t.join();
  }

 private:
  std::atomic<bool> stop_{false};
  std::vector<std::thread> threads_;
};

// A scene whose every stage runs parallel sections (minParallelItems 8): circles with random
// velocities and a small pyramid of boxes on a ground, in a closed box.
void BuildBusyScene(World& world) {
  AddGround(world, 12, Real(0.5), {0, -0.5});
  AddGround(world, Real(0.5), 10, {-12.5, 9.5});
  AddGround(world, Real(0.5), 10, {12.5, 9.5});
  std::mt19937 rng(7);
  auto uni = [&](double lo, double hi) { return lo + (hi - lo) * (double(rng()) / double(std::mt19937::max())); };
  for (int row = 0; row < 6; ++row) {
    for (int col = 0; col < 4 - row / 2; ++col) AddBox(world, {Real(-10 + 1.1 * col + 0.55 * (row % 2)), Real(0.5 + row)});
  }
  for (int row = 0; row < 8; ++row) {
    for (int col = 0; col < 12; ++col) {
      Vec2 p{Real(-4 + 1.3 * col), Real(2 + 1.2 * row)};
      AddCircle(world, p, Real(uni(0.2, 0.5)), {Real(uni(-4, 4)), Real(uni(-4, 4))}, 1, Real(0.4), Real(0.3));
    }
  }
}

// test_helpers.h sets QUADRANT_POOL_ALONE=0, so that determinism tests compare the partitioned
// path with one thread; while one of these is in scope the pool may run steps alone again.
class PoolMayRunAlone {
 public:
  PoolMayRunAlone() {
    if (const char* v = std::getenv("QUADRANT_POOL_ALONE")) saved_ = v;
    unsetenv("QUADRANT_POOL_ALONE");
  }
  ~PoolMayRunAlone() {
    if (!saved_.empty()) setenv("QUADRANT_POOL_ALONE", saved_.c_str(), 1);
  }

 private:
  std::string saved_;
};

uint64_t HashAfterSteps(int threads, int steps, SolverType solver = SolverType::kPgs) {
  WorldDef def;
  def.threadCount = threads;
  def.solver = solver;
  def.minParallelItems = 8;
  World world(def);
  BuildBusyScene(world);
  StepN(world, steps);
  return world.StateHash();
}

TEST(ThreadPoolTest, MoreThreadsThanFreeCoresGiveTheOneThreadHash) {
  // Every core is kept busy by a spinning thread while the world steps on more threads than the
  // machine has cores, so the pool's workers are descheduled mid-step and blocks move between
  // threads; the result must still be the one-thread result, bit for bit.
  const int hardware = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  for (SolverType solver : {SolverType::kPgs, SolverType::kSoftStep}) {
    SCOPED_TRACE(solver == SolverType::kPgs ? "pgs" : "soft_step");
    const uint64_t serial = HashAfterSteps(1, 90, solver);
    uint64_t busy2 = 0, busyMany = 0, busyAlone = 0;
    {
      BusyCores busy(hardware);
      busy2 = HashAfterSteps(2, 90, solver);
      busyMany = HashAfterSteps(hardware + 2, 90, solver);
      // Steps on the one-thread path (RunsAlone) mixed with partitioned ones: the pool's first
      // step is partitioned, and the busy cores make it run later ones alone.
      PoolMayRunAlone may;
      busyAlone = HashAfterSteps(2, 90, solver);
    }
    EXPECT_EQ(busy2, serial);
    EXPECT_EQ(busyMany, serial);
    EXPECT_EQ(busyAlone, serial);
  }
}

TEST(ThreadPoolTest, StepsWithPausesBetweenThemGiveTheOneThreadHash) {
  // A game loop: every step is followed by a pause longer than a worker's spin, so the workers
  // sleep between steps and each step wakes them (TaskSystem::Prepare) before its first job.
  auto paused = [](int threads) {
    WorldDef def;
    def.threadCount = threads;
    def.solver = SolverType::kPgs;  // as HashAfterSteps
    def.minParallelItems = 8;
    World world(def);
    BuildBusyScene(world);
    for (int i = 0; i < 25; ++i) {
      world.Step(kDt);
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return world.StateHash();
  };
  const uint64_t serial = HashAfterSteps(1, 25);
  EXPECT_EQ(paused(2), serial);
  EXPECT_EQ(paused(3), serial);
  PoolMayRunAlone may;  // and where the pool may take some of the steps alone
  EXPECT_EQ(paused(2), serial);
}

#if defined(__linux__)
// Restricts the calling thread to its first allowed core while in scope.
class OneCore {
 public:
  OneCore() {
    ok_ = sched_getaffinity(0, sizeof(saved_), &saved_) == 0;
    if (!ok_) return;
    cpu_set_t one;
    CPU_ZERO(&one);
    for (int c = 0; c < CPU_SETSIZE; ++c) {
      if (CPU_ISSET(c, &saved_)) {
        CPU_SET(c, &one);
        break;
      }
    }
    ok_ = sched_setaffinity(0, sizeof(one), &one) == 0;
  }
  ~OneCore() {
    if (ok_) sched_setaffinity(0, sizeof(saved_), &saved_);
  }
  bool ok() const { return ok_; }

 private:
  cpu_set_t saved_;
  bool ok_ = false;
};

// Each thread's Cpus_allowed_list from /proc/self/task/*/status.
std::vector<std::string> ThreadAffinities() {
  std::vector<std::string> lists;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
    std::ifstream status(task.path() / "status");
    std::string line;
    while (std::getline(status, line)) {
      if (line.rfind("Cpus_allowed_list:", 0) == 0) lists.push_back(line);
    }
  }
  return lists;
}

TEST(ThreadPoolTest, WorkersWokenAfterAPauseGetTheirWholeAffinityBack) {
  // After a pause longer than a spin, the pool keeps sleeping workers off the caller's core while
  // it wakes them (SteerSleepers); each takes the process's mask back once it runs, so no thread
  // is left narrowed. Where the process has one core there is nothing to steer.
  cpu_set_t mine;
  ASSERT_EQ(sched_getaffinity(0, sizeof(mine), &mine), 0);
  if (CPU_COUNT(&mine) < 2) GTEST_SKIP() << "one usable core";
  auto tasks = MakeThreadPool(2);
  std::vector<int> hits;
  for (int frame = 0; frame < 5; ++frame) {
    std::this_thread::sleep_for(std::chrono::milliseconds(4));  // the worker sleeps
    tasks->Prepare();
    RunOnce(*tasks, 1000, hits);
    for (int h : hits) ASSERT_EQ(h, 1);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(20));  // the worker is up and asleep again
  // This thread, the worker, and any thread of the runtime (ThreadSanitizer has one): all with
  // the process's mask.
  const std::vector<std::string> lists = ThreadAffinities();
  ASSERT_GE(lists.size(), 2u);
  for (const std::string& list : lists) EXPECT_EQ(list, lists[0]);
}

TEST(ThreadPoolTest, APoolWithoutWorkersRunsAloneAndStepsGiveTheOneThreadHash) {
  // On one usable core the pool starts no worker: it says so (RunsAlone), every step takes the
  // engine's one-thread path, and the state is the one-thread state, bit for bit.
  const uint64_t serial = HashAfterSteps(1, 60, SolverType::kSoftStep);
  uint64_t alone = 0;
  {
    PoolMayRunAlone may;  // here the pool may run steps alone
    OneCore pin;
    ASSERT_TRUE(pin.ok());
    std::unique_ptr<TaskSystem> pool = MakeThreadPool(3);
    EXPECT_EQ(pool->WorkerCount(), 3);
    EXPECT_EQ(pool->ThreadCount(), 1);
    EXPECT_TRUE(pool->RunsAlone());
    std::vector<int> hits;
    const std::vector<Call> calls = RunOnce(*pool, 10, hits);
    EXPECT_EQ(calls.size(), 3u);  // the partition is unchanged: three blocks, run by the caller
    for (int h : hits) EXPECT_EQ(h, 1);
    alone = HashAfterSteps(3, 60, SolverType::kSoftStep);
  }
  EXPECT_EQ(alone, serial);
}
#endif

#if defined(__linux__)
TEST(ThreadPoolTest, APoolBornBesideBusyCoresRunsAloneFromItsFirstStep) {
  // Every core busy when the pool is made: it starts serial (issue #14: a short run would end
  // before a window of parallel jobs could show the contention), and the steps still give the
  // one-thread hash.
  const int hardware = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  if (hardware < 2) GTEST_SKIP() << "one core: the pool starts no worker";
  const uint64_t serial = HashAfterSteps(1, 30, SolverType::kSoftStep);
  uint64_t alone = 0;
  {
    PoolMayRunAlone may;
    BusyCores busy(hardware);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));  // the spinners are running
    std::unique_ptr<TaskSystem> pool = MakeThreadPool(2);
    if (pool->ThreadCount() < 2) GTEST_SKIP() << "the affinity mask allows one core";
    EXPECT_TRUE(pool->RunsAlone());
    alone = HashAfterSteps(2, 30, SolverType::kSoftStep);
  }
  EXPECT_EQ(alone, serial);
}
#endif

TEST(ThreadPoolTest, AFreshPoolWithWorkersDoesNotRunAlone) {
  // Before it has run anything the pool has seen no contention: its first step is parallel.
  if (std::thread::hardware_concurrency() < 2) GTEST_SKIP() << "one core: the pool starts no worker";
  std::unique_ptr<TaskSystem> pool = MakeThreadPool(2);
  if (pool->ThreadCount() < 2) GTEST_SKIP() << "the affinity mask allows one core";
  // (QUADRANT_POOL_ALONE=0, set by test_helpers.h, makes this false too; without it the pool
  // gives false on its first call unless it was born beside other running threads, the test
  // below.)
  EXPECT_FALSE(pool->RunsAlone());
  EXPECT_FALSE(MakeThreadPool(1)->RunsAlone());  // one thread is no pool: the engine's own path
}

// ParallelStages: every item of every stage once, in runs of consecutive chunks of the
// StageChunks partition (or a whole stage in one call, when the pool runs the region on the
// caller alone), and no call of a stage before every call of the previous stages has returned.
TEST(ThreadPoolTest, StagesRunInOrderAndCoverEveryItemOnce) {
  const int hardware = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const std::vector<TaskSystem::StagePlan> plan = {{1000, 16}, {0, 1}, {1, 1}, {7, 1}, {4099, 64}, {64, 1000}, {300, 1}};
  std::vector<int> first(plan.size() + 1, 0);
  for (size_t s = 0; s < plan.size(); ++s) first[s + 1] = first[s] + plan[s].count;
  for (int threads : {1, 2, 3, 4, hardware + 3}) {
    auto tasks = MakeThreadPool(threads);
    for (int round = 0; round < 50; ++round) {
      SCOPED_TRACE(testing::Message() << threads << " threads, round " << round);
      std::vector<std::atomic<int>> hits(size_t(first.back()));
      std::atomic<int> finished{0};  // items of all stages whose calls have returned
      std::atomic<bool> outOfOrder{false}, badChunk{false};
      tasks->ParallelStages(static_cast<int>(plan.size()), plan.data(), [&](int s, int begin, int end, int chunk) {
        if (finished.load() < first[size_t(s)]) outOfOrder.store(true);
        const int count = plan[size_t(s)].count;
        const int chunks = StageChunks(count, plan[size_t(s)].grain, threads);
        const bool whole = begin == 0 && end == count;
        bool partition = chunk >= 0 && chunk < chunks && begin == BlockBegin(count, chunks, chunk);
        int last = chunk + 1;  // the run ends at a chunk boundary
        while (partition && last < chunks && BlockBegin(count, chunks, last) < end) ++last;
        partition = partition && end == BlockBegin(count, chunks, last);
        if (!whole && !partition) badChunk.store(true);
        for (int i = begin; i < end; ++i) hits[size_t(first[size_t(s)] + i)].fetch_add(1);
        finished.fetch_add(end - begin);
      });
      EXPECT_FALSE(outOfOrder.load());
      EXPECT_FALSE(badChunk.load());
      EXPECT_TRUE(std::all_of(hits.begin(), hits.end(), [](const std::atomic<int>& h) { return h.load() == 1; }));
    }
  }
}

// A region with a stage whose plan says runs = false: there every call is one chunk (or the whole
// stage, when the region runs on the caller alone), never a run of several.
TEST(ThreadPoolTest, AStageWithoutRunsIsCalledChunkByChunk) {
  const std::vector<TaskSystem::StagePlan> plan = {{1000, 16}, {300, 1, false}};
  for (int threads : {1, 2, 4}) {
    auto tasks = MakeThreadPool(threads);
    for (int round = 0; round < 50; ++round) {
      SCOPED_TRACE(testing::Message() << threads << " threads, round " << round);
      std::atomic<int> items{0};
      std::atomic<bool> badChunk{false};
      tasks->ParallelStages(2, plan.data(), [&](int s, int begin, int end, int chunk) {
        items.fetch_add(end - begin);
        if (s != 1) return;
        const int chunks = StageChunks(300, 1, threads);
        const bool whole = begin == 0 && end == 300;
        const bool one = chunk >= 0 && chunk < chunks && begin == BlockBegin(300, chunks, chunk) &&
                         end == BlockBegin(300, chunks, chunk + 1);
        if (!whole && !one) badChunk.store(true);
      });
      EXPECT_EQ(items.load(), 1300);
      EXPECT_FALSE(badChunk.load());
    }
  }
}

TEST(ThreadPoolTest, AnExceptionInAStageReachesTheCallerSkipsLaterStagesAndThePoolStaysUsable) {
  for (int threads : {1, 2, 4}) {
    SCOPED_TRACE(testing::Message() << threads << " threads");
    auto tasks = MakeThreadPool(threads);
    const std::vector<TaskSystem::StagePlan> plan = {{500, 8}, {500, 8}, {500, 8}};
    for (int round = 0; round < 20; ++round) {
      std::atomic<int> lastStageCalls{0};
      EXPECT_THROW(tasks->ParallelStages(3, plan.data(),
                                         [&](int s, int, int end, int) {
                                           if (s == 1 && end == 500) throw std::runtime_error("stage failed");
                                           if (s == 2) lastStageCalls.fetch_add(1);
                                         }),
                   std::runtime_error);
      EXPECT_EQ(lastStageCalls.load(), 0);
      std::atomic<int> items{0};
      tasks->ParallelStages(3, plan.data(), [&](int, int begin, int end, int) { items.fetch_add(end - begin); });
      EXPECT_EQ(items.load(), 1500);
    }
  }
}

TEST(ThreadPoolTest, StagesNestedInABlockRunInline) {
  auto tasks = MakeThreadPool(2);
  std::vector<std::atomic<int>> hits(20 * 100);
  const TaskSystem::StagePlan plan[2] = {{60, 4}, {40, 4}};
  tasks->ParallelFor(20, [&](int begin, int end, int) {
    for (int i = begin; i < end; ++i) {
      tasks->ParallelStages(2, plan, [&](int s, int b, int e, int) {
        for (int j = b; j < e; ++j) hits[size_t(i * 100 + s * 60 + j)].fetch_add(1);
      });
    }
  });
  for (const auto& h : hits) EXPECT_EQ(h.load(), 1);
}

TEST(ThreadPoolTest, AStepTooSmallToSplitRunsAloneWithTheSameBits) {
  // StageRunner::BeginStep: a step whose last step's work was below minParallelItems items'
  // worth (50 ns an item) takes the one-thread path. With minParallelItems at
  // 10^6 (50 ms) every step of the busy scene is that small after the first, which has no last
  // step to go by; at 8 (0.4 us) none is. Both give the one-thread bits.
  auto run = [](int minItems, Profile& total) {
    WorldDef def;
    def.threadCount = 2;
    def.solver = SolverType::kSoftStep;
    def.minParallelItems = minItems;
    World world(def);
    BuildBusyScene(world);
    for (int i = 0; i < 30; ++i) {
      world.Step(kDt);
      total += world.GetProfile();
    }
    return world.StateHash();
  };
  Profile small, split;
  const uint64_t smallHash = run(1000000, small), splitHash = run(8, split);
  EXPECT_EQ(small.smallSteps, 29);
  EXPECT_EQ(small.aloneSteps, 29);
  EXPECT_EQ(split.smallSteps, 0);
  EXPECT_EQ(split.aloneSteps, 0);  // QUADRANT_POOL_ALONE=0 (test_helpers.h): the pool never runs alone
  EXPECT_EQ(smallHash, HashAfterSteps(1, 30, SolverType::kSoftStep));
  EXPECT_EQ(splitHash, smallHash);
}

}  // namespace
}  // namespace quadrant
