// The suite's ETA (issue #29 item 3): the time the remaining runs will take, from the work each
// of them implies, calibrated on the runs done so far.
//
// The old ETA was elapsed / runs reported x runs left. It said "6 h 1 min" at run 1 of 570 and
// "28 min" at run 123 of a run that took 9 min 55 s, for two reasons: Google Benchmark reports a
// benchmark only when its last repetition is done, so with random interleaving most repetitions
// had run, unreported, before the first line; and runs differ in cost by a factor of 500 (Bullet
// on 16000 polygons against Quadrant on 1000 circles), so an average over whichever runs came
// first says little about those left. Here the suite reports every repetition as it ends (its
// own count, not Google Benchmark's), and each run is predicted from its work:
//
//   work = bodies x (bodies / 4000)^a x (steps + warmup + kSetupSteps) x engine cost factor,
//
// the factor and exponent a per engine and kind of scene (a prior from the committed runs:
// microseconds per body and step at N = 4000, 1 thread), then scaled by the observed seconds per
// unit of work: of the same benchmark if it has run, else of the same engine, scene and thread
// count, else engine and scene, else engine, else of every run (each level shrunk towards the one
// above by one pseudo-run, so a single noisy run does not decide). The priors need only be right
// relative to each other; the machine's speed comes from the calibration.
//
// tests/tools/eta_test.py replays recorded runs (results/<machine>/bench.json) through this model
// (tests/tools/eta_replay.cpp) and checks that from the tenth run on the ETA is within a factor
// of 1.5 of the time the remaining runs took.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace quadrant::bench {

/// One run of the suite: a repetition of the benchmark <scene>/<engine>/n:<bodies>/threads:<T>.
struct RunSpec {
  std::string scene;
  std::string engine;
  int bodies = 0;
  int threads = 1;
  int steps = 0;
  int warmup = 0;

  std::string Name() const {
    return scene + "/" + engine + "/n:" + std::to_string(bodies) + "/threads:" + std::to_string(threads);
  }
};

/// Setup (building the scene, loading the engine) counted as this many steps of the run's work.
inline constexpr double kSetupSteps = 5;

/// The engine's family for the priors: "quadrant" for every Quadrant variant.
inline std::string_view EngineFamily(std::string_view engine) {
  return engine.substr(0, engine.find(':'));
}

/// The prior work of one run (arbitrary units, about microseconds on the machine the priors came
/// from): bodies x size factor x steps x the engine's cost per body and step on that kind of
/// scene.
inline double PriorWork(const RunSpec& run) {
  // Microseconds per body and step at N = 4000 on one thread (results/amd-epyc-2c/bench.json,
  // rounded): circles (sparse), polygons (sparse), piles (dense polygons), tumbler.
  struct Costs {
    std::string_view engine;
    std::array<double, 4> perBodyStep;
    // Per-body cost grows as (N / 4000)^a: the peers' broad phases on the sparse scenes; the
    // tumbler's drum fills up, so there the cost per body about doubles with N.
    std::array<double, 4> sizeExponent;
  };
  static constexpr std::array<Costs, 4> kCosts{{
      {"quadrant", {0.05, 0.11, 0.40, 0.14}, {0.0, 0.0, 0.1, 1.0}},
      {"box2d", {0.60, 0.90, 1.90, 1.40}, {0.3, 0.3, 0.1, 0.8}},
      {"bullet", {1.00, 2.50, 5.50, 3.00}, {0.3, 0.3, 0.2, 0.8}},
      {"chipmunk", {0.35, 0.60, 1.50, 0.70}, {0.3, 0.3, 0.15, 1.0}},
  }};
  const std::string_view scene = run.scene;
  size_t kind = 2;  // piles: pyramid, many_pyramids and the hard cases
  if (scene.starts_with("circle_stress")) kind = 0;
  else if (scene.starts_with("polygon_stress")) kind = 1;
  else if (scene == "tumbler") kind = 3;
  double perBodyStep = 1.0, exponent = 0.3;  // an engine without a prior: about a peer's cost
  const std::string_view family = EngineFamily(run.engine);
  for (const Costs& c : kCosts) {
    if (c.engine == family) {
      perBodyStep = c.perBodyStep[kind];
      exponent = c.sizeExponent[kind];
    }
  }
  if (family == "quadrant" && run.engine != "quadrant") perBodyStep *= 1.2;  // variants: about the default's
  const double n = std::max(1, run.bodies);
  const double steps = std::max(0, run.steps) + std::max(0, run.warmup) + kSetupSteps;
  return n * std::pow(n / 4000.0, exponent) * steps * perBodyStep;
}

/// The ETA of a planned sequence of runs, calibrated on the runs done so far.
class EtaModel {
 public:
  /// Adds `repetitions` runs of `run` to the plan.
  void Plan(const RunSpec& run, int repetitions) {
    Entry& e = entries_[run.Name()];
    e.spec = run;
    e.prior = PriorWork(run);
    e.left += repetitions;
    total_ += repetitions;
  }

  /// One run of `run` took `seconds` (a run not in the plan is counted as done all the same).
  void Finished(const RunSpec& run, double seconds) {
    auto it = entries_.find(run.Name());
    const double prior = it != entries_.end() ? it->second.prior : PriorWork(run);
    if (it != entries_.end() && it->second.left > 0) --it->second.left;
    ++done_;
    seconds = std::max(0.0, seconds);
    for (const std::string& key : Keys(run)) {
      Sum& s = sums_[key];
      s.seconds += seconds;
      s.work += prior;
      s.runs += 1;
    }
  }

  /// Seconds the planned runs not yet done will take; -1 before the first run is done.
  double RemainingSeconds() const {
    if (done_ == 0) return -1;
    double total = 0;
    for (const auto& [name, e] : entries_) {
      if (e.left > 0) total += e.left * e.prior * SecondsPerWork(e.spec);
    }
    return total;
  }

  int Done() const { return done_; }
  int Total() const { return total_; }

  /// Seconds per unit of work for a run like `run`, from the runs done (see the header comment).
  double SecondsPerWork(const RunSpec& run) const {
    const std::vector<std::string> keys = Keys(run);  // coarsest last
    double rate = 0;
    bool have = false;
    for (auto key = keys.rbegin(); key != keys.rend(); ++key) {
      auto it = sums_.find(*key);
      if (it == sums_.end() || it->second.runs == 0) continue;
      const Sum& s = it->second;
      if (!have) {
        rate = s.work > 0 ? s.seconds / s.work : 0;
        have = true;
        continue;
      }
      // One pseudo-run of this level's mean work at the coarser level's rate.
      const double meanWork = s.work / s.runs;
      rate = (s.seconds + kShrinkRuns * meanWork * rate) / (s.work + kShrinkRuns * meanWork);
    }
    return rate;
  }

 private:
  static constexpr double kShrinkRuns = 1.0;

  struct Entry {
    RunSpec spec;
    double prior = 0;
    int left = 0;
  };
  struct Sum {
    double seconds = 0, work = 0;
    int runs = 0;
  };

  /// Calibration levels, finest first: the benchmark; engine, scene and threads; engine and
  /// scene; engine; every run.
  static std::vector<std::string> Keys(const RunSpec& run) {
    return {"b:" + run.Name(), "est:" + run.engine + "/" + run.scene + "/" + std::to_string(run.threads),
            "es:" + run.engine + "/" + run.scene, "e:" + run.engine, "all"};
  }

  std::map<std::string, Entry> entries_;
  std::map<std::string, Sum> sums_;
  int total_ = 0;
  int done_ = 0;
};

}  // namespace quadrant::bench
