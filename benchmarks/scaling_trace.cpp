// quadrant_scaling_trace: records the structure of a scene's steps at several thread counts for
// the scaling model (tools/scaling.py, tools/quadrant scaling): per step, in order, every serial
// section, every parallel-for with its blocks' times and every region of stages with each
// stage's chunks' times (engine/src/parallel/step_trace.h), and the time between them (the
// step's code outside the stage runner, serial too).
//
// How P threads are recorded on a machine with fewer cores: the world runs with threadCount P,
// so every section is cut into the P-way partition (blocks and chunks depend on P only), but the
// process is pinned to one core with QUADRANT_POOL_ALONE=0, so the caller runs every block and
// chunk in order, each timed on its own (the runner's wall clock); the sections' begins and ends
// are read on the thread's CPU clock, which other processes cannot add to, and a section whose
// chunks add up to more than its CPU time lost the core inside them: they are scaled down to it.
// Each thread count is recorded in --repeats worlds, interleaved, and every time reduced over
// them (median, or --reduce least); the scenes are deterministic, so every repeat runs the same
// sections with the same chunks (checked).
//
// Output: JSON (--out FILE, or stdout): {"scene", "count", "bodies", "warmup", "steps",
// "repeats", "recorded_on", "clock", "clock_read_us", "reduce", "traces": [{"threads": P, "steps":
// [{"us": the step (the sum of its parts, reduced), "sections": [...]}]}]}, a section being {"kind": "serial", "stage", "us"}, {"kind": "gap", "us"} (between
// sections), {"kind": "for", "stage", "span_us", "us": [[block us...]]} or {"kind": "region",
// "stage", "runs", "span_us", "us": [[chunk us of stage 0...], ...]}. Times in microseconds.
#include <sched.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "adapter.h"
#include "cli_args.h"
#include "parallel/step_trace.h"
#include "scenes.h"

