// quadrant_bench: the Google Benchmark suite that runs identical scenes on every engine.
//
// One benchmark per scene x body count x thread count x engine, registered at run time and
// named `<scene>/<engine>/n:<N>/threads:<T>` (Google Benchmark appends
// `/iterations:1/real_time` to the reported name, and `_mean`, `_median`, ... to aggregates).
// Engines are registered interleaved (for each scene, N and T, every engine in turn) so that
// machine drift hits all engines alike; `--benchmark_enable_random_interleaving=true` goes
// further and shuffles the repetitions of all benchmarks.
//
// Each benchmark (and each repetition of it: the setup is inside the benchmark function)
// builds the scene, makes and loads a fresh adapter, runs `--warmup` untimed steps and then
// times exactly `--steps` steps in one iteration, in real (wall-clock) time. The JSON output
// (--benchmark_out=... --benchmark_out_format=json) is the record of the run: its context
// holds the commit, compiler, flags, machine, settings, scene descriptions, engine notes and
// the combinations that were not run (and why).
//
// Per benchmark: real_time (the timed steps), counters (steps_per_second, ms_per_step, bodies,
// contacts, engine_threads, steps, warmup, memory_mb, heap_mb, others_cpu: cores' worth of CPU
// other processes used, load_avg), label = final state hash (16 hex digits); the benchmark
// function's counters say what each is.
//
// N is the scene's dynamic bodies as built: a count the scene rounds (pyramid to a whole base,
// many_pyramids to a multiple of 55) is named and reported as the count that ran (issue #29).
//
// Own flags (--scenes, --engines, --counts, --threads, --steps, --warmup, --seed, --frame-rate,
// --list) are declared in ParseOwnFlags and removed before Google Benchmark sees the command
// line; --help lists them with their defaults. --frame-rate HZ is a game's frame loop: each step
// is followed by sleeping to the next frame boundary (absolute deadlines) and only the steps are
// timed (manual time). Google Benchmark's own flags go to it; other arguments are refused.

#include <benchmark/benchmark.h>
#include <fmt/format.h>
#include <malloc.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "adapter.h"
#include "cli_args.h"
#include "cli_engines.h"
#include "progress_reporter.h"
#include "quadrant/error.h"
#include "scene.h"
#include "scenes.h"

#ifndef QUADRANT_CXX_FLAGS
#define QUADRANT_CXX_FLAGS "unknown"
#endif
#ifndef QUADRANT_BUILD_TYPE
#define QUADRANT_BUILD_TYPE "unknown"
#endif

