// soft_step's SIMD row kernels (soft_rows.h) against their one-row path: the same state bit
// for bit, on a pile with two-point and one-point manifolds, static, kinematic and dynamic
// bodies, at 1 and 3 threads with parallel sections that really run in parallel; and the
// four-wide SSE2 kernels against the eight-wide AVX ones (WorldDef::softVex; the AVX ones run only
// on a CPU with AVX, so on one without it the two runs below are the same path).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "quadrant/world.h"
#include "dynamics/soft_rows.h"

namespace quadrant {
namespace {

// A static ground slab 1 m thick, its top at y = 0.
void AddGround(World& world, Real halfWidth) {
  BodyDef ground;
  ground.position = {0, -0.5f};
  ground.shape = ShapeDef::Box(halfWidth, 0.5f);
  world.CreateBody(ground);
}

uint64_t RunPile(bool simd, int threads, bool vex = true) {
  WorldDef def;
  def.solver = SolverType::kSoftStep;
  def.softSimd = simd;
  def.softVex = vex;
  def.threadCount = threads;
  def.minParallelItems = 8;  // split every section that has 8 items: colours run on several threads
  World world(def);
  AddGround(world, 30);
  BodyDef platform;  // kinematic: read by the rows, never written
  platform.type = BodyType::kKinematic;
  platform.position = {12, 2};
  platform.linearVelocity = {0.5f, 0};
  platform.shape = ShapeDef::Box(3, 0.25f);
  world.CreateBody(platform);
  // A pyramid of boxes (two-point manifolds), and circles and rotated boxes dropped on it and
  // on the platform (one-point manifolds, rotation, friction).
  for (int row = 0; row < 12; ++row) {
    for (int i = 0; i < 12 - row; ++i) {
      BodyDef b;
      b.type = BodyType::kDynamic;
      b.position = {Real(i) * 1.05f - (11 - row) * 0.525f, 0.5f + Real(row)};
      b.shape = ShapeDef::Box(0.5f, 0.5f);
      world.CreateBody(b);
    }
  }
  for (int i = 0; i < 40; ++i) {
    BodyDef b;
    b.type = BodyType::kDynamic;
    b.position = {Real(i % 10) * 1.3f - 4 + (i / 10 % 2 ? 10 : 0), 14.0f + Real(i / 10) * 1.5f};
    b.angle = 0.3f * Real(i);
    b.shape = i % 2 ? ShapeDef::MakeCircle(0.4f) : ShapeDef::Box(0.3f, 0.45f);
    b.shape.restitution = i % 3 == 0 ? 0.5f : 0.0f;
    world.CreateBody(b);
  }
  for (int s = 0; s < 150; ++s) world.Step(1.0f / 60);
  return world.StateHash();
}

TEST(SoftSimdTest, FourWideAndOneRowPathsGiveTheSameState) {
  const uint64_t scalar = RunPile(false, 1);
  EXPECT_EQ(RunPile(true, 1), scalar);
  EXPECT_EQ(RunPile(false, 3), scalar);
  EXPECT_EQ(RunPile(true, 3), scalar);
  EXPECT_EQ(RunPile(true, 1, false), scalar);
  EXPECT_EQ(RunPile(true, 3, false), scalar);
}

// The position pass and the restitution passes run on this pile too (restitution on, deep
// overlap at the start): the AVX-encoded position kernel against SSE2's and the one-row path.
TEST(SoftSimdTest, AvxEncodingGivesTheSameStateAsSse2WithOverlapAndBounces) {
  auto run = [](bool simd, bool vex) {
    WorldDef def;
    def.solver = SolverType::kSoftStep;
    def.softSimd = simd;
    def.softVex = vex;
    def.threadCount = 2;
    def.minParallelItems = 8;
    World world(def);
    AddGround(world, 20);
    for (int i = 0; i < 60; ++i) {  // spawned 0.2 m into each other: the position pass acts
      BodyDef b;
      b.type = BodyType::kDynamic;
      b.position = {Real(i % 10) * 0.8f - 4, 0.45f + Real(i / 10) * 0.8f};
      b.angle = 0.05f * Real(i % 7);
      b.shape = ShapeDef::Box(0.5f, 0.5f);
      b.shape.restitution = i % 4 == 0 ? 0.6f : 0.0f;
      world.CreateBody(b);
    }
    for (int s = 0; s < 120; ++s) world.Step(1.0f / 60);
    return world.StateHash();
  };
  const uint64_t scalar = run(false, false);
  EXPECT_EQ(run(true, false), scalar);
  EXPECT_EQ(run(true, true), scalar);
}

// Free bodies (no contact row) are moved over the whole step four at a time (MoveFour in
// soft_step_state.cpp) or one at a time (MoveFree) with the same bits: bodies in the air next to
// pairs that touch (so groups of four mix free bodies with bodies in rows, and a static one),
// spinning fast enough that some turn by 0.5 rad or more in a step, one faster than the speed
// limit, with damping and with sleep, 1 and 3 threads; 83 bodies, so the last group is partial.
uint64_t RunFree(bool simd, int threads, bool damping, bool sleep, bool vex = true) {
  WorldDef def;
  def.solver = SolverType::kSoftStep;
  def.softSimd = simd;
  def.softVex = vex;
  def.threadCount = threads;
  def.minParallelItems = 8;
  def.effects.damping = damping;
  def.effects.sleep = sleep;
  World world(def);
  for (int i = 0; i < 83; ++i) {
    BodyDef b;
    b.type = i % 17 == 5 ? BodyType::kStatic : BodyType::kDynamic;
    // Every sixth body sits just above the previous one: they touch within a few steps.
    const bool onPrevious = i % 6 == 1;
    b.position = {Real(i / 6) * 3.0f, onPrevious ? 1.05f : Real(i % 6) * 4.0f - 0.1f * Real(i % 6 == 0)};
    b.shape = i % 2 ? ShapeDef::MakeCircle(0.5f) : ShapeDef::Box(0.5f, 0.5f);
    b.angularVelocity = Real(i % 9) * 9.0f - 20.0f;  // -20 .. 52 rad/s: 0.87 rad a step at 52
    b.linearVelocity = {Real(i % 5) - 2.0f, Real(i % 7) - 3.0f};
    if (i == 40) b.linearVelocity = {500.0f, 0};  // beyond maxLinearSpeed (400 m/s)
    b.linearDamping = Real(i % 4) * 0.3f;
    b.angularDamping = Real(i % 3) * 0.5f;
    world.CreateBody(b);
  }
  for (int s = 0; s < 90; ++s) world.Step(1.0f / 60);
  return world.StateHash();
}

TEST(SoftSimdTest, FreeBodiesFourAtATimeGiveTheSameState) {
  for (const bool damping : {false, true}) {
    for (const bool sleep : {false, true}) {
      const uint64_t scalar = RunFree(false, 1, damping, sleep);
      EXPECT_EQ(RunFree(true, 1, damping, sleep), scalar) << "damping " << damping << " sleep " << sleep;
      EXPECT_EQ(RunFree(true, 3, damping, sleep), scalar) << "damping " << damping << " sleep " << sleep;
      EXPECT_EQ(RunFree(true, 1, damping, sleep, false), scalar) << "SSE2 encoding, damping " << damping << " sleep " << sleep;
    }
  }
}

TEST(SoftSimdTest, BuildHasTheFourWidePathWhereExpected) {
#if defined(__SSE2__) && !defined(QUADRANT_DOUBLE)
  EXPECT_EQ(QUADRANT_SOFT_SIMD, 1);
#else
  EXPECT_EQ(QUADRANT_SOFT_SIMD, 0);
#endif
#if defined(__SSE2__) && !defined(QUADRANT_DOUBLE) && defined(__x86_64__) && defined(__GNUC__)
  EXPECT_EQ(QUADRANT_SOFT_VEX, 1);
#else
  EXPECT_EQ(QUADRANT_SOFT_VEX, 0);
  EXPECT_FALSE(CpuHasAvx());
#endif
}

}  // namespace
}  // namespace quadrant

