// The deterministic scheme: bit-identical state for any thread count.
//
// These tests run worlds with 1 to 4 threads (also under the tsan preset in CI), with the
// parallel grain lowered so that even small scenes exercise every parallel section.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <algorithm>
#include <vector>

#include "adapter.h"
#include "quadrant/world.h"
#include "scenes.h"

namespace quadrant {
namespace {

constexpr Real kDt = Real(1) / Real(60);

// Loads a scene into a World directly (the adapter's translation, but with the grain knob).
std::vector<BodyId> Load(World& world, const scene::Scene& s) {
  std::vector<BodyId> ids;
  for (const scene::BodyDesc& b : s.bodies) {
    BodyDef bd;
    bd.type = b.dynamic ? BodyType::kDynamic : b.kinematic ? BodyType::kKinematic : BodyType::kStatic;
    bd.position = b.position;
    bd.angle = b.angle;
    bd.linearVelocity = b.velocity;
    bd.angularVelocity = b.angularVelocity;
    if (!b.extraShapes.empty() || b.shape == scene::ShapeKind::kSegment) {
      // Compound bodies and segments (compounds, washer) as the scene API maps them.
      const BodyDef full = scene::ToBodyDef(b);
      bd.shape = full.shape;
      bd.extraShapes = full.extraShapes;
    } else {
      bd.shape = b.shape == scene::ShapeKind::kCircle ? ShapeDef::MakeCircle(b.radius)
                                                       : ShapeDef::FromPolygon(MakePolygon(b.vertices));
    }
    bd.shape.density = b.density;
    bd.shape.friction = b.friction;
    bd.shape.restitution = b.restitution;
    ids.push_back(world.CreateBody(bd));
  }
  return ids;
}

WorldDef DefFor(const scene::Scene& s, int threads, int grain) {
  WorldDef def;
  def.gravity = s.gravity;
  def.restitutionThreshold = s.restitutionThreshold;
  def.effects.gravity = s.effects.gravity;
  def.effects.friction = s.effects.friction;
  def.threadCount = threads;
  def.minParallelItems = grain;
  return def;
}

// Whether the last Step ran a section on more than one worker (its work then exceeds its
// critical path; a serial section adds the same to both).
// A busy machine must not turn these determinism tests into one-thread-against-one-thread
// comparisons (the pool's RunsAlone): QUADRANT_POOL_ALONE=0, set before main unless already set.
[[maybe_unused]] const bool kPoolStepsSplit = (setenv("QUADRANT_POOL_ALONE", "0", 0), true);

bool ParallelSectionRan(const Profile& profile) {
  for (const StageBalance& b : profile.balance) {
    if (b.workMs > b.criticalMs) return true;
  }
  return false;
}

// The state hash after `steps` steps. With more than one thread it also checks that parallel
// sections really ran, so a determinism test cannot pass by comparing serial with serial.
uint64_t HashAfter(const scene::Scene& s, int threads, int grain, int steps) {
  World world(DefFor(s, threads, grain));
  Load(world, s);
  int parallelSteps = 0;
  for (int i = 0; i < steps; ++i) {
    world.Step(kDt);
    parallelSteps += ParallelSectionRan(world.GetProfile()) ? 1 : 0;
  }
  if (threads > 1 && grain < 2048) {
    EXPECT_GT(parallelSteps, 0) << threads << " threads, grain " << grain << ": no section ran in parallel";
  }
  return world.StateHash();
}

// A pyramid of 1 m boxes with a base of `base`, on a static ground: a pile that loads the
// solver (many colours, many constraints per colour).
scene::Scene Pyramid(int base) {
  scene::Scene s;
  s.name = "pyramid";
  scene::BodyDesc ground;
  ground.dynamic = false;
  ground.shape = scene::ShapeKind::kPolygon;
  ground.vertices = {{-40, -1}, {40, -1}, {40, 0}, {-40, 0}};
  ground.friction = Real(0.6);
  s.bodies.push_back(ground);
  for (int row = 0; row < base; ++row) {
    for (int i = 0; i < base - row; ++i) {
      scene::BodyDesc box;
      box.shape = scene::ShapeKind::kPolygon;
      box.vertices = {{Real(-0.5), Real(-0.5)}, {Real(0.5), Real(-0.5)}, {Real(0.5), Real(0.5)}, {Real(-0.5), Real(0.5)}};
      box.position = {Real(-0.5 * (base - row - 1) + i * 1.0), Real(0.5 + row * 1.0)};
      box.friction = Real(0.6);
      s.bodies.push_back(box);
    }
  }
  return s;
}

class DeterministicScheme : public ::testing::TestWithParam<const char*> {};

// 300 steps, as the issue asks; N = 1000 keeps the tsan run short. Grain 64 makes every stage
// split across threads even at this size.
TEST_P(DeterministicScheme, SameHashForOneToFourThreads) {
  const std::string name = GetParam();
  const scene::Scene s = name == "pyramid" ? Pyramid(20) : scene::MakeScene(name, 1000, 7);
  const uint64_t one = HashAfter(s, 1, 64, 300);
  for (int threads = 2; threads <= 4; ++threads) {
    EXPECT_EQ(HashAfter(s, threads, 64, 300), one) << name << " with " << threads << " threads";
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, DeterministicScheme,
                         ::testing::Values("circle_stress", "polygon_stress", "pyramid", "many_pyramids", "tumbler", "joint_grid", "junkyard",
                                           "smash", "compounds", "washer"));

TEST(DeterministicSchemeTest, GrainDoesNotChangeTheResult) {
  // Serial and parallel execution of a section must agree bit for bit.
  const scene::Scene s = Pyramid(12);
  EXPECT_EQ(HashAfter(s, 2, 1, 120), HashAfter(s, 2, 100000, 120));
}

// Bodies made while the contacts change (rain's ragdolls, spawned every 8 steps): the soft
// step clears last step's colour masks in a pass over the bodies, and a range reaching past the
// bodies made since must still be cleared below them (ConstraintGraph::ClearColors). It was
// skipped whole, so masks stayed set, and which stayed depended on how the pass was split: the
// next colouring, and the state, then differed between 1 and 2 threads.
uint64_t HashWithBoxesMadeWhileColouring(int threads) {
  const scene::Scene s = Pyramid(34);  // 595 boxes: more than two chunks of the body passes (256 each)
  World world(DefFor(s, threads, 16));
  Load(world, s);
  BodyDef drop;
  drop.shape = ShapeDef::Box(Real(0.4), Real(0.4));
  int parallelSteps = 0;
  for (int i = 0; i < 120; ++i) {
    if (i < 24) {
      // A column against the pyramid's left corner, each box made on the one before (made a
      // step earlier, coloured since): a new contact of a coloured body, so a new colouring, in
      // every step a box is made.
      drop.position = {Real(-17.4), Real(0.4 + 0.8 * i)};
      world.CreateBody(drop);
    }
    world.Step(kDt);
    parallelSteps += ParallelSectionRan(world.GetProfile()) ? 1 : 0;
  }
  if (threads > 1) {
    EXPECT_GT(parallelSteps, 0) << threads << " threads: no section ran in parallel";
  }
  return world.StateHash();
}

TEST(DeterministicSchemeTest, BodiesMadeMidRunSameHashForOneToFourThreads) {
  const uint64_t one = HashWithBoxesMadeWhileColouring(1);
  for (int threads = 2; threads <= 4; ++threads) EXPECT_EQ(HashWithBoxesMadeWhileColouring(threads), one) << threads;
}

TEST(DeterministicSchemeTest, AdapterHashMatchesWorldHashAndBenchmarkPath) {
  // The benchmark's label is the adapter's StateHash after warm-up + timed steps; the same
  // scene, steps and threads through the adapter must give the same hash at 1 and 3 threads.
  // 4000 bodies: above the default grain of 2048 items, so the adapter's world (which keeps the
  // default) runs its sections in parallel at 3 threads (checked from its stage totals).
  const scene::Scene s = scene::MakeScene("circle_stress", 4000, 42);
  uint64_t hashes[2];
  const int threads[2] = {1, 3};
  for (int k = 0; k < 2; ++k) {
    auto adapter = scene::MakeAdapter("quadrant");
    adapter->Load(s, threads[k]);
    for (int i = 0; i < 150; ++i) adapter->Step();
    hashes[k] = adapter->StateHash();
    if (threads[k] > 1) {
      double work = 0, critical = 0;
      for (const auto& [name, ms] : adapter->StageTotals()) {
        if (name.starts_with("work_")) work += ms;
        if (name.starts_with("critical_")) critical += ms;
      }
      EXPECT_GT(work, critical) << "no section ran in parallel";
    }
  }
  EXPECT_EQ(hashes[0], hashes[1]);
}

TEST(DeterministicSchemeTest, PyramidStandsWithFourThreads) {
  const scene::Scene s = Pyramid(10);
  World world(DefFor(s, 4, 16));
  std::vector<BodyId> ids = Load(world, s);
  const Vec2 top0 = world.GetPosition(ids.back());
  for (int i = 0; i < 240; ++i) world.Step(kDt);
  const Vec2 top = world.GetPosition(ids.back());
  EXPECT_LT(Length(top - top0), 0.05f);
}

TEST(DeterministicSchemeTest, ProfileReportsLoadBalance) {
  const scene::Scene s = scene::MakeScene("circle_stress", 4000, 3);
  World world(DefFor(s, 4, 512));
  Load(world, s);
  world.Step(kDt);
  const Profile& p = world.GetProfile();
  const StageBalance& broad = p.balance[size_t(Stage::kBroadPhase)];
  EXPECT_GT(broad.workMs, 0.0);
  EXPECT_GT(broad.criticalMs, 0.0);
  // A serial section counts fully on the critical path, so critical <= work always.
  EXPECT_LE(broad.criticalMs, broad.workMs * (1 + 1e-9));
}

TEST(DeterministicSchemeTest, ThreadCountOutOfRangeIsRefused) {
  WorldDef def;
  def.threadCount = 0;
  EXPECT_THROW(World{def}, Error);
  def.threadCount = 65;
  EXPECT_THROW(World{def}, Error);
  def.threadCount = 2;
  def.minParallelItems = 0;
  EXPECT_THROW(World{def}, Error);
}

}  // namespace
}  // namespace quadrant

namespace quadrant {
namespace {

// pgs: the thesis's scheme is measured with Box2D 2.4's solver (with soft_step the boundary
// collision below loses its bounce: both circles end near rest; not yet understood).
WorldDef QuadrantsDef(int threads) {
  WorldDef def;
  def.solver = SolverType::kPgs;
  def.gravity = {0, 0};
  def.restitutionThreshold = 0;
  def.effects.friction = false;
  def.threadCount = threads;
  def.scheme = ParallelScheme::kQuadrants;
  return def;
}

// Two equal circles meet head-on exactly on the boundary between two threads' regions: each
// thread resolves its own body against a ghost of the other, so the impulses are equal and
// opposite (no double resolution): momentum is conserved and the velocities exchange.
TEST(QuadrantsScheme, BoundaryCollisionConservesMomentum) {
  for (int threads : {2, 4}) {
    World world(QuadrantsDef(threads));
    // Corner bodies fix the partitioned square to about [-10, 10]^2, so y = 0 is a region
    // boundary for 2 threads (bottom and top halves) and for 4 (quadrants).
    BodyDef corner;
    corner.shape = ShapeDef::MakeCircle(Real(0.5));
    corner.position = {Real(-9.5), Real(-9.5)};
    world.CreateBody(corner);
    corner.position = {Real(9.5), Real(9.5)};
    world.CreateBody(corner);
    BodyDef a;
    a.type = BodyType::kDynamic;
    a.shape = ShapeDef::MakeCircle(Real(0.5));
    a.shape.restitution = 1;
    a.shape.friction = 0;
    a.position = {Real(-5), Real(-3)};
    a.linearVelocity = {0, Real(2)};
    BodyDef b = a;
    b.position = {Real(-5), Real(3)};
    b.linearVelocity = {0, Real(-2)};
    BodyId ia = world.CreateBody(a), ib = world.CreateBody(b);
    bool sawSplit = false;
    for (int i = 0; i < 150; ++i) {
      world.Step(Real(1) / Real(60));
      const std::vector<int> owners = world.GetOwners();
      sawSplit = sawSplit || (owners[2] >= 0 && owners[3] >= 0 && owners[2] != owners[3]);
      const Real py = world.GetLinearVelocity(ia).y + world.GetLinearVelocity(ib).y;
      ASSERT_NEAR(py, 0.0, 1e-5) << threads << " threads, step " << i;
    }
    EXPECT_TRUE(sawSplit) << "the bodies should have been owned by different threads";
    EXPECT_NEAR(world.GetLinearVelocity(ia).y, -2.0, 1e-4);
    EXPECT_NEAR(world.GetLinearVelocity(ib).y, 2.0, 1e-4);
  }
}

// Many bodies crossing region boundaries for many steps: every body stays owned by exactly one
// partition (owners are -1..T-1), none is lost (count, finite state, inside the box) and total
// momentum stays what it was (elastic, frictionless, walls static).
TEST(QuadrantsScheme, BodiesCrossingBoundariesAreNeverLostOrDuplicated) {
  const scene::Scene s = scene::MakeScene("circle_stress", 600, 11);
  for (int threads : {2, 3, 4}) {
    auto adapter = scene::MakeAdapter("quadrant:quadrants");
    adapter->Load(s, threads);
    std::vector<scene::BodyState> st;
    for (int i = 0; i < 600; ++i) adapter->Step();
    adapter->ReadBodies(st);
    ASSERT_EQ(st.size(), s.bodies.size());
    for (size_t k = 0; k < st.size(); ++k) {
      ASSERT_TRUE(IsFinite(st[k].position) && IsFinite(st[k].velocity)) << k;
      if (!s.bodies[k].dynamic) continue;  // the walls stand outside the box
      EXPECT_GE(st[k].position.x, s.bounds.lower.x - 0.1f);
      EXPECT_LE(st[k].position.x, s.bounds.upper.x + 0.1f);
      EXPECT_GE(st[k].position.y, s.bounds.lower.y - 0.1f);
      EXPECT_LE(st[k].position.y, s.bounds.upper.y + 0.1f);
    }
    const double e0 = scene::KineticEnergy(s, [&] {
      std::vector<scene::BodyState> s0;
      for (const scene::BodyDesc& b : s.bodies) s0.push_back({b.position, b.angle, b.velocity, b.angularVelocity});
      return s0;
    }());
    const double e1 = scene::KineticEnergy(s, st);
    EXPECT_NEAR(e1 / e0, 1.0, 0.05) << threads << " threads";
  }
}

TEST(QuadrantsScheme, OwnersCoverEveryBodyOnce) {
  const scene::Scene s = scene::MakeScene("circle_stress", 2000, 5);
  World world(QuadrantsDef(4));
  Load(world, s);
  for (int i = 0; i < 30; ++i) world.Step(Real(1) / Real(60));
  const std::vector<int> owners = world.GetOwners();
  ASSERT_EQ(static_cast<int>(owners.size()), world.GetBodyCount());
  int perOwner[5] = {};
  for (int o : owners) {
    ASSERT_GE(o, -1);
    ASSERT_LT(o, 4);
    ++perOwner[o + 1];
  }
  // A uniform scene spreads over the four quadrants; the master holds only straddlers.
  for (int t = 1; t <= 4; ++t) EXPECT_GT(perOwner[t], 300) << "thread " << t - 1;
  EXPECT_LT(perOwner[0], 200);
}

TEST(QuadrantsScheme, ClumpedSceneLoadsOneThread) {
  // The thesis's known weakness: all bodies in one quadrant means one thread does the work.
  const scene::Scene s = scene::MakeScene("circle_stress_clumped", 2000, 5);
  World world(QuadrantsDef(4));
  Load(world, s);
  for (int i = 0; i < 10; ++i) world.Step(Real(1) / Real(60));
  const std::vector<int> owners = world.GetOwners();
  int perOwner[5] = {};
  for (int o : owners) ++perOwner[o + 1];
  EXPECT_GT(*std::max_element(perOwner + 1, perOwner + 5), 1500);
}

}  // namespace
}  // namespace quadrant