namespace {

namespace qs = quadrant::scene;

struct Options {
  std::vector<std::string> scenes;   // empty: DefaultBenchScenes, or Box2d3Scenes with --protocol box2d3
  std::vector<std::string> engines;  // empty: every adapter
  std::vector<int> counts;           // empty: each scene's DefaultBenchCounts
  std::vector<int> threads{1, 2, 3, 4};
  int steps = 120;
  int warmup = 30;
  uint64_t seed = 42;
  int frameRate = 0;  // Hz; 0: back to back
  bool list = false;
  std::string protocol = "suite";  // or "box2d3": Box2D 3's sizes, step counts and continuous collision
};

template <typename T>
std::string JoinList(const std::vector<T>& items, std::string_view sep = ",") {
  std::string out;
  for (size_t i = 0; i < items.size(); ++i) {
    if (i) out += sep;
    out += fmt::format("{}", items[i]);
  }
  return out;
}

/// Declares the suite's own flags on `p`, then parses and removes them from argv ("--flag value"
/// and "--flag=value"); leaves Google Benchmark's (--benchmark_*) for benchmark::Initialize. A bad
/// flag is one line naming it and what it accepts, exit 2 (issue 16); --help prints these flags,
/// then Google Benchmark's.
Options ParseOwnFlags(quadrant::cli::Parser& p, int& argc, char** argv) {
  Options opts;
  std::string counts;
  for (const std::string& scene : qs::DefaultBenchScenes()) {
    counts += fmt::format("{}{} {}", counts.empty() ? "" : ", ", scene, JoinList(qs::DefaultBenchCounts(scene)));
  }
  p.NameList("--scenes", &opts.scenes, qs::SceneNames(), "scene", "scenes")
      .Default(JoinList(qs::DefaultBenchScenes()) + "; with --protocol box2d3: " + JoinList(qs::Box2d3Scenes()));
  p.NameList("--engines", &opts.engines, {}, "engine", "engines")
      .Accepts(quadrant::cli::kEngineList)
      .Check(quadrant::cli::EngineProblem)
      .Default("every adapter, and quadrant:quadrants");
  p.IntList("--counts", &opts.counts, 1, 10'000'000, "body counts for every scene").Default("each scene's own: " + counts);
  // 64: WorldDef.threadCount's limit, the most any engine runs.
  p.IntList("--threads", &opts.threads, 1, 64, "engine thread counts");
  p.Int("--steps", &opts.steps, 1, 100'000'000, "timed steps per run");
  p.Int("--warmup", &opts.warmup, 0, 100'000'000, "untimed steps before timing");
  p.Int("--seed", &opts.seed, 0, INT64_MAX, "scene seed");
  p.Int("--frame-rate", &opts.frameRate, 0, 10'000,
        "frames a second: sleep after each step to the next frame boundary and time the steps only (0: back to back)");
  p.Name("--protocol", &opts.protocol, {"suite", "box2d3"}, "protocol",
         "suite: --steps timed after --warmup, each scene as defined; box2d3: Box2D 3's benchmark protocol "
         "(its sizes where --counts is not given, its step count per scene with the first untimed, "
         "continuous collision on)");
  p.Flag("--list", &opts.list, "print the engine and scene names and exit");
  p.PassThrough("--benchmark_",
                "The rest goes to Google Benchmark, e.g. --benchmark_repetitions=3 --benchmark_out=bench.json\n"
                "--benchmark_out_format=json --benchmark_enable_random_interleaving=true.\n\n"
                "Google Benchmark flags:");
  p.Parse(argc, argv);
  return opts;
}

/// --list: the accepted engine and scene names, one "kind: name" per line (tools/quadrant help
/// prints the same lists; tests/tools/cli_test.sh checks that they agree).
void PrintNames() {
  for (const std::string& name : qs::AdapterNames()) std::printf("engine: %s\n", name.c_str());
  for (const std::string& name : qs::SceneNames()) std::printf("scene: %s\n", name.c_str());
}

/// Value of a Google Benchmark flag still on the command line ("--name=value"), if given.
std::optional<std::string> PeekFlag(int argc, char** argv, std::string_view name) {
  const std::string prefix = fmt::format("--{}=", name);
  std::optional<std::string> found;
  for (int i = 1; i < argc; ++i) {
    std::string_view arg = argv[i];
    if (arg.substr(0, prefix.size()) == prefix) found = std::string(arg.substr(prefix.size()));
  }
  return found;
}

// ---- Machine description -------------------------------------------------------------------

std::string CpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("model name", 0) == 0) {
      size_t colon = line.find(':');
      if (colon != std::string::npos) {
        size_t start = line.find_first_not_of(" \t", colon + 1);
        return start == std::string::npos ? std::string() : line.substr(start);
      }
    }
  }
  return "unknown";
}

std::string HostName() {
  char buf[256] = {};
  if (gethostname(buf, sizeof buf - 1) != 0) return "unknown";
  return buf;
}

std::string EnvOr(const char* name, std::string fallback) {
  const char* value = std::getenv(name);
  return (value != nullptr && *value != '\0') ? std::string(value) : fallback;
}

// ---- Machine load ----------------------------------------------------------------------------

/// What other processes did to the machine during a run: CPU time used by anyone but this
/// process (busy time from /proc/stat, steal included, less this process's own user + system
/// time), in cores, and the 1-minute load average at the end. A load average alone cannot tell
/// this run's own threads from a neighbour's; the CPU time difference can.
class LoadProbe {
 public:
  void Begin() {
    machine0_ = MachineBusySeconds();
    own0_ = OwnSeconds();
    wall0_ = std::chrono::steady_clock::now();
  }
  /// Cores' worth of CPU used by other processes since Begin(), or -1 if unknown or if less
  /// than 0.25 s passed (/proc/stat counts in 10 ms ticks per core: too coarse below that).
  double OthersCores() const {
    const double machine = MachineBusySeconds();
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
    if (machine0_ < 0 || machine < 0 || wall < 0.25) return -1;
    return std::max(0.0, (machine - machine0_) - (OwnSeconds() - own0_)) / wall;
  }
  static double LoadAverage() {
    double one = -1;
    if (FILE* f = std::fopen("/proc/loadavg", "r")) {
      if (std::fscanf(f, "%lf", &one) != 1) one = -1;
      std::fclose(f);
    }
    return one;
  }

