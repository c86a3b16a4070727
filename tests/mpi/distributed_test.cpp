// The distributed world under mpirun (tests/CMakeLists.txt runs this with 1, 2, 3 and 4 ranks).
//
// Every test is collective: all ranks run the same steps and every checked value is one all
// ranks share (a gathered state, a reduced count), so a failure fails on every rank and no rank
// is left waiting in a collective. Rank 0 runs the single-process World for the comparison and
// broadcasts its hashes.
//
// Special mode (tests/CMakeLists.txt, mpi_bad_input_exit): `--bad-scene-exit` loads a scene that
// differs between ranks and lets the error end the program: every rank must print it and the
// job must exit non-zero.
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <unistd.h>
#include <random>
#include <string>
#include <vector>

#include "quadrant/distributed_world.h"
#include "quadrant/error.h"
#include "quadrant/world.h"
#include "scenes.h"

namespace quadrant {
namespace {

int Rank() {
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}
int Size() {
  int s = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &s);
  return s;
}

// The scene's bodies through the scene API's own mapping (scene::ToBodyDef).
std::vector<BodyDef> ToBodyDefs(const scene::Scene& s) {
  std::vector<BodyDef> out;
  out.reserve(s.bodies.size());
  for (const scene::BodyDesc& b : s.bodies) out.push_back(scene::ToBodyDef(b));
  return out;
}

WorldDef JacobiDef(const scene::Scene& s) {
  WorldDef def;
  def.gravity = s.gravity;
  def.solver = SolverType::kJacobi;
  def.velocityIterations = s.velocityIterations;
  def.restitutionThreshold = s.restitutionThreshold;
  def.effects = s.effects;
  return def;
}

// A World (rank 0 only) and a distributed world loaded with the same bodies, stepped together;
// the distributed one may run other settings (threads inside ranks).
struct SideBySide {
  SideBySide(const WorldDef& def, const DistributedDef& dist, const std::vector<BodyDef>& bodies)
      : SideBySide(def, def, dist, bodies) {}
  SideBySide(const WorldDef& def, const WorldDef& distributedDef, const DistributedDef& dist,
             const std::vector<BodyDef>& bodies)
      : dw(distributedDef, dist, MPI_COMM_WORLD) {
    if (Rank() == 0) {
      world = std::make_unique<World>(def);
      for (const BodyDef& b : bodies) world->CreateBody(b);
    }
    dw.Load(bodies);
  }
  void Step(Real dt) {
    if (world) world->Step(dt);
    dw.Step(dt);
  }
  // The World's hash, sent from rank 0 to every rank.
  uint64_t WorldHash() const {
    uint64_t expected = world ? world->StateHash() : 0;
    MPI_Bcast(&expected, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD);
    return expected;
  }
  std::unique_ptr<World> world;
  DistributedWorld dw;
};

// Steps a World (rank 0 only) and the distributed world side by side; compares their state
// hashes every `every` steps. Returns the distributed world's migrations summed over steps and
// ranks; `patched`, if given, gets the steps summed over ranks that patched the local arrays
// (DistributedStats::layoutPatched), `moved` the rows those patches moved (rowsMoved).
int64_t CompareWithWorld(const WorldDef& def, const DistributedDef& dist, const std::vector<BodyDef>& bodies,
                         Real dt, int steps, int every, int64_t* patched = nullptr, int64_t* moved = nullptr) {
  SideBySide both(def, dist, bodies);
  int64_t migrated = 0, patches = 0, moves = 0;
  for (int step = 1; step <= steps; ++step) {
    both.Step(dt);
    migrated += both.dw.GetStats().migratedIn;
    patches += both.dw.GetStats().layoutPatched;
    moves += both.dw.GetStats().rowsMoved;
    if (step % every == 0 || step == steps) {
      const uint64_t expected = both.WorldHash(), got = both.dw.StateHash();
      EXPECT_EQ(got, expected) << "step " << step << " at " << Size() << " ranks";
      if (got != expected) break;  // every rank sees the same values, so every rank stops here
    }
  }
  int64_t total = 0;
  MPI_Allreduce(&migrated, &total, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
  if (patched != nullptr) MPI_Allreduce(&patches, patched, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
  if (moved != nullptr) MPI_Allreduce(&moves, moved, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
  return total;
}

// Circle stress (the thesis's Figure 14 scene, elastic, no gravity, closed box) on 4 x 4 tiles:
// every body crosses tiles, the hashes equal the World's all the way.
TEST(Distributed, CircleStressMatchesWorld) {
  scene::StressParams p;
  p.count = 1000;
  const scene::Scene s = scene::MakeStressScene(p);
  DistributedDef dist;
  dist.bounds = s.bounds;
  dist.tilesX = dist.tilesY = 4;
  int64_t patched = 0, moved = 0;
  const int64_t migrated = CompareWithWorld(JacobiDef(s), dist, ToBodyDefs(s), s.timeStep, 200, 50, &patched, &moved);
  if (Size() > 1) {
    EXPECT_GT(migrated, 0);  // bodies crossed between ranks (the 2000-step test below moves many more)
    EXPECT_GT(patched, 0);   // and the steps where they did patched the local arrays (PatchLocal)
    EXPECT_GT(moved, 0);     // rows out of id order: pairs and contacts are ordered by id all the same
  }
  if (Rank() == 0) std::printf("[ info ] circle stress 1000, 200 steps, %d ranks: %lld migrations\n", Size(), (long long)migrated);
}

// Threads inside a rank: two workers per rank with small parallel grains (the broad and narrow
// phases split even this scene) give the same hashes as the World on one thread.
TEST(Distributed, ThreadsInsideRanksMatchWorld) {
  scene::StressParams p;
  p.count = 1000;
  const scene::Scene s = scene::MakeStressScene(p);
  const WorldDef def = JacobiDef(s);
  DistributedDef dist;
  dist.bounds = s.bounds;
  dist.tilesX = dist.tilesY = 4;
  WorldDef threaded = def;
  threaded.threadCount = 2;
  threaded.minParallelItems = 64;
  SideBySide both(def, threaded, dist, ToBodyDefs(s));
  for (int step = 0; step < 60; ++step) both.Step(s.timeStep);
  const uint64_t expected = both.WorldHash();
  EXPECT_EQ(both.dw.StateHash(), expected);
}

// The stress scene's circles falling under gravity with friction and no bounce into a pile: many
// lasting contacts whose bodies change owner while they carry warm-start impulses (the entries
// must travel with a migrating body, or the next step starts from other impulses). Every third
// circle is in collision category 2, which does not collide with itself (the World's filter).
TEST(Distributed, GranularPileMatchesWorld) {
  scene::StressParams p;
  p.count = 600;
  scene::Scene s = scene::MakeStressScene(p);
  for (scene::BodyDesc& b : s.bodies) {
    b.restitution = 0;
    b.friction = Real(0.6);
  }
  std::vector<BodyDef> bodies = ToBodyDefs(s);
  for (size_t i = 0; i < bodies.size(); i += 3) {
    if (bodies[i].type != BodyType::kDynamic) continue;
    bodies[i].filter.categoryBits = 2;
    bodies[i].filter.maskBits = ~uint32_t(2);
  }
  WorldDef def = JacobiDef(s);
  def.gravity = {0, -10};
  def.effects.gravity = true;
  def.effects.friction = true;
  DistributedDef dist;
  dist.bounds = s.bounds;
  dist.tilesX = dist.tilesY = 4;
  const int64_t migrated = CompareWithWorld(def, dist, bodies, s.timeStep, 150, 25);
  if (Size() > 1) {
    EXPECT_GT(migrated, 0);
  }
}

// A pyramid's middle: the middle of its boxes' centres (the ground left out).
Vec2 PyramidMiddle(const std::vector<BodyDef>& bodies) {
  Real lo = 1e9, hi = -1e9, top = -1e9, bottom = 1e9;
  for (const BodyDef& b : bodies) {
    if (b.type != BodyType::kDynamic) continue;
    lo = std::min(lo, b.position.x), hi = std::max(hi, b.position.x);
    top = std::max(top, b.position.y), bottom = std::min(bottom, b.position.y);
  }
  return Vec2{(lo + hi) / 2, (bottom + top) / 2};
}

// 2 x 2 tiles of `half` metres whose common corner is `corner`.
DistributedDef FourTilesAround(Vec2 corner, Real half) {
  DistributedDef dist;
  dist.bounds = AABB{corner - Vec2{half, half}, corner + Vec2{half, half}};
  dist.tilesX = dist.tilesY = 2;
  return dist;
}

// A base-10 pyramid whose centre is the corner of four tiles: contacts across every boundary.
// Also measures what the Jacobi solve costs in stability: the apex's drift after 5 s against the
// pgs solver's in one process. Jacobi needs about four times pgs's iterations for the same hold
// (one process, base 10, 300 steps: apex drift 0.089 m at 8 iterations, 0.030 at 16, 0.013 at 32;
// pgs 0.013 m at 8), so this runs 32 iterations (34 neighbour rounds per step).
TEST(Distributed, PyramidAcrossTilesMatchesWorld) {
  const scene::Scene s = scene::MakePyramid(10);
  const std::vector<BodyDef> bodies = ToBodyDefs(s);
  const DistributedDef dist = FourTilesAround(PyramidMiddle(bodies), 20);
  const int steps = 300;
  WorldDef def = JacobiDef(s);
  def.velocityIterations = 32;
  SideBySide both(def, dist, bodies);
  int kept = 0;  // steps that kept last step's local arrays on this rank (DistributedStats::layoutKept)
  for (int step = 1; step <= steps; ++step) {
    both.Step(s.timeStep);
    kept += both.dw.GetStats().layoutKept;
    if (step % 100 == 0) {
      const uint64_t expected = both.WorldHash();
      ASSERT_EQ(both.dw.StateHash(), expected) << "step " << step;  // the same on every rank: all return
    }
  }
  // The apex is the last body (MakePyramid). Distributed (Jacobi) against one process with pgs.
  const BodyState apex = both.dw.GatherStates().back();
  const Vec2 start = bodies.back().position;
  const double jacobiDrift = std::hypot(double(apex.position.x - start.x), double(apex.position.y - start.y));
  if (Rank() == 0) {
    WorldDef pgs = JacobiDef(s);
    pgs.solver = SolverType::kPgs;
    pgs.velocityIterations = s.velocityIterations;
    pgs.positionIterations = s.positionIterations;
    World reference(pgs);
    BodyId last;
    for (const BodyDef& b : bodies) last = reference.CreateBody(b);
    for (int step = 0; step < steps; ++step) reference.Step(s.timeStep);
    const Vec2 p = reference.GetPosition(last);
    const double pgsDrift = std::hypot(double(p.x - start.x), double(p.y - start.y));
    std::printf("[ info ] pyramid base 10, %d steps: apex drift jacobi %.4f m (32 iterations, %d ranks), pgs %.4f m "
                "(8 iterations, 1 process)\n", steps, jacobiDrift, Size(), pgsDrift);
  }
  EXPECT_LT(jacobiDrift, 0.02);  // the bound for a pyramid across a boundary
  // A resting pile: no body changes owner and the shadows stay the same, so nearly every step keeps
  // its local arrays and only refreshes the shadows' rows (the hashes above hold through it); the
  // first step builds them. The fewest over the ranks, so every rank checks the same value.
  int fewest = 0;
  MPI_Allreduce(&kept, &fewest, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  if (Rank() == 0) std::printf("[ info ] pyramid base 10: local arrays kept in %d of %d steps (fewest over %d ranks)\n", fewest, steps, Size());
  if (Size() == 1) {
    EXPECT_EQ(fewest, steps - 1);
  } else {
    EXPECT_GT(fewest, steps / 2);
  }
}

// WorldDef's soft step inside each rank (kSoftStep), with the defaults a World steps with.
WorldDef SoftStepDef(const scene::Scene& s, int threads = 1) {
  WorldDef def;
  def.gravity = s.gravity;
  def.restitutionThreshold = s.restitutionThreshold;
  def.effects = s.effects;
  def.effects.sleep = false;
  def.threadCount = threads;
  return def;
}

// The dense case for the per-rank solver: the hard cases' base-20 pyramid (210 boxes)
// with its middle on the corner of four tiles, at soft_step's default budget (4 sub-steps), 60 s:
// its apex stays within 0.02 m of where it stood after the first second (sampled every 0.5 s, as
// the hard cases do). Measured 0.0014 / 0.0012 / 0.0019 / 0.0024 m at 1 / 2 / 3 / 4 ranks; without
// the exchange after the warm start 0.14-0.56 m across ranks, and 0.013 m on one rank without the
// manifolds' recycling (as the World's without it).
TEST(DistributedSoftStep, PyramidAcrossFourTilesStandsAtTheDefaultBudget) {
  const scene::Scene s = scene::MakePyramid(20);
  const std::vector<BodyDef> bodies = ToBodyDefs(s);
  const DistributedDef dist = FourTilesAround(PyramidMiddle(bodies), 25);
  DistributedWorld dw(SoftStepDef(s), dist, MPI_COMM_WORLD);
  dw.Load(bodies);
  const int settle = 60, steps = 3600;
  for (int step = 0; step < settle; ++step) dw.Step(s.timeStep);
  const Vec2 from = dw.GatherStates().back().position;  // the apex is the last body (MakePyramid)
  double drift = 0;
  int shadows = 0;
  for (int step = settle + 1; step <= steps; ++step) {
    dw.Step(s.timeStep);
    shadows += dw.GetStats().shadowBodies;
    if (step % 30 == 0) drift = std::max(drift, double(Length(dw.GatherStates().back().position - from)));
  }
  if (Rank() == 0) std::printf("[ info ] soft_step pyramid base 20 on 2 x 2 tiles, %d ranks: apex drift %.5f m\n", Size(), drift);
  EXPECT_LT(drift, 0.02);
  int total = 0;
  MPI_Allreduce(&shadows, &total, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  if (Size() > 1) {
    EXPECT_GT(total, 0);  // the boundaries carry contacts
  }
}

// The per-rank solver's determinism: on a given rank count, the same bits on 1 and 2 threads per
// rank and on a second run; bodies migrate (circle stress on 4 x 4 tiles) and none is lost.
TEST(DistributedSoftStep, SameBitsOnAnyThreadCountAndEveryRun) {
  scene::StressParams p;
  p.count = 1000;
  const scene::Scene s = scene::MakeStressScene(p);
  const std::vector<BodyDef> bodies = ToBodyDefs(s);
  DistributedDef dist;
  dist.bounds = s.bounds;
  dist.tilesX = dist.tilesY = 4;
  uint64_t hashes[3] = {};
  int64_t migrated = 0;
  for (int run = 0; run < 3; ++run) {
    DistributedWorld dw(SoftStepDef(s, run == 1 ? 2 : 1), dist, MPI_COMM_WORLD);
    dw.Load(bodies);
    for (int step = 0; step < 200; ++step) {
      dw.Step(s.timeStep);
      migrated += dw.GetStats().migratedIn;
    }
    hashes[run] = dw.StateHash();
    const std::vector<BodyState> states = dw.GatherStates();
    ASSERT_EQ(states.size(), bodies.size());
    for (size_t i = 0; i < states.size(); ++i) ASSERT_EQ(states[i].id, uint32_t(i));
  }
  EXPECT_EQ(hashes[1], hashes[0]) << "2 threads per rank";
  EXPECT_EQ(hashes[2], hashes[0]) << "second run";
  int64_t total = 0;
  MPI_Allreduce(&migrated, &total, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
  if (Size() > 1) {
    EXPECT_GT(total, 0);
  }
}

// Between the soft step's passes only a boundary body's velocity travels, unless a pass moved
// bodies through their rows (the Box2D-style bounces): a shadow integrates its motion (dp, dq)
// from the velocities its owner sent, which must give the owner's bits. With
// QUADRANT_CHECK_SHADOW_MOTION every round sends the whole state and the ranks count the shadows
// whose motion differs (the step throws on every rank if one does): elastic circles with both
// restitution models, 4 x 4 tiles, and the base-10 pyramid across four tiles.
TEST(DistributedSoftStep, ShadowsIntegrateTheirOwnersMotion) {
  setenv("QUADRANT_CHECK_SHADOW_MOTION", "1", 1);
  struct Unset {
    ~Unset() { unsetenv("QUADRANT_CHECK_SHADOW_MOTION"); }
  } unset;
  scene::StressParams p;
  p.count = 1000;
  const scene::Scene stress = scene::MakeStressScene(p);
  for (const RestitutionPolicy policy : {RestitutionPolicy::kCollisions, RestitutionPolicy::kBox2d}) {
    WorldDef def = SoftStepDef(stress);
    def.restitution = policy;
    DistributedDef dist;
    dist.bounds = stress.bounds;
    dist.tilesX = dist.tilesY = 4;
    DistributedWorld dw(def, dist, MPI_COMM_WORLD);
    dw.Load(ToBodyDefs(stress));
    int shadows = 0;
    for (int step = 0; step < 150; ++step) {
      ASSERT_NO_THROW(dw.Step(stress.timeStep)) << "restitution policy " << int(policy) << ", step " << step;
      shadows += dw.GetStats().shadowBodies;
    }
    if (Size() > 1) {
      EXPECT_GT(shadows, 0);
    }
  }
  const scene::Scene pyramid = scene::MakePyramid(10);
  const std::vector<BodyDef> bodies = ToBodyDefs(pyramid);
  DistributedWorld dw(SoftStepDef(pyramid), FourTilesAround(PyramidMiddle(bodies), 15), MPI_COMM_WORLD);
  dw.Load(bodies);
  for (int step = 0; step < 120; ++step) ASSERT_NO_THROW(dw.Step(pyramid.timeStep)) << "pyramid, step " << step;
}

// Where the rows lie changes no bit (OrderRows puts them back in id order between steps: over a
// long run the patches scatter them). With QUADRANT_ORDER_ROWS every step ends with the rows
// reordered, alternately into id order and into its reverse, against never within these steps:
// circle stress on 4 x 4 tiles (bodies cross every step) with both solvers, and the base-10
// pyramid across four tiles (resting boxes: the soft step recycles last step's manifolds, which
// name their bodies by row).
TEST(Distributed, RowsReorderedBetweenStepsChangeNoBit) {
  scene::StressParams p;
  p.count = 1000;
  const scene::Scene stress = scene::MakeStressScene(p);
  const scene::Scene pyramid = scene::MakePyramid(10);
  DistributedDef stressTiles;
  stressTiles.bounds = stress.bounds;
  stressTiles.tilesX = stressTiles.tilesY = 4;
  const std::vector<BodyDef> pyramidBodies = ToBodyDefs(pyramid);
  struct Case {
    const char* name;
    const scene::Scene& scene;
    WorldDef def;
    DistributedDef dist;
    int steps;
  };
  const Case cases[] = {{"soft_step circle stress", stress, SoftStepDef(stress), stressTiles, 200},
                        {"jacobi circle stress", stress, JacobiDef(stress), stressTiles, 200},
                        {"soft_step pyramid", pyramid, SoftStepDef(pyramid), FourTilesAround(PyramidMiddle(pyramidBodies), 15), 240}};
  for (const Case& c : cases) {
    uint64_t hashes[2] = {};
    for (int run = 0; run < 2; ++run) {
      if (run == 1) setenv("QUADRANT_ORDER_ROWS", "1", 1);
      DistributedWorld dw(c.def, c.dist, MPI_COMM_WORLD);
      unsetenv("QUADRANT_ORDER_ROWS");
      dw.Load(ToBodyDefs(c.scene));
      for (int step = 0; step < c.steps; ++step) dw.Step(c.scene.timeStep);
      hashes[run] = dw.StateHash();
    }
    EXPECT_EQ(hashes[1], hashes[0]) << c.name << " at " << Size() << " ranks";
  }
}

// On one rank the per-rank solver is the World's soft step on the same bodies: the same bits
// (the rows are in id order there, the contacts in the World's order, and the manifolds are
// recycled as the World recycles them).
TEST(DistributedSoftStep, OneRankIsTheWorld) {
  if (Size() != 1) GTEST_SKIP() << "one rank only";
  const scene::Scene s = scene::MakePyramid(10);
  const std::vector<BodyDef> bodies = ToBodyDefs(s);
  DistributedDef dist;
  dist.bounds = AABB{{-40, -10}, {40, 70}};
  const WorldDef def = SoftStepDef(s);
  World world(def);
  for (const BodyDef& b : bodies) world.CreateBody(b);
  DistributedWorld dw(def, dist, MPI_COMM_WORLD);
  dw.Load(bodies);
  for (int step = 1; step <= 120; ++step) {
    world.Step(s.timeStep);
    dw.Step(s.timeStep);
    if (step % 30 == 0) {
      ASSERT_EQ(dw.StateHash(), world.StateHash()) << "step " << step;
    }
  }
}

// 2000 steps of circle stress on 8 x 8 tiles: bodies change owner thousands of times; Step checks
// the global count and id checksum every step (it throws on a difference) and the gathered state
// holds every id once.
TEST(Distributed, HeavyMigrationKeepsEveryBody) {
  scene::StressParams p;
  p.count = 500;
  const scene::Scene s = scene::MakeStressScene(p);
  DistributedDef dist;
  dist.bounds = s.bounds;
  dist.tilesX = dist.tilesY = 8;
  // Two velocity iterations (4 neighbour rounds a step instead of 10): this test is about the
  // bookkeeping, and rounds are what an oversubscribed, busy machine makes slow.
  WorldDef def = JacobiDef(s);
  def.velocityIterations = 2;
  DistributedWorld dw(def, dist, MPI_COMM_WORLD);
  const std::vector<BodyDef> bodies = ToBodyDefs(s);
  dw.Load(bodies);
  int64_t migrated = 0;
  for (int step = 0; step < 2000; ++step) {
    dw.Step(s.timeStep);
    migrated += dw.GetStats().migratedIn;
  }
  const std::vector<BodyState> all = dw.GatherStates();
  ASSERT_EQ(all.size(), bodies.size());
  for (size_t i = 0; i < all.size(); ++i) EXPECT_EQ(all[i].id, uint32_t(i));
  int64_t total = 0;
  MPI_Allreduce(&migrated, &total, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
  if (Size() > 1) {
    // Heavy: owner changes of the order of the body count (measured for 500 bodies: 517 at 2
    // ranks, 1392 at 3, 1035 at 4; the gas diffuses, mean free path about a metre, so a body
    // crosses a boundary far less often than its path length allows). Bound: half the bodies.
    EXPECT_GT(total, int64_t(bodies.size()) / 2);
  }
  if (Rank() == 0) std::printf("[ info ] circle stress 500, 2000 steps, %d ranks: %lld migrations\n", Size(), (long long)total);
}

// The clumped stress scene (every body in the lower-left quarter of the box): with the tiles
// dealt equally, one rank would hold nearly all the work; Load deals them by the bodies in each.
// Rebalancing every 10 steps re-deals the tiles by the work measured (bodies and contacts) while
// the clump spreads; the imbalance stays low and the hashes stay the World's.
TEST(Distributed, RebalanceClumpedSceneKeepsHashes) {
  scene::StressParams p;
  p.count = 800;
  p.clumped = true;
  const scene::Scene s = scene::MakeStressScene(p);
  const WorldDef def = JacobiDef(s);
  const std::vector<BodyDef> bodies = ToBodyDefs(s);
  DistributedDef dist;
  dist.bounds = s.bounds;
  dist.tilesX = dist.tilesY = 8;
  dist.rebalanceInterval = 10;
  dist.rebalanceThreshold = Real(1.01);  // Load dealt the tiles by their bodies: what is left triggers it
  SideBySide both(def, dist, bodies);
  double first = 0, last = 0;
  int rebalances = 0;
  for (int step = 1; step <= 60; ++step) {
    both.Step(s.timeStep);
    if (step == 1) first = both.dw.GetStats().imbalance;
    last = both.dw.GetStats().imbalance;
    rebalances += both.dw.GetStats().rebalances;
  }
  const uint64_t expected = both.WorldHash();
  EXPECT_EQ(both.dw.StateHash(), expected);
  if (Size() > 1) {
    EXPECT_LT(first, 1.3);  // Load shares the clump out (dealt by tiles alone, 1.8 and more: it sat in rank 0's)
    EXPECT_LT(last, 1.3);
    EXPECT_GE(rebalances, 1);
  }
  if (Rank() == 0) {
    std::printf("[ info ] clumped 800, %d ranks: imbalance %.3f at step 1, %.3f at step 60, %d rebalances\n", Size(), first,
                last, rebalances);
  }
}

// The tiles are dealt in bisection order: on a 6 x 6 grid (not a power of two, where Morton
// order's runs are an L and a corner) 2 ranks get the lower and upper halves and 4 the quadrants;
// on 4 x 4 it is Morton order (4 ranks: 2 x 2 quadrants). On any rank count the counts differ by
// at most one (a run may be two pieces, as a run of Morton order may: 6 x 6 tiles at 3 ranks).
TEST(Distributed, TilesDealtInBisectionOrder) {
  WorldDef def;
  for (const int side : {6, 4, 7}) {
    DistributedDef dist;
    dist.tilesX = dist.tilesY = side;
    const DistributedWorld dw(def, dist, MPI_COMM_WORLD);
    const std::vector<int> owner = dw.TileOwners();
    ASSERT_EQ(owner.size(), size_t(side * side));
    const int half = side / 2;
    for (int ty = 0; ty < side; ++ty) {
      for (int tx = 0; tx < side; ++tx) {
        const int o = owner[size_t(tx + ty * side)];
        if (side % 2 == 0 && Size() == 2) {
          EXPECT_EQ(o, ty < half ? 0 : 1) << side << " tiles, tile " << tx << "," << ty;
        }
        if (side % 2 == 0 && Size() == 4) {
          EXPECT_EQ(o, (ty < half ? 0 : 2) + (tx < half ? 0 : 1)) << side << " tiles, tile " << tx << "," << ty;
        }
      }
    }
    std::vector<int> count(size_t(Size()), 0);
    for (int o : owner) ++count[size_t(o)];
    EXPECT_LE(*std::max_element(count.begin(), count.end()) - *std::min_element(count.begin(), count.end()), 1);
  }
}

// Zero gravity, restitution 1, no walls: a cloud of circles colliding in open space. Linear
// momentum is exact in every contact (equal and opposite impulses); only rounding moves it.
TEST(Distributed, MomentumConservedWithoutGravity) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> jitter(-0.2f, 0.2f), speed(-4.0f, 4.0f);
  std::vector<BodyDef> bodies;
  for (int y = 0; y < 20; ++y) {
    for (int x = 0; x < 20; ++x) {
      BodyDef b;
      b.type = BodyType::kDynamic;
      b.position = {Real(x) * 1.5f + jitter(rng) - 15, Real(y) * 1.5f + jitter(rng) - 15};
      b.linearVelocity = {speed(rng), speed(rng)};
      b.shape = ShapeDef::MakeCircle(0.5f);
      b.shape.restitution = 1;
      b.shape.friction = 0;
      bodies.push_back(b);
    }
  }
  WorldDef def;
  def.solver = SolverType::kJacobi;
  def.effects.gravity = false;
  DistributedDef dist;
  dist.bounds = AABB{{-20, -20}, {20, 20}};
  dist.tilesX = dist.tilesY = 4;
  DistributedWorld dw(def, dist, MPI_COMM_WORLD);
  dw.Load(bodies);
  auto momentum = [&](double& scale) {
    double px = 0, py = 0;
    scale = 0;
    for (const BodyState& b : dw.GatherStates()) {
      px += double(b.mass) * b.linearVelocity.x;
      py += double(b.mass) * b.linearVelocity.y;
      scale += double(b.mass) * std::hypot(double(b.linearVelocity.x), double(b.linearVelocity.y));
    }
    return std::array<double, 2>{px, py};
  };
  double scale0 = 0, scale1 = 0;
  const auto p0 = momentum(scale0);
  int64_t contacts = 0;
  for (int step = 0; step < 200; ++step) {
    dw.Step(Real(1.0 / 60.0));
    contacts += dw.GetStats().contacts;
  }
  const auto p1 = momentum(scale1);
  // Relative to the sum of |m v| (the net momentum of random velocities is near zero).
  const double error = std::hypot(p1[0] - p0[0], p1[1] - p0[1]) / scale0;
  EXPECT_LT(error, 1e-5);
  int64_t total = 0;
  MPI_Allreduce(&contacts, &total, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_GT(total, 1000);  // the bodies did collide
  if (Rank() == 0) std::printf("[ info ] momentum: relative change %.3g over 200 steps (%lld contacts)\n", error, (long long)total);
}

// Every rank must have caught the same error: the count of ranks that did is reduced.
void ExpectErrorOnEveryRank(const std::function<void()>& fn, const std::string& expected) {
  int caught = 0;
  try {
    fn();
  } catch (const Error& e) {
    caught = std::string(e.what()).find(expected) != std::string::npos ? 1 : 0;
    if (!caught) ADD_FAILURE() << "unexpected message: " << e.what();
  }
  int total = 0;
  MPI_Allreduce(&caught, &total, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_EQ(total, Size()) << "expected '" << expected << "' on every rank";
}

std::vector<BodyDef> SmallScene(Real shift) {
  std::vector<BodyDef> bodies;
  for (int i = 0; i < 10; ++i) {
    BodyDef b;
    b.type = BodyType::kDynamic;
    b.position = {Real(i) * 2 - 9 + shift, 0};
    b.shape = ShapeDef::MakeCircle(0.5f);
    bodies.push_back(b);
  }
  return bodies;
}

// A file name unique to this job (rank 0's process id) in the temporary directory.
std::string CheckpointPath(const std::string& name) {
  int pid = Rank() == 0 ? static_cast<int>(getpid()) : 0;
  MPI_Bcast(&pid, 1, MPI_INT, 0, MPI_COMM_WORLD);
  return (std::filesystem::temp_directory_path() / ("quadrant_" + name + "_" + std::to_string(pid) + ".ckpt")).string();
}

TEST(DistributedBadInput, ScenesDifferBetweenRanks) {
  if (Size() < 2) GTEST_SKIP() << "needs two ranks";
  WorldDef def;
  def.solver = SolverType::kJacobi;
  DistributedDef dist;
  DistributedWorld dw(def, dist, MPI_COMM_WORLD);
  ExpectErrorOnEveryRank([&] { dw.Load(SmallScene(Rank() == 1 ? Real(0.25) : Real(0))); }, "differs between ranks");
  // Nothing was loaded: stepping is refused, on every rank alike.
  ExpectErrorOnEveryRank([&] { dw.Step(Real(1.0 / 60.0)); }, "Load a scene first");
}

TEST(DistributedBadInput, BodyLargerThanARegion) {
  WorldDef def;
  def.solver = SolverType::kJacobi;
  DistributedDef dist;
  dist.bounds = AABB{{-10, -10}, {10, 10}};
  dist.tilesX = dist.tilesY = 4;  // 5 m tiles: a body may reach 2.5 m from its centre
  std::vector<BodyDef> bodies = SmallScene(0);
  bodies[3].shape = ShapeDef::MakeCircle(3);
  DistributedWorld dw(def, dist, MPI_COMM_WORLD);
  dw.Load(bodies);
  ExpectErrorOnEveryRank([&] { dw.Step(Real(1.0 / 60.0)); }, "more than half a tile");
}

TEST(DistributedBadInput, GravityScaleAndBulletRefused) {
  WorldDef def;
  def.solver = SolverType::kJacobi;
  DistributedWorld dw(def, DistributedDef{}, MPI_COMM_WORLD);
  std::vector<BodyDef> bodies = SmallScene(0);
  bodies[3].gravityScale = 0;
  ExpectErrorOnEveryRank([&] { dw.Load(bodies); }, "body 3: gravityScale other than 1 and isBullet are not supported");
  bodies[3].gravityScale = 1;
  bodies[5].isBullet = true;
  ExpectErrorOnEveryRank([&] { dw.Load(bodies); }, "body 5: gravityScale other than 1 and isBullet are not supported");
  ExpectErrorOnEveryRank([&] { dw.Step(Real(1.0 / 60.0)); }, "Load a scene first");
}

TEST(DistributedBadInput, CapsuleSegmentAndCompoundShapesRefused) {
  // A rank's record carries a circle or a polygon.
  WorldDef def;
  def.solver = SolverType::kJacobi;
  DistributedWorld dw(def, DistributedDef{}, MPI_COMM_WORLD);
  std::vector<BodyDef> bodies = SmallScene(0);
  bodies[3].shape = ShapeDef::MakeCapsule({Real(-0.2), 0}, {Real(0.2), 0}, Real(0.1));
  ExpectErrorOnEveryRank([&] { dw.Load(bodies); }, "DistributedWorld::Load: capsule shapes are not supported (body 3)");
  bodies[3].type = BodyType::kStatic;
  bodies[3].shape = ShapeDef::MakeSegment({Real(-0.2), 0}, {Real(0.2), 0});
  ExpectErrorOnEveryRank([&] { dw.Load(bodies); }, "DistributedWorld::Load: segment shapes are not supported (body 3)");
  bodies[3] = SmallScene(0)[3];
  bodies[3].extraShapes.push_back(ShapeDef::MakeCircle(Real(0.1), {Real(0.3), 0}));
  ExpectErrorOnEveryRank([&] { dw.Load(bodies); },
                         "DistributedWorld::Load: compound bodies (BodyDef.extraShapes) are not supported (body 3)");
  ExpectErrorOnEveryRank([&] { dw.Step(Real(1.0 / 60.0)); }, "Load a scene first");
}

TEST(DistributedBadInput, MoreRanksThanTiles) {
  if (Size() < 2) GTEST_SKIP() << "needs two ranks";
  WorldDef def;
  def.solver = SolverType::kJacobi;
  DistributedDef dist;
  dist.tilesX = dist.tilesY = 1;
  ExpectErrorOnEveryRank([&] { DistributedWorld dw(def, dist, MPI_COMM_WORLD); }, "every rank needs at least one tile");
}

TEST(DistributedBadInput, PgsAndThesisSolversRefused) {
  for (SolverType solver : {SolverType::kPgs, SolverType::kThesis}) {
    WorldDef def;
    def.solver = solver;
    ExpectErrorOnEveryRank([&] { DistributedWorld dw(def, DistributedDef{}, MPI_COMM_WORLD); },
                           "must be kSoftStep (per rank) or kJacobi");
  }
}

// Checkpoint on about half the ranks, restart on all of them (1 -> 1, 1 -> 2, 2 -> 3, 2 -> 4):
// the restarted world continues with the hashes of the one that wrote the file.
TEST(DistributedCheckpoint, RestartOnAnotherRankCountKeepsHashes) {
  scene::StressParams p;
  p.count = 600;
  const scene::Scene s = scene::MakeStressScene(p);
  DistributedDef dist;
  dist.bounds = s.bounds;
  dist.tilesX = dist.tilesY = 4;
  const WorldDef def = JacobiDef(s);
  const std::string path = CheckpointPath("restart");
  const int writers = std::max(1, (Size() + 1) / 2);
  MPI_Comm half;
  MPI_Comm_split(MPI_COMM_WORLD, Rank() < writers ? 0 : MPI_UNDEFINED, Rank(), &half);
  uint64_t written[3] = {0, 0, 0};  // hashes 20, 40 and 60 steps after the checkpoint
  if (half != MPI_COMM_NULL) {
    DistributedWorld dw(def, dist, half);
    dw.Load(ToBodyDefs(s));
    for (int step = 0; step < 50; ++step) dw.Step(s.timeStep);
    dw.WriteCheckpoint(path);
    for (int k = 0; k < 3; ++k) {
      for (int step = 0; step < 20; ++step) dw.Step(s.timeStep);
      written[k] = dw.StateHash();
    }
    MPI_Comm_free(&half);
  }
  MPI_Bcast(written, 3, MPI_UINT64_T, 0, MPI_COMM_WORLD);
  DistributedWorld restarted(def, dist, MPI_COMM_WORLD);
  restarted.ReadCheckpoint(path);
  for (int k = 0; k < 3; ++k) {
    for (int step = 0; step < 20; ++step) restarted.Step(s.timeStep);
    EXPECT_EQ(restarted.StateHash(), written[k]) << "written on " << writers << " ranks, read on " << Size();
  }
  MPI_Barrier(MPI_COMM_WORLD);
  if (Rank() == 0) std::remove(path.c_str());
}

// A missing, truncated or corrupt checkpoint: the same error on every rank, the world unchanged.
TEST(DistributedCheckpoint, BadFilesRefusedOnEveryRank) {
  WorldDef def;
  def.solver = SolverType::kJacobi;
  DistributedWorld dw(def, DistributedDef{}, MPI_COMM_WORLD);
  dw.Load(SmallScene(0));
  const uint64_t before = dw.StateHash();
  const std::string good = CheckpointPath("good"), truncated = CheckpointPath("truncated"),
                    corrupt = CheckpointPath("corrupt");
  dw.WriteCheckpoint(good);
  if (Rank() == 0) {
    std::FILE* f = std::fopen(good.c_str(), "rb");
    std::vector<char> bytes(1 << 20);
    bytes.resize(std::fread(bytes.data(), 1, bytes.size(), f));
    std::fclose(f);
    f = std::fopen(truncated.c_str(), "wb");
    std::fwrite(bytes.data(), 1, bytes.size() - 100, f);
    std::fclose(f);
    bytes[bytes.size() / 2] ^= 0x20;
    f = std::fopen(corrupt.c_str(), "wb");
    std::fwrite(bytes.data(), 1, bytes.size(), f);
    std::fclose(f);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  ExpectErrorOnEveryRank([&] { dw.ReadCheckpoint(truncated); }, "is truncated");
  ExpectErrorOnEveryRank([&] { dw.ReadCheckpoint(corrupt); }, "is corrupt");
  ExpectErrorOnEveryRank([&] { dw.ReadCheckpoint(good + ".missing"); }, "cannot open");
  EXPECT_EQ(dw.StateHash(), before);
  MPI_Barrier(MPI_COMM_WORLD);
  if (Rank() == 0) {
    std::remove(good.c_str());
    std::remove(truncated.c_str());
    std::remove(corrupt.c_str());
  }
}

}  // namespace
}  // namespace quadrant

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  if (argc > 1 && std::strcmp(argv[1], "--bad-scene-exit") == 0) {
    // Uncaught by any test: the program's own error path, as a user's program would have it.
    int code = 0;
    try {
      quadrant::WorldDef def;
      def.solver = quadrant::SolverType::kJacobi;
      quadrant::DistributedWorld dw(def, quadrant::DistributedDef{}, MPI_COMM_WORLD);
      dw.Load(quadrant::SmallScene(quadrant::Rank() == 1 ? quadrant::Real(0.25) : quadrant::Real(0)));
    } catch (const quadrant::Error& e) {
      std::fprintf(stderr, "rank %d: error: %s\n", quadrant::Rank(), e.what());
      code = 1;
    }
    MPI_Finalize();
    return code;
  }
  ::testing::InitGoogleTest(&argc, argv);
  const int failed = RUN_ALL_TESTS();
  int any = 0;
  MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  MPI_Finalize();
  return any;
}
