// Box2D 3's spinner and rain scenes (benchmarks/scenes/box2d3.cpp) and the adapters' group API
// (Adapter::AddGroup, RemoveGroup) that rain spawns its ragdolls with: the builders keep their
// contracts, every engine runs them or says why not, Quadrant's state hash is the same at 1, 2
// and 4 threads, and bad group calls are refused in one line with the world unchanged.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "adapter.h"
#include "quadrant/error.h"
#include "scenes.h"

namespace quadrant::scene {
namespace {

// Box2D 3's spinner: 360 chain segments, the paddle, then the small bodies.
TEST(Box2d3Scenes, SpinnerLayout) {
  const Scene s = MakeScene("spinner", 6076);
  ASSERT_EQ(s.bodies.size(), 360u + 1u + 6076u);
  ASSERT_EQ(s.joints.size(), 1u);
  EXPECT_NO_THROW(ValidateScene(s));
  EXPECT_EQ(s.bodies[0].shape, ShapeKind::kChainSegment);
  EXPECT_TRUE(s.bodies[360].dynamic);
  EXPECT_EQ(s.joints[0].bodyB, 360);
  EXPECT_TRUE(s.joints[0].enableMotor);
  EXPECT_TRUE(IsDenseScene("spinner"));
  EXPECT_THROW(MakeSpinner(0), Error);
  EXPECT_THROW(MakeSpinner(10001), Error);
}

// The paddle turns at its motor's 5 rad/s about its pin, and most bodies stay in the loop (radius
// 40 m about (0, 32)). Not all: the paddle's ends reach 0.2 m past the loop's lowest point (Box2D
// 3's sizes) and move at 100 m/s, and bodies caught there are pushed through the chain; the test
// prints how many left.
void ExpectSpins(const std::string& engine) {
  SCOPED_TRACE(engine);
  const Scene s = MakeSpinner(300);
  ASSERT_TRUE(s.effects.continuous);
  auto adapter = MakeAdapter(engine);
  adapter->Load(s, 1);
  for (int i = 0; i < 40; ++i) adapter->Step();
  std::vector<BodyState> st;
  adapter->ReadBodies(st);
  ASSERT_EQ(st.size(), s.bodies.size());
  EXPECT_NEAR(double(st[360].angularVelocity), 5.0, 0.5);
  EXPECT_NEAR(std::remainder(double(st[360].angle) - 5.0 * 40 / 60, 2 * 3.14159265358979), 0.0, 0.1);
  // The pin gives a little where the paddle's ends scrape the loop (0.1 and 0.18 m at most here).
  EXPECT_NEAR(double(st[360].position.x), 0.0, 0.3);
  EXPECT_NEAR(double(st[360].position.y), 12.0, 0.3);
  int outside = 0;
  for (size_t i = 361; i < st.size(); ++i) {
    const double dx = st[i].position.x, dy = double(st[i].position.y) - 32.0;
    if (!(std::sqrt(dx * dx + dy * dy) < 40.0)) ++outside;
  }
  std::printf("spinner, %s: %d of 300 bodies outside the loop after 40 steps\n", engine.c_str(), outside);
  EXPECT_LE(outside, 30);
}

TEST(Box2d3Scenes, SpinnerTurnsInEveryEngineThatLoadsJointsAndChains) {
  ExpectSpins("quadrant");
  ExpectSpins("box2d");
  // The paddle's ends knock bodies through the loop without continuous collision, which the
  // scene therefore turns on, and Chipmunk has none.
  EXPECT_THROW(MakeAdapter("chipmunk")->Load(MakeSpinner(30), 1), Unsupported);
  auto bullet = MakeAdapter("bullet");
  try {
    bullet->Load(MakeSpinner(30), 1);
    ADD_FAILURE() << "bullet loaded the spinner";
  } catch (const Unsupported& e) {
    EXPECT_NE(std::string(e.what()).find("chain"), std::string::npos) << e.what();
  }
}

TEST(Box2d3Scenes, RainLayoutAndSpawning) {
  const Scene s = MakeScene("rain", 11000);  // Box2D 3's five storeys
  EXPECT_EQ(s.bodies.size(), 2505u);
  EXPECT_EQ(s.groupBodies, 11000);
  ASSERT_EQ(s.groupSamples.size(), 1u);
  EXPECT_EQ(s.groupSamples[0].bodies.size(), 55u);
  EXPECT_EQ(s.groupSamples[0].joints.size(), 50u);
  EXPECT_NO_THROW(ValidateScene(s));
  EXPECT_NO_THROW(ValidateGroup(s, s.groupSamples[0]));
  EXPECT_EQ(MakeRain(4399).bodies.size(), 501u);  // rounds down to whole storeys
  EXPECT_THROW(MakeRain(2199), Error);
  EXPECT_THROW(MakeRain(44001), Error);
  EXPECT_TRUE(IsDenseScene("rain"));

  // One storey: a group of five ragdolls every 8 steps from step 0, 40 at most, then the oldest
  // goes as a new one comes.
  const Scene one = MakeRain(2200);
  auto adapter = MakeAdapter("quadrant");
  adapter->Load(one, 1);
  adapter->Step();
  EXPECT_EQ(adapter->BodyCount(), 501 + 55);
  for (int i = 1; i < 9; ++i) adapter->Step();  // steps 1..8
  EXPECT_EQ(adapter->BodyCount(), 501 + 2 * 55);
  for (int i = 9; i < 40 * 8 + 1; ++i) adapter->Step();  // to step 320: the first replacement
  EXPECT_EQ(adapter->BodyCount(), 501 + 40 * 55);
  std::vector<BodyState> st;
  adapter->ReadBodies(st);
  ASSERT_EQ(st.size(), size_t(501 + 40 * 55));
  // The newest group is last: its hip just spawned, 40.95 m up; the oldest group's bodies (the
  // second group now first) have landed on the floor.
  EXPECT_NEAR(double(st.back().position.y), 40.975, 0.1);
  EXPECT_LT(st[501].position.y, Real(5));
  EXPECT_GT(st[501].position.y, Real(-0.5));
  // Loaded again, the driver starts again (its state is the Load's own copy).
  adapter->Load(one, 1);
  EXPECT_EQ(adapter->BodyCount(), 501);
  adapter->Step();
  EXPECT_EQ(adapter->BodyCount(), 501 + 55);
}

TEST(Box2d3Scenes, RainIsRefusedWithTheReasonByEnginesThatCannotRunItsRagdolls) {
  const Scene s = MakeRain(2200);
  auto reason = [&](const char* engine) {
    try {
      MakeAdapter(engine)->Load(s, 1);
    } catch (const Unsupported& e) {
      return std::string(e.what());
    }
    return std::string("loaded");
  };
  EXPECT_NE(reason("box2d").find("revolute joint has no spring"), std::string::npos) << reason("box2d");
  EXPECT_NE(reason("chipmunk").find("damping"), std::string::npos) << reason("chipmunk");
  // Bullet loads the ragdolls (capsules along y as compound children, revolute joints with limit,
  // motor and spring): see RainRunsOnBullet.
  EXPECT_EQ(reason("bullet"), "loaded");
}

// Bullet runs rain: groups of ragdolls come every 8 steps and fall; after 2 s the first group's
// bodies are still finite and above the floor, and the first group's ragdolls hold together
// (every bone within 1 m of its hip; a ragdoll is 1.6 m tall, its hip 0.95 m up).
TEST(Box2d3Scenes, RainRunsOnBullet) {
  const Scene one = MakeRain(2200);
  auto adapter = MakeAdapter("bullet");
  adapter->Load(one, 1);
  for (int i = 0; i < 120; ++i) adapter->Step();
  EXPECT_EQ(adapter->BodyCount(), 501 + 15 * 55);
  std::vector<BodyState> st;
  adapter->ReadBodies(st);
  for (size_t i = 501; i < st.size(); ++i) {
    ASSERT_TRUE(std::isfinite(double(st[i].position.y))) << i;
    EXPECT_GT(st[i].position.y, Real(-0.5)) << i;
  }
  for (size_t r = 0; r < 5; ++r) {  // the first group's five ragdolls of 11 bones
    const size_t hip = 501 + r * 11;
    for (size_t b = 1; b < 11; ++b) EXPECT_LT(Length(st[hip + b].position - st[hip].position), Real(1.0)) << r << " " << b;
  }
}

// Quadrant: the same state hash at 1, 2 and 4 threads (DeterministicScheme.SameHashForOneToFourThreads
// for the scenes that need a driver's groups or joints; through the adapter, whose world runs its
// sections in parallel above 2048 items: these scenes have more bodies than that).
uint64_t HashAfter(const Scene& s, int threads, int steps) {
  auto adapter = MakeAdapter("quadrant");
  adapter->Load(s, threads);
  for (int i = 0; i < steps; ++i) adapter->Step();
  return adapter->StateHash();
}

// Rain at 2 and 4 threads: the same hash over 330 steps, past the first removals (step 320).
TEST(Box2d3Scenes, RainSameHashForTwoAndFourThreads) {
  const Scene s = MakeRain(2200);
  EXPECT_EQ(HashAfter(s, 4, 330), HashAfter(s, 2, 330));
}

// At 1 thread the hash parted from the 2- and 4-thread one at step 224, the first step with more
// than 2048 bodies (the parallel grain): colour masks left set when bodies had been made since
// the last colouring (ConstraintGraph::ClearColors; docs/notes/rain_determinism.md).
TEST(Box2d3Scenes, RainSameHashForOneToFourThreads) {
  const Scene s = MakeRain(2200);
  const uint64_t one = HashAfter(s, 1, 330);
  EXPECT_EQ(HashAfter(s, 2, 330), one);
  EXPECT_EQ(HashAfter(s, 4, 330), one);
}

TEST(Box2d3Scenes, SpinnerSameHashForOneToFourThreads) {
  const Scene s = MakeSpinner(2400);
  const uint64_t one = HashAfter(s, 1, 90);
  EXPECT_EQ(HashAfter(s, 2, 90), one);
  EXPECT_EQ(HashAfter(s, 4, 90), one);
}

// ---- The group API -------------------------------------------------------------------------

Scene Floor() {
  Scene s;
  s.name = "floor";
  s.bodies.push_back(MakeBoxBody({0, -0.5}, 20, 0.5, /*dynamic=*/false));
  return s;
}

// A pendulum of two capsules on a revolute joint (or two boxes without one) at x.
BodyGroup Pair(Real x, bool joint) {
  BodyGroup g;
  g.bodies.push_back(joint ? MakeCapsuleBody({x, 2}, Real(0.3), Real(0.1)) : MakeBoxBody({x, 2}, Real(0.3), Real(0.1)));
  g.bodies.push_back(joint ? MakeCapsuleBody({x + 1, 2}, Real(0.3), Real(0.1)) : MakeBoxBody({x + 1, 2}, Real(0.3), Real(0.1)));
  if (joint) g.joints.push_back(JointDesc{0, 1, {x + Real(0.5), 2}});
  return g;
}

class GroupApi : public ::testing::TestWithParam<const char*> {};

// Body order: scene bodies, then live groups by ascending id; removing one moves the later
// groups' bodies down.
TEST_P(GroupApi, BodiesAreInSceneThenGroupOrder) {
  const std::string engine = GetParam();
  auto adapter = MakeAdapter(engine);
  adapter->Load(Floor(), 1);
  EXPECT_EQ(adapter->AddGroup(Pair(-5, true)), 0);
  EXPECT_EQ(adapter->AddGroup(Pair(5, true)), 1);
  EXPECT_EQ(adapter->AddGroup(Pair(10, true)), 2);
  ASSERT_EQ(adapter->BodyCount(), 7);
  std::vector<BodyState> st;
  adapter->ReadBodies(st);
  EXPECT_EQ(st[1].position.x, Real(-5));
  EXPECT_EQ(st[3].position.x, Real(5));
  EXPECT_EQ(st[5].position.x, Real(10));
  adapter->RemoveGroup(1);
  ASSERT_EQ(adapter->BodyCount(), 5);
  adapter->ReadBodies(st);
  ASSERT_EQ(st.size(), 5u);
  EXPECT_EQ(st[1].position.x, Real(-5));
  EXPECT_EQ(st[3].position.x, Real(10));
  EXPECT_EQ(adapter->AddGroup(Pair(0, true)), 3);  // ids are never reused
  adapter->SetVelocity(5, {1, 0}, 0);               // the new group's first body
  for (int i = 0; i < 30; ++i) adapter->Step();
  adapter->ReadBodies(st);
  ASSERT_EQ(st.size(), 7u);
  EXPECT_GT(st[5].position.x, Real(0.2));
  EXPECT_LT(st[1].position.y, Real(2));  // falling
  adapter->RemoveGroup(0);
  adapter->RemoveGroup(2);
  adapter->RemoveGroup(3);
  EXPECT_EQ(adapter->BodyCount(), 1);
  for (int i = 0; i < 5; ++i) adapter->Step();
}

// Bad calls: one line, the world unchanged.
TEST_P(GroupApi, RefusesBadCallsWithTheWorldUnchanged) {
  const std::string engine = GetParam();
  auto adapter = MakeAdapter(engine);
  EXPECT_THROW(adapter->AddGroup(Pair(0, true)), Error);  // before Load
  EXPECT_THROW(adapter->RemoveGroup(0), Error);
  adapter->Load(Floor(), 1);
  const int id = adapter->AddGroup(Pair(0, true));
  for (int i = 0; i < 3; ++i) adapter->Step();
  const uint64_t hash = adapter->StateHash();
  auto expectRefused = [&](auto call, const char* contains) {
    try {
      call();
      ADD_FAILURE() << "accepted: " << contains;
    } catch (const Unsupported& e) {
      ADD_FAILURE() << "Unsupported instead of Error: " << e.what();
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(contains), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
    EXPECT_EQ(adapter->BodyCount(), 3);
    EXPECT_EQ(adapter->StateHash(), hash);
  };
  expectRefused([&] { adapter->AddGroup(BodyGroup{}); }, "at least one body");
  BodyGroup badJoint = Pair(0, true);
  badJoint.joints = {JointDesc{0, 2, {0, 2}}};
  expectRefused([&] { adapter->AddGroup(badJoint); }, "group joint 0: body index out of range");
  BodyGroup badBody = Pair(0, true);
  badBody.bodies[1].position.x = std::nan("");
  expectRefused([&] { adapter->AddGroup(badBody); }, "group body 1");
  expectRefused([&] { adapter->RemoveGroup(id + 1); }, "never added");
  expectRefused([&] { adapter->RemoveGroup(-1); }, "never added");
  adapter->RemoveGroup(id);
  EXPECT_EQ(adapter->BodyCount(), 1);
  try {
    adapter->RemoveGroup(id);
    ADD_FAILURE() << "removed twice";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("removed already"), std::string::npos) << e.what();
  }
  EXPECT_EQ(adapter->BodyCount(), 1);
}

INSTANTIATE_TEST_SUITE_P(Engines, GroupApi, ::testing::Values("quadrant", "box2d", "chipmunk", "bullet"));

TEST(GroupApiTest, AnEngineRefusesAGroupItCannotRunAsUnsupported) {
  auto bullet = MakeAdapter("bullet");
  bullet->Load(Floor(), 1);
  BodyGroup rod = Pair(0, true);  // Bullet has no distance joint
  rod.joints[0].kind = JointKind::kDistance;
  rod.joints[0].anchorB = {1, 2};
  EXPECT_THROW(bullet->AddGroup(rod), Unsupported);
  EXPECT_EQ(bullet->BodyCount(), 1);
  auto box2d = MakeAdapter("box2d");
  box2d->Load(Floor(), 1);
  BodyGroup spring = Pair(0, true);
  spring.joints[0].enableSpring = true;
  spring.joints[0].hertz = 5;
  EXPECT_THROW(box2d->AddGroup(spring), Unsupported);
  EXPECT_EQ(box2d->BodyCount(), 1);
  // Load checks the scene's groupSamples, so such a scene is refused before it runs.
  Scene withSamples = Floor();
  withSamples.groupSamples = {spring};
  EXPECT_THROW(box2d->Load(withSamples, 1), Unsupported);
  EXPECT_NO_THROW(MakeAdapter("quadrant")->Load(withSamples, 1));
  withSamples.groupSamples[0].joints[0].bodyB = 7;
  EXPECT_THROW(MakeAdapter("quadrant")->Load(withSamples, 1), Error);
}

}  // namespace
}  // namespace quadrant::scene