 private:
  static double MachineBusySeconds() {
    FILE* f = std::fopen("/proc/stat", "r");
    if (f == nullptr) return -1;
    // cpu user nice system idle iowait irq softirq steal ...
    unsigned long long v[8] = {};
    const int got = std::fscanf(f, "cpu %llu %llu %llu %llu %llu %llu %llu %llu", &v[0], &v[1], &v[2], &v[3], &v[4],
                                &v[5], &v[6], &v[7]);
    std::fclose(f);
    if (got < 4) return -1;
    const double ticks = double(sysconf(_SC_CLK_TCK));
    return double(v[0] + v[1] + v[2] + v[5] + v[6] + v[7]) / ticks;
  }
  static double OwnSeconds() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
  }
  double machine0_ = -1, own0_ = 0;
  std::chrono::steady_clock::time_point wall0_;
};

// ---- Memory measurement --------------------------------------------------------------------

/// A field of /proc/self/status in kB (VmRSS, VmHWM), or -1.
long StatusKb(std::string_view key) {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.size() > key.size() && line.compare(0, key.size(), key) == 0 &&
        line[key.size()] == ':')
      return std::atol(line.c_str() + key.size() + 1);
  }
  return -1;
}

/// Peak growth of the process's resident memory (RSS) from Begin() to End(), in MB, plus the
/// growth of malloc's bytes in use. Used around "make adapter + Load + warm-up": it measures
/// what loading that scene into that engine and warming it up costs in resident memory.
///
/// Begin() first returns freed heap pages to the kernel (malloc_trim), so what earlier
/// benchmarks freed is not reused silently, then resets the kernel's peak-RSS mark (VmHWM, via
/// /proc/self/clear_refs, Linux >= 4.0). End() reads the peak: rss_mb = VmHWM - RSS before.
/// Where the reset is refused it falls back to the RSS at End(). heap_mb is the growth of
/// mallinfo2's bytes in use (main arena plus mmapped chunks: what the engine still holds after
/// warm-up, without allocator slack; allocations by worker threads in their own arenas are not
/// in it).
class MemoryProbe {
 public:
  void Begin() {
    malloc_trim(0);
    baseKb_ = StatusKb("VmRSS");
    std::ofstream clear("/proc/self/clear_refs");
    clear << "5";
    clear.flush();
    peakReset_ = bool(clear);
    const struct mallinfo2 info = mallinfo2();
    baseHeap_ = double(info.uordblks) + double(info.hblkhd);
  }
  /// RSS growth (peak during the probe where measurable), MB.
  double RssMb() const {
    long now = peakReset_ ? StatusKb("VmHWM") : StatusKb("VmRSS");
    if (now < 0 || baseKb_ < 0) return 0;
    return std::max(0.0, double(now - baseKb_) / 1024.0);
  }
  /// Heap bytes in use, growth, MB.
  double HeapMb() const {
    const struct mallinfo2 info = mallinfo2();
    double now = double(info.uordblks) + double(info.hblkhd);
    return std::max(0.0, (now - baseHeap_) / (1024.0 * 1024.0));
  }

 private:
  long baseKb_ = -1;
  bool peakReset_ = false;
  double baseHeap_ = 0;
};

// ---- Scenes --------------------------------------------------------------------------------

/// The scene's dynamic bodies, with the most its driver's groups hold at once (rain): the N a
/// benchmark is named and reported by.
/// The scene a job runs: the named scene, with continuous collision on under Box2D 3's protocol
/// (its benchmark app's default).
qs::Scene BuildScene(const std::string& name, int count, uint64_t seed, const std::string& protocol) {
  qs::Scene scene = qs::MakeScene(name, count, seed);
  if (protocol == "box2d3") scene.effects.continuous = true;
  return scene;
}

int DynamicBodies(const qs::Scene& scene) {
  return scene.groupBodies +
         int(std::count_if(scene.bodies.begin(), scene.bodies.end(), [](const qs::BodyDesc& b) { return b.dynamic; }));
}

