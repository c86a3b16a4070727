// A record of the structure of a world's steps, for the scaling model (tools/scaling.py, whose
// recordings benchmarks/scaling_trace.cpp makes): in the order the step ran them, every section
// that ran on one thread (serial), every parallel-for (its blocks' times) and every region of
// stages (each stage's chunks' times; a stage's end is a barrier).
//
// Off unless a program points stepTraceSink at a StepTrace before it makes its World: a
// StageRunner reads the sink once, when it is made, and with none it tests one pointer per
// section. Times are the runner's own (StageRunner::NowMs, less one clock read) for blocks and
// chunks, and Now() for a section's begin and end, so the time between two sections (the step's
// code outside the runner) can be read from a trace too. A run of chunks that one
// thread claimed together is timed as one and filed under its first chunk, so a trace holds
// every chunk's own time only where the task system runs chunks one at a time: a pool with one
// running thread (the recording program pins itself to one core).
#pragma once

#include <time.h>

#include <chrono>
#include <cstdint>
#include <span>
#include <vector>

#include "quadrant/task_system.h"
#include "quadrant/types.h"

namespace quadrant {

struct StepTrace {
  enum class Kind : uint8_t {
    kSerial,  ///< ran on the calling thread alone (StageRunner::Serial, and For or Stages inline)
    kFor,     ///< a parallel-for: one stage whose chunks are the static blocks, one a claim
    kRegion,  ///< a region of stages (StageRunner::Stages, Dynamic, Beside)
  };
  struct Section {
    Kind kind = Kind::kSerial;
    Stage stage = Stage::kBroadPhase;
    /// A region whose chunks a thread may claim several at a time (every stage's plan allows it).
    bool runs = false;
    double beginMs = 0, endMs = 0;       ///< Now(), around the whole section
    std::vector<std::vector<double>> ms;  ///< per stage (a parallel-for: one), each chunk's ms
    /// Now() from endMs to the end of the record's own work (copying the times), which the time
    /// to the next section includes.
    double recordMs = 0;
  };
  std::vector<Section> sections;

  /// The clock of every begin and end: the steady clock, or with threadClock this thread's CPU
  /// time (a recording on a shared core: time another process took is not counted; a read is a
  /// system call on some machines, so a recording measures and subtracts it). Blocks and chunks
  /// keep the runner's clock: timed by this one, the 16-block partition of the base-100 pyramid
  /// summed to 60 % more work than one thread on a 2-core VM (reads inside a step cost more than
  /// the back-to-back least that the runner subtracts).
  static inline bool threadClock = false;
  static double Now() {
    if (threadClock) {
      timespec ts;
      clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
      return double(ts.tv_sec) * 1e3 + double(ts.tv_nsec) * 1e-6;
    }
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
  }
  void AddSerial(Stage stage, double beginMs, double endMs) {
    sections.push_back({Kind::kSerial, stage, false, beginMs, endMs, {}});
    sections.back().recordMs = Now() - endMs;
  }
  /// A parallel-for: each block's ms, in block order.
  void AddFor(Stage stage, double beginMs, double endMs, std::span<const double> blockMs) {
    sections.push_back({Kind::kFor, stage, false, beginMs, endMs, {{blockMs.begin(), blockMs.end()}}});
    sections.back().recordMs = Now() - endMs;
  }
  /// A region run by `plan`: stage s's chunks' ms are chunkMs[offsets[s], offsets[s + 1]). A
  /// stage of no items has no chunk (the task system skips it: no barrier).
  void AddRegion(Stage stage, double beginMs, double endMs, std::span<const TaskSystem::StagePlan> plan,
                 std::span<const double> chunkMs, std::span<const int> offsets) {
    Section s{Kind::kRegion, stage, true, beginMs, endMs, {}};
    for (size_t k = 0; k < plan.size(); ++k) {
      s.runs = s.runs && plan[k].runs;
      s.ms.emplace_back();
      if (plan[k].count > 0) s.ms.back().assign(chunkMs.begin() + offsets[k], chunkMs.begin() + offsets[k + 1]);
    }
    sections.push_back(std::move(s));
    sections.back().recordMs = Now() - endMs;
  }
};

/// Where the StageRunners made from now on record (nullptr: nowhere, the default). Set it before
/// a World is made and clear it after; the World's runner keeps the pointer for its life.
inline StepTrace* stepTraceSink = nullptr;

}  // namespace quadrant
