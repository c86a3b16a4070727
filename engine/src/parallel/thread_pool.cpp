// The default task system: at most one thread per core, and any thread (the caller included)
// claims any chunk, so no chunk waits for a thread the scheduler is not running.
//
// Promises (task_system.h): every block of a ParallelFor and every chunk of a ParallelStages
// region runs exactly once; which thread runs it, and whether a step is split at all, never
// changes the arithmetic, so results are bit-identical at any thread count and load. A chunk
// that throws skips the chunks not yet started; the first exception is rethrown once the started
// ones finish, and the pool stays usable. A call from inside a chunk runs inline on that thread.
//
// How: a region is one job; one 64-bit word publishes its current stage (job tag, stage, chunk
// count), and the thread that finishes a stage's last chunk publishes the next. Each running
// thread has a lane of every stage's chunks (ClaimFromLanes): it runs its own lane's first, then
// takes from the back of others', so the same thread runs the same chunks stage after stage and
// their data stays in its cache (one shared claim range gave that only to two threads). On the
// lent 16-core VM, against the shared range, three interleaved pairs: the solve stage of the
// pyramid 5050 at 4 / 8 / 16 threads 1.23 / 1.01 / 1.12 -> 1.16 / 0.87 / 0.87 ms, of
// many_pyramids 22000 5.47 / 3.40 / 2.62 -> 4.96 / 3.00 / 2.08 ms. Stages whose chunks differ by
// design (StageRunner::Beside's lone part) are claimed from the word itself, the caller and even
// workers from the front, odd workers from the back. Idle threads
// spin up to kMaxSpinMicros, then sleep on a futex. A step's start (Prepare) wakes them, and
// after the caller was away longer than a spin (a game loop's sleep) it first keeps them off its
// own core (SteerSleepers): on the 2-core VMs the kernel put a woken worker on the caller's core
// 9 times in 10, where it queued behind the caller while the other core idled (7975 boxes at
// 60 Hz, 2 threads: 4.2 ms a step against 2.7 back to back). On a busy machine the caller runs
// jobs alone (Judge) and steps take the one-thread path (RunsAlone; not with
// QUADRANT_POOL_ALONE=0, which determinism tests set). QUADRANT_POOL_STATS=1 prints the counters.
//
// Why the caller may run alone: a preempted worker holding a chunk stalls its stage for a time
// slice (beside one busy loop a pool whose caller waited for every block took 161 ms a step on
// 16000 circles at 2 threads, 3.49 ms at 1); this pool stays within 10 % of one thread there.
// Its signs: stalls and idle workers seen from inside, run-queue waits, and /proc for a pool
// born beside busy cores; limits scale with the threads, and a worker's wake-up after the
// caller slept is excused, so that a quiet machine is not misread (16 threads on a quiet 16-core
// machine had run 122 of 180 steps alone). Not OpenMP: GCC's libgomp is not instrumented for
// ThreadSanitizer. docs/notes/thread_pool.md holds the earlier pools and the measurements.
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cerrno>
#include <climits>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <exception>
#include <limits>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <utility>
#include <vector>

#include "quadrant/task_system.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif
#if defined(__linux__)
#include <fcntl.h>
#include <linux/futex.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

namespace quadrant {

// The default region: one ParallelFor per stage over the stage's chunks. Task systems with a
// cheaper way (the pool below) override it.
void TaskSystem::ParallelStages(int stages, const StagePlan* plan, const StageFn& fn) {
  for (int s = 0; s < stages; ++s) {
    const int count = plan[s].count, chunks = StageChunks(count, plan[s].grain, WorkerCount());
    if (chunks == 0) continue;
    ParallelFor(chunks, [&](int cb, int ce, int) {
      for (int c = cb; c < ce; ++c) {
        const int begin = BlockBegin(count, chunks, c), end = BlockBegin(count, chunks, c + 1);
        if (begin < end) fn(s, begin, end, c);
      }
    });
  }
}

namespace {

using Clock = std::chrono::steady_clock;

// This thread's time on a CPU and waiting on a run queue (ns) and its time slices, from
// /proc/thread-self/schedstat (zeros where unavailable): QUADRANT_POOL_STATS.
void ReadSchedStat(std::array<long long, 3>& out) {
  out = {};
#if defined(__linux__)
  if (FILE* f = std::fopen("/proc/thread-self/schedstat", "r")) {
    if (std::fscanf(f, "%lld %lld %lld", &out[0], &out[1], &out[2]) != 3) out = {};
    std::fclose(f);
  }
#endif
}

#if defined(__linux__)
// A thread's schedstat file, opened once per thread and closed when the thread ends.
struct SchedFile {
  int fd = -2;  // -2: not opened yet, -1: unavailable
  ~SchedFile() {
    if (fd >= 0) close(fd);
  }
};
// The second field of a schedstat file: the thread's time waiting on a run queue, in ns.
long long RunqNanos(int fd) {
  if (fd < 0) return -1;
  char buf[128];
  const ssize_t n = pread(fd, buf, sizeof(buf) - 1, 0);
  if (n <= 0) return -1;
  buf[n] = 0;
  char* end = nullptr;
  std::strtoll(buf, &end, 10);
  if (end == buf) return -1;
  char* end2 = nullptr;
  const long long runq = std::strtoll(end, &end2, 10);
  return end2 == end ? -1 : runq;
}
#endif

class InlineTaskSystem final : public TaskSystem {
 public:
  InlineTaskSystem() {
    if (std::getenv("QUADRANT_POOL_STATS")) {
      stats_ = true;
      born_ = Clock::now();
      ReadSchedStat(sched_);
    }
  }
  ~InlineTaskSystem() override {
    if (!stats_) return;
    std::array<long long, 3> now{};
    ReadSchedStat(now);
    std::fprintf(stderr, "pool 1: life %.1f ms; caller cpu %.1f ms runq %.1f ms slices %lld\n",
                 std::chrono::duration<double, std::milli>(Clock::now() - born_).count(), (now[0] - sched_[0]) * 1e-6,
                 (now[1] - sched_[1]) * 1e-6, now[2] - sched_[2]);
  }
  int WorkerCount() const override { return 1; }
  int ThreadCount() const override { return 1; }
  void ParallelFor(int count, const RangeFn& fn) override {
    if (count > 0) fn(0, count, 0);
  }
  void ParallelStages(int stages, const StagePlan* plan, const StageFn& fn) override {
    for (int s = 0; s < stages; ++s) {
      if (plan[s].count > 0) fn(s, 0, plan[s].count, 0);
    }
  }

