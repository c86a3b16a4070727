// The stage runner's step trace (parallel/step_trace.h), which the scaling model reads: every
// section recorded in order with the partition's blocks and chunks, and nothing without a sink.
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <memory>

#include "parallel/stage_runner.h"
#include "parallel/step_trace.h"
#include "quadrant/task_system.h"
#include "quadrant/world.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

// Sets the sink for the runners made in its life.
struct Sink {
  explicit Sink(StepTrace* trace) { stepTraceSink = trace; }
  ~Sink() { stepTraceSink = nullptr; }
};

TEST(StepTrace, RecordsEverySectionInOrder) {
  constexpr int kWorkers = 4;
  std::unique_ptr<TaskSystem> tasks = MakeThreadPool(kWorkers);
  StepTrace trace;
  std::unique_ptr<StageRunner> run;
  {
    Sink sink(&trace);
    run = std::make_unique<StageRunner>(*tasks, 100);
  }
  std::atomic<long long> sum{0};
  run->BeginStep();  // test_helpers.h: QUADRANT_POOL_ALONE=0, the partition runs however busy the machine
  ASSERT_EQ(run->Workers(), kWorkers);
  run->Serial(Stage::kBroadPhase, [&] { sum += 1; });
  run->For(Stage::kNarrowPhase, 1000, 100, [&](int b, int e, int) { sum += e - b; });
  run->For(Stage::kNarrowPhase, 10, 100, [&](int b, int e, int) { sum += e - b; });  // inline: serial
  // Three stages, the second of no items; grain 25: stage 0 is 8 chunks (200 / 25, under 4 a
  // worker), stage 2 is 16 (StageChunks' most, 4 a worker).
  const std::array<TaskSystem::StagePlan, 3> plan{{{200, 25}, {0, 1}, {1000, 1}}};
  run->Stages(Stage::kSolve, plan, 100, [&](int, int b, int e) { sum += e - b; });
  run->Beside(Stage::kSolve, [&] { sum += 1; }, 1000, 100, [&](int b, int e) { sum += e - b; });

  ASSERT_EQ(trace.sections.size(), 5u);
  const StepTrace::Section& serial = trace.sections[0];
  EXPECT_EQ(serial.kind, StepTrace::Kind::kSerial);
  EXPECT_EQ(serial.stage, Stage::kBroadPhase);
  EXPECT_TRUE(serial.ms.empty());
  const StepTrace::Section& pfor = trace.sections[1];
  EXPECT_EQ(pfor.kind, StepTrace::Kind::kFor);
  EXPECT_EQ(pfor.stage, Stage::kNarrowPhase);
  ASSERT_EQ(pfor.ms.size(), 1u);
  EXPECT_EQ(pfor.ms[0].size(), size_t(kWorkers));  // one time per block
  EXPECT_EQ(trace.sections[2].kind, StepTrace::Kind::kSerial);  // the small For ran inline
  const StepTrace::Section& region = trace.sections[3];
  EXPECT_EQ(region.kind, StepTrace::Kind::kRegion);
  EXPECT_EQ(region.stage, Stage::kSolve);
  EXPECT_TRUE(region.runs);
  ASSERT_EQ(region.ms.size(), 3u);
  EXPECT_EQ(region.ms[0].size(), 8u);
  EXPECT_TRUE(region.ms[1].empty());  // no items: no chunk, no barrier
  EXPECT_EQ(region.ms[2].size(), size_t(4 * kWorkers));
  const StepTrace::Section& beside = trace.sections[4];
  EXPECT_EQ(beside.kind, StepTrace::Kind::kRegion);
  EXPECT_FALSE(beside.runs);  // one item a claim: item 0 is the lone part
  ASSERT_EQ(beside.ms.size(), 1u);
  EXPECT_EQ(beside.ms[0].size(), size_t(4 * kWorkers));
  for (size_t k = 0; k < trace.sections.size(); ++k) {
    EXPECT_LE(trace.sections[k].beginMs, trace.sections[k].endMs);
    if (k > 0) {
      EXPECT_LE(trace.sections[k - 1].endMs, trace.sections[k].beginMs);
    }
  }
  EXPECT_EQ(sum.load(), 1 + 1000 + 10 + 1200 + 1 + 1000);
}

TEST(StepTrace, NothingWithoutASink) {
  StepTrace trace;
  {
    Sink sink(&trace);
  }
  std::unique_ptr<TaskSystem> tasks = MakeThreadPool(2);
  StageRunner run(*tasks, 1);
  run.BeginStep();
  run.Serial(Stage::kSolve, [] {});
  run.For(Stage::kSolve, 100, 1, [](int, int, int) {});
  EXPECT_TRUE(trace.sections.empty());
}

TEST(StepTrace, AWorldsStepsAtOneThreadAreSerial) {
  StepTrace trace;
  WorldDef def;
  def.threadCount = 1;
  std::unique_ptr<World> world;
  {
    Sink sink(&trace);
    world = std::make_unique<World>(def);
  }
  test::AddGround(*world);
  test::AddBox(*world, {0, 1});
  world->Step(test::kDt);
  ASSERT_FALSE(trace.sections.empty());
  for (const StepTrace::Section& s : trace.sections) EXPECT_EQ(s.kind, StepTrace::Kind::kSerial);
}

}  // namespace
}  // namespace quadrant
