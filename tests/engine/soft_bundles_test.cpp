// soft_step's bundles of contact islands (soft_step_bundles.cpp): at 4 threads or more, on a
// sparse scene or on a pile of many small islands, the rows run bundle by bundle, each bundle
// through every sub-step on one thread. The state must be the one colour by colour gives, bit for
// bit, at every thread count; no bundle is formed where a row would need the whole world (a
// moving kinematic body in rows, joints), nor on a pile whose largest island exceeds a bundle.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "quadrant/joints.h"
#include "quadrant/world.h"

namespace quadrant {
namespace {

struct Outcome {
  uint64_t hash = 0;
  int bundledSteps = 0;  // steps whose Counters::rowBundles was above 0
};

enum class Extra { kNone, kKinematic, kJoint };

// A static ground slab 1 m thick, its top at y = 0.
void AddGround(World& world, Real halfWidth) {
  BodyDef ground;
  ground.position = {0, -0.5f};
  ground.shape = ShapeDef::Box(halfWidth, 0.5f);
  world.CreateBody(ground);
}

// Sixty stacks of three boxes on the ground (the islands), with 600 circles falling from above
// (free bodies, until they land); restitution on every fourth circle, so both the lean rows and
// the constraint list are taken; or the elastic gas of circle stress (restitution, no gravity).
Outcome Sparse(int threads, bool gas, Extra extra = Extra::kNone) {
  WorldDef def;
  def.threadCount = threads;
  def.minParallelItems = 8;  // parallel sections split even when small
  if (gas) {
    def.effects.gravity = false;
    def.effects.friction = false;
    def.restitutionThreshold = 0;
  }
  World world(def);
  AddGround(world, 200);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(-1, 1);
  if (gas) {
    for (int i = 0; i < 1500; ++i) {
      BodyDef b;
      b.type = BodyType::kDynamic;
      b.position = {Real(i % 50) * 1.1f - 27, 1 + Real(i / 50) * 1.1f};
      b.linearVelocity = {4 * unit(rng), 4 * unit(rng)};
      b.shape = ShapeDef::MakeCircle(0.5f);
      b.shape.restitution = 1;
      world.CreateBody(b);
    }
  } else {
    for (int s = 0; s < 60; ++s) {
      for (int k = 0; k < 3; ++k) {
        BodyDef b;
        b.type = BodyType::kDynamic;
        b.position = {Real(s) * 3 - 90, 0.5f + Real(k)};
        b.shape = ShapeDef::Box(0.5f, 0.5f);
        world.CreateBody(b);
      }
    }
    for (int i = 0; i < 600; ++i) {
      BodyDef b;
      b.type = BodyType::kDynamic;
      b.position = {Real(i % 60) * 3 - 89.5f + 0.3f * unit(rng), 12 + Real(i / 60) * 1.2f};
      b.shape = ShapeDef::MakeCircle(0.4f);
      b.shape.restitution = i % 4 == 0 ? 0.5f : 0.0f;
      world.CreateBody(b);
    }
  }
  if (extra == Extra::kKinematic) {  // a moving kinematic body the rows read
    BodyDef k;
    k.type = BodyType::kKinematic;
    k.position = {-85, 3.5f};
    k.linearVelocity = {0.5f, 0};
    k.shape = ShapeDef::Box(1, 0.25f);
    world.CreateBody(k);
  }
  if (extra == Extra::kJoint) {
    BodyDef a;
    a.type = BodyType::kDynamic;
    a.position = {100, 5};
    a.shape = ShapeDef::MakeCircle(0.3f);
    const BodyId first = world.CreateBody(a);
    a.position = {101, 5};
    const BodyId second = world.CreateBody(a);
    DistanceJointDef j;
    j.bodyA = first;
    j.bodyB = second;
    j.length = 1;
    world.CreateDistanceJoint(j);
  }
  Outcome run;
  for (int s = 0; s < 120; ++s) {
    world.Step(1.0f / 60);
    run.bundledSteps += world.GetCounters().rowBundles > 0 ? 1 : 0;
  }
  run.hash = world.StateHash();
  return run;
}

TEST(SoftBundlesTest, BundledRowsGiveTheColourByColourStateAtEveryThreadCount) {
  for (const bool gas : {false, true}) {
    const Outcome one = Sparse(1, gas);
    EXPECT_EQ(one.bundledSteps, 0);
    EXPECT_EQ(Sparse(2, gas).bundledSteps, 0) << "bundles start at 4 threads";
    for (const int threads : {4, 8}) {
      const Outcome many = Sparse(threads, gas);
      EXPECT_EQ(many.hash, one.hash) << (gas ? "gas" : "stacks") << " at " << threads << " threads";
      EXPECT_GT(many.bundledSteps, 60) << (gas ? "gas" : "stacks") << " at " << threads << " threads";
    }
  }
}

// Pyramids of `base` boxes a side, `count` of them side by side on the ground (each its own
// island), and with `big` one more of base 30 beside them; 240 steps, so the piles come to rest
// and the colouring (with the islands) is kept from step to step.
Outcome Pyramids(int threads, int count, int base, bool big, bool edits = false) {
  WorldDef def;
  def.threadCount = threads;
  def.minParallelItems = 8;
  World world(def);
  AddGround(world, 400);
  std::vector<BodyId> ids;
  auto pyramid = [&](float left, int n) {
    for (int row = 0; row < n; ++row) {
      for (int j = 0; j < n - row; ++j) {
        BodyDef b;
        b.type = BodyType::kDynamic;
        b.position = {left + 0.5f * Real(row) + Real(j) + 0.5f, 0.5f + Real(row)};
        b.shape = ShapeDef::Box(0.5f, 0.5f);
        ids.push_back(world.CreateBody(b));
      }
    }
  };
  for (int p = 0; p < count; ++p) pyramid(-300 + Real(p) * Real(base + 1), base);
  if (big) pyramid(200, 30);
  Outcome run;
  for (int s = 0; s < 240; ++s) {
    // Edits between steps of a pile at rest, whose islands are kept from step to step: a top box
    // lifted (its contacts go), a box added far away (a body in no row), one destroyed (the last
    // body moves into its place).
    if (edits && s == 100) world.SetTransform(ids[size_t(base * (base + 1) / 2 - 1)], {-300.5f, 20}, 0);
    if (edits && s == 140) {
      BodyDef b;
      b.type = BodyType::kDynamic;
      b.position = {300, 40};
      b.shape = ShapeDef::Box(0.5f, 0.5f);
      world.CreateBody(b);
    }
    if (edits && s == 180) world.DestroyBody(ids[1]);
    world.Step(1.0f / 60);
    run.bundledSteps += world.GetCounters().rowBundles > 0 ? 1 : 0;
  }
  run.hash = world.StateHash();
  return run;
}

TEST(SoftBundlesTest, APileOfSmallIslandsIsBundledWithTheSameBits) {
  const Outcome one = Pyramids(1, 40, 6, false);
  for (const int threads : {4, 8}) {
    const Outcome many = Pyramids(threads, 40, 6, false);
    EXPECT_EQ(many.hash, one.hash) << threads << " threads";
    EXPECT_GT(many.bundledSteps, 200) << threads << " threads";
  }
  // Edited between steps: the kept islands are found anew where the ends change.
  const Outcome editedOne = Pyramids(1, 40, 6, false, true);
  for (const int threads : {4, 8}) {
    const Outcome edited = Pyramids(threads, 40, 6, false, true);
    EXPECT_EQ(edited.hash, editedOne.hash) << "edited, " << threads << " threads";
    EXPECT_GT(edited.bundledSteps, 200) << "edited, " << threads << " threads";
  }
  // One island of 465 boxes beside 40 of 21: more rows than a bundle's share in one island.
  const Outcome unevenOne = Pyramids(1, 40, 6, true), uneven = Pyramids(8, 40, 6, true);
  EXPECT_EQ(uneven.hash, unevenOne.hash);
  EXPECT_EQ(uneven.bundledSteps, 0);
}

TEST(SoftBundlesTest, NoBundlesWhereARowNeedsTheWholeWorld) {
  for (const Extra extra : {Extra::kKinematic, Extra::kJoint}) {
    const Outcome one = Sparse(1, false, extra), four = Sparse(4, false, extra);
    EXPECT_EQ(four.bundledSteps, 0);
    EXPECT_EQ(four.hash, one.hash);
  }
}

}  // namespace
}  // namespace quadrant