namespace {

namespace qs = quadrant::scene;
using quadrant::StepTrace;

struct Args {
  std::string scene = "circle_stress";
  int count = 1000;
  std::vector<int> threads = {1, 2, 4, 8, 16};
  int warmup = 30;
  int steps = 10;
  int repeats = 3;
  uint64_t seed = 42;
  std::string out;
  bool noPin = false;
  std::string clock = "thread";
  std::string reduce = "median";
};

// One step as recorded: the sections and the step's own begin and end (steady clock, ms).
struct RecordedStep {
  std::vector<StepTrace::Section> sections;
  double beginMs = 0, endMs = 0;
};

// A step flattened into one list of times (us), with a signature of its structure (the kinds,
// stages and chunk counts) that must be equal across repeats. `readMs`: one clock read, taken
// out of every interval (each holds about one read's worth of the two around it). `cpuSpans`: the
// sections were timed on the CPU clock, their chunks on the wall clock (a section's chunks are
// scaled down to its span where they add up to more).
struct FlatStep {
  std::vector<double> us;
  std::vector<long long> shape;
};

FlatStep Flatten(const RecordedStep& step, double readMs, bool cpuSpans) {
  FlatStep f;
  f.us.push_back(0);  // the step: the sum of the parts, below
  double last = step.beginMs, lastRecord = 0;
  auto put = [&](double ms) {
    f.us.push_back(std::max(0.0, ms) * 1e3);
    f.us[0] += f.us.back();
  };
  for (const StepTrace::Section& s : step.sections) {
    put(s.beginMs - last - lastRecord - readMs);  // the gap before the section
    const double span = s.endMs - s.beginMs - readMs;
    put(span);
    f.shape.push_back(static_cast<long long>(s.kind) * 64 + static_cast<long long>(s.stage) * 2 + s.runs);
    f.shape.push_back(static_cast<long long>(s.ms.size()));
    double sum = 0;
    for (const std::vector<double>& stage : s.ms) {
      for (double ms : stage) sum += ms;
    }
    const double scale = cpuSpans && sum > span && sum > 0 ? std::max(0.0, span) / sum : 1.0;
    for (const std::vector<double>& stage : s.ms) {
      f.shape.push_back(static_cast<long long>(stage.size()));
      for (double ms : stage) f.us.push_back(ms * scale * 1e3);
    }
    last = s.endMs;
    lastRecord = s.recordMs;
  }
  put(step.endMs - last - lastRecord - readMs);  // the tail after the last section
  return f;
}

double Reduce(std::vector<double>& v, bool least) {
  std::sort(v.begin(), v.end());
  if (least) return v.front();
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// One read of StepTrace::Now(): the least of 32 back-to-back differences.
double ClockReadMs() {
  double least = 1e9;
  for (int k = 0; k < 32; ++k) {
    const double a = StepTrace::Now();
    least = std::min(least, StepTrace::Now() - a);
  }
  return least;
}


void Put(std::string& out, double us) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", us);
  out += buf;
}

// Writes one step from its reduced times (in Flatten's order) and its sections' structure.
void WriteStep(std::string& out, const RecordedStep& shape, const std::vector<double>& us) {
  size_t k = 0;
  out += "{\"us\": ";
  Put(out, us[k++]);
  out += ", \"sections\": [";
  bool first = true;
  auto open = [&] {
    out += first ? "\n      " : ",\n      ";
    first = false;
  };
  for (const StepTrace::Section& s : shape.sections) {
    const double gap = us[k++], span = us[k++];
    if (gap > 0) {
      open();
      out += "{\"kind\": \"gap\", \"us\": ";
      Put(out, gap);
      out += "}";
    }
    open();
    const char* stage = quadrant::kStageNames[static_cast<size_t>(s.stage)];
    if (s.kind == StepTrace::Kind::kSerial) {
      out += std::string("{\"kind\": \"serial\", \"stage\": \"") + stage + "\", \"us\": ";
      Put(out, span);
      out += "}";
      continue;
    }
    out += s.kind == StepTrace::Kind::kFor ? "{\"kind\": \"for\"" : "{\"kind\": \"region\"";
    out += std::string(", \"stage\": \"") + stage + "\"";
    if (s.kind == StepTrace::Kind::kRegion) out += s.runs ? ", \"runs\": true" : ", \"runs\": false";
    out += ", \"span_us\": ";
    Put(out, span);
    out += ", \"us\": [";
    for (size_t st = 0; st < s.ms.size(); ++st) {
      out += st ? ", [" : "[";
      for (size_t c = 0; c < s.ms[st].size(); ++c) {
        if (c) out += ", ";
        Put(out, us[k++]);
      }
      out += "]";
    }
    out += "]}";
  }
  const double tail = us[k++];
  if (tail > 0) {
    open();
    out += "{\"kind\": \"gap\", \"us\": ";
    Put(out, tail);
    out += "}";
  }
  out += "]}";
}

// Runs `repeats` worlds of the scene at each thread count, interleaved, and returns per thread
// count the recorded steps of every repeat.
std::vector<std::vector<std::vector<RecordedStep>>> Record(const qs::Scene& scene, const Args& a) {
  std::vector<std::vector<std::vector<RecordedStep>>> byThreads(a.threads.size());  // [P][repeat][step]
  for (int r = 0; r < a.repeats; ++r) {
    for (size_t t = 0; t < a.threads.size(); ++t) {
      StepTrace trace;
      std::unique_ptr<qs::Adapter> adapter = qs::MakeAdapter("quadrant");
      quadrant::stepTraceSink = &trace;
      try {
        adapter->Load(scene, a.threads[t]);
      } catch (...) {
        quadrant::stepTraceSink = nullptr;
        throw;
      }
      quadrant::stepTraceSink = nullptr;
      for (int i = 0; i < a.warmup; ++i) {
        adapter->Step();
        trace.sections.clear();
      }
      std::vector<RecordedStep> steps;
      for (int i = 0; i < a.steps; ++i) {
        trace.sections.clear();
        RecordedStep step;
        step.beginMs = StepTrace::Now();
        adapter->Step();
        step.endMs = StepTrace::Now();
        step.sections = std::move(trace.sections);
        steps.push_back(std::move(step));
      }
      byThreads[t].push_back(std::move(steps));
    }
  }
  return byThreads;
}

}  // namespace