/// One line saying how a scene is set up, computed from the scene itself.
std::string DescribeScene(const qs::Scene& scene) {
  double bodyArea = 0;
  int dynamic = 0;
  double fMin = 1e300, fMax = -1e300, eMin = 1e300, eMax = -1e300;
  int circles = 0, polygons = 0;
  for (const qs::BodyDesc& body : scene.bodies) {
    if (!body.dynamic) continue;
    ++dynamic;
    (body.shape == qs::ShapeKind::kCircle ? circles : polygons)++;
    if (body.density > 0) bodyArea += double(qs::ComputeMassProperties(body).mass) / double(body.density);
    fMin = std::min(fMin, double(body.friction));
    fMax = std::max(fMax, double(body.friction));
    eMin = std::min(eMin, double(body.restitution));
    eMax = std::max(eMax, double(body.restitution));
  }
  auto range = [](double lo, double hi) {
    if (lo > hi) return std::string("n/a");
    return lo == hi ? fmt::format("{:g}", lo) : fmt::format("{:g}..{:g}", lo, hi);
  };
  const double w = double(scene.bounds.upper.x) - double(scene.bounds.lower.x);
  const double h = double(scene.bounds.upper.y) - double(scene.bounds.lower.y);
  const double boxArea = w * h;
  const qs::Effects& fx = scene.effects;
  std::string effects;
  auto add = [&](bool on, const char* name) {
    if (!on) return;
    if (!effects.empty()) effects += "+";
    effects += name;
  };
  add(fx.gravity, "gravity");
  add(fx.friction, "friction");
  add(fx.restitution, "restitution");
  add(fx.rotation, "rotation");
  add(fx.warmStarting, "warm-starting");
  add(fx.sleep, "sleep");
  add(fx.continuous, "continuous");
  add(fx.damping, "damping");
  return fmt::format(
      "dt {:.6g} s; {} dynamic bodies ({} circles, {} polygons) and {} static; box {:.4g} x "
      "{:.4g} m; area fraction {}; restitution {}; friction {}; gravity ({:g}, {:g}); "
      "restitution threshold {:g} m/s; velocity/position iterations {}/{}; pipeline repeats {}; "
      "effects {}",
      double(scene.timeStep), dynamic, circles, polygons, int(scene.bodies.size()) - dynamic, w,
      h, boxArea > 0 ? fmt::format("{:.3f}", bodyArea / boxArea) : std::string("n/a"),
      range(eMin, eMax), range(fMin, fMax), double(scene.gravity.x), double(scene.gravity.y),
      double(scene.restitutionThreshold), scene.velocityIterations, scene.positionIterations,
      scene.pipelineRepeats, effects.empty() ? std::string("none") : effects);
}

// ---- The frame loop (--frame-rate) ----------------------------------------------------------

