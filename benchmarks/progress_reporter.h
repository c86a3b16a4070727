// What quadrant_bench prints while it runs (issue 16): one short header and one line per
// finished run with its result and an ETA, instead of Google Benchmark's console output (a
// context dump with 5,000-character lines, the library's DEBUG warning unexplained, and a
// 300-column table). Everything it leaves out is in the JSON (--benchmark_out), which Google
// Benchmark writes through its own file reporter, untouched by this one.
#pragma once

#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include <chrono>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

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
    start_ = std::chrono::steady_clock::now();
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

  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& run : runs) {
      if (run.run_type == Run::RT_Aggregate) continue;  // medians, means: in the JSON
      ++done_;
      std::string result;
      if (run.error_occurred) {
        result = "ERROR " + run.error_message;
      } else {
        const auto ms = run.counters.find("ms_per_step");
        result = ms != run.counters.end() ? fmt::format("{:.4g} ms/step", ms->second.value) : "no ms_per_step";
      }
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
      std::string eta;
      if (total_ > 0 && done_ < total_) eta = ", ETA " + Duration(elapsed / done_ * (total_ - done_));
      if (total_ > 0)
        std::fprintf(stderr, "[%d/%d] %s: %s (%s elapsed%s)\n", done_, total_, run.run_name.function_name.c_str(),
                     result.c_str(), Duration(elapsed).c_str(), eta.c_str());
      else
        std::fprintf(stderr, "[%d] %s: %s\n", done_, run.run_name.function_name.c_str(), result.c_str());
    }
    std::fflush(stderr);
  }

 private:
  int total_ = 0;
  int done_ = 0;
  std::string buildType_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace quadrant::bench
