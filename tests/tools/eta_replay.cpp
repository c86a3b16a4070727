// Replays a recorded sequence of suite runs through the ETA model (benchmarks/eta.h): reads
// "scene engine bodies threads steps warmup seconds" lines on stdin (the run order), plans them
// all, then for each run in turn counts it done and prints "<runs done> <ETA seconds>".
// tests/tools/eta_test.py feeds it runs from a committed bench.json and judges the ETAs.
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "eta.h"

int main() {
  using quadrant::bench::RunSpec;
  std::vector<std::pair<RunSpec, double>> runs;
  std::string line;
  while (std::getline(std::cin, line)) {
    if (line.empty()) continue;
    std::istringstream in(line);
    RunSpec run;
    double seconds = 0;
    if (!(in >> run.scene >> run.engine >> run.bodies >> run.threads >> run.steps >> run.warmup >> seconds)) {
      std::fprintf(stderr, "eta_replay: bad line: %s\n", line.c_str());
      return 2;
    }
    runs.emplace_back(run, seconds);
  }
  quadrant::bench::EtaModel eta;
  for (const auto& [run, seconds] : runs) eta.Plan(run, 1);
  for (const auto& [run, seconds] : runs) {
    eta.Finished(run, seconds);
    std::printf("%d %.6f\n", eta.Done(), eta.RemainingSeconds());
  }
  return 0;
}