int main(int argc, char** argv) {
  Args a;
  quadrant::cli::Parser p("quadrant_scaling_trace",
                          "Records the structure of a scene's steps at several thread counts (serial sections, "
                          "parallel-fors' blocks,\nregions' chunks, all timed on one core) as JSON for the "
                          "scaling model (tools/scaling.py).");
  p.Name("--scene", &a.scene, qs::SceneNames(), "scene", "the scene");
  p.Int("--count", &a.count, 1, 10000000, "its body count");
  p.IntList("--threads", &a.threads, 1, 64, "thread counts (each a partition)").Value("a,b").Default("1,2,4,8,16");
  p.Int("--warmup", &a.warmup, 0, 100000000, "steps before the recorded ones");
  p.Int("--steps", &a.steps, 1, 100000, "recorded steps");
  p.Int("--repeats", &a.repeats, 1, 100, "worlds per thread count (each time is reduced over them: --reduce)");
  p.Int("--seed", &a.seed, 0, INT64_MAX, "the scene's seed");
  p.String("--out", &a.out, "FILE", "the JSON file to write (default: stdout)");
  p.Name("--reduce", &a.reduce, {"median", "least"}, "reduction", "how each time is taken over the repeats");
  p.Name("--clock", &a.clock, {"thread", "wall"}, "clock",
         "the clock of the sections' begins and ends: the thread's CPU time, or the steady clock");
  p.Flag("--no-pin", &a.noPin,
         "do not pin the process to one core (then a pool of several threads runs the chunks, "
         "and a run of chunks is timed as one)");
  p.Parse(argc, argv);
  if (std::find(a.threads.begin(), a.threads.end(), 1) == a.threads.end()) a.threads.insert(a.threads.begin(), 1);

  // Before any pool is made: its blocks and chunks are run however busy the machine looks.
  setenv("QUADRANT_POOL_ALONE", "0", 1);
  if (!a.noPin) {
    cpu_set_t set;
    CPU_ZERO(&set);
    const int cpu = sched_getcpu();
    CPU_SET(cpu >= 0 ? cpu : 0, &set);
    if (sched_setaffinity(0, sizeof set, &set) != 0) {
      std::fprintf(stderr, "quadrant_scaling_trace: cannot pin the process to one core\n");
      return 1;
    }
  }
  StepTrace::threadClock = a.clock == "thread";
  const double readMs = ClockReadMs();
  try {
    const qs::Scene scene = qs::MakeScene(a.scene, a.count, a.seed);
    const auto byThreads = Record(scene, a);
    std::string out = "{\"scene\": \"" + a.scene + "\", \"count\": " + std::to_string(a.count) +
                      ", \"bodies\": " + std::to_string(scene.bodies.size()) + ", \"warmup\": " + std::to_string(a.warmup) +
                      ", \"steps\": " + std::to_string(a.steps) + ", \"repeats\": " + std::to_string(a.repeats) +
                      ", \"recorded_on\": \"" + (a.noPin ? "unpinned" : "one core") + "\", \"clock\": \"" + a.clock +
                      "\", \"clock_read_us\": " + std::to_string(readMs * 1e3) + ", \"reduce\": \"" + a.reduce +
                      "\", \"traces\": [";
    for (size_t t = 0; t < a.threads.size(); ++t) {
      out += t ? ",\n {" : "\n {";
      out += "\"threads\": " + std::to_string(a.threads[t]) + ", \"steps\": [";
      for (int i = 0; i < a.steps; ++i) {
        const RecordedStep& shape = byThreads[t][0][i];
        const FlatStep reference = Flatten(shape, readMs, StepTrace::threadClock);
        std::vector<std::vector<double>> samples(reference.us.size());
        for (int r = 0; r < a.repeats; ++r) {
          const FlatStep f = Flatten(byThreads[t][r][i], readMs, StepTrace::threadClock);
          if (f.shape != reference.shape || f.us.size() != reference.us.size()) {
            throw std::runtime_error("step " + std::to_string(i) + " at " + std::to_string(a.threads[t]) +
                                     " threads ran other sections in repeat " + std::to_string(r) +
                                     " than in repeat 0 (the scene is not deterministic?)");
          }
          for (size_t k = 0; k < f.us.size(); ++k) samples[k].push_back(f.us[k]);
        }
        std::vector<double> us(samples.size());
        for (size_t k = 0; k < samples.size(); ++k) us[k] = Reduce(samples[k], a.reduce == "least");
        out += i ? ",\n    " : "\n    ";
        WriteStep(out, shape, us);
      }
      out += "]}";
    }
    out += "]}\n";
    if (a.out.empty()) {
      std::fputs(out.c_str(), stdout);
    } else {
      std::ofstream f(a.out);
      f << out;
      if (!f) throw std::runtime_error("cannot write " + a.out);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "quadrant_scaling_trace: %s\n", e.what());
    return 1;
  }
  return 0;
}