/// A game's loop: after each step, sleep until the next frame boundary. Boundaries are absolute
/// (start + k / HZ on the monotonic clock, clock_nanosleep TIMER_ABSTIME), so a step's duration
/// and the sleep's wake-up delay do not drift the frames; a step that ends past its boundary
/// waits for the first boundary after it (a dropped frame, counted). Hz 0: Wait does nothing.
class FramePacer {
 public:
  explicit FramePacer(int hz)
      : period_(hz > 0 ? std::chrono::nanoseconds(1'000'000'000LL / hz) : std::chrono::nanoseconds(0)),
        next_(std::chrono::steady_clock::now()) {}
  bool On() const { return period_.count() > 0; }
  void Wait() {
    if (!On()) return;
    next_ += period_;
    const auto now = std::chrono::steady_clock::now();
    if (next_ < now) {
      ++late_;
      next_ += ((now - next_) / period_ + 1) * period_;
    }
    // libstdc++'s steady_clock is CLOCK_MONOTONIC.
    const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(next_.time_since_epoch()).count();
    const timespec at{static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &at, nullptr) == EINTR) {
    }
  }
  /// Steps that ended past their frame's boundary.
  int Late() const { return late_; }

 private:
  std::chrono::nanoseconds period_;
  std::chrono::steady_clock::time_point next_;
  int late_ = 0;
};

// ---- The benchmark -------------------------------------------------------------------------

struct Job {
  std::string scene;
  std::string engine;
  int count = 0;
  int threads = 1;
  int steps = 120;
  int warmup = 30;
  uint64_t seed = 42;
  int frameRate = 0;
  std::string name;
  std::string protocol = "suite";
};

quadrant::bench::RunSpec SpecOf(const Job& job) {
  return {job.scene, job.engine, job.count, job.threads, job.steps, job.warmup};
}

/// One repetition of a job; returns what the progress line says of it ("7.1 ms/step", or the
/// error).
std::string RunJob(benchmark::State& state, const Job& job) {
  LoadProbe load;  // over the whole benchmark (setup, warm-up, timed steps): long enough to count
  load.Begin();
  // Setup, untimed, repeated for every repetition so that repetitions are independent.
  std::unique_ptr<qs::Adapter> adapter;
  MemoryProbe memory;
  FramePacer pacer(job.frameRate);  // --frame-rate: warm-up and timed steps alike, each a frame
  try {
    const qs::Scene scene = BuildScene(job.scene, job.count, job.seed, job.protocol);
    memory.Begin();
    adapter = qs::MakeAdapter(job.engine);
    adapter->Load(scene, job.threads);
    for (int i = 0; i < job.warmup; ++i) {
      adapter->Step();
      pacer.Wait();
    }
  } catch (const std::exception& e) {
    const std::string error = fmt::format("setup failed: {}", e.what());
    state.SkipWithError(error.c_str());
    return "ERROR " + error;
  }
  const double memoryMb = memory.RssMb();
  const double heapMb = memory.HeapMb();

  // Timed: exactly job.steps steps in one iteration. The two clock reads give ms_per_step
  // as a plain counter (Google Benchmark prints an inverted rate with an "s" suffix, which
  // would mislabel milliseconds); it matches real_time / steps. In a frame loop each step is
  // timed on its own and the sum is the iteration's (manual) time.
  double elapsedMs = 0;
  std::string stepError;
  const int lateBefore = pacer.Late();
  const auto stagesBefore = adapter->StageTotals();
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    std::chrono::steady_clock::duration stepped{};
    try {
      for (int i = 0; i < job.steps; ++i) {
        if (!pacer.On()) {
          adapter->Step();
          continue;
        }
        const auto s0 = std::chrono::steady_clock::now();
        adapter->Step();
        stepped += std::chrono::steady_clock::now() - s0;
        pacer.Wait();
      }
    } catch (const std::exception& e) {
      stepError = fmt::format("step failed: {}", e.what());
      state.SkipWithError(stepError.c_str());
      break;
    }
    if (pacer.On()) {
      elapsedMs = std::chrono::duration<double, std::milli>(stepped).count();
      state.SetIterationTime(elapsedMs * 1e-3);
    } else {
      elapsedMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    }
  }
  if (state.error_occurred()) return "ERROR " + stepError;
  const double othersCores = load.OthersCores();

  using benchmark::Counter;
  state.counters["steps_per_second"] = Counter(double(job.steps), Counter::kIsRate);
  state.counters["ms_per_step"] = Counter(elapsedMs / double(job.steps));
  state.counters["bodies"] = Counter(double(adapter->BodyCount()));
  state.counters["contacts"] = Counter(double(adapter->ContactCount()));
  // Not "threads": Google Benchmark writes its own "threads" (benchmark threads, always 1) in
  // every JSON row, and a counter of that name would give the row a duplicate key.
  state.counters["engine_threads"] = Counter(double(job.threads));
  state.counters["steps"] = Counter(double(job.steps));
  state.counters["warmup"] = Counter(double(job.warmup));
  if (pacer.On()) state.counters["late_frames"] = Counter(double(pacer.Late() - lateBefore));
  // RSS growth (peak) while making, loading and warming up this adapter, MB; see MemoryProbe.
  state.counters["memory_mb"] = Counter(memoryMb);
  state.counters["heap_mb"] = Counter(heapMb);
  // What the rest of the machine did during this benchmark (LoadProbe): other processes' CPU
  // use in cores (the run's own `--busy` processes included) and the 1-minute load average.
  if (othersCores >= 0) state.counters["others_cpu"] = Counter(othersCores);
  if (const double avg = LoadProbe::LoadAverage(); avg >= 0) state.counters["load_avg"] = Counter(avg);
  // Load balance over the timed steps (engines that time their stages): work over the critical
  // path, the speed-up this thread count allows whatever the machine's cores (see StageRunner:
  // thread CPU time when oversubscribed, wall time otherwise; one thread is not measured, its
  // bound is 1).
  const auto stagesAfter = adapter->StageTotals();
  double work = 0, critical = 0;
  for (size_t k = 0; k < stagesAfter.size() && k < stagesBefore.size(); ++k) {
    const double delta = stagesAfter[k].second - stagesBefore[k].second;
    if (stagesAfter[k].first.starts_with("work_")) work += delta;
    if (stagesAfter[k].first.starts_with("critical_")) critical += delta;
  }
  // Where a step's time went: wall-clock ms per step of each stage the engine times (for
  // Quadrant: broad_phase, narrow_phase, persistence, solve, integrate; "total" is the whole
  // Step, so total minus the stages is the step's own bookkeeping).
  for (size_t k = 0; k < stagesAfter.size() && k < stagesBefore.size(); ++k) {
    const std::string& name = stagesAfter[k].first;
    if (name.starts_with("work_") || name.starts_with("critical_")) continue;
    if (name.starts_with("steps_")) {  // a count of steps: the share of the timed steps (alone_share, small_share)
      state.counters[name.substr(6) + "_share"] = Counter((stagesAfter[k].second - stagesBefore[k].second) / double(job.steps));
      continue;
    }
    state.counters["stage_" + name + "_ms"] =
        Counter((stagesAfter[k].second - stagesBefore[k].second) / double(job.steps));
  }
  if (critical > 0) {
    state.counters["balance_bound"] = Counter(work / critical);
  } else if (!stagesAfter.empty() && job.threads == 1) {
    state.counters["balance_bound"] = Counter(1.0);
  }
  state.SetLabel(fmt::format("{:016x}", adapter->StateHash()));
  return fmt::format("{:.4g} ms/step", elapsedMs / double(job.steps));
}

