// The Bullet adapter: 2D-constrained Bullet must simulate the scene as the scene describes it
// (sizes, masses, body origins) and refuse what Debian's Bullet cannot do.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "adapter.h"
#include "adapter_factories.h"
#include "quadrant/error.h"
#include "scenes.h"

namespace quadrant::scene {

// Defined in bullet_adapter.cpp as a test hook.
double BulletOutOfPlane(const Adapter& adapter);
std::pair<double, double> BulletMassOf(const Adapter& adapter, int body);

namespace {

constexpr Real kDt = Real(1.0 / 60.0);

BodyDesc Circle(Vec2 position, Real radius = Real(0.5)) { return MakeCircleBody(position, radius); }
BodyDesc Box(Vec2 position, Real hx, Real hy, bool dynamic = true) { return MakeBoxBody(position, hx, hy, dynamic); }

// A static ground whose top face is at y = 0.5.
BodyDesc Ground() { return Box({0, 0}, 10, Real(0.5), /*dynamic=*/false); }

Scene BaseScene() {
  Scene s;
  s.name = "bullet-test";
  s.timeStep = kDt;
  s.bounds = {{-20, -20}, {20, 20}};
  return s;
}

BodyState StepAndRead(Adapter& adapter, int steps, int body) {
  for (int i = 0; i < steps; ++i) adapter.Step();
  std::vector<BodyState> states;
  adapter.ReadBodies(states);
  return states.at(body);
}

TEST(BulletAdapter, NameAndCapabilities) {
  auto adapter = MakeBulletAdapter();
  EXPECT_EQ(adapter->Name(), "bullet");
  Capabilities caps = adapter->Caps();
  EXPECT_EQ(caps.maxThreads, 1);
  EXPECT_NE(caps.notes.find("BT_THREADSAFE"), std::string::npos);
  EXPECT_NE(caps.notes.find("multiplied"), std::string::npos);
}

// Bullet's split impulse pushes resting contacts fully out (measured: the ball centre is at
// 1.00000 after 1 s) and a sphere's margin is its radius, so 5 mm is loose; a hull margin not
// compensated in the ground box would put the ball at 1.04.
TEST(BulletAdapter, BallComesToRestOnStaticBox) {
  Scene s = BaseScene();
  s.bodies = {Ground(), Circle({0, 3})};
  auto adapter = MakeBulletAdapter();
  adapter->Load(s, 1);
  BodyState ball = StepAndRead(*adapter, 180, 1);
  EXPECT_NEAR(ball.position.y, 1.0, 0.005);
  EXPECT_NEAR(ball.position.x, 0.0, 1e-4);
  EXPECT_NEAR(ball.velocity.y, 0.0, 0.05);
  EXPECT_EQ(adapter->ContactCount(), 1);
}

// The circles start 3 m apart closing at 4 m/s, so they touch exactly at a step boundary with
// no penetration: Bullet folds 0.2 * penetration / dt into the bounce for penetrations under
// 0.04 m (its split impulse handles only deeper ones), which would add up to 0.4 m/s here.
TEST(BulletAdapter, HeadOnElasticCirclesExchangeVelocities) {
  Scene s = BaseScene();
  s.effects.gravity = false;
  s.restitutionThreshold = 0;
  BodyDesc a = Circle({-2, 0});
  BodyDesc b = Circle({2, 0});
  a.velocity = {3, 0};
  b.velocity = {-1, 0};
  for (BodyDesc* d : {&a, &b}) {
    d->restitution = 1;
    d->friction = 0;
  }
  s.bodies = {a, b};
  auto adapter = MakeBulletAdapter();
  adapter->Load(s, 1);
  std::vector<BodyState> before;
  adapter->ReadBodies(before);
  const Vec2 p0 = LinearMomentum(s, before);
  for (int i = 0; i < 120; ++i) adapter->Step();
  std::vector<BodyState> after;
  adapter->ReadBodies(after);
  // Equal masses, e = 1: the velocities swap.
  EXPECT_NEAR(after[0].velocity.x, -1.0, 0.05);
  EXPECT_NEAR(after[1].velocity.x, 3.0, 0.05 * 3.0);
  EXPECT_NEAR(after[0].velocity.y, 0.0, 1e-4);
  const Vec2 p1 = LinearMomentum(s, after);
  EXPECT_NEAR(p1.x, p0.x, 1e-3 * std::abs(p0.x));
  EXPECT_NEAR(p1.y, p0.y, 1e-4);
  EXPECT_GT(after[1].position.x, after[0].position.x + 1.0);  // they separated
}

// Separating speed after two e = 1 circles met head-on, closing at 0.5 m/s.
double SeparatingSpeedAfterBounce(Real threshold, bool restitution) {
  Scene s = BaseScene();
  s.effects.gravity = false;
  s.effects.restitution = restitution;
  s.restitutionThreshold = threshold;
  BodyDesc a = Circle({-1, 0});
  BodyDesc b = Circle({1, 0});
  a.velocity = {Real(0.25), 0};
  b.velocity = {Real(-0.25), 0};
  for (BodyDesc* d : {&a, &b}) {
    d->restitution = 1;
    d->friction = 0;
  }
  s.bodies = {a, b};
  auto adapter = MakeBulletAdapter();
  adapter->Load(s, 1);
  for (int i = 0; i < 240; ++i) adapter->Step();
  std::vector<BodyState> st;
  adapter->ReadBodies(st);
  return st[1].velocity.x - st[0].velocity.x;
}

// Below a 1 m/s scene threshold they must not bounce; with 0.2 m/s (Bullet's default) they do;
// with the restitution effect off they never do. What separation remains without a bounce is
// Bullet's Baumgarte push-out (0.1 m/s measured).
TEST(BulletAdapter, RestitutionThresholdAndEffectComeFromTheScene) {
  EXPECT_LT(SeparatingSpeedAfterBounce(1, true), 0.25);
  EXPECT_NEAR(SeparatingSpeedAfterBounce(Real(0.2), true), 0.5, 0.15);
  EXPECT_LT(SeparatingSpeedAfterBounce(0, false), 0.25);
}

// A triangle whose centroid is not at its body origin: Bullet holds it at the centroid, the
// adapter must still report the origin.
BodyDesc OffsetTriangle(Vec2 position, Real angle) {
  BodyDesc b;
  b.shape = ShapeKind::kPolygon;
  b.vertices = {{0, 0}, {1, 0}, {0, 1}};  // centroid (1/3, 1/3)
  b.position = position;
  b.angle = angle;
  return b;
}

TEST(BulletAdapter, PolygonOriginReadBackAndStaysInPlane) {
  Scene s = BaseScene();
  BodyDesc tri = OffsetTriangle({Real(0.5), 3}, Real(0.3));
  tri.angularVelocity = 2;
  BodyDesc box = Box({Real(-0.4), Real(1.5)}, Real(0.4), Real(0.3));
  box.angle = Real(0.7);
  s.bodies = {Ground(), tri, box};
  auto adapter = MakeBulletAdapter();
  adapter->Load(s, 1);
  std::vector<BodyState> states;
  adapter->ReadBodies(states);
  ASSERT_EQ(states.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_NEAR(states[i].position.x, s.bodies[i].position.x, 1e-5) << i;
    EXPECT_NEAR(states[i].position.y, s.bodies[i].position.y, 1e-5) << i;
    EXPECT_NEAR(states[i].angle, s.bodies[i].angle, 1e-5) << i;
  }
  EXPECT_NEAR(states[1].angularVelocity, 2.0, 1e-6);
  // Tumble onto the ground and into each other: contacts with 3D normals must not lift them.
  int touching = 0;
  for (int i = 0; i < 180; ++i) {
    adapter->Step();
    touching = std::max(touching, adapter->ContactCount());
  }
  EXPECT_GE(touching, 1);
  EXPECT_LT(BulletOutOfPlane(*adapter), 1e-6);
}

// Free spin about the centroid: the origin circles the centroid, which stays put.
TEST(BulletAdapter, OffCentrePolygonSpinsAboutItsCentroid) {
  Scene s = BaseScene();
  s.effects.gravity = false;
  BodyDesc tri = OffsetTriangle({0, 0}, 0);
  tri.angularVelocity = 1;
  s.bodies = {tri};
  auto adapter = MakeBulletAdapter();
  adapter->Load(s, 1);
  BodyState st = StepAndRead(*adapter, 60, 0);
  const double a = st.angle;
  EXPECT_NEAR(a, 1.0, 1e-3);
  // origin = c - R(a) c with c = (1/3, 1/3).
  const double c = 1.0 / 3.0;
  EXPECT_NEAR(st.position.x, c - (std::cos(a) * c - std::sin(a) * c), 1e-4);
  EXPECT_NEAR(st.position.y, c - (std::sin(a) * c + std::cos(a) * c), 1e-4);
}

// The thin-shape pitfall: a box spawned 0.25 m into the ground (as deep as two bodies closing
// at 15 m/s get in one step) must be pushed out along y. With Planar2D's 0.04 m half-thickness
// the shallowest overlap is along z, which the linear factor cancels, and the box stays stuck.
// Then it must rest without sinking and slide freely when pushed.
TEST(BulletAdapter, BoxOnStaticBoxNeitherSinksNorSticks) {
  Scene s = BaseScene();
  BodyDesc box = Box({0, Real(0.75)}, Real(0.5), Real(0.5));
  box.friction = 0;
  s.bodies = {Ground(), box};
  auto adapter = MakeBulletAdapter();
  adapter->Load(s, 1);
  BodyState rest = StepAndRead(*adapter, 120, 1);
  // Bullet's split impulse removes the whole penetration within a few steps (measured: 1.00000
  // after 1 s); an uncompensated 0.04 m hull margin would leave the box at 1.08.
  EXPECT_NEAR(rest.position.y, 1.0, 0.005);
  EXPECT_NEAR(rest.angle, 0.0, 1e-3);
  EXPECT_NEAR(rest.velocity.y, 0.0, 0.01);
  EXPECT_EQ(adapter->ContactCount(), 1);

  adapter->SetVelocity(1, {2, 0}, 0);
  BodyState slid = StepAndRead(*adapter, 30, 1);
  EXPECT_NEAR(slid.position.x - rest.position.x, 1.0, 0.02);  // 2 m/s for 0.5 s, no friction
  // Sliding, the 2D algorithm's manifold keeps one fresh point per step (older ones slide out
  // of the breaking threshold), so the box rocks slightly and sits lower: 8 mm measured.
  EXPECT_NEAR(slid.position.y, 1.0, 0.02);
}

// Two boxes overlapping by half their width (far deeper than one step at stress-scene speeds,
// but what a spawn or a pile can produce) must separate; Bullet's Minkowski sampling solver
// finds no contact here and leaves them inside each other.
TEST(BulletAdapter, DeeplyOverlappingBoxesSeparate) {
  Scene s = BaseScene();
  s.effects.gravity = false;
  BodyDesc a = Box({0, 0}, Real(0.5), Real(0.5));
  BodyDesc b = Box({Real(0.5), 0}, Real(0.5), Real(0.5));
  b.angle = Real(0.3);
  s.bodies = {a, b};
  auto adapter = MakeBulletAdapter();
  adapter->Load(s, 1);
  for (int i = 0; i < 60; ++i) adapter->Step();
  std::vector<BodyState> st;
  adapter->ReadBodies(st);
  EXPECT_GT(st[1].position.x - st[0].position.x, 1.0);
  EXPECT_LT(BulletOutOfPlane(*adapter), 1e-6);
}

TEST(BulletAdapter, DroppedBoxDoesNotSink) {
  Scene s = BaseScene();
  s.bodies = {Ground(), Box({0, 4}, Real(0.5), Real(0.5))};
  auto adapter = MakeBulletAdapter();
  adapter->Load(s, 1);
  BodyState rest = StepAndRead(*adapter, 120, 1);
  EXPECT_NEAR(rest.position.y, 1.0, 0.005);  // margins compensated in both boxes
  EXPECT_NEAR(rest.angle, 0.0, 1e-3);
}

TEST(BulletAdapter, TwoThreadsAreUnsupported) {
  Scene s = BaseScene();
  s.bodies = {Circle({0, 0})};
  auto adapter = MakeBulletAdapter();
  EXPECT_THROW(adapter->Load(s, 2), Unsupported);
  adapter->Load(s, 1);
  EXPECT_EQ(adapter->BodyCount(), 1);
}

TEST(BulletAdapter, InvalidSceneThrowsError) {
  Scene s = BaseScene();
  BodyDesc bad = Circle({0, 0});
  bad.radius = -1;
  s.bodies = {bad};
  EXPECT_THROW(MakeBulletAdapter()->Load(s, 1), Error);
}

TEST(BulletAdapter, SetVelocityWithBadIndexThrows) {
  Scene s = BaseScene();
  s.effects.gravity = false;
  s.bodies = {Circle({0, 0})};
  auto adapter = MakeBulletAdapter();
  EXPECT_THROW(adapter->SetVelocity(0, {1, 0}, 0), Error);  // nothing loaded
  adapter->Load(s, 1);
  EXPECT_THROW(adapter->SetVelocity(1, {1, 0}, 0), Error);
  EXPECT_THROW(adapter->SetVelocity(-1, {1, 0}, 0), Error);
  adapter->SetVelocity(0, {1, 0}, 0);
  BodyState st = StepAndRead(*adapter, 60, 0);
  EXPECT_NEAR(st.position.x, 1.0, 1e-4);
}

TEST(BulletAdapter, SpinningCircleAngleReadBack) {
  Scene s = BaseScene();
  s.effects.gravity = false;
  BodyDesc ball = Circle({0, 0});
  ball.angularVelocity = 1;
  s.bodies = {ball};
  auto adapter = MakeBulletAdapter();
  adapter->Load(s, 1);
  BodyState st = StepAndRead(*adapter, 60, 0);
  EXPECT_NEAR(st.angle, 1.0, 1e-3);
  EXPECT_NEAR(st.angularVelocity, 1.0, 1e-6);
  // Past pi the read-back wraps to (-pi, pi].
  st = StepAndRead(*adapter, 180, 0);
  EXPECT_NEAR(st.angle, 4.0 - 2.0 * std::numbers::pi, 1e-3);
}

// The z inertia must be m r^2 / 2 (Bullet's own would be 2/5 m r^2): a ball sliding at v0 on
// a rough floor ends rolling at v0 / (1 + I/(m r^2)) = 2/3 v0, not 5/7 v0.
TEST(BulletAdapter, CircleInertiaIsThatOfADisc) {
  Scene s = BaseScene();
  BodyDesc ball = Circle({0, 1});
  ball.velocity = {3, 0};
  ball.friction = 1;
  BodyDesc ground = Ground();
  ground.friction = 1;
  s.bodies = {ground, ball};
  auto adapter = MakeBulletAdapter();
  adapter->Load(s, 1);
  BodyState st = StepAndRead(*adapter, 120, 1);
  EXPECT_NEAR(st.velocity.x, 2.0, 0.05);
  EXPECT_NEAR(st.angularVelocity, -st.velocity.x / 0.5, 0.1);  // rolling without slipping
}

TEST(BulletAdapter, FrictionEffectOffLetsBodiesSlide) {
  Scene s = BaseScene();
  s.effects.friction = false;
  BodyDesc box = Box({0, 1}, Real(0.5), Real(0.5));
  box.velocity = {2, 0};
  s.bodies = {Ground(), box};
  auto adapter = MakeBulletAdapter();
  adapter->Load(s, 1);
  BodyState st = StepAndRead(*adapter, 60, 1);
  EXPECT_NEAR(st.velocity.x, 2.0, 0.02);
}

TEST(BulletAdapter, RotationEffectOffKeepsAngle) {
  Scene s = BaseScene();
  s.effects.rotation = false;
  BodyDesc tri = OffsetTriangle({0, 3}, Real(0.2));
  tri.angularVelocity = 5;
  s.bodies = {Ground(), tri};
  auto adapter = MakeBulletAdapter();
  adapter->Load(s, 1);
  BodyState st = StepAndRead(*adapter, 120, 1);
  EXPECT_NEAR(st.angle, 0.2, 1e-5);
  EXPECT_EQ(st.angularVelocity, 0);
  EXPECT_LT(st.position.y, 1.0);  // it fell onto the ground
}

// Continuous collision: a 0.5 m box at 50 m/s (0.83 m per step) onto a 0.1 m plank.
TEST(BulletAdapter, ContinuousStopsFastBoxAtThinPlank) {
  Scene s = BaseScene();
  s.effects.continuous = true;
  s.effects.gravity = false;
  BodyDesc plank = Box({0, 0}, 5, Real(0.05), /*dynamic=*/false);
  BodyDesc box = Box({0, 5}, Real(0.25), Real(0.25));
  box.velocity = {0, -50};
  s.bodies = {plank, box};
  auto adapter = MakeBulletAdapter();
  adapter->Load(s, 1);
  BodyState st = StepAndRead(*adapter, 60, 1);
  EXPECT_GT(st.position.y, 0.0);

  // Without it the same box tunnels, so the test above means something.
  s.effects.continuous = false;
  adapter->Load(s, 1);
  st = StepAndRead(*adapter, 60, 1);
  EXPECT_LT(st.position.y, 0.0);
}

TEST(BulletAdapter, SecondLoadReplacesTheWorld) {
  Scene s = BaseScene();
  s.bodies = {Ground(), Circle({0, 3}), Circle({2, 3})};
  auto adapter = MakeBulletAdapter();
  adapter->Load(s, 1);
  StepAndRead(*adapter, 30, 1);
  s.bodies = {Circle({5, 5})};
  s.effects.gravity = false;
  adapter->Load(s, 1);
  EXPECT_EQ(adapter->BodyCount(), 1);
  BodyState st = StepAndRead(*adapter, 10, 0);
  EXPECT_EQ(st.position.x, 5);
  EXPECT_EQ(st.position.y, 5);
  EXPECT_EQ(adapter->ContactCount(), 0);
}

TEST(BulletAdapter, DriverRunsBeforeEachStep) {
  Scene s = BaseScene();
  s.effects.gravity = false;
  s.bodies = {Circle({0, 0})};
  std::vector<int> seen;
  s.driver = [&seen](int step, Adapter& a) {
    seen.push_back(step);
    a.SetVelocity(0, {Real(step + 1), 0}, 0);
  };
  auto adapter = MakeBulletAdapter();
  adapter->Load(s, 1);
  BodyState st = StepAndRead(*adapter, 3, 0);
  EXPECT_EQ(seen, (std::vector<int>{0, 1, 2}));
  EXPECT_NEAR(st.velocity.x, 3.0, 1e-6);
  EXPECT_NEAR(st.position.x, (1.0 + 2.0 + 3.0) * kDt, 1e-5);
}

// A capsule off the body's x axis is a one-child btCompoundShape turned onto its centres' line:
// dropped tilted, it falls onto the ground and comes to rest lying on it, both centres one
// radius above the ground's top (y = 0.5).
TEST(BulletAdapter, AnOffAxisCapsuleRestsLyingOnTheGround) {
  Scene s = BaseScene();
  BodyDesc capsule = MakeCapsuleBody({0, 2}, Real(0.5), Real(0.25));
  capsule.vertices = {{0, 0}, {1, Real(0.5)}};
  s.bodies = {Ground(), capsule};
  auto a = MakeBulletAdapter();
  a->Load(s, 1);
  const BodyState st = StepAndRead(*a, 240, 1);
  const Vec2 c1 = st.position;
  const Vec2 c2 = st.position + Rotate(MakeRot(st.angle), Vec2{1, Real(0.5)});
  EXPECT_NEAR(c1.y, 0.75, 0.01);
  EXPECT_NEAR(c2.y, 0.75, 0.01);
  EXPECT_LT(BulletOutOfPlane(*a), 1e-6);
}

// Two 1 m boxes side by side on one body, the right one twice as dense.
BodyDesc TwoBoxCompound(Vec2 position) {
  BodyDesc b = Box(position, Real(0.5), Real(0.5));
  for (Vec2& v : b.vertices) v.x -= 1;  // left box about (-1, 0)
  ShapeDesc right;
  right.vertices = {{Real(0.5), Real(-0.5)}, {Real(1.5), Real(-0.5)}, {Real(1.5), Real(0.5)}, {Real(0.5), Real(0.5)}};
  right.density = 2;
  b.extraShapes.push_back(right);
  return b;
}

// Mass 1 + 2 kg, centre of mass x = (-1 + 2) / 3; inertia about it: each box's m (1 + 1) / 12
// plus m d^2 (parallel axes), 1/6 + 16/9 + 2/6 + 8/9 = 19/6.
TEST(BulletAdapter, CompoundMassAndInertiaAreTheSumOfItsShapes) {
  Scene s = BaseScene();
  s.bodies = {Ground(), TwoBoxCompound({0, 3})};
  auto a = MakeBulletAdapter();
  a->Load(s, 1);
  const auto [mass, inertia] = BulletMassOf(*a, 1);
  EXPECT_NEAR(mass, 3.0, 1e-5);
  EXPECT_NEAR(inertia, 19.0 / 6.0, 1e-5);
  EXPECT_EQ(BulletMassOf(*a, 0), std::make_pair(0.0, 0.0));
  EXPECT_THROW(BulletMassOf(*a, 2), Error);
}

// Both boxes collide: the compound lands flat on the ground (its origin, between the boxes,
// 0.5 m above the ground's top) and, spun in the air, turns about its centre
// of mass (1/3, 0) at its own angular velocity.
TEST(BulletAdapter, CompoundLandsFlatAndSpinsAboutItsCentreOfMass) {
  Scene s = BaseScene();
  BodyDesc b = TwoBoxCompound({0, 3});
  s.bodies = {Ground(), b};
  auto a = MakeBulletAdapter();
  a->Load(s, 1);
  BodyState st = StepAndRead(*a, 180, 1);
  EXPECT_NEAR(st.position.y, 1.0, 0.01);
  EXPECT_NEAR(st.position.x, 0.0, 0.01);
  EXPECT_NEAR(st.angle, 0.0, 0.01);

  Scene air = BaseScene();
  b.angularVelocity = 4;
  air.bodies = {b};
  a->Load(air, 1);
  st = StepAndRead(*a, 30, 0);
  const Vec2 centre = st.position + Rotate(MakeRot(st.angle), Vec2{Real(1.0 / 3.0), 0});
  EXPECT_NEAR(centre.x, 1.0 / 3.0, 1e-3);
  EXPECT_NEAR(st.angle, 2.0, 1e-3);
}

TEST(BulletAdapter, CompoundShapesWithDifferentFrictionAreUnsupported) {
  Scene s = BaseScene();
  BodyDesc b = TwoBoxCompound({0, 3});
  b.extraShapes[0].friction = Real(0.1);
  s.bodies = {Ground(), b};
  auto a = MakeBulletAdapter();
  try {
    a->Load(s, 1);
    ADD_FAILURE() << "loaded";
  } catch (const Unsupported& e) {
    EXPECT_NE(std::string(e.what()).find("share friction"), std::string::npos) << e.what();
  }
  EXPECT_EQ(a->BodyCount(), 0);
}

// A static 0.2 m pivot block at (0, 5) and a ball of radius 0.1 m on a revolute joint there.
Scene Pendulum(Vec2 ball) {
  Scene s = BaseScene();
  s.bodies = {Box({0, 5}, Real(0.1), Real(0.1), false), Circle(ball, Real(0.1))};
  s.joints = {JointDesc{0, 1, {0, 5}}};
  return s;
}

// Released 0.1 rad from the vertical, 1 m long: a physical pendulum of I = m (L^2 + r^2 / 2)
// about the pin, period 2 pi sqrt(I / (m g L)) (1 + theta^2 / 16) = 1.99295 s. The length stays
// within 1 % and the period, from the first to the last upward crossing of x = 0 in 600 steps,
// within 5 %.
TEST(BulletAdapter, RevolutePendulumKeepsItsLengthAndPeriod) {
  const double theta = 0.1, length = 1.0;
  auto a = MakeBulletAdapter();
  a->Load(Pendulum({Real(length * std::sin(theta)), Real(5 - length * std::cos(theta))}), 1);
  std::vector<BodyState> st;
  double worst = 0, prevX = std::sin(theta), first = -1, last = -1;
  int crossings = 0;
  for (int i = 1; i <= 600; ++i) {
    a->Step();
    a->ReadBodies(st);
    const Vec2 d = st[1].position - Vec2{0, 5};
    worst = std::max(worst, std::abs(double(Length(d)) - length));
    const double x = d.x;
    if (prevX < 0 && x >= 0) {  // upward crossing, interpolated
      const double t = (i - 1 + prevX / (prevX - x)) * double(kDt);
      if (first < 0) first = t;
      last = t;
      ++crossings;
    }
    prevX = x;
  }
  EXPECT_LT(worst, 0.01 * length);
  ASSERT_GE(crossings, 4);
  const double expected = 2 * std::numbers::pi * std::sqrt((1.0 + 0.005) / 10.0) * (1 + theta * theta / 16);
  EXPECT_NEAR((last - first) / (crossings - 1), expected, 0.05 * expected);
}

// A 1 m bar pinned at its left end to a static block, released level: it swings clockwise
// (negative joint angle) onto a lower limit of -0.5 rad; it gets there and not more than 0.02
// rad past it. Pinned at its right end it swings the other way, onto the upper limit of 0.3 rad.
TEST(BulletAdapter, RevoluteLimitHoldsTheAngle) {
  for (double side : {1.0, -1.0}) {
    Scene s = BaseScene();
    s.bodies = {Box({0, 5}, Real(0.1), Real(0.1), false), Box({Real(0.5 * side), 5}, Real(0.5), Real(0.05))};
    s.joints = {JointDesc{0, 1, {0, 5}}};
    s.joints[0].enableLimit = true;
    s.joints[0].lowerAngle = Real(-0.5);
    s.joints[0].upperAngle = Real(0.3);
    auto a = MakeBulletAdapter();
    a->Load(s, 1);
    std::vector<BodyState> st;
    double lo = 0, hi = 0;
    for (int i = 0; i < 300; ++i) {
      a->Step();
      a->ReadBodies(st);
      lo = std::min(lo, double(st[1].angle));
      hi = std::max(hi, double(st[1].angle));
    }
    if (side > 0) {
      EXPECT_LT(lo, -0.45);
      EXPECT_GT(lo, -0.52);
    } else {
      EXPECT_GT(hi, 0.25);
      EXPECT_LT(hi, 0.32);
    }
  }
}

// A wheel pinned at its centre to a static block, driven at 3 rad/s (bodyB relative to bodyA)
// by up to 10 N m: after half a second it turns at 3 rad/s; with 0.01 N m it cannot get there.
TEST(BulletAdapter, RevoluteMotorReachesItsSpeed) {
  for (double torque : {10.0, 0.01}) {
    Scene s = BaseScene();
    s.bodies = {Box({0, 5}, Real(0.1), Real(0.1), false), Circle({0, 5}, Real(0.5))};
    JointDesc j{0, 1, {0, 5}};
    j.enableMotor = true;
    j.motorSpeed = 3;
    j.maxMotorTorque = Real(torque);
    s.joints = {j};
    auto a = MakeBulletAdapter();
    a->Load(s, 1);
    const BodyState st = StepAndRead(*a, 30, 1);
    // Disc inertia pi r^4 / 2 = 0.09817 kg m^2: 0.01 N m gives 0.1019 rad/s^2, 0.0509 rad/s in 0.5 s.
    if (torque > 1) {
      EXPECT_NEAR(st.angularVelocity, 3.0, 0.01);
    } else {
      EXPECT_NEAR(st.angularVelocity, 0.5 * 0.01 / 0.09817, 0.002);
    }
    EXPECT_NEAR(st.position.y, 5.0, 0.01);
  }
}

// A ball pinned at its centre to a static block by a revolute spring of 1 Hz, no damping,
// started turning: its angle oscillates with a period of 1 s (within 5 %).
TEST(BulletAdapter, RevoluteSpringHasTheScenesFrequency) {
  Scene s = BaseScene();
  BodyDesc ball = Circle({0, 5}, Real(0.5));
  ball.angularVelocity = 1;
  s.bodies = {Box({0, 5}, Real(0.1), Real(0.1), false), ball};
  JointDesc j{0, 1, {0, 5}};
  j.enableSpring = true;
  j.hertz = 1;
  s.joints = {j};
  auto a = MakeBulletAdapter();
  a->Load(s, 1);
  std::vector<BodyState> st;
  double prev = 0, first = -1, last = -1, peak = 0;
  int crossings = 0;
  for (int i = 1; i <= 300; ++i) {
    a->Step();
    a->ReadBodies(st);
    const double angle = st[1].angle;
    peak = std::max(peak, angle);
    if (prev < 0 && angle >= 0) {
      const double t = (i - 1 + prev / (prev - angle)) * double(kDt);
      if (first < 0) first = t;
      last = t;
      ++crossings;
    }
    prev = angle;
  }
  ASSERT_GE(crossings, 3);
  EXPECT_NEAR((last - first) / (crossings - 1), 1.0, 0.05);
  EXPECT_NEAR(peak, 1.0 / (2 * std::numbers::pi), 0.02);  // amplitude w0 / omega
}

// Two boxes welded side by side, thrown spinning onto the ground (the second box's own velocity
// disagrees with the first's): they keep their relative pose, B 1 m along A's x axis, turned
// by 0, within 2 cm and 0.02 rad (Bullet corrects joint drift by 20 % a step; measured worst
// 1.29 cm and 0.0101 rad, on the first steps and the landing).
TEST(BulletAdapter, WeldHoldsTwoBoxesRelativePose) {
  Scene s = BaseScene();
  BodyDesc a = Box({Real(-0.5), 3}, Real(0.5), Real(0.5));
  BodyDesc b = Box({Real(0.5), 3}, Real(0.5), Real(0.5));
  a.velocity = {1, 2};
  a.angularVelocity = 3;
  s.bodies = {Ground(), a, b};
  JointDesc w{1, 2, {0, 3}};
  w.kind = JointKind::kWeld;
  s.joints = {w};
  auto adapter = MakeBulletAdapter();
  adapter->Load(s, 1);
  std::vector<BodyState> st;
  double worstGap = 0, worstAngle = 0;
  for (int i = 0; i < 180; ++i) {
    adapter->Step();
    adapter->ReadBodies(st);
    const Vec2 expected = st[1].position + Rotate(MakeRot(st[1].angle), Vec2{1, 0});
    worstGap = std::max(worstGap, double(Length(st[2].position - expected)));
    const double da = std::remainder(double(st[2].angle - st[1].angle), 2 * std::numbers::pi);
    worstAngle = std::max(worstAngle, std::abs(da));
  }
  EXPECT_LT(worstGap, 0.02);
  EXPECT_LT(worstAngle, 0.02);
  EXPECT_LT(st[1].position.y, Real(1.6));  // it fell onto the ground
}

// The prismatic_stop hard case's scene (a box on a horizontal prismatic joint through a static
// post, travel [-2, 2] m, launched at 10 m/s, gravity across the axis): it stops at 2 m (within
// 5 cm), stays on the axis and does not turn.
TEST(BulletAdapter, PrismaticLimitStopsTheSlider) {
  const Scene s = MakePrismaticStop();
  auto a = MakeBulletAdapter();
  a->Load(s, 1);
  std::vector<BodyState> st;
  double hi = 0, off = 0, turn = 0;
  for (int i = 0; i < 120; ++i) {
    a->Step();
    a->ReadBodies(st);
    hi = std::max(hi, double(st[1].position.x));
    off = std::max(off, std::abs(double(st[1].position.y) - 5));
    turn = std::max(turn, std::abs(double(st[1].angle)));
  }
  EXPECT_GT(hi, 1.95);
  EXPECT_LT(hi, 2.05);
  EXPECT_LT(off, 0.01);
  EXPECT_LT(turn, 0.01);
}

// The prismatic joint's motor drives bodyB along the axis at its speed, a wheel joint's motor
// turns its wheel, and a distance joint is refused with the reason, the world kept.
TEST(BulletAdapter, PrismaticAndWheelMotorsDistanceRefused) {
  Scene s = BaseScene();
  s.gravity = {0, 0};
  s.bodies = {Box({0, 5}, Real(0.1), Real(0.1), false), Box({0, 5}, Real(0.5), Real(0.5)), Circle({3, 5}, Real(0.5))};
  JointDesc p{0, 1, {0, 5}};
  p.kind = JointKind::kPrismatic;
  p.axis = {0, 1};
  p.enableMotor = true;
  p.motorSpeed = -2;
  p.maxMotorForce = 1000;
  JointDesc w{0, 2, {3, 5}};
  w.kind = JointKind::kWheel;
  w.axis = {0, 1};
  w.enableSpring = true;
  w.hertz = 4;
  w.dampingRatio = Real(0.7);
  w.enableMotor = true;
  w.motorSpeed = -6;
  w.maxMotorTorque = 100;
  s.joints = {p, w};
  auto a = MakeBulletAdapter();
  a->Load(s, 1);
  std::vector<BodyState> st;
  for (int i = 0; i < 30; ++i) a->Step();
  a->ReadBodies(st);
  EXPECT_NEAR(st[1].velocity.y, -2.0, 0.01);
  EXPECT_NEAR(st[1].position.x, 0.0, 0.01);
  EXPECT_NEAR(st[2].angularVelocity, -6.0, 0.05);
  EXPECT_NEAR(st[2].position.y, 5.0, 0.01);  // the spring holds it where it was loaded

  Scene d = s;
  JointDesc rod{1, 2, {0, 5}};
  rod.kind = JointKind::kDistance;
  rod.anchorB = {3, 5};
  d.joints.push_back(rod);
  try {
    a->Load(d, 1);
    ADD_FAILURE() << "loaded a distance joint";
  } catch (const Unsupported& e) {
    EXPECT_NE(std::string(e.what()).find("distance"), std::string::npos) << e.what();
  }
  EXPECT_EQ(a->BodyCount(), 3);
}

}  // namespace
}  // namespace quadrant::scene