 private:
  bool stats_ = false;
  Clock::time_point born_;
  std::array<long long, 3> sched_{};
};

// Longest spin on a quiet machine. A sleeping worker takes about 100 us to wake on the 2-core
// VMs, and a step's serial gaps are of that order: 2000 circles at 2 threads ran 0.65 ms a step
// with a 100 us spin, 0.24 ms with 1 ms (0.22 ms at 1 thread).
constexpr int kMaxSpinMicros = 1000;
// Contention is judged by the caller's stalls: the part of each wait at a stage's end beyond
// twice its longest chunk of the job plus kStallSlackMicros (a worker that runs finishes its
// chunk within about that), summed over windows of kWindowMillis of parallel running (judged from
// kFirstJudgeMillis on, see Judge). A window with more than kStallShare of it stalled makes the
// pool serial (the caller alone) for kContendedMillis; a window that is stalled again right
// after such a period doubles the next one, up to kMaxContendedMillis, so a machine that stays
// busy pays for a probe rarely.
constexpr int kStallSlackMicros = 50;
constexpr int kWindowMillis = 40;
constexpr int kFirstJudgeMillis = 10;
constexpr double kStallShare = 0.2;
// A window in which the workers took part in fewer than this share of the jobs (at least
// kMinJobs of them) also makes the pool serial: the workers were not running when the jobs came
// (another process had their cores), so waking them only cost the caller a system call per job.
// Counted in jobs, not chunks: one job of pgs's velocity iterations has hundreds of chunks, and
// a worker that arrived for one such job in ten (measured beside niced builds: 44 of 637 jobs)
// outweighed the rest. Every job counts, however short: a job that is over before a worker
// could join gains nothing from the workers either (counting only jobs of 200 us or more kept
// 5050 circles beside a busy loop parallel, the worker in 13 of 595 jobs, each job paying a
// futex wake).
constexpr double kMinHelpShare = 0.5;
constexpr int kMinJobs = 8;
// The pool's threads together waiting on run queues for more than this share of a window: more
// runnable threads than cores (see Judge). Seen on a quiet machine: 0.00-0.20 (once 0.26 while
// the VM itself was slow); beside one busy loop 0.4-1.9 over the first 10 ms.
constexpr double kQueueShare = 0.35;
constexpr int kQueueFloorMillis = 20;
// Other processes using more than SpareCores + this many cores over a serial period keep the pool
// serial without a probe (OthersHoldCores).
constexpr double kOthersMargin = 0.5;
// Reads of procs_running that must all show other running threads (OthersPersist).
constexpr int kPersistReads = 3;
constexpr int kContendedMillis = 200;
constexpr int kMaxContendedMillis = 1600;

// Sleeps while *word == expected (or returns at once if it differs). Linux: the futex system
// call itself, because libstdc++'s std::atomic::wait first calls sched_yield four times, and a
// yield hands the core to a competing process for its time slice (measured with the first
// pool, which yielded while spinning: 16000 circles at 2 threads beside a nice -n 19 build took
// 5.8 ms per step, 1.2 ms without yields). Elsewhere std::atomic::wait. Callers re-check the
// word after waking: wake-ups may be spurious.
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

// The cores this process may run on (its affinity mask on Linux, so `taskset -c 0` counts 1).
int UsableCores() {
#if defined(__linux__)
  cpu_set_t set;
  if (sched_getaffinity(0, sizeof(set), &set) == 0) return std::max(1, CPU_COUNT(&set));
#endif
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

// The core this thread runs on right now, or -1 where the system cannot say.
int CurrentCpu() {
#if defined(__linux__)
  return sched_getcpu();
#else
  return -1;
#endif
}

// The pool thread (or caller) that is running a chunk of some pool right now, for nesting.
thread_local const TaskSystem* tRunning = nullptr;

// The claim word of the current region: job tag, stage, and the stage's unclaimed chunks
// [front, back), 16 bits each. Everything a thread needs to claim a chunk is in the one word, so
// a thread reads the job's other fields only after a successful claim, when the job cannot end
// before the chunk it holds does.
constexpr uint32_t kDoneStage = 0xFFFF;
// The tag's top bit: the job is a region (ParallelStages), whose chunks may be claimed in runs.
constexpr uint32_t kRunsTag = 0x8000;
// The next bit: the job's stages are claimed from lanes (ThreadPool::ClaimFromLanes), not from
// the claim word's [front, back).
constexpr uint32_t kLanesTag = 0x4000;
constexpr int kMaxThreads = 0xFFFF / 4;
constexpr int kMaxStagesPerJob = 0xFFFE;
constexpr uint64_t Pack(uint32_t tag, uint32_t stage, uint32_t front, uint32_t back) {
  return uint64_t(tag & 0xFFFF) << 48 | uint64_t(stage & 0xFFFF) << 32 | uint64_t(front & 0xFFFF) << 16 | (back & 0xFFFF);
}
constexpr uint32_t TagOf(uint64_t w) { return uint32_t(w >> 48); }
constexpr uint32_t StageOf(uint64_t w) { return uint32_t(w >> 32) & 0xFFFF; }
constexpr uint32_t FrontOf(uint64_t w) { return uint32_t(w >> 16) & 0xFFFF; }
constexpr uint32_t BackOf(uint64_t w) { return uint32_t(w) & 0xFFFF; }

class ThreadPool final : public TaskSystem {
 public:
  explicit ThreadPool(int threads) : workers_(threads) {
    // The claim word holds a stage's chunk count (up to 4 per thread) in 16 bits.
    if (threads > kMaxThreads) throw std::invalid_argument("MakeThreadPool: at most 16383 threads");
    // More threads than cores would only take turns on them: the extra ones are not started
    // (every block still exists and is run by the threads that are).
    const int running = std::min(threads, UsableCores());
    stats_ = std::getenv("QUADRANT_POOL_STATS") != nullptr;
    // QUADRANT_POOL_ALONE=0: serial steps still run the partition's blocks (on the caller), as
    // determinism tests need, which must compare the partitioned path with one thread whatever
    // the machine's load.
    if (const char* alone = std::getenv("QUADRANT_POOL_ALONE")) splitSerialSteps_ = std::strcmp(alone, "0") == 0;
    born_ = Clock::now();
    if (stats_) ReadSchedStat(callerSched_);
    workerSched_.assign(running, {});
    schedFds_ = std::vector<std::atomic<int>>(running);
    for (auto& fd : schedFds_) fd.store(-1, std::memory_order_relaxed);
    cpuOf_ = std::vector<std::atomic<int>>(running);
    tids_ = std::vector<std::atomic<int>>(running);
    steered_ = std::vector<std::atomic<bool>>(running);
    for (auto& tid : tids_) tid.store(0, std::memory_order_relaxed);
#if defined(__linux__)
    CPU_ZERO(&affinity_);
    hasAffinity_ = sched_getaffinity(0, sizeof(affinity_), &affinity_) == 0;
#endif
    for (auto& cpu : cpuOf_) cpu.store(-1, std::memory_order_relaxed);
#if defined(__linux__)
    // /proc/stat covers every core of the machine: it describes this process's cores only when
    // the process may run on all of them.
    if (UsableCores() == static_cast<int>(std::thread::hardware_concurrency())) machineCores_ = UsableCores();
    ticksPerSecond_ = sysconf(_SC_CLK_TCK);
    if (ticksPerSecond_ <= 0) machineCores_ = 0;
    // Niced processes count as others when this process is niced too, or when the kernel groups
    // processes by session (sched_autogroup_enabled): nice then only orders the threads of one
    // session, and a niced build in another session gets as much of a core as this process
    // (measured on these VMs: one thread beside a busy loop and two other sessions' nice -n 19
    // builds ran 120 ms of a 470 ms life, waiting 330 ms on the run queue).
    errno = 0;
    countNiced_ = getpriority(PRIO_PROCESS, 0) > 0;
    if (FILE* f = std::fopen("/proc/sys/kernel/sched_autogroup_enabled", "r")) {
      int on = 0;
      if (std::fscanf(f, "%d", &on) == 1 && on != 0) countNiced_ = true;
      std::fclose(f);
    }
    // Born beside other running processes (more of them than the cores the pool leaves free),
    // the pool starts serial for a period and then judges the machine as at the end of any
    // serial period (StayOrProbe). Judging by windows of parallel jobs alone takes 10-20 ms of
    // them (Judge), longer than a short run: beside one busy loop a benchmark run of 1000-8000
    // circles (70 steps of 0.08-0.6 ms, a new World and pool each) ended before any verdict, and
    // 2 threads ran 1.0-2.1x slower than 1 (issue #14, this pool before the check).
    // /proc/stat's procs_running counts the threads on a core right now, this one included
    // (seen on these VMs: 1 when quiet, 3-4 beside one shell busy loop).
    //
    // The reading must hold over kPersistReads reads 1 ms apart: on a quiet machine a single read
    // saw another thread on a core at 1 of 6 births (a kernel thread's or another process's
    // burst), and the pool's 2 threads then ran serially for its whole life (base-100 pyramid,
    // 70 steps: 2.1-2.4 ms a step against 1.4-1.5 in parallel). A busy loop is on a core at
    // every read.
    if (!splitSerialSteps_ && running > 1 && machineCores_ > 0) {
      if (OthersPersist(/*ownRunning=*/1, SpareCores(running), kPersistReads, std::chrono::milliseconds(1))) {
        const Clock::time_point now = Clock::now();
        serialUntil_ = now + std::chrono::milliseconds(kContendedMillis);
        windowOpen_ = false;
        probing_ = true;
        machine_ = SampleMachine(now);
        statBornSerial_ = 1;
      }
    }
#endif
    threads_.reserve(running - 1);
    laneCount_ = running;
    lanes_ = std::make_unique<Lane[]>(size_t(running));
    // Where a stage is not laned, odd workers claim from the back, the caller and even workers
    // from the front (lanes do the same for every thread count; ClaimFromLanes):
    // on two threads the caller runs the low chunks and the worker the high ones in every stage
    // and pass, meeting wherever their speeds put the split, so a chunk's rows and bodies stay in
    // one core's cache from pass to pass (a soft_step sub-step is 13 stages over the same groups
    // on circle stress). Claimed from one end the threads took turns, and each pass moved about
    // half the chunks' data to the other core: circle stress 16000, 2 threads, quiet 2-core VM,
    // solve stage 0.264 -> 0.217 ms a step; polygon stress 16000 0.494 -> 0.413 ms.
    for (int w = 1; w < running; ++w) threads_.emplace_back([this, w] { WorkerLoop(w, /*fromBack=*/w % 2 == 1); });
  }

  ~ThreadPool() override {
    stop_.store(true, std::memory_order_seq_cst);
    jobWord_.fetch_add(1, std::memory_order_seq_cst);
    WakeAll(jobWord_);
    for (std::thread& t : threads_) t.join();
#if defined(__linux__)
    for (auto& fd : schedFds_) {
      if (fd.load() >= 0) close(fd.load());
    }
#endif
    if (stats_) {
      std::array<long long, 3> now{};
      ReadSchedStat(now);
      for (int k = 0; k < 3; ++k) callerSched_[k] = now[k] - callerSched_[k];
      std::fprintf(stderr,
                   "pool %d: life %.1f ms, steps %lld (alone %lld), jobs %lld, serial %lld, caller alone %lld, parallel-job time %.3f ms, wait %.3f ms, "
                   "waits>1ms %lld, first job at %.1f ms, marks %d (first at %.1f ms), probes %d, failed probes %d; caller cpu %.1f ms runq %.1f ms "
                   "slices %lld; marks by stall %d idle %d queue %d, first queue share %.2f, max %.2f, extended %d, others %.2f cores, born serial %d, queue unconfirmed %d, "
                   "excused jobs %lld (helped %lld), prepare wakes %lld, spreads %lld, steers %lld",
                   workers_, std::chrono::duration<double, std::milli>(Clock::now() - born_).count(), statSteps_, statAloneSteps_, statJobs_, statSerial_,
                   statAlone_, statJobNs_ * 1e-6, statWaitNs_ * 1e-6, statLong_, statFirstJobMs_, statMarks_, statFirstMarkMs_, statProbes_,
                   statFailedProbes_, callerSched_[0] * 1e-6, callerSched_[1] * 1e-6, callerSched_[2], statMarkStall_, statMarkIdle_,
                   statMarkQueued_, statFirstQueue_, statMaxQueue_, statExtended_, statOthers_, statBornSerial_, statQueueUnconfirmed_,
                   statExcused_, statExcusedHelped_, statPrepareWakes_, statSpreads_.load(), statSteers_.load());
      for (size_t w = 1; w < workerSched_.size(); ++w) {
        std::fprintf(stderr, "; worker %zu cpu %.1f ms runq %.1f ms slices %lld", w, workerSched_[w][0] * 1e-6,
                     workerSched_[w][1] * 1e-6, workerSched_[w][2]);
      }
      std::fprintf(stderr, "\n");
    }
  }

  int WorkerCount() const override { return workers_; }
  int ThreadCount() const override { return static_cast<int>(threads_.size()) + 1; }

  void ParallelFor(int count, const RangeFn& fn) override {
    if (count <= 0) return;
    if (threads_.empty() || tRunning == this || Serial()) {
      const TaskSystem* outer = std::exchange(tRunning, this);
      try {
        for (int b = 0; b < workers_; ++b) {
          const int begin = BlockBegin(count, workers_, b), end = BlockBegin(count, workers_, b + 1);
          if (begin < end) fn(begin, end, b);
        }
      } catch (...) {
        tRunning = outer;
        throw;
      }
      tRunning = outer;
      return;
    }
    rangeFn_ = &fn;
    stageFn_ = nullptr;
    oneStage_ = {count, 1};
    plan_ = &oneStage_;
    chunks_.assign(1, workers_);
    Run(1);
  }

  void ParallelStages(int stages, const StagePlan* plan, const StageFn& fn) override {
    if (threads_.empty() || tRunning == this || Serial()) {
      const TaskSystem* outer = std::exchange(tRunning, this);
      // Chunk by chunk, as the threads would run them, so that StageRunner's load-balance bound
      // describes the partition whichever way the region ran.
      try {
        for (int s = 0; s < stages; ++s) {
          const int count = plan[s].count, chunks = StageChunks(count, plan[s].grain, workers_);
          for (int c = 0; c < chunks; ++c) {
            const int begin = BlockBegin(count, chunks, c), end = BlockBegin(count, chunks, c + 1);
            if (begin < end) fn(s, begin, end, c);
          }
        }
      } catch (...) {
        tRunning = outer;
        throw;
      }
      tRunning = outer;
      return;
    }
    for (int first = 0; first < stages; first += kMaxStagesPerJob) {
      const int n = std::min(stages - first, kMaxStagesPerJob);
      StageFn shifted;
      const StageFn* f = &fn;
      if (first > 0) {
        shifted = [&fn, first](int s, int b, int e, int c) { fn(first + s, b, e, c); };
        f = &shifted;
      }
      rangeFn_ = nullptr;
      stageFn_ = f;
      plan_ = plan + first;
      chunks_.resize(n);
      for (int s = 0; s < n; ++s) chunks_[s] = StageChunks(plan_[s].count, plan_[s].grain, workers_);
      Run(n);
    }
  }

 private:
  // A step asks before it starts (StageRunner::BeginStep): while the pool is serial, the
  // engine's one-thread path is cheaper than running the partition's blocks one by one.
  bool RunsAlone() override {
    if (splitSerialSteps_) return false;
    if (threads_.empty()) return true;
    if (tRunning == this) return false;
    const Clock::time_point now = Clock::now();
    const bool alone = now < serialUntil_ || (!windowOpen_ && StayOrProbe(now));
    ++statSteps_;
    statAloneSteps_ += alone;
    return alone;
  }

  // The step begins (StageRunner::BeginStep, after RunsAlone said no): wake sleeping workers, so
  // that they spin by the step's first job. Only where the last step (or none yet) ran a job: a
  // step with no parallel section would only keep a core spinning for a millisecond. Where the
  // caller was away from the pool for longer than a spin (a game loop sleeping to its next
  // frame), the workers sleep by design, and the jobs published before they are up are excused
  // from the idle rule (Run): a wake-up's latency is no sign of a busy machine (a 60 Hz frame
  // loop of 8000 boxes at 2 threads ran 271 of 300 steps alone on that sign). Steps back to back
  // get no excuse: there a worker asleep at a step's start was preempted while it spun.
  void Prepare() override {
    waking_ = false;
    if (threads_.empty() || tRunning == this) return;
    cpuOf_[0].store(CurrentCpu(), std::memory_order_relaxed);
    const bool ranJobs = jobs_ != jobsAtPrepare_ || !prepared_;
    jobsAtPrepare_ = jobs_;
    prepared_ = true;
    if (!ranJobs || jobSleepers_.load(std::memory_order_seq_cst) == 0) return;
    ++statPrepareWakes_;
    waking_ = Clock::now() - lastJobEnd_ > std::chrono::microseconds(kMaxSpinMicros);
    if (waking_) SteerSleepers();
    // A bump without a new job: a woken worker finds the claim word of a finished job, claims
    // nothing and spins for the next one (WorkerLoop).
    jobWord_.fetch_add(1, std::memory_order_seq_cst);
    WakeAll(jobWord_);
  }

  // True while the pool runs every job on the caller alone (contention, see Judge).
  bool Serial() {
    const Clock::time_point now = Clock::now();
    if (now < serialUntil_ || (!windowOpen_ && StayOrProbe(now))) {
      ++statSerial_;
      return true;
    }
    if (now - windowStart_ >= std::chrono::milliseconds(kFirstJudgeMillis)) Judge(now);
    return now < serialUntil_;
  }

  // The window's stalled share above which the caller alone is faster. Alone gives up P - 1
  // threads, so it pays only where stalls took more of the window than those threads gave back:
  // about 1 - 1/P of it with perfect speed-up. The limit keeps the measured 2-thread margin
  // (kStallShare) on that scale: 1 - (1 - kStallShare) * 2 / P, 0.2 at 2 threads, 0.6 at 4, 0.9
  // at 16. On a quiet machine a stage's end waits for the slowest thread's last chunk, a larger
  // part of the stage the more threads share it, so a fixed share that fits 2 threads reads the
  // waits of 16 as stalls (seen on a quiet 16-core machine: 64000 circles at 16 threads ran 122
  // of 180 steps alone, slower than 4 threads).
  double StallShareLimit() const { return 1.0 - (1.0 - kStallShare) * 2.0 / std::max(2, ThreadCount()); }

  // No window is open: the pool has not run a parallel job yet, or a serial period has ended.
  // If other processes kept the cores busy all through that period, a probe would only fail
  // again: stay serial for another period (true). Otherwise open a window (false).
  bool StayOrProbe(Clock::time_point now) {
    if (probing_ && OthersHoldCores(now)) {
      serialUntil_ = now + std::chrono::milliseconds(kContendedMillis);
      ++statExtended_;
      return true;
    }
    statProbes_ += probing_;
    windowOpen_ = true;
    OpenWindow(now);
    return false;
  }

  void OpenWindow(Clock::time_point now) {
    windowStart_ = now;
    stalled_ = {};
    windowJobs_ = windowHelped_ = 0;
    runqStart_ = PoolRunqNanos();
    runqCheck_ = now;
  }

  // The window of parallel jobs so far. More than kStallShare of it spent waiting for chunks
  // whose threads were not running means another process wants these cores: every stage end
  // then waits a time slice for a preempted worker, and the caller alone is faster. Stalls are
  // judged from kFirstJudgeMillis on, as soon as they exceed kStallShare of a whole window (a
  // benchmark run of 16000 circles is 70 steps of about 1.2 ms: waiting for the end of a 40 ms
  // window at the 2-thread busy speed would be half of it); idle workers, and a clean window,
  // only after kWindowMillis. The pool's threads waiting on run queues for more than
  // kQueueShare of the window (checked every kFirstJudgeMillis) also means more runnable threads
  // than cores.
  void Judge(Clock::time_point now) {
    // Over at least a whole window: a lone preemption of 2-3 ms in the first 10 ms of a run on an
    // otherwise quiet machine (another process's burst) must not make the run serial.
    const double share =
        std::chrono::duration<double>(stalled_).count() /
        std::chrono::duration<double>(std::max<Clock::duration>(now - windowStart_, std::chrono::milliseconds(kWindowMillis))).count();
    const bool full = now - windowStart_ >= std::chrono::milliseconds(kWindowMillis);
    // Idle workers are judged on full windows only: a worker woken at a run's start can be late
    // for a few milliseconds behind a niced neighbour's time slice (seen: 53 of the first 105
    // jobs of a 16000-circle run on an otherwise quiet machine, which then ran serially), and
    // idle workers cost the caller little (a spinning worker needs no wake-up).
    const bool idle = full && windowJobs_ >= kMinJobs && windowHelped_ < kMinHelpShare * windowJobs_;
    bool queued = false;
    if (runqStart_ >= 0 && now - runqCheck_ >= std::chrono::milliseconds(kFirstJudgeMillis)) {
      runqCheck_ = now;
      const long long runq = PoolRunqNanos();
      if (runq >= 0) {
        // Over at least kQueueFloorMillis: one time slice of another process (about 3 ms) in
        // the first 10 ms is a burst, not a busy machine (one busy loop queued the two threads
        // for 0.4-1.9 of the first 10 ms: 4-19 ms).
        // Per two threads of the pool, the limit's scale: every wake-up of every thread waits on
        // a run queue a little, so the sum over 16 threads grows 8-fold on a quiet machine.
        const Clock::duration over = std::max<Clock::duration>(now - windowStart_, std::chrono::milliseconds(kQueueFloorMillis));
        const double queue = 2.0 / ThreadCount() * double(runq - runqStart_) * 1e-9 / std::chrono::duration<double>(over).count();
        if (statFirstQueue_ < 0) statFirstQueue_ = queue;
        statMaxQueue_ = std::max(statMaxQueue_, queue);
        // Confirmed by the machine's run queue right now (OthersPersist, reads back to back):
        // on a quiet machine another thread's burst of a few milliseconds reached a share of
        // 0.38 in the first window (2 of 14 base-100 pyramid processes at 2 threads), which then
        // went serial; a busy loop is still on a core when the pool looks.
        queued = queue > kQueueShare &&
                 OthersPersist(ThreadCount() - jobSleepers_.load(std::memory_order_relaxed), SpareCores(ThreadCount()),
                               kPersistReads, std::chrono::microseconds(0));
        statQueueUnconfirmed_ += queue > kQueueShare && !queued;
      }
    }
    const bool stalls = share > StallShareLimit();
    if (!stalls && !idle && !queued) {
      if (!full) return;
      probing_ = false;
      OpenWindow(now);
      contendedMillis_ = kContendedMillis;
      return;
    }
    const bool probe = probing_;  // the first window after a serial period
    probing_ = false;
    ++statMarks_;
    statMarkStall_ += stalls;
    statMarkIdle_ += idle;
    statMarkQueued_ += queued;
    statFailedProbes_ += probe;
    if (statFirstMarkMs_ < 0) statFirstMarkMs_ = std::chrono::duration<double, std::milli>(now - born_).count();
    contendedMillis_ = probe ? std::min(2 * contendedMillis_, kMaxContendedMillis) : kContendedMillis;
    serialUntil_ = now + std::chrono::milliseconds(contendedMillis_);
    windowOpen_ = false;
    probing_ = true;
    machine_ = SampleMachine(now);
  }

  // Whether other processes used more of the machine's cores since machine_ was sampled than
  // the pool could spare (more than SpareCores + kOthersMargin of them), from
  // /proc/stat's busy ticks less this process's own CPU time. /proc/stat counts in ticks of
  // 10 ms per core, which is enough over a serial period of 200 ms. Niced processes count only
  // where they compete with this one (countNiced_). False where /proc/stat cannot say.
  bool OthersHoldCores(Clock::time_point now) {
    const MachineSample before = machine_, after = SampleMachine(now);
    machine_ = after;
    if (before.busySeconds < 0 || after.busySeconds < 0) return false;
    const double wall = std::chrono::duration<double>(after.at - before.at).count();
    if (wall < 0.1) return false;
    const double others = ((after.busySeconds - before.busySeconds) - (after.ownSeconds - before.ownSeconds)) / wall;
    statOthers_ = others;
    return others > double(SpareCores(ThreadCount())) + kOthersMargin;
  }

  // The machine's cores that other processes may use before they crowd a pool of `threads`: all
  // but the two a parallel step needs (all but the pool's threads where it has one or two). On 2
  // cores that is none, as the busy-machine figures need; on 16 cores a pool of 16 threads does
  // not go alone because a background process uses half a core: beside 15 free cores the caller
  // alone is the slowest schedule, and a preempted thread's stalls are what Judge weighs.
  int SpareCores(int threads) const { return machineCores_ - std::min(threads, 2); }

  // Whether other threads than the pool's `ownRunning` ones are on the machine's cores, more
  // of them than `freeCores` + kOthersMargin, at each of `samples` reads of procs_running, `gap`
  // apart. False where procs_running cannot be read or this process may not run on every core.
  bool OthersPersist(int ownRunning, int freeCores, int samples, std::chrono::microseconds gap) const {
    if (machineCores_ <= 0) return false;
    for (int k = 0; k < samples; ++k) {
      if (k > 0 && gap.count() > 0) std::this_thread::sleep_for(gap);
      const int running = RunningThreadsNow();
      if (running < 0) return false;
      const int others = running - ownRunning;
      if (!(others > 0 && double(others) > double(freeCores) + kOthersMargin)) return false;
    }
    return true;
  }

  // /proc/stat's procs_running: the threads of the whole machine on a core at this moment; -1
  // where unavailable (then the check at birth does nothing).
  static int RunningThreadsNow() {
#if defined(__linux__)
    FILE* f = std::fopen("/proc/stat", "r");
    if (f == nullptr) return -1;
    char line[256];
    int running = -1;
    while (std::fgets(line, sizeof line, f) != nullptr) {
      if (std::sscanf(line, "procs_running %d", &running) == 1) break;
    }
    std::fclose(f);
    return running;
#else
    return -1;
#endif
  }

  struct MachineSample {
    double busySeconds = -1;  // every core's busy time (niced processes' only if this one is niced)
    double ownSeconds = 0;    // this process's CPU time
    Clock::time_point at;
  };
  MachineSample SampleMachine(Clock::time_point now) const {
    MachineSample m;
    m.at = now;
#if defined(__linux__)
    if (machineCores_ <= 0) return m;
    FILE* f = std::fopen("/proc/stat", "r");
    if (f == nullptr) return m;
    // cpu user nice system idle iowait irq softirq steal
    unsigned long long v[8] = {};
    const int got = std::fscanf(f, "cpu %llu %llu %llu %llu %llu %llu %llu %llu", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5],
                                &v[6], &v[7]);
    std::fclose(f);
    if (got < 8) return m;
    const unsigned long long busy = v[0] + (countNiced_ ? v[1] : 0) + v[2] + v[5] + v[6] + v[7];
    timespec own{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &own);
    m.busySeconds = double(busy) / double(ticksPerSecond_);
    m.ownSeconds = double(own.tv_sec) + 1e-9 * double(own.tv_nsec);
#endif
    return m;
  }

  // The run-queue waits of the pool's threads (the calling thread and every started worker) so
  // far, in ns, from /proc/thread-self/schedstat; -1 where unavailable.
  long long PoolRunqNanos() {
#if defined(__linux__)
    thread_local SchedFile caller;
    if (caller.fd == -2) caller.fd = open("/proc/thread-self/schedstat", O_RDONLY | O_CLOEXEC);
    long long total = RunqNanos(caller.fd);
    if (total < 0) return -1;
    for (size_t w = 1; w < schedFds_.size(); ++w) {
      const long long runq = RunqNanos(schedFds_[w].load(std::memory_order_acquire));
      if (runq < 0) return -1;
      total += runq;
    }
    return total;
#else
    return -1;
#endif
  }

  // Spins until done() or `budget` runs out; true if done() became true.
  template <class Done>
  bool Spin(Done done, Clock::duration budget) {
    const Clock::time_point end = Clock::now() + budget;
    for (;;) {
      for (int k = 0; k < 4; ++k) {
        if (done()) return true;
#if defined(__x86_64__) || defined(__i386__)
        for (int p = 0; p < 8; ++p) _mm_pause();
#else
        std::this_thread::yield();
#endif
      }
      if (Clock::now() >= end) return done();
    }
  }

  // The caller: publishes the job (its fields first, then the claim word, then the wake word),
  // runs chunks with the workers and returns when the last stage is done.
  void Run(int stages) {
    stages_ = stages;
    cpuOf_[0].store(CurrentCpu(), std::memory_order_relaxed);
    int first = 0;
    while (first < stages && chunks_[first] == 0) ++first;
    if (first == stages) return;
    ++statJobs_;
    ++jobs_;
    const Clock::time_point jobStart = stats_ ? Clock::now() : Clock::time_point{};
    if (stats_ && statFirstJobMs_ < 0) statFirstJobMs_ = std::chrono::duration<double, std::milli>(jobStart - born_).count();
    // A job published while the workers that Prepare woke are still getting up says nothing about
    // the machine (Judge's idle rule); the first job that finds them up ends the excuse.
    waking_ = waking_ && jobSleepers_.load(std::memory_order_seq_cst) > 0;
    const bool excused = waking_;
    failed_.store(false, std::memory_order_relaxed);
    done_.store(0, std::memory_order_relaxed);
    tag_ = (tag_ + 1) & (kLanesTag - 1);
    if (!rangeFn_) {  // a region: its stages are claimed in runs of chunks, unless one says not
      bool runs = true;
      for (int s = 0; s < stages; ++s) runs = runs && plan_[s].runs;
      if (runs) tag_ |= kRunsTag | kLanesTag;
    } else {
      tag_ |= kLanesTag;
    }
    // Workers that slept since the step began (a serial part longer than a spin) are steered too.
    const bool wake = jobSleepers_.load(std::memory_order_seq_cst) > 0;
    if (wake) SteerSleepers();
    claim_.store(Pack(tag_, first, 0, chunks_[first]), std::memory_order_seq_cst);
    jobWord_.fetch_add(1, std::memory_order_seq_cst);
    if (wake || jobSleepers_.load(std::memory_order_seq_cst) > 0) WakeAll(jobWord_);
    const int mine = Claim(tag_, 0, false), total = TotalChunks();
    if (mine == total) ++statAlone_;
    if (excused) {
      ++statExcused_;
      statExcusedHelped_ += mine < total;
    } else {
      ++windowJobs_;
      windowHelped_ += mine < total;
    }
    lastJobEnd_ = Clock::now();
    if (stats_) statJobNs_ += std::chrono::duration_cast<std::chrono::nanoseconds>(lastJobEnd_ - jobStart).count();
    rangeFn_ = nullptr;
    stageFn_ = nullptr;
    if (error_) {
      std::exception_ptr error = std::exchange(error_, nullptr);
      std::rethrow_exception(error);
    }
  }
  int TotalChunks() const {
    int total = 0;
    for (int s = 0; s < stages_; ++s) total += chunks_[s];
    return total;
  }

  // Claims and runs chunks of job `tag` until its last stage is done (the caller) or it has
  // ended or moved on (a worker). A thread whose stage has no chunk left waits for the stage to
  // finish: it spins briefly, then sleeps on the progress word. The thread that finishes a
  // stage's last chunk publishes the next stage. A laned job's chunks come from the lanes
  // (ClaimFromLanes); another's from the front of the claim word's unclaimed chunks, or from the
  // back if fromBack (the constructor says why). Returns the chunks it ran.
  int Claim(uint32_t tag, int self, bool fromBack) {
    const bool caller = self == 0;
    const TaskSystem* outer = std::exchange(tRunning, this);
    int ran = 0;
    uint64_t w = claim_.load(std::memory_order_acquire);
    Clock::duration lastChunk{};  // the caller's longest chunk of this job so far
    // Runs chunks [chunk, chunk + take) of `stage` (held), and publishes the next stage after
    // the stage's last chunk.
    auto run = [&](uint32_t stage, uint32_t chunk, uint32_t take) {
      const uint32_t stageChunks = uint32_t(chunks_[stage]);
      const Clock::time_point t0 = caller ? Clock::now() : Clock::time_point{};
      RunChunks(static_cast<int>(stage), static_cast<int>(chunk), static_cast<int>(take));
      if (caller) lastChunk = std::max<Clock::duration>(lastChunk, Clock::now() - t0);
      ran += static_cast<int>(take);
      if (done_.fetch_add(take, std::memory_order_acq_rel) + take == stageChunks) Advance(tag, stage);
    };
    for (;;) {
      if (TagOf(w) != tag || StageOf(w) == kDoneStage) break;
      if (TagOf(w) & kLanesTag) {
        uint32_t chunk = 0, take = 0;
        if (ClaimFromLanes(w, self, chunk, take)) {
          run(StageOf(w), chunk, take);
          w = claim_.load(std::memory_order_acquire);
          continue;
        }
        // Nothing to claim: wait for the stage's end, unless it ended meanwhile or a lane refilled
        // its view (a claim lost on a race, a lane opened since).
        const uint64_t now = claim_.load(std::memory_order_acquire);
        if (now != w || !LanesEmpty(w)) {
          w = now;
          continue;
        }
        w = WaitForChange(w, self, lastChunk);
        continue;
      }
      if (FrontOf(w) < BackOf(w)) {
        // Only stages whose chunks differ by design come here (a region with runs = false,
        // StageRunner::Beside's, whose first chunk is its lone part): one chunk a claim. Runs of
        // chunks are the lanes' (a region's runs took a stage's time beyond half its work on the
        // base-100 pyramid at 2 threads from 0.53 to 0.40 us, 148 -> 112 claims a region).
        const uint32_t take = 1;
        const uint64_t claimed = fromBack ? w - take : w + (uint64_t(take) << 16);
        if (!claim_.compare_exchange_weak(w, claimed, std::memory_order_acq_rel, std::memory_order_acquire)) {
          continue;
        }
        // The stage's chunk count is read while these chunks are held (the job cannot end before them).
        run(StageOf(w), fromBack ? BackOf(w) - take : FrontOf(w), take);
        w = claim_.load(std::memory_order_acquire);
        continue;
      }
      w = WaitForChange(w, self, lastChunk);
    }
    tRunning = outer;
    return ran;
  }

  // Lanes: a laned stage's C chunks (BackOf its claim word) are cut into one lane per running
  // thread, lane i holding [BlockBegin(C, n, i), BlockBegin(C, n, i + 1)). A thread claims from
  // the front of its own lane (half of what is left in a region's runs, else one chunk), then
  // from the back of the others' (half, or one). So in every stage and pass of a step thread i
  // runs the same chunks, whose rows and bodies stay in its core's cache, unless another ran out
  // of work first. The one claim word gave that only to two threads (front and back); from 4 on
  // the chunks moved between cores from stage to stage (the head comment has the gain). A
  // lane's word is the stage's stamp (the claim word's tag and
  // stage), front and back; the first thread to touch a lane in a stage opens it (CAS from the
  // older stamp to the stage's range), so a stage's publication writes no lane. Only chunk
  // counts from the claim word are read before a claim, never the job's fields.
  bool ClaimFromLanes(uint64_t w, int self, uint32_t& chunk, uint32_t& take) {
    const uint32_t stamp = uint32_t(w >> 32), count = BackOf(w);
    const bool runs = (TagOf(w) & kRunsTag) != 0;
    const int n = laneCount_;
    for (int k = 0; k < n; ++k) {
      const int lane = (self + k) % n;  // its own first, then the next ones
      std::atomic<uint64_t>& word = lanes_[size_t(lane)].word;
      uint64_t l = word.load(std::memory_order_acquire);
      for (;;) {
        if (uint32_t(l >> 32) != stamp) {
          // Not opened in this stage. If the claim word has moved on, so has the stage (the
          // caller re-reads it); while it has not, the lane's stamp is an earlier stage's.
          if (claim_.load(std::memory_order_acquire) != w) return false;
          const uint64_t open = uint64_t(stamp) << 32 | uint64_t(BlockBegin(int(count), n, lane)) << 16 |
                                uint64_t(BlockBegin(int(count), n, lane + 1));
          if (!word.compare_exchange_weak(l, open, std::memory_order_acq_rel, std::memory_order_acquire)) continue;
          l = open;
        }
        const uint32_t front = FrontOf(l), back = BackOf(l);
        if (front >= back) break;  // empty: the next lane
        const uint32_t left = back - front;
        const uint32_t t = k == 0 ? (runs ? (left + 1) / 2 : 1) : (runs ? std::max<uint32_t>(1, left / 2) : 1);
        const uint64_t next = k == 0 ? l + (uint64_t(t) << 16) : l - t;
        if (word.compare_exchange_weak(l, next, std::memory_order_acq_rel, std::memory_order_acquire)) {
          chunk = k == 0 ? front : back - t;
          take = t;
          return true;
        }
      }
    }
    return false;
  }
  // Whether a laned stage may still have an unclaimed chunk: a lane of it not yet opened, or
  // opened and not empty (a claim that failed on a race, or a lane that another opened since).
  bool LanesEmpty(uint64_t w) const {
    const uint32_t stamp = uint32_t(w >> 32), count = BackOf(w);
    for (int lane = 0; lane < laneCount_; ++lane) {
      const uint64_t l = lanes_[size_t(lane)].word.load(std::memory_order_acquire);
      if (uint32_t(l >> 32) != stamp) {
        if (BlockBegin(int(count), laneCount_, lane) < BlockBegin(int(count), laneCount_, lane + 1)) return false;
      } else if (FrontOf(l) < BackOf(l)) {
        return false;
      }
    }
    return true;
  }

  // The stage's last chunk is done: publish the next non-empty stage, or the end of the job.
  void Advance(uint32_t tag, uint32_t stage) {
    done_.store(0, std::memory_order_relaxed);
    uint32_t next = stage + 1;
    while (next < uint32_t(stages_) && chunks_[next] == 0) ++next;
    const uint64_t w = next < uint32_t(stages_) ? Pack(tag, next, 0, chunks_[next]) : Pack(tag, kDoneStage, 0, 0);
    claim_.store(w, std::memory_order_seq_cst);
    progress_.fetch_add(1, std::memory_order_seq_cst);
    if (progressSleepers_.load(std::memory_order_seq_cst) > 0) WakeAll(progress_);
  }

  // Waits until the claim word is no longer w (the stage was finished by the threads that hold
  // its last chunks). Spins up to kMaxSpinMicros, then sleeps. A caller whose wait outlasts a
  // few tens of microseconds more than twice its own last chunk was (in that excess) waiting
  // on a chunk whose thread was not running: a stall (Judge).
  uint64_t WaitForChange(uint64_t w, int self, Clock::duration ownChunk) {
    const bool caller = self == 0;
    auto changed = [&] { return claim_.load(std::memory_order_acquire) != w; };
    const Clock::time_point start = Clock::now();
    if (!Spin(changed, std::chrono::microseconds(kMaxSpinMicros))) {
      progressSleepers_.fetch_add(1, std::memory_order_seq_cst);
      if (!caller) cpuOf_[self].store(-1, std::memory_order_relaxed);
      for (;;) {
        const uint32_t seen = progress_.load(std::memory_order_seq_cst);
        if (changed()) break;
        WaitWhileEqual(progress_, seen);
      }
      progressSleepers_.fetch_sub(1, std::memory_order_seq_cst);
      if (!caller) Spread(self);
    }
    if (caller) {
      const Clock::time_point now = Clock::now();
      const Clock::duration waited = now - start;
      statWaitNs_ += std::chrono::duration_cast<std::chrono::nanoseconds>(waited).count();
      if (waited > std::chrono::milliseconds(1)) ++statLong_;
      const Clock::duration normal = 2 * ownChunk + std::chrono::microseconds(kStallSlackMicros);
      if (waited > normal) stalled_ += waited - normal;
    }
    return claim_.load(std::memory_order_acquire);
  }

  // Chunks [chunk, chunk + take) of the stage, as one call over their items.
  void RunChunks(int stage, int chunk, int take) {
    if (failed_.load(std::memory_order_relaxed)) return;  // an earlier chunk threw: skip
    const int count = plan_[stage].count, chunks = chunks_[stage];
    const int begin = BlockBegin(count, chunks, chunk), end = BlockBegin(count, chunks, chunk + take);
    if (begin >= end) return;
    try {
      if (rangeFn_) {
        (*rangeFn_)(begin, end, chunk);
      } else {
        (*stageFn_)(stage, begin, end, chunk);
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(errorMutex_);
      if (!error_) error_ = std::current_exception();
      failed_.store(true, std::memory_order_relaxed);
    }
  }

  // A worker just woken: if it landed on a core where another of the pool's threads runs, it
  // moves to a core none of them uses (its affinity without theirs, then the whole mask again,
  // which leaves it where it went). On the 2-core VMs the kernel puts a woken worker on the
  // waking caller's core 9 times in 10 while the other core idles (it sees no cache shared
  // between them), and the worker, spinning there, holds the caller off its own core: a 60 Hz
  // frame loop of 7975 boxes at 2 threads took 4.2 ms a step against 2.7 back to back, the caller
  // waiting 0.6 ms a frame on the run queue. Back to back the threads never sleep and never meet.
  void Spread(int self) {
#if defined(__linux__)
    if (steered_[self].exchange(false, std::memory_order_acq_rel)) sched_setaffinity(0, sizeof(affinity_), &affinity_);
    const int here = CurrentCpu();
    if (here < 0) return;
    bool shared = false;
    for (size_t t = 0; t < cpuOf_.size(); ++t) shared = shared || (int(t) != self && cpuOf_[t].load(std::memory_order_relaxed) == here);
    if (shared) {
      cpu_set_t all, elsewhere;
      if (sched_getaffinity(0, sizeof(all), &all) == 0) {
        elsewhere = all;
        CPU_CLR(here, &elsewhere);
        for (size_t t = 0; t < cpuOf_.size(); ++t) {
          const int cpu = cpuOf_[t].load(std::memory_order_relaxed);
          if (cpu >= 0 && cpu < CPU_SETSIZE) CPU_CLR(cpu, &elsewhere);
        }
        if (CPU_COUNT(&elsewhere) > 0 && sched_setaffinity(0, sizeof(elsewhere), &elsewhere) == 0) {
          sched_setaffinity(0, sizeof(all), &all);
          statSpreads_.fetch_add(1, std::memory_order_relaxed);
        }
      }
    }
    cpuOf_[self].store(CurrentCpu(), std::memory_order_relaxed);
#else
    (void)self;
#endif
  }

  // The caller, back after longer than a spin (a frame loop's sleep), is about to wake the
  // workers: each sleeping one may for now run anywhere but on the caller's core, so that the
  // kernel cannot queue it behind the caller there (Spread says how often it did); the worker
  // takes back the whole mask once it runs. Without this, 7975 boxes at 60 Hz on 2 threads: the
  // worker waited 2.4 ms a frame on the caller's run queue and took part in 93 of 1573 jobs.
  void SteerSleepers() {
#if defined(__linux__)
    const int here = CurrentCpu();
    if (!hasAffinity_ || here < 0 || here >= CPU_SETSIZE || !CPU_ISSET(here, &affinity_)) return;
    cpu_set_t elsewhere = affinity_;
    CPU_CLR(here, &elsewhere);
    if (CPU_COUNT(&elsewhere) == 0) return;
    for (size_t w = 1; w < tids_.size(); ++w) {
      const int tid = tids_[w].load(std::memory_order_acquire);
      if (tid <= 0 || cpuOf_[w].load(std::memory_order_relaxed) >= 0) continue;  // not started, or awake
      if (sched_setaffinity(tid, sizeof(elsewhere), &elsewhere) == 0) {
        steered_[w].store(true, std::memory_order_release);
        statSteers_.fetch_add(1, std::memory_order_relaxed);
      }
    }
#endif
  }

  void WorkerLoop(int index, bool fromBack) {
    std::array<long long, 3> start{};
    if (stats_) ReadSchedStat(start);
#if defined(__linux__)
    schedFds_[index].store(open("/proc/thread-self/schedstat", O_RDONLY | O_CLOEXEC), std::memory_order_release);
    tids_[index].store(static_cast<int>(syscall(SYS_gettid)), std::memory_order_release);
#endif
    uint32_t seen = 0;
    for (;;) {
      auto arrived = [&] { return jobWord_.load(std::memory_order_acquire) != seen; };
      if (!Spin(arrived, std::chrono::microseconds(kMaxSpinMicros))) {
        jobSleepers_.fetch_add(1, std::memory_order_seq_cst);
        cpuOf_[index].store(-1, std::memory_order_relaxed);
        while (jobWord_.load(std::memory_order_seq_cst) == seen) WaitWhileEqual(jobWord_, seen);
        jobSleepers_.fetch_sub(1, std::memory_order_relaxed);
        Spread(index);
      }
      // The word first, then the stop flag: the destructor sets the flag before its bump, so a
      // word that holds the bump comes with the flag set. Read the other way round, a worker
      // between the two reads took the destructor's bump as its `seen`, went back to sleep on it
      // and was never woken: the destructor's join hung (seen under load: a World destroyed while
      // its worker was just back from a job; docs/notes/thread_pool.md).
      const uint32_t now = jobWord_.load(std::memory_order_acquire);
      if (stop_.load(std::memory_order_acquire)) {
        if (stats_) {
          ReadSchedStat(workerSched_[index]);
          for (int k = 0; k < 3; ++k) workerSched_[index][k] -= start[k];
        }
        return;
      }
      seen = now;
      Claim(TagOf(claim_.load(std::memory_order_acquire)), index, fromBack);
    }
  }

  const int workers_;
  std::vector<std::thread> threads_;

  // The current job: written by the caller before the claim word is published, read by the
  // others only while they hold a chunk.
  const RangeFn* rangeFn_ = nullptr;  // ParallelFor: one stage whose chunks are the blocks
  const StageFn* stageFn_ = nullptr;
  const StagePlan* plan_ = nullptr;
  StagePlan oneStage_;
  std::vector<int> chunks_;
  int stages_ = 0;
  uint32_t tag_ = 0;

  std::atomic<uint64_t> claim_{Pack(0, kDoneStage, 0, 0)};
  struct alignas(64) Lane {
    std::atomic<uint64_t> word{Pack(0, kDoneStage, 0, 0)};  // stamp (tag, stage), front, back
  };
  std::unique_ptr<Lane[]> lanes_;  // one per running thread (ClaimFromLanes)
  int laneCount_ = 1;
  std::atomic<uint32_t> done_{0};            // chunks of the current stage finished
  std::atomic<uint32_t> jobWord_{0};         // bumped per job, for workers to wait on
  std::atomic<uint32_t> progress_{0};        // bumped per stage, for waiters inside a job
  std::atomic<int> jobSleepers_{0};
  std::vector<std::atomic<int>> cpuOf_;  // the core each started thread (0: the caller) last ran on, -1 asleep
  std::atomic<long long> statSpreads_{0}, statSteers_{0};
  std::vector<std::atomic<int>> tids_;       // each started worker's thread id (0 until it starts)
  std::vector<std::atomic<bool>> steered_;   // SteerSleepers narrowed the worker's affinity
#if defined(__linux__)
  cpu_set_t affinity_;  // the process's cores at the pool's birth
#endif
  bool hasAffinity_ = false;
  std::atomic<int> progressSleepers_{0};
  std::atomic<bool> stop_{false};

  // Contention (the caller's alone): see Serial and Judge.
  Clock::time_point serialUntil_{};
  Clock::time_point windowStart_{};
  Clock::duration stalled_{};
  bool windowOpen_ = false;
  bool probing_ = false;
  long long windowJobs_ = 0, windowHelped_ = 0;  // this window's jobs, those a worker took part in
  bool waking_ = false;                            // Prepare woke workers after the caller's time away
  Clock::time_point lastJobEnd_{};                 // the end of the caller's last parallel job
  long long jobs_ = 0, jobsAtPrepare_ = 0;         // jobs run; jobs_ at the last Prepare
  bool prepared_ = false;
  int contendedMillis_ = kContendedMillis;
  long long runqStart_ = -1;  // PoolRunqNanos at the window's start
  Clock::time_point runqCheck_{};
  MachineSample machine_;  // at the start of the serial period
  int machineCores_ = 0;   // the machine's cores when /proc/stat describes this process's, else 0
  long ticksPerSecond_ = 100;
  bool countNiced_ = false;  // whether /proc/stat's niced time counts as others' (see the constructor)
  std::vector<std::atomic<int>> schedFds_;  // each worker's schedstat file (-1 until it opens it)

  long long statJobs_ = 0, statSerial_ = 0, statAlone_ = 0, statWaitNs_ = 0, statLong_ = 0, statJobNs_ = 0;
  int statMarks_ = 0, statProbes_ = 0, statFailedProbes_ = 0, statMarkStall_ = 0, statMarkIdle_ = 0, statMarkQueued_ = 0;
  int statExtended_ = 0;
  long long statExcused_ = 0, statExcusedHelped_ = 0, statPrepareWakes_ = 0;
  long long statSteps_ = 0, statAloneSteps_ = 0;
  double statFirstQueue_ = -1, statMaxQueue_ = 0, statOthers_ = -1;
  double statFirstMarkMs_ = -1, statFirstJobMs_ = -1;
  bool stats_ = false;
  bool splitSerialSteps_ = false;  // QUADRANT_POOL_ALONE=0: RunsAlone is always false
  int statQueueUnconfirmed_ = 0;   // queue shares above kQueueShare that procs_running did not confirm
  int statBornSerial_ = 0;         // 1: the pool started serial (the check at birth)
  Clock::time_point born_;
  std::array<long long, 3> callerSched_{};
  std::vector<std::array<long long, 3>> workerSched_;



  std::mutex errorMutex_;
  std::exception_ptr error_;  // the first exception of the current job
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
