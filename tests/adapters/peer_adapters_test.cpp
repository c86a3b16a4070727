// Tests of the adapters on hand-built scenes whose outcome is known from first principles (free
// fall, elastic collisions, rolling without slipping): the shared checks on all four engines,
// then what is particular to Box2D 2.4.1 and Chipmunk 7.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "adapter.h"
#include "adapter_factories.h"
#include "quadrant/error.h"
#include "quadrant/math.h"

namespace quadrant::scene {
namespace {

using Factory = std::function<std::unique_ptr<Adapter>()>;

constexpr Real kDt = Real(1.0 / 60.0);
constexpr Real kGroundTop = Real(0.5);

// A wide static slab whose top face is at y = kGroundTop.
BodyDesc Ground() { return MakeBoxBody({0, 0}, 50, kGroundTop, /*dynamic=*/false); }

Scene ZeroGravityScene() {
  Scene s;
  s.name = "test";
  s.effects.gravity = false;
  s.effects.friction = false;
  return s;
}

std::vector<BodyState> Read(const Adapter& a) {
  std::vector<BodyState> out;
  a.ReadBodies(out);
  return out;
}

void StepN(Adapter& a, int n) {
  for (int i = 0; i < n; ++i) a.Step();
}

// ---- Checks shared by every engine --------------------------------------------------------

void CheckBallFallsAndRestsOnGround(const Factory& make, int threads) {
  Scene s;
  s.bodies = {Ground(), MakeCircleBody({0, 3}, Real(0.5))};
  auto a = make();
  a->Load(s, threads);
  ASSERT_EQ(a->BodyCount(), 2);

  // Half a second of free fall: v = -g t exactly; y within one step's worth of -g t^2 / 2
  // (engines differ in whether position or velocity is integrated first).
  StepN(*a, 30);
  std::vector<BodyState> st = Read(*a);
  EXPECT_NEAR(st[1].velocity.y, -5.0, 1e-3);
  EXPECT_NEAR(st[1].position.y, 3.0 - 1.25, 0.05);
  EXPECT_EQ(a->ContactCount(), 0);

  StepN(*a, 150);
  st = Read(*a);
  EXPECT_NEAR(st[1].position.y, kGroundTop + 0.5, 0.02);
  EXPECT_NEAR(st[1].position.x, 0.0, 1e-4);
  EXPECT_LT(std::abs(st[1].velocity.y), 0.05);
  EXPECT_EQ(a->ContactCount(), 1);
  // The static ground never moves.
  EXPECT_EQ(st[0].position.x, 0);
  EXPECT_EQ(st[0].position.y, 0);
  EXPECT_EQ(st[0].velocity.y, 0);
}

// A capsule dropped at an angle lands on one end and comes to rest on its side: its centre a
// radius above the ground, its axis level. Engines differ in skin (Box2D's polygon radius adds
// 0.01 m to the box of its capsule), hence 0.03 m.
void CheckCapsuleComesToRestOnItsSide(const Factory& make) {
  Scene s;
  BodyDesc capsule = MakeCapsuleBody({0, 2}, Real(0.5), Real(0.25));
  capsule.angle = Real(0.7);
  s.bodies = {Ground(), capsule};
  auto a = make();
  a->Load(s, 1);
  StepN(*a, 300);
  const std::vector<BodyState> st = Read(*a);
  EXPECT_NEAR(st[1].position.y, kGroundTop + 0.25, 0.03);
  EXPECT_NEAR(std::sin(st[1].angle), 0.0, 0.03);
  EXPECT_LT(Length(st[1].velocity), 0.05);
}

// A circle and a box rest on a static segment, a box on a kinematic one. Bullet has no segment.
void CheckBodiesRestOnSegments(const Factory& make, bool supported) {
  Scene s;
  BodyDesc lift = MakeSegmentBody({0, 3}, {-2, 0}, {2, 0}, /*kinematic=*/true);
  s.bodies = {MakeSegmentBody({0, 0}, {-10, 0}, {10, 0}), lift, MakeCircleBody({-2, 1}, Real(0.25)),
              MakeBoxBody({2, 1}, Real(0.25), Real(0.25)), MakeBoxBody({0, Real(3.5)}, Real(0.25), Real(0.25))};
  auto a = make();
  if (!supported) {
    EXPECT_THROW(a->Load(s, 1), Unsupported);
    return;
  }
  a->Load(s, 1);
  StepN(*a, 120);
  const std::vector<BodyState> st = Read(*a);
  EXPECT_NEAR(st[2].position.y, 0.25, 0.02);
  EXPECT_NEAR(st[3].position.y, 0.25, 0.02);  // Box2D's polygon skin adds 0.01 m
  EXPECT_NEAR(st[4].position.y, 3.25, 0.02);
  EXPECT_LT(Length(st[3].velocity), 0.05);
}

// A frictionless box sliding at 5 m/s along a flat chain of 1 m segments crosses 20 joins
// without catching (its speed within 1 %) or jumping (upward speed below 0.05 m/s).
void CheckBoxSlidesAlongAChain(const Factory& make, bool supported) {
  Scene s;
  s.effects.friction = false;
  std::vector<Vec2> points;
  for (int x = 40; x >= -3; --x) points.push_back({Real(x), 0});  // right to left: the face is up
  s.bodies = MakeChainBodyDescs(points);
  BodyDesc box = MakeBoxBody({Real(0.3), Real(0.25)}, Real(0.25), Real(0.25));
  box.velocity = {5, 0};
  s.bodies.push_back(box);
  const size_t id = s.bodies.size() - 1;
  auto a = make();
  if (!supported) {
    EXPECT_THROW(a->Load(s, 1), Unsupported);
    return;
  }
  a->Load(s, 1);
  Real minSpeed = 10, maxSpeed = 0, maxUp = 0;
  for (int i = 0; i < 252; ++i) {
    a->Step();
    const BodyState b = Read(*a)[id];
    minSpeed = std::min(minSpeed, b.velocity.x);
    maxSpeed = std::max(maxSpeed, b.velocity.x);
    maxUp = std::max(maxUp, b.velocity.y);
  }
  EXPECT_GT(Read(*a)[id].position.x, 21);
  EXPECT_GT(minSpeed, 5 * 0.99);
  EXPECT_LT(maxSpeed, 5 * 1.01);
  EXPECT_LT(maxUp, 0.05);
}

void CheckHeadOnElasticCollision(const Factory& make) {
  // Masses 1 : 3, v = (2, 0): a perfectly elastic hit leaves (-1, 1).
  Scene s = ZeroGravityScene();
  BodyDesc light = MakeCircleBody({-2, 0}, Real(0.5));
  light.velocity = {2, 0};
  light.restitution = 1;
  BodyDesc heavy = MakeCircleBody({1, 0}, Real(0.5));
  heavy.density = 3;
  heavy.restitution = 1;
  s.bodies = {light, heavy};

  auto a = make();
  a->Load(s, 1);
  const std::vector<BodyState> before = Read(*a);
  const Vec2 p0 = LinearMomentum(s, before);
  const double e0 = KineticEnergy(s, before);
  StepN(*a, 120);
  const std::vector<BodyState> after = Read(*a);
  const Vec2 p1 = LinearMomentum(s, after);

  EXPECT_NEAR(p1.x, p0.x, 1e-3 * std::abs(p0.x));
  EXPECT_NEAR(p1.y, 0.0, 1e-4);
  EXPECT_NEAR(after[0].velocity.x, -1.0, 0.02);
  EXPECT_NEAR(after[1].velocity.x, 1.0, 0.02);
  EXPECT_NEAR(KineticEnergy(s, after), e0, 0.02 * e0);
  // Contact comes at x = 0 after 1 s; then 1 s back at 1 m/s.
  EXPECT_NEAR(after[0].position.x, -1.0, 0.1);
}

void CheckPolygonReadsBackAtOrigin(const Factory& make) {
  // A triangle whose centroid (2/3, 1/3) is far from its origin.
  Scene s = ZeroGravityScene();
  BodyDesc tri;
  tri.shape = ShapeKind::kPolygon;
  tri.vertices = {{0, 0}, {2, 0}, {0, 1}};
  tri.position = {3, 4};
  tri.angle = Real(0.7);
  BodyDesc wall = tri;
  wall.dynamic = false;
  wall.position = {-6, 5};
  wall.angle = Real(-0.4);
  s.bodies = {tri, wall};

  auto a = make();
  a->Load(s, 1);
  const std::vector<BodyState> st = Read(*a);
  ASSERT_EQ(st.size(), 2u);
  EXPECT_NEAR(st[0].position.x, 3.0, 1e-5);
  EXPECT_NEAR(st[0].position.y, 4.0, 1e-5);
  EXPECT_NEAR(st[0].angle, 0.7, 1e-6);
  EXPECT_NEAR(st[1].position.x, -6.0, 1e-5);
  EXPECT_NEAR(st[1].position.y, 5.0, 1e-5);
  EXPECT_NEAR(st[1].angle, -0.4, 1e-6);
}

void CheckSpinAboutCentroid(const Factory& make) {
  // A free body spins about its centre of mass: the centroid stays put, the origin circles it,
  // and the linear velocity read back (the centre's) stays zero.
  Scene s = ZeroGravityScene();
  BodyDesc tri;
  tri.shape = ShapeKind::kPolygon;
  tri.vertices = {{0, 0}, {2, 0}, {0, 1}};
  tri.position = {3, 4};
  tri.angle = Real(0.7);
  tri.angularVelocity = 2;
  s.bodies = {tri};
  const Vec2 centroid{Real(2.0 / 3.0), Real(1.0 / 3.0)};
  const Vec2 start = tri.position + Rotate(MakeRot(tri.angle), centroid);

  auto a = make();
  a->Load(s, 1);
  StepN(*a, 60);
  const BodyState st = Read(*a)[0];
  const Vec2 now = st.position + Rotate(MakeRot(st.angle), centroid);
  EXPECT_NEAR(now.x, start.x, 1e-3);
  EXPECT_NEAR(now.y, start.y, 1e-3);
  EXPECT_NEAR(st.angle, 0.7 + 2.0, 1e-3);
  EXPECT_NEAR(st.angularVelocity, 2.0, 1e-4);
  EXPECT_NEAR(st.velocity.x, 0.0, 1e-3);
  EXPECT_NEAR(st.velocity.y, 0.0, 1e-3);
  // The origin did move: it is off the centroid.
  EXPECT_GT(Distance(st.position, tri.position), 0.5);
}

void CheckSceneOrder(const Factory& make) {
  Scene s = ZeroGravityScene();
  for (int i = 0; i < 6; ++i) {
    const Vec2 p{Real(3 * i), Real(-2 * i)};
    s.bodies.push_back(i % 2 == 0 ? MakeCircleBody(p, Real(0.4), i % 3 != 0)
                                  : MakeBoxBody(p, Real(0.5), Real(0.3), i % 3 != 0));
  }
  auto a = make();
  a->Load(s, 1);
  ASSERT_EQ(a->BodyCount(), 6);
  const std::vector<BodyState> st = Read(*a);
  ASSERT_EQ(st.size(), 6u);
  for (int i = 0; i < 6; ++i) {
    EXPECT_NEAR(st[i].position.x, 3.0 * i, 1e-5) << "body " << i;
    EXPECT_NEAR(st[i].position.y, -2.0 * i, 1e-5) << "body " << i;
  }
}

Scene SlidingDiskScene(bool friction) {
  Scene s;
  s.effects.friction = friction;
  BodyDesc disk = MakeCircleBody({0, kGroundTop + Real(0.5)}, Real(0.5));
  disk.velocity = {2, 0};
  s.bodies = {Ground(), disk};
  return s;
}

void CheckFriction(const Factory& make) {
  // With friction a sliding disk (I = m r^2 / 2) ends up rolling at v0 / (1 + 1/2).
  auto a = make();
  a->Load(SlidingDiskScene(true), 1);
  StepN(*a, 60);
  BodyState st = Read(*a)[1];
  EXPECT_NEAR(st.velocity.x, 4.0 / 3.0, 0.03);
  EXPECT_NEAR(st.angularVelocity, -st.velocity.x / 0.5, 0.06);

  // Without friction it keeps sliding at v0 and never spins (within 0.2 %: Bullet loses 0.16 %
  // over these 60 steps, the others less than 0.05 %).
  a->Load(SlidingDiskScene(false), 1);
  StepN(*a, 60);
  st = Read(*a)[1];
  EXPECT_NEAR(st.velocity.x, 2.0, 4e-3);
  EXPECT_NEAR(st.angularVelocity, 0.0, 1e-4);
}

void CheckRestitutionEffect(const Factory& make) {
  auto maxUpwardSpeed = [&make](bool restitution) {
    Scene s;
    s.effects.restitution = restitution;
    BodyDesc ground = Ground();
    ground.restitution = 1;
    BodyDesc ball = MakeCircleBody({0, 3}, Real(0.5));
    ball.restitution = 1;
    s.bodies = {ground, ball};
    auto a = make();
    a->Load(s, 1);
    double best = -1e9;
    for (int i = 0; i < 60; ++i) {
      a->Step();
      best = std::max(best, double(Read(*a)[1].velocity.y));
    }
    return best;
  };
  EXPECT_GT(maxUpwardSpeed(true), 4.0);   // bounces back up at about its 5.5 m/s impact speed
  EXPECT_LT(maxUpwardSpeed(false), 0.5);  // stays on the ground
}

void CheckRotationOff(const Factory& make) {
  // A tilted box lands on a corner: it tips over with rotation, keeps its angle without.
  auto angleAfterLanding = [&make](bool rotation) {
    Scene s;
    s.effects.rotation = rotation;
    BodyDesc box = MakeBoxBody({0, 2}, Real(0.5), Real(0.5));
    box.angle = Real(0.3);
    box.angularVelocity = 1;  // ignored without rotation
    s.bodies = {Ground(), box};
    auto a = make();
    a->Load(s, 1);
    StepN(*a, 120);
    a->SetVelocity(1, {0, 0}, 5);  // also ignored without rotation
    a->Step();
    return Read(*a)[1];
  };
  const BodyState fixed = angleAfterLanding(false);
  EXPECT_NEAR(fixed.angle, 0.3, 1e-6);
  EXPECT_EQ(fixed.angularVelocity, 0);
  const BodyState free = angleAfterLanding(true);
  EXPECT_GT(std::abs(free.angle - Real(0.3)), 0.1);
}

void CheckGravityOff(const Factory& make) {
  Scene s;
  s.effects.gravity = false;
  s.gravity = {3, -20};
  s.bodies = {MakeCircleBody({1, 2}, Real(0.5))};
  auto a = make();
  a->Load(s, 1);
  StepN(*a, 60);
  const BodyState st = Read(*a)[0];
  EXPECT_EQ(st.velocity.x, 0);
  EXPECT_EQ(st.velocity.y, 0);
  EXPECT_NEAR(st.position.x, 1.0, 1e-6);
  EXPECT_NEAR(st.position.y, 2.0, 1e-6);
}

void CheckSleep(const Factory& make) {
  // A lone body creeping at 0.005 m/s (below every engine's idle speed) falls asleep and stops;
  // without sleep it creeps on for the whole 4 s. Box2D, Chipmunk and Quadrant wait 0.5 s before
  // sleeping, Bullet 2 s (its notes), so with sleep it covers at most 0.01 m of the 0.02 m.
  auto distance = [&make](bool sleep) {
    Scene s = ZeroGravityScene();
    s.effects.sleep = sleep;
    BodyDesc b = MakeCircleBody({0, 0}, Real(0.5));
    b.velocity = {Real(0.005), 0};
    s.bodies = {b};
    auto a = make();
    a->Load(s, 1);
    StepN(*a, 240);
    return double(Read(*a)[0].position.x);
  };
  EXPECT_NEAR(distance(false), 0.02, 2e-4);
  EXPECT_LT(distance(true), 0.6 * 0.02);
}

void CheckContactsSurviveSleep(const Factory& make) {
  // Sleeping bodies still touch: their contacts count.
  Scene s;
  s.effects.sleep = true;
  s.bodies = {Ground(), MakeCircleBody({0, kGroundTop + Real(0.5)}, Real(0.5)),
              MakeBoxBody({3, kGroundTop + Real(0.5)}, Real(0.5), Real(0.5)),
              MakeBoxBody({3, kGroundTop + Real(1.5)}, Real(0.5), Real(0.5))};
  auto a = make();
  a->Load(s, 1);
  StepN(*a, 300);
  const uint64_t asleep = a->StateHash();
  a->Step();
  EXPECT_EQ(a->StateHash(), asleep);  // nothing moves any more
  EXPECT_EQ(a->ContactCount(), 3);
}

void CheckStackContacts(const Factory& make) {
  // Two boxes stacked on the ground: two touching pairs, one of them dynamic-dynamic.
  Scene s;
  s.bodies = {Ground(), MakeBoxBody({0, 1}, Real(0.5), Real(0.5)),
              MakeBoxBody({0, 2}, Real(0.5), Real(0.5))};
  auto a = make();
  a->Load(s, 1);
  StepN(*a, 120);
  EXPECT_EQ(a->ContactCount(), 2);
  const std::vector<BodyState> st = Read(*a);
  EXPECT_NEAR(st[2].position.y, 2.0, 0.05);
}

void CheckDriver(const Factory& make) {
  Scene s = ZeroGravityScene();
  s.bodies = {MakeCircleBody({0, 0}, Real(0.5))};
  std::vector<int> seen;
  s.driver = [&seen](int step, Adapter& adapter) {
    seen.push_back(step);
    if (step == 0) adapter.SetVelocity(0, {1, 0}, 0);
  };
  auto a = make();
  a->Load(s, 1);
  StepN(*a, 3);
  EXPECT_EQ(seen, (std::vector<int>{0, 1, 2}));
  // The driver runs before the step: all three steps moved the body.
  EXPECT_NEAR(Read(*a)[0].position.x, 3 * kDt, 1e-5);
}

void CheckLoadTwice(const Factory& make) {
  Scene first;
  first.bodies = {Ground(), MakeCircleBody({0, 3}, Real(0.5)), MakeCircleBody({2, 3}, Real(0.5))};
  Scene second = ZeroGravityScene();
  second.bodies = {MakeCircleBody({7, 8}, Real(0.25))};
  auto a = make();
  a->Load(first, 1);
  StepN(*a, 10);
  a->Load(second, 1);
  ASSERT_EQ(a->BodyCount(), 1);
  a->Step();
  const std::vector<BodyState> st = Read(*a);
  ASSERT_EQ(st.size(), 1u);
  EXPECT_NEAR(st[0].position.x, 7.0, 1e-6);
  EXPECT_NEAR(st[0].position.y, 8.0, 1e-6);
  EXPECT_EQ(a->ContactCount(), 0);
}

void CheckSetVelocity(const Factory& make) {
  Scene s = ZeroGravityScene();
  s.bodies = {Ground(), MakeCircleBody({0, 5}, Real(0.5))};
  auto a = make();
  a->Load(s, 1);
  EXPECT_THROW(a->SetVelocity(-1, {1, 0}, 0), quadrant::Error);
  EXPECT_THROW(a->SetVelocity(2, {1, 0}, 0), quadrant::Error);
  a->SetVelocity(1, {Real(1.5), Real(-0.5)}, Real(0.25));
  const BodyState st = Read(*a)[1];
  EXPECT_NEAR(st.velocity.x, 1.5, 1e-6);
  EXPECT_NEAR(st.velocity.y, -0.5, 1e-6);
  EXPECT_NEAR(st.angularVelocity, 0.25, 1e-6);
}

void CheckRefusals(const Factory& make, int refusedThreads) {
  Scene ok;
  ok.bodies = {Ground(), MakeCircleBody({0, 3}, Real(0.5))};
  auto a = make();
  a->Load(ok, 1);
  EXPECT_THROW(a->Load(ok, refusedThreads), Unsupported);
  EXPECT_THROW(a->Load(ok, 0), quadrant::Error);  // fewer than one thread is bad input, not a limit
  // An invalid scene is an Error, checked before anything engine-specific (the thread count too).
  Scene bad = ok;
  bad.bodies[1].radius = -1;
  EXPECT_THROW(a->Load(bad, refusedThreads), quadrant::Error);
  // A refused Load leaves the loaded world usable.
  ASSERT_EQ(a->BodyCount(), 2);
  a->Step();
  EXPECT_NEAR(Read(*a)[1].velocity.y, -10 * kDt, 1e-5);
}

const Factory kBox2d = [] { return MakeBox2dAdapter(); };
const Factory kChipmunk = [] { return MakeChipmunkAdapter(); };

// ---- The shared checks, on every engine ---------------------------------------------------
// One parameterised suite over the four engines (they ran on Box2D and Chipmunk only; Quadrant
// and Bullet had their own variants or none).

class SharedAdapterChecks : public ::testing::TestWithParam<std::string> {
 protected:
  Factory Make() const {
    const std::string name = GetParam();
    return [name] { return MakeAdapter(name); };
  }
  Capabilities Caps() const { return MakeAdapter(GetParam())->Caps(); }
};
TEST_P(SharedAdapterChecks, BallFallsAndRestsOnGround) { CheckBallFallsAndRestsOnGround(Make(), 1); }
TEST_P(SharedAdapterChecks, CapsuleComesToRestOnItsSide) { CheckCapsuleComesToRestOnItsSide(Make()); }
TEST_P(SharedAdapterChecks, BodiesRestOnSegments) { CheckBodiesRestOnSegments(Make(), GetParam() != "bullet"); }
TEST_P(SharedAdapterChecks, BoxSlidesAlongAChain) { CheckBoxSlidesAlongAChain(Make(), GetParam() != "bullet"); }
TEST_P(SharedAdapterChecks, HeadOnElasticCollision) {
  if (GetParam() == "bullet") {
    // Measured: Bullet's split impulse adds energy to this unequal-mass elastic collision (kinetic
    // energy 2.09 J after, 1.57 J before; velocities -1.30 and 1.10 m/s for -1 and 1); docs/suite.md
    // documents the same gain on the stress scenes. Its equal-mass case is checked in
    // bullet_adapter_test.cpp (HeadOnElasticCirclesExchangeVelocities).
    GTEST_SKIP() << "bullet: elastic collisions gain energy (split impulse), measured +33 % here";
  }
  CheckHeadOnElasticCollision(Make());
}
TEST_P(SharedAdapterChecks, PolygonReadsBackAtOrigin) { CheckPolygonReadsBackAtOrigin(Make()); }
TEST_P(SharedAdapterChecks, SpinsAboutCentroid) { CheckSpinAboutCentroid(Make()); }
TEST_P(SharedAdapterChecks, ReadsBodiesInSceneOrder) { CheckSceneOrder(Make()); }
TEST_P(SharedAdapterChecks, FrictionEffect) { CheckFriction(Make()); }
TEST_P(SharedAdapterChecks, RestitutionEffect) { CheckRestitutionEffect(Make()); }
TEST_P(SharedAdapterChecks, RotationOff) { CheckRotationOff(Make()); }
TEST_P(SharedAdapterChecks, GravityOff) { CheckGravityOff(Make()); }
TEST_P(SharedAdapterChecks, Sleep) { CheckSleep(Make()); }
TEST_P(SharedAdapterChecks, StackContacts) { CheckStackContacts(Make()); }
TEST_P(SharedAdapterChecks, ContactsSurviveSleep) { CheckContactsSurviveSleep(Make()); }
TEST_P(SharedAdapterChecks, DriverRunsBeforeEachStep) { CheckDriver(Make()); }
TEST_P(SharedAdapterChecks, LoadTwiceReplacesWorld) { CheckLoadTwice(Make()); }
TEST_P(SharedAdapterChecks, SetVelocity) { CheckSetVelocity(Make()); }
TEST_P(SharedAdapterChecks, RefusesMoreThreadsThanItRunsAndInvalidScenes) {
  CheckRefusals(Make(), Caps().maxThreads + 1);
}

INSTANTIATE_TEST_SUITE_P(Engines, SharedAdapterChecks, ::testing::Values("quadrant", "box2d", "bullet", "chipmunk"),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });

// ---- Box2D ---------------------------------------------------------------------------------

TEST(Box2dAdapter, NameAndCapabilities) {
  auto a = MakeBox2dAdapter();
  EXPECT_EQ(a->Name(), "box2d");
  const Capabilities c = a->Caps();
  EXPECT_EQ(c.maxThreads, 1);
  EXPECT_TRUE(c.continuous);
  EXPECT_TRUE(c.sleep);
  EXPECT_TRUE(c.disableWarmStarting);
  EXPECT_TRUE(c.damping);
  EXPECT_NE(c.notes.find("sqrt"), std::string::npos);
  EXPECT_NE(c.notes.find("0.01 m"), std::string::npos);
}


TEST(Box2dAdapter, ContinuousFlagDecidesTunnelling) {
  // A 0.1 m ball at Box2D's speed cap (2 m per step) against a 0.1 m plank: the discrete
  // positions straddle the plank, so only continuous collision stops it.
  auto finalY = [](bool continuous) {
    Scene s = ZeroGravityScene();
    s.effects.continuous = continuous;
    BodyDesc ball = MakeCircleBody({0, 5}, Real(0.1));
    ball.velocity = {0, -120};
    s.bodies = {MakeBoxBody({0, 0}, 2, Real(0.05), false), ball};
    auto a = MakeBox2dAdapter();
    a->Load(s, 1);
    StepN(*a, 5);
    return double(Read(*a)[1].position.y);
  };
  EXPECT_GT(finalY(true), 0.0);
  EXPECT_LT(finalY(false), -1.0);
}

TEST(Box2dAdapter, RestitutionThresholdFromScene) {
  // An elastic ball meets the ground at 0.5 m/s: it bounces only if the threshold is lower.
  auto reboundSpeed = [](Real threshold) {
    Scene s = ZeroGravityScene();
    s.restitutionThreshold = threshold;
    BodyDesc ground = Ground();
    ground.restitution = 1;
    BodyDesc ball = MakeCircleBody({0, Real(1.2)}, Real(0.5));
    ball.restitution = 1;
    ball.velocity = {0, Real(-0.5)};
    s.bodies = {ground, ball};
    auto a = MakeBox2dAdapter();
    a->Load(s, 1);
    StepN(*a, 120);
    return double(Read(*a)[1].velocity.y);
  };
  EXPECT_NEAR(reboundSpeed(1), 0.0, 0.05);
  EXPECT_NEAR(reboundSpeed(Real(0.1)), 0.5, 0.05);
}

// ---- Chipmunk ------------------------------------------------------------------------------

TEST(ChipmunkAdapter, NameAndCapabilities) {
  auto a = MakeChipmunkAdapter();
  EXPECT_EQ(a->Name(), "chipmunk");
  const Capabilities c = a->Caps();
  EXPECT_EQ(c.maxThreads, 2);
  EXPECT_FALSE(c.continuous);
  EXPECT_FALSE(c.disableWarmStarting);
  EXPECT_TRUE(c.sleep);
  EXPECT_TRUE(c.disableRotation);
  EXPECT_NE(c.notes.find("multiplied"), std::string::npos);
  EXPECT_NE(c.notes.find("0.005"), std::string::npos);
}


TEST(ChipmunkAdapter, TwoThreadsRunAHastySpace) {
  CheckBallFallsAndRestsOnGround(kChipmunk, 2);
  // Loading a hasty space over a plain one and back frees each with its own function.
  Scene s;
  s.bodies = {Ground(), MakeCircleBody({0, 3}, Real(0.5))};
  auto a = MakeChipmunkAdapter();
  a->Load(s, 1);
  a->Load(s, 2);
  StepN(*a, 10);
  a->Load(s, 1);
  StepN(*a, 10);
  EXPECT_LT(Read(*a)[1].position.y, 3.0);
}

TEST(ChipmunkAdapter, RefusesContinuousAndWarmStartingOff) {
  Scene s;
  s.bodies = {MakeCircleBody({0, 3}, Real(0.5))};
  s.effects.continuous = true;
  auto a = MakeChipmunkAdapter();
  EXPECT_THROW(a->Load(s, 1), Unsupported);
  s.effects.continuous = false;
  s.effects.warmStarting = false;
  EXPECT_THROW(a->Load(s, 1), Unsupported);
  s.effects.warmStarting = true;
  EXPECT_NO_THROW(a->Load(s, 1));
  EXPECT_EQ(a->BodyCount(), 1);
}

}  // namespace
}  // namespace quadrant::scene
