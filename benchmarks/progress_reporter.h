// What quadrant_bench prints while it runs (issue 16): one short header (ProgressReporter) and
// one line per finished run with its result and an ETA (Progress), instead of Google Benchmark's
// console output (a context dump with 5,000-character lines, the library's DEBUG warning
// unexplained, and a 300-column table). Everything it leaves out is in the JSON
// (--benchmark_out), which Google Benchmark writes through its own file reporter, untouched here.
//
// The run lines come from the suite's benchmark function as each repetition ends, not from
// ReportRuns: Google Benchmark reports a benchmark only once its last repetition is done, so
// under random interleaving most of a run went by before its first report (issue #29 item 3).
#pragma once

#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include <chrono>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "eta.h"

namespace quadrant::bench {

/// "4 min 10 s", "35 s": an ETA a reader takes in at a glance.
inline std::string Duration(double seconds) {
  const long s = long(seconds + 0.5);
  if (s >= 3600) return fmt::format("{} h {} min", s / 3600, (s % 3600) / 60);
  if (s >= 60) return fmt::format("{} min {} s", s / 60, s % 60);
  return fmt::format("{} s", s);
}

class ProgressReporter : public benchmark::BenchmarkReporter {
 public:
  /// `total`: runs to expect (benchmarks x repetitions), 0 if unknown (a filter is in use).
  /// `buildType`: this program's build type, for the note on the library's own build.
  ProgressReporter(int total, std::string buildType) : total_(total), buildType_(std::move(buildType)) {}

  bool ReportContext(const Context& context) override {
    const auto& cpu = context.cpu_info;
    std::string load;
    for (double l : cpu.load_avg) load += fmt::format("{}{:.2f}", load.empty() ? "" : " ", l);
    std::fprintf(stderr, "quadrant_bench: %d runs on %d CPUs at %.0f MHz, load average %s (the full context is in the JSON)\n",
                 total_, cpu.num_cpus, cpu.cycles_per_second / 1e6, load.c_str());
    // Google Benchmark's own header would say "***WARNING*** Library was built as DEBUG" here:
    // Debian builds libbenchmark without NDEBUG. Asked, not assumed: the library writes it.
    std::ostringstream basic;
    PrintBasicContext(&basic, context);
    if (basic.str().find("DEBUG") != std::string::npos) {
      std::fprintf(stderr,
                   "quadrant_bench: note: Debian's libbenchmark is built without NDEBUG, so Google Benchmark calls "
                   "itself a DEBUG build (library_build_type in the JSON); that is the harness's own bookkeeping "
                   "around each run, not the timed steps, which are this program's %s build\n",
                   buildType_.c_str());
    }
    return true;
  }

  /// Nothing: Progress prints a line per run as it ends (see the header comment).
  void ReportRuns(const std::vector<Run>&) override {}

 private:
  int total_ = 0;
  std::string buildType_;
};

/// One line per finished run on stderr: "[k/total] name: result (elapsed, ETA ...)", the ETA from
/// the work the remaining runs imply (EtaModel, eta.h).
class Progress {
 public:
  /// Adds `repetitions` runs of `run` to the plan (every registered benchmark, unless a filter
  /// makes the total unknown: then Known(false), and lines carry no total or ETA).
  void Plan(const RunSpec& run, int repetitions) { eta_.Plan(run, repetitions); }
  void Known(bool known) { known_ = known; }
  /// The clock of "elapsed" starts here (after registration, before the first run).
  void Start() { start_ = std::chrono::steady_clock::now(); }

  /// A run of `run` ended after `seconds` (setup, warm-up and timed steps) with `result`.
  void Finished(const RunSpec& run, double seconds, const std::string& result) {
    eta_.Finished(run, seconds);
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    const int done = eta_.Done(), total = eta_.Total();
    if (known_ && total > 0) {
      std::string eta;
      if (done < total) eta = ", ETA " + Duration(std::max(0.0, eta_.RemainingSeconds()));
      std::fprintf(stderr, "[%d/%d] %s: %s (%s elapsed%s)\n", done, total, run.Name().c_str(), result.c_str(),
                   Duration(elapsed).c_str(), eta.c_str());
    } else {
      std::fprintf(stderr, "[%d] %s: %s\n", done, run.Name().c_str(), result.c_str());
    }
    std::fflush(stderr);
  }

 private:
  EtaModel eta_;
  bool known_ = true;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace quadrant::bench