namespace quadrant {
namespace {

struct SlabRun {
  double heavySink = 0, slabSink = 0, heavyDx = 0;
  uint64_t hash = 0;
};

// Issue #13 item 3: a 2 m box of 1000 kg on one 4 m x 0.2 m slab of 1 kg on the ground, soft_step
// at its default 4 sub-steps, 10 s.
SlabRun RunSlab(Real massRatioLimit) {
  WorldDef def;
  def.solver = SolverType::kSoftStep;
  def.softMassRatioLimit = massRatioLimit;
  World world(def);
  AddGround(world, 20);
  BodyDef slab;
  slab.type = BodyType::kDynamic;
  slab.position = {0, 0.1f};
  slab.shape = ShapeDef::Box(2, 0.1f);
  slab.shape.density = 1.25f;
  const BodyId slabId = world.CreateBody(slab);
  BodyDef heavy;
  heavy.type = BodyType::kDynamic;
  heavy.position = {0, 1.2f};
  heavy.shape = ShapeDef::Box(1, 1);
  heavy.shape.density = 250;
  const BodyId heavyId = world.CreateBody(heavy);
  SlabRun r;
  for (int s = 1; s <= 600; ++s) {
    world.Step(1.0f / 60);
    const Vec2 p = world.GetPosition(heavyId);
    r.heavySink = std::max(r.heavySink, 1.2 - double(p.y));
    r.heavyDx = std::max(r.heavyDx, std::abs(double(p.x)));
  }
  r.slabSink = 0.1 - double(world.GetPosition(slabId).y);
  r.hash = world.StateHash();
  return r;
}

TEST(SoftMassRatioLimitTest, HeavyBoxHoldsOnALightSlab) {
  const SlabRun held = RunSlab(10);
  EXPECT_LT(held.heavySink, 0.02);
  EXPECT_LT(held.slabSink, 0.01);
  EXPECT_LT(held.heavyDx, 0.01);
}

TEST(SoftMassRatioLimitTest, ALimitNoContactReachesChangesNothing) {
  // 1000:1 is the largest ratio here: a limit of 2000 scales no contact, so the state is the
  // same bits as with the limit off.
  EXPECT_EQ(RunSlab(2000).hash, RunSlab(0).hash);
  EXPECT_NE(RunSlab(10).hash, RunSlab(0).hash);
}

// Forty columns of three light boxes (1 kg) under a heavy one (100 kg, over the limit of 10),
// each created top down, so that in the contacts' body order support climbs one box a pass
// (PropagateSupport). Passes split across the threads from 8 contacts on. Returns the heavy
// boxes' largest sink below their rest height and the state hash.
struct PileRun {
  double heavySink = 0;
  uint64_t hash = 0;
};
PileRun RunHeavyOnPiles(int threads, Real massRatioLimit) {
  WorldDef def;
  def.solver = SolverType::kSoftStep;
  def.softMassRatioLimit = massRatioLimit;
  def.threadCount = threads;
  def.minParallelItems = 8;
  World world(def);
  AddGround(world, 100);
  std::vector<BodyId> heavy;
  for (int col = 0; col < 40; ++col) {
    for (int k = 3; k >= 0; --k) {
      BodyDef b;
      b.type = BodyType::kDynamic;
      b.position = {Real(col) * 3 - 60, 0.5f + Real(k)};
      b.shape = ShapeDef::Box(0.5f, 0.5f);
      b.shape.density = k == 3 ? 100 : 1;
      const BodyId id = world.CreateBody(b);
      if (k == 3) heavy.push_back(id);
    }
  }
  PileRun r;
  for (int s = 0; s < 600; ++s) {
    world.Step(1.0f / 60);
    for (const BodyId id : heavy) r.heavySink = std::max(r.heavySink, 3.5 - double(world.GetPosition(id).y));
  }
  r.hash = world.StateHash();
  return r;
}

TEST(SoftMassRatioLimitTest, SupportClimbsAPileWithTheSameBitsAtEveryThreadCount) {
  const PileRun one = RunHeavyOnPiles(1, 10);
  for (int threads : {2, 4, 8}) EXPECT_EQ(RunHeavyOnPiles(threads, 10).hash, one.hash) << threads << " threads";
  // Held through the pile: the top box presses the boxes below as on a box that touches the
  // ground.
  const PileRun unlimited = RunHeavyOnPiles(1, 0);
  EXPECT_LT(one.heavySink, 0.5 * unlimited.heavySink);
}

TEST(SoftMassRatioLimitTest, BadLimitIsRefused) {
  for (Real bad : {Real(0.5), Real(-1), std::numeric_limits<Real>::quiet_NaN(), std::numeric_limits<Real>::infinity()}) {
    WorldDef def;
    def.softMassRatioLimit = bad;
    EXPECT_THROW(World{def}, Error);
  }
}

}  // namespace
}  // namespace quadrant

namespace quadrant {
namespace {

TEST(SoftRelaxIterationsTest, BadCountIsRefusedAndASecondPassChangesTheResult) {
  for (int bad : {0, -1, 1001}) {
    WorldDef def;
    def.softRelaxIterations = bad;
    EXPECT_THROW(World{def}, Error);
  }
  // The relax pass count reaches the solver: a box settling on the ground ends elsewhere with two.
  auto run = [](int relax) {
    WorldDef def;
    def.solver = SolverType::kSoftStep;
    def.softRelaxIterations = relax;
    World world(def);
    BodyDef ground;
    ground.shape = ShapeDef::Box(5, 0.5f);
    world.CreateBody(ground);
    BodyDef box;
    box.type = BodyType::kDynamic;
    box.position = {0, 1.2f};
    box.angle = 0.2f;
    box.shape = ShapeDef::Box(0.5f, 0.5f);
    world.CreateBody(box);
    for (int s = 0; s < 60; ++s) world.Step(1.0f / 60);
    return world.StateHash();
  };
  EXPECT_NE(run(1), run(2));
}

}  // namespace
}  // namespace quadrant