// The progress lines: one per repetition as it ends, with the ETA (progress_reporter.h, eta.h).
quadrant::bench::Progress progress;

}  // namespace

int main(int argc, char** argv) {
  quadrant::cli::Parser parser(
      "quadrant_bench",
      "The engine comparison suite (Google Benchmark). Benchmarks are named "
      "<scene>/<engine>/n:<N>/threads:<T>,\nN the scene's dynamic bodies (a scene that rounds a count, as "
      "pyramid to a whole base, runs and names\nthe count it built). Combinations an engine cannot run are "
      "counted in one line on stderr and listed\nin the JSON context 'unsupported'.");
  Options opts = ParseOwnFlags(parser, argc, argv);
  if (opts.list) {
    PrintNames();
    return 0;
  }
  // Progress total: every registered benchmark runs once per repetition (unless filtered).
  // Read before Initialize, which removes the flags it knows from argv.
  int repetitions = 1;
  if (auto reps = PeekFlag(argc, argv, "benchmark_repetitions")) repetitions = std::max(1, std::atoi(reps->c_str()));
  const bool filtered = PeekFlag(argc, argv, "benchmark_filter").has_value();
  // Google Benchmark's flags first (prints its help and exits on --help), so that a mistyped
  // flag is reported before the engines are probed.
  benchmark::Initialize(&argc, argv);
  parser.FailOnRest(argc, argv);

  std::vector<std::string> unsupported;
  std::map<std::string, int> unsupportedReasons;  // reason -> combinations, for the summary line
  std::string unsupportedSummary;
  std::vector<std::string> errors;
  int registered = 0;
  try {
    if (opts.engines.empty()) {
      // Quadrant's default scheme is the deterministic one ("quadrant" = "quadrant:deterministic");
      // the thesis's quadrant partition runs beside it.
      opts.engines = qs::AdapterNames();
      opts.engines.insert(opts.engines.begin() + 1, "quadrant:quadrants");
    }

    // Engines: made once here for their capabilities (and to reject unknown names early).
    std::vector<qs::Capabilities> caps;
    for (const std::string& engine : opts.engines) caps.push_back(qs::MakeAdapter(engine)->Caps());

    // Counts per scene: --counts for every scene, or each scene's own defaults, each taken as the
    // dynamic bodies the scene builds for it (issue #29: pyramid rounds a count down to a whole
    // base, many_pyramids to a multiple of 55, a fixed-size scene ignores it), so that n:<N> and
    // the report's "N = " are the count that ran; counts that build the same scene run once.
    // Building a scene with its own count gives the same scene.
    const bool box2d3 = opts.protocol == "box2d3";
    if (opts.scenes.empty()) opts.scenes = box2d3 ? qs::Box2d3Scenes() : qs::DefaultBenchScenes();
    if (box2d3) {
      for (const std::string& scene : opts.scenes) (void)qs::Box2d3Steps(scene);  // a scene Box2D 3 has: else an error
    }
    std::vector<std::vector<int>> sceneCounts;
    std::vector<std::string> countsText, rounded;
    for (const std::string& sceneName : opts.scenes) {
      std::vector<int>& built = sceneCounts.emplace_back();
      const std::vector<int> defaults = box2d3 ? std::vector<int>{qs::Box2d3Count(sceneName)} : qs::DefaultBenchCounts(sceneName);
      for (int asked : opts.counts.empty() ? defaults : opts.counts) {
        const int n = DynamicBodies(qs::MakeScene(sceneName, asked, opts.seed));
        if (n != asked) rounded.push_back(fmt::format("{}:{}->{}", sceneName, asked, n));
        if (std::find(built.begin(), built.end(), n) == built.end()) built.push_back(n);
      }
      countsText.push_back(fmt::format("{}:{}", sceneName, JoinList(built, "+")));
    }
    if (!rounded.empty()) {
      std::fprintf(stderr, "quadrant_bench: run and named as the scenes build them: %s (asked->built)\n",
                   JoinList(rounded, ", ").c_str());
    }

    // Scene descriptions for the context, from the smallest count (the settings do not depend
    // on N; the body count and box size do).
    for (size_t s = 0; s < opts.scenes.size(); ++s) {
      const int smallest = *std::min_element(sceneCounts[s].begin(), sceneCounts[s].end());
      const qs::Scene scene = BuildScene(opts.scenes[s], smallest, opts.seed, opts.protocol);
      benchmark::AddCustomContext(fmt::format("scene_{}", opts.scenes[s]),
                                  fmt::format("n={}: {}{}", smallest, qs::IsDenseScene(opts.scenes[s]) ? "dense; " : "",
                                              DescribeScene(scene)));
    }

    // Registration order: for each scene, N and T, every engine in turn (interleaved).
    for (size_t s = 0; s < opts.scenes.size(); ++s) {
      const std::string& sceneName = opts.scenes[s];
      for (int count : sceneCounts[s]) {
        const qs::Scene scene = BuildScene(sceneName, count, opts.seed, opts.protocol);
        for (int threads : opts.threads) {
          for (size_t e = 0; e < opts.engines.size(); ++e) {
            const std::string& engine = opts.engines[e];
            Job job{sceneName, engine, count, threads, opts.steps, opts.warmup, opts.seed, opts.frameRate,
                    fmt::format("{}/{}/n:{}/threads:{}", sceneName, engine, count, threads), opts.protocol};
            if (box2d3) {
              // Box2D 3 steps once untimed after creation, then times the rest of its count.
              job.warmup = 1;
              job.steps = qs::Box2d3Steps(sceneName) - 1;
            }
            std::string reason;
            if (threads > caps[e].maxThreads) {
              reason = fmt::format("{} runs at most {} thread(s)", engine, caps[e].maxThreads);
            } else {
              // Probe: an engine says what it cannot run by throwing Unsupported from Load.
              try {
                auto probe = qs::MakeAdapter(engine);
                probe->Load(scene, threads);
              } catch (const qs::Unsupported& ex) {
                reason = ex.what();
              } catch (const std::exception& ex) {
                errors.push_back(fmt::format("{}: {}", job.name, ex.what()));
                std::fprintf(stderr, "error: %s: %s\n", job.name.c_str(), ex.what());
                continue;
              }
            }
            if (!reason.empty()) {
              unsupported.push_back(fmt::format("{}: {}", job.name, reason));
              ++unsupportedReasons[reason];
              continue;
            }
            benchmark::internal::Benchmark* b = benchmark::RegisterBenchmark(
                job.name.c_str(), [job](benchmark::State& state) {
                  const auto t0 = std::chrono::steady_clock::now();
                  const std::string result = RunJob(state, job);
                  progress.Finished(SpecOf(job),
                                    std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(),
                                    result);
                });
            b->Iterations(1)->Unit(benchmark::kMillisecond);
            // A frame loop's iteration time is its steps' (the sleeps between them are not work).
            if (opts.frameRate > 0) {
              b->UseManualTime();
            } else {
              b->UseRealTime();
            }
            ++registered;
            progress.Plan(SpecOf(job), repetitions);
          }
        }
      }
    }

    // One line for the unsupported combinations, counted by reason (issue 16: it was one line
    // per combination, 80 in the default run); the full list goes into the JSON context.
    for (const auto& [reason, n] : unsupportedReasons)
      unsupportedSummary += fmt::format("{}{} x {}", unsupportedSummary.empty() ? "" : "; ", n, reason);
    if (!unsupported.empty() && registered > 0) {
      const std::string& summary = unsupportedSummary;
      std::fprintf(stderr, "quadrant_bench: %zu of %zu combinations skipped as unsupported (%s); the list is in the JSON context 'unsupported'\n",
                   unsupported.size(), unsupported.size() + size_t(registered), summary.c_str());
    }

    // The record of the run.
    benchmark::AddCustomContext("commit", EnvOr("QUADRANT_COMMIT", "unknown"));
#if defined(__clang__)
    benchmark::AddCustomContext("compiler", __VERSION__);  // "Debian Clang 14.0.6"
#elif defined(__GNUC__)
    benchmark::AddCustomContext("compiler", "GCC " __VERSION__);  // __VERSION__ is "12.2.0"
#else
    benchmark::AddCustomContext("compiler", __VERSION__);
#endif
    benchmark::AddCustomContext("cxx_flags", QUADRANT_CXX_FLAGS);
    benchmark::AddCustomContext("build_type", QUADRANT_BUILD_TYPE);
    benchmark::AddCustomContext("quadrant_real", sizeof(quadrant::Real) == 8 ? "double" : "float");
    benchmark::AddCustomContext("cpu_model", CpuModel());
    benchmark::AddCustomContext("cores", fmt::format("{}", std::thread::hardware_concurrency()));
    benchmark::AddCustomContext("machine", EnvOr("QUADRANT_MACHINE", HostName()));
    benchmark::AddCustomContext("hostname", HostName());
    benchmark::AddCustomContext("scenes", JoinList(opts.scenes));
    benchmark::AddCustomContext("engines", JoinList(opts.engines));
    benchmark::AddCustomContext("counts", JoinList(countsText));
    benchmark::AddCustomContext("counts_rounded", JoinList(rounded));  // asked->built, where they differ
    benchmark::AddCustomContext("thread_counts", JoinList(opts.threads));
    benchmark::AddCustomContext("steps", fmt::format("{}", opts.steps));
    benchmark::AddCustomContext("warmup", fmt::format("{}", opts.warmup));
    // box2d3: steps and warm-up per scene (Box2D 3's count less one, after one), continuous on.
    benchmark::AddCustomContext("protocol", opts.protocol);
    benchmark::AddCustomContext("seed", fmt::format("{}", opts.seed));
    // Frames a second of the frame loop (0: steps back to back).
    benchmark::AddCustomContext("frame_rate", fmt::format("{}", opts.frameRate));
    // Set by tools/quadrant bench: busy processes it ran beside the suite (--busy K), and the
    // 1-minute load average before it started them.
    benchmark::AddCustomContext("busy_processes", EnvOr("QUADRANT_BUSY", "0"));
    benchmark::AddCustomContext("load_avg_before", EnvOr("QUADRANT_LOAD_BEFORE", "unknown"));
    for (size_t e = 0; e < opts.engines.size(); ++e) {
      benchmark::AddCustomContext(fmt::format("engine_notes_{}", opts.engines[e]), caps[e].notes);
      benchmark::AddCustomContext(fmt::format("engine_max_threads_{}", opts.engines[e]),
                                  fmt::format("{}", caps[e].maxThreads));
    }
    benchmark::AddCustomContext("unsupported", JoinList(unsupported, ";"));
    benchmark::AddCustomContext("errors", JoinList(errors, ";"));
  } catch (const std::exception& e) {
    // Unknown scene or engine names, bad counts: a usage error.
    std::fprintf(stderr, "quadrant_bench: %s\n", e.what());
    return 2;
  }

  if (registered == 0 && errors.empty()) {
    // Every combination unsupported (e.g. --engines box2d --threads 2): say so in one line
    // instead of Google Benchmark's "Failed to match any benchmarks".
    std::fprintf(stderr, "quadrant_bench: nothing to run: all %zu combinations are unsupported (%s)\n",
                 unsupported.size(), unsupportedSummary.c_str());
    return 2;
  }
  // Progress on stderr: the header here, one line per finished run with an ETA from the
  // benchmark function (Progress, progress_reporter.h); the JSON file reporter (--benchmark_out)
  // is Google Benchmark's own.
  progress.Known(!filtered);
  progress.Start();
  quadrant::bench::ProgressReporter header(filtered ? 0 : registered * repetitions, QUADRANT_BUILD_TYPE);
  benchmark::RunSpecifiedBenchmarks(&header);
  benchmark::Shutdown();
  return errors.empty() ? 0 : 1;
}
