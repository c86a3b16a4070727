// main() of a benchmark program on Google Benchmark with no options of its own (quadrant_queries,
// quadrant_task_overhead): its command line through cli_args.h, so --help names the program and
// an unknown argument is one line and exit 2, and the --benchmark_* flags go to Google Benchmark.
#pragma once

#include <benchmark/benchmark.h>

#include "cli_args.h"

namespace quadrant::cli {

/// Parses argv (no options but Google Benchmark's), then runs the registered benchmarks.
inline int GoogleBenchmarkMain(const char* program, const char* summary, int argc, char** argv) {
  Parser parser(program, summary);
  parser.PassThrough("--benchmark_", "Google Benchmark flags:");
  parser.Parse(argc, argv);
  benchmark::Initialize(&argc, argv);
  parser.FailOnRest(argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

}  // namespace quadrant::cli
