// Tests for joints (quadrant/joints.h, dynamics/soft_step_joints.cpp, world/joint_set.cpp): a
// pendulum keeps its length and period, a hanging chain does not stretch, limits, motor and spring
// do what they say, a weld holds a beam, a prismatic motor runs to its stop, a wheel's suspension
// carries a car its motor drives, motor and mouse joints reach their targets, joined bodies do not collide unless asked, a joint grid has
// the same state hash on 1, 2 and 4 threads, a body's removal removes its joints, sleeping joined
// bodies sleep and wake together, and every bad input is refused with the world unchanged.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "quadrant/world.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

using namespace test;

BodyId Ball(World& w, Vec2 p, Real radius = Real(0.25), BodyType type = BodyType::kDynamic) {
  BodyDef d;
  d.type = type;
  d.position = p;
  d.shape = ShapeDef::MakeCircle(radius);
  return w.CreateBody(d);
}

BodyId Anchor(World& w, Vec2 p) {
  BodyDef d;
  d.position = p;
  d.shape = ShapeDef::MakeCircle(Real(0.05));
  return w.CreateBody(d);
}

RevoluteJointDef Pin(World& w, BodyId a, BodyId b, Vec2 worldPoint) {
  RevoluteJointDef j;
  j.bodyA = a;
  j.bodyB = b;
  j.localAnchorA = w.GetLocalPoint(a, worldPoint);
  j.localAnchorB = w.GetLocalPoint(b, worldPoint);
  return j;
}

TEST(JointTest, PendulumKeepsItsLengthAndPeriod) {
  World w;
  const BodyId pivot = Anchor(w, {0, 10});
  const Real length = 2;
  const Real start = Real(0.2);  // rad: small enough for the small-angle period within 1 %
  const BodyId bob = Ball(w, {length * std::sin(start), 10 - length * std::cos(start)}, Real(0.1));
  RevoluteJointDef j = Pin(w, pivot, bob, {0, 10});
  w.CreateRevoluteJoint(j);
  // Count the crossings of x = 0 from positive to negative over 20 s.
  Real worst = 0, lastX = w.GetPosition(bob).x;
  std::vector<int> crossings;
  for (int s = 1; s <= 1200; ++s) {
    w.Step(kDt);
    const Vec2 p = w.GetPosition(bob);
    worst = std::max(worst, std::abs(Length(p - Vec2{0, 10}) - length));
    if (lastX > 0 && p.x <= 0) crossings.push_back(s);
    lastX = p.x;
  }
  EXPECT_LT(worst, Real(0.002)) << "the rod stretched";
  ASSERT_GE(crossings.size(), 5u);
  const double period = double(crossings.back() - crossings.front()) / double(crossings.size() - 1) * kDt;
  const double expected = 2 * kPi * std::sqrt(double(length) / 10.0);
  EXPECT_NEAR(period, expected, 0.02 * expected);
  // Soft joints lose a little energy, never gain: the swing stays within its start height.
  EXPECT_LT(w.GetPosition(bob).y, 10 - length * std::cos(start) + Real(0.01));
}

// A chain of 20 links of 0.5 m hanging straight down, with a ball 10 times a link's mass at its
// end: the whole stretches under 1 % and comes to rest.
TEST(JointTest, HangingChainDoesNotStretch) {
  World w;
  const BodyId top = Anchor(w, {0, 30});
  BodyId prev = top;
  const int links = 20;
  for (int k = 0; k < links; ++k) {
    const Real r = k == links - 1 ? Real(0.2) * std::sqrt(Real(10)) : Real(0.2);
    const BodyId link = Ball(w, {0, 30 - Real(k + 1) * Real(0.5)}, r);
    w.CreateRevoluteJoint(Pin(w, prev, link, {0, 30 - Real(k) * Real(0.5)}));
    prev = link;
  }
  Real worst = 0;
  for (int s = 0; s < 600; ++s) {
    w.Step(kDt);
    worst = std::max(worst, (30 - w.GetPosition(prev).y) / (Real(links) * Real(0.5)) - 1);
  }
  EXPECT_EQ(w.GetJointCount(), links);
  EXPECT_LT(worst, Real(0.01)) << "the chain stretched";
  EXPECT_LT(std::abs(w.GetPosition(prev).x), Real(1e-3));
  EXPECT_LT(Length(w.GetLinearVelocity(prev)), Real(0.01));
}

// WorldDef::jointChainSolve: a chain of 30 links (0.5 x 0.2 m boxes) holding a body 1000 times a
// link's mass, over 60 s at the default budget. Solved as one system per chain it does not stretch
// measurably; joint by joint it stretches by tens of per cent.
Real HeavyChainStretch(bool chainSolve, int threads = 1, uint64_t* hash = nullptr) {
  WorldDef def;
  def.jointChainSolve = chainSolve;
  def.threadCount = threads;
  def.minParallelItems = 1;
  World w(def);
  const int links = 30;
  const Real length = Real(0.5);
  Real worst = 0;
  std::vector<BodyId> heavies;
  for (int chain = 0; chain < 3; ++chain) {  // three chains side by side: a pass over several
    const Real x = Real(chain) * 15;  // the 100 kg balls are 5.6 m in radius
    BodyId prev = Anchor(w, {x, 40});
    for (int k = 0; k < links; ++k) {
      BodyDef b;
      b.type = BodyType::kDynamic;
      b.position = {x, 40 - length * (Real(k) + Real(0.5))};
      b.shape = ShapeDef::Box(Real(0.1), length / 2);
      const BodyId link = w.CreateBody(b);
      w.CreateRevoluteJoint(Pin(w, prev, link, {x, 40 - length * Real(k)}));
      prev = link;
    }
    const Real r = std::sqrt(Real(1000) * w.GetMass(prev) / Real(kPi));
    const BodyId heavy = Ball(w, {x, 40 - length * links - r}, r);
    w.CreateRevoluteJoint(Pin(w, prev, heavy, {x, 40 - length * links}));
    heavies.push_back(heavy);
  }
  for (int s = 0; s < 3600; ++s) {
    w.Step(kDt);
    for (size_t c = 0; c < heavies.size(); ++c) {
      const Real r = w.GetShape(heavies[c]).circle.radius;
      worst = std::max(worst, (40 - (w.GetPosition(heavies[c]).y + r)) / (length * links) - 1);
    }
  }
  if (hash) *hash = w.StateHash();
  return worst;
}

TEST(JointChainTest, HeavyChainHoldsWithTheChainSolve) {
  EXPECT_LT(HeavyChainStretch(true), Real(0.001));
  EXPECT_GT(HeavyChainStretch(false), Real(0.1)) << "joint by joint the chain stretches";
}

// A cantilever of ten 1 m segments welded end to end: welds form a chain too (point and angle, 3 x 3
// blocks). Solved as one system the tip sags less than a millimetre; weld by weld, metres.
Real CantileverSag(bool chainSolve) {
  WorldDef def;
  def.jointChainSolve = chainSolve;
  World w(def);
  BodyId prev = Anchor(w, {0, 10});
  BodyId tip{};
  for (int k = 0; k < 10; ++k) {
    BodyDef seg;
    seg.type = BodyType::kDynamic;
    seg.position = {Real(k) + Real(0.5), 10};
    seg.shape = ShapeDef::Box(Real(0.5), Real(0.1));
    tip = w.CreateBody(seg);
    WeldJointDef j;
    j.bodyA = prev;
    j.bodyB = tip;
    j.localAnchorA = w.GetLocalPoint(prev, {Real(k), 10});
    j.localAnchorB = w.GetLocalPoint(tip, {Real(k), 10});
    w.CreateWeldJoint(j);
    prev = tip;
  }
  Real sag = 0;
  for (int s = 0; s < 600; ++s) {
    w.Step(kDt);
    sag = std::max(sag, 10 - w.GetPosition(tip).y);
  }
  return sag;
}

TEST(JointChainTest, WeldedCantileverHoldsWithTheChainSolve) {
  EXPECT_LT(CantileverSag(true), Real(0.001));
  EXPECT_GT(CantileverSag(false), Real(1)) << "weld by weld the cantilever droops";
}

TEST(JointChainTest, ChainSolveIsBitIdenticalAcrossThreadCounts) {
  uint64_t one = 0, two = 0, four = 0;
  HeavyChainStretch(true, 1, &one);
  HeavyChainStretch(true, 2, &two);
  HeavyChainStretch(true, 4, &four);
  EXPECT_EQ(two, one);
  EXPECT_EQ(four, one);
}

// A closed ring of links (a loop, cut open into one chain) and a body with three chains on it (two
// of them paired across the hub, the third alone): the world runs and every joint keeps its two
// anchors together.
TEST(JointChainTest, LoopsAndBranchesStayJoined) {
  WorldDef def;
  def.gravity = {0, 0};
  World w(def);
  std::vector<RevoluteJointDef> made;
  auto pin = [&](BodyId a, BodyId b, Vec2 p) {
    made.push_back(Pin(w, a, b, p));
    w.CreateRevoluteJoint(made.back());
  };
  const int n = 12;
  std::vector<BodyId> ring;
  for (int k = 0; k < n; ++k) {
    const Real a = Real(2 * kPi) * Real(k) / Real(n);
    ring.push_back(Ball(w, {3 * std::cos(a), 3 * std::sin(a)}, Real(0.2)));
  }
  for (int k = 0; k < n; ++k) {
    const BodyId a = ring[size_t(k)], b = ring[size_t((k + 1) % n)];
    pin(a, b, Real(0.5) * (w.GetPosition(a) + w.GetPosition(b)));
  }
  const BodyId hub = Ball(w, {10, 0}, Real(0.3));
  for (int arm = 0; arm < 3; ++arm) {
    BodyId prev = hub;
    for (int k = 1; k <= 4; ++k) {
      const Vec2 p{10 + Real(k) * std::cos(Real(arm) * 2), Real(k) * std::sin(Real(arm) * 2)};
      const BodyId link = Ball(w, p, Real(0.1));
      pin(prev, link, Real(0.5) * (w.GetPosition(prev) + p));
      prev = link;
    }
  }
  w.SetAngularVelocity(ring[0], 5);
  w.SetLinearVelocity(hub, {1, 1});
  w.SetAngularVelocity(hub, 3);
  for (int s = 0; s < 240; ++s) w.Step(kDt);
  for (const RevoluteJointDef& j : made) {
    const Vec2 a = w.GetWorldPoint(j.bodyA, j.localAnchorA), b = w.GetWorldPoint(j.bodyB, j.localAnchorB);
    EXPECT_LT(Length(a - b), Real(0.01));
  }
  EXPECT_GT(w.GetPosition(hub).x, Real(10.5)) << "the hub and its arms moved off together";
}

TEST(JointTest, RevoluteLimitHolds) {
  WorldDef def;
  def.gravity = {0, 0};
  World w(def);
  const BodyId pivot = Anchor(w, {0, 0});
  BodyDef bar;
  bar.type = BodyType::kDynamic;
  bar.position = {1, 0};
  bar.shape = ShapeDef::Box(1, Real(0.1));
  const BodyId b = w.CreateBody(bar);
  RevoluteJointDef j = Pin(w, pivot, b, {0, 0});
  j.enableLimit = true;
  j.lowerAngle = Real(-0.5);
  j.upperAngle = Real(0.5);
  const JointId id = w.CreateRevoluteJoint(j);
  w.SetAngularVelocity(b, 5);
  Real most = 0;
  for (int s = 0; s < 240; ++s) {
    w.Step(kDt);
    most = std::max(most, w.GetJointAngle(id));
  }
  EXPECT_GT(most, Real(0.45));
  EXPECT_LT(most, Real(0.51));
  // Stopped by the limit, not bounced back: after the hit it turns away at under 2 % of its speed.
  EXPECT_LT(std::abs(w.GetAngularVelocity(b)), Real(0.03));
}

TEST(JointTest, MotorReachesItsSpeedAndSpringReturns) {
  WorldDef def;
  def.gravity = {0, 0};
  World w(def);
  const BodyId pivot = Anchor(w, {0, 0});
  const BodyId wheel = Ball(w, {0, 0}, Real(0.5));
  RevoluteJointDef m = Pin(w, pivot, wheel, {0, 0});
  m.enableMotor = true;
  m.motorSpeed = 2;
  m.maxMotorTorque = 1000;
  const JointId motor = w.CreateRevoluteJoint(m);
  for (int s = 0; s < 60; ++s) w.Step(kDt);
  EXPECT_NEAR(w.GetAngularVelocity(wheel), Real(2), Real(0.01));
  w.SetMotorSpeed(motor, -1);
  for (int s = 0; s < 60; ++s) w.Step(kDt);
  EXPECT_NEAR(w.GetAngularVelocity(wheel), Real(-1), Real(0.01));
  // A weak motor is joint friction: it only slows a spin.
  m.maxMotorTorque = Real(0.01);
  m.motorSpeed = 0;
  const BodyId other = Ball(w, {5, 0}, Real(0.5));
  const BodyId pivot2 = Anchor(w, {5, 0});
  RevoluteJointDef f = Pin(w, pivot2, other, {5, 0});
  f.enableMotor = true;
  f.maxMotorTorque = Real(0.01);
  w.CreateRevoluteJoint(f);
  w.SetAngularVelocity(other, 3);
  for (int s = 0; s < 60; ++s) w.Step(kDt);
  EXPECT_LT(w.GetAngularVelocity(other), Real(3));
  EXPECT_GT(w.GetAngularVelocity(other), Real(2.5));

  // A spring of 1 Hz, damped, brings the joint angle back to 0.
  const BodyId pivot3 = Anchor(w, {10, 0});
  BodyDef bar;
  bar.type = BodyType::kDynamic;
  bar.position = {11, 0};
  bar.shape = ShapeDef::Box(1, Real(0.1));
  const BodyId b = w.CreateBody(bar);
  RevoluteJointDef s = Pin(w, pivot3, b, {10, 0});
  s.enableSpring = true;
  s.hertz = 1;
  s.dampingRatio = Real(0.7);
  const JointId spring = w.CreateRevoluteJoint(s);
  w.SetAngularVelocity(b, 4);
  Real most = 0;
  for (int k = 0; k < 300; ++k) {
    w.Step(kDt);
    most = std::max(most, std::abs(w.GetJointAngle(spring)));
  }
  EXPECT_GT(most, Real(0.1));
  EXPECT_LT(std::abs(w.GetJointAngle(spring)), Real(0.01));
}

TEST(JointTest, DistanceJointsRodSpringAndRope) {
  World w;
  const BodyId top = Anchor(w, {0, 10});
  const BodyId rodEnd = Ball(w, {2, 10}, Real(0.1));
  DistanceJointDef rod;
  rod.bodyA = top;
  rod.bodyB = rodEnd;
  rod.length = 2;
  const JointId r = w.CreateDistanceJoint(rod);
  const BodyId ropeEnd = Ball(w, {-1, 10}, Real(0.1));
  DistanceJointDef rope;
  rope.bodyA = top;
  rope.bodyB = ropeEnd;
  rope.enableSpring = true;  // hertz 0: no spring, only the limits
  rope.enableLimit = true;
  rope.minLength = Real(0.005);
  rope.maxLength = 3;
  const JointId p = w.CreateDistanceJoint(rope);
  Real rodWorst = 0, ropeMost = 0;
  for (int s = 0; s < 600; ++s) {
    w.Step(kDt);
    rodWorst = std::max(rodWorst, std::abs(w.GetJointLength(r) - 2));
    ropeMost = std::max(ropeMost, w.GetJointLength(p));
  }
  EXPECT_LT(rodWorst, Real(0.01));
  EXPECT_GT(ropeMost, Real(2.9));
  EXPECT_LT(ropeMost, Real(3.03));
}

TEST(JointTest, WeldHoldsABeam) {
  World w;
  const BodyId wall = Anchor(w, {0, 5});
  BodyDef seg;
  seg.type = BodyType::kDynamic;
  BodyId prev = wall;
  BodyId last{};
  for (int k = 0; k < 4; ++k) {
    seg.position = {Real(k) + Real(0.5), 5};
    seg.shape = ShapeDef::Box(Real(0.5), Real(0.1));
    last = w.CreateBody(seg);
    WeldJointDef j;
    j.bodyA = prev;
    j.bodyB = last;
    j.localAnchorA = w.GetLocalPoint(prev, {Real(k), 5});
    j.localAnchorB = w.GetLocalPoint(last, {Real(k), 5});
    w.CreateWeldJoint(j);
    prev = last;
  }
  for (int s = 0; s < 600; ++s) w.Step(kDt);
  // A soft-rigid beam of 4 m sags a little at its tip, and stays put.
  EXPECT_GT(w.GetPosition(last).y, Real(4.6));
  EXPECT_LT(std::abs(w.GetLinearVelocity(last).y), Real(0.01));
}

// A slider on a horizontal axis: a motor drives it to its upper stop, where it stays, level
// and on the line, without turning.
TEST(JointTest, PrismaticMotorRunsToItsStop) {
  World w;
  const BodyId base = Anchor(w, {0, 5});
  BodyDef box;
  box.type = BodyType::kDynamic;
  box.position = {0, 5};
  box.shape = ShapeDef::Box(Real(0.5), Real(0.25));
  const BodyId slider = w.CreateBody(box);
  PrismaticJointDef p;
  p.bodyA = base;
  p.bodyB = slider;
  p.localAxisA = {2, 0};  // normalised by the world
  p.enableLimit = true;
  p.lowerTranslation = -1;
  p.upperTranslation = 3;
  p.enableMotor = true;
  p.motorSpeed = 2;
  p.maxMotorForce = 100;
  const JointId id = w.CreatePrismaticJoint(p);
  Real most = 0;
  for (int s = 0; s < 180; ++s) {
    w.Step(kDt);
    most = std::max(most, w.GetJointLength(id));
  }
  EXPECT_LT(most, Real(3.02));
  EXPECT_NEAR(w.GetJointLength(id), Real(3), Real(0.01));
  EXPECT_NEAR(w.GetPosition(slider).y, Real(5), Real(0.005)) << "held on the axis against gravity";
  EXPECT_NEAR(w.GetAngle(slider), Real(0), Real(0.002)) << "no turn relative to the base";
  // The motor reverses it to the lower stop.
  w.SetMotorSpeed(id, -3);
  for (int s = 0; s < 180; ++s) w.Step(kDt);
  EXPECT_NEAR(w.GetJointLength(id), Real(-1), Real(0.01));
}

// A car's wheel: the hub rides on a vertical spring (1 Hz) and the motor spins the wheel.
TEST(JointTest, WheelSuspensionCarriesAndMotorSpins) {
  World w;
  AddGround(w, 50, Real(0.5));
  BodyDef chassisDef;
  chassisDef.type = BodyType::kDynamic;
  chassisDef.position = {0, 2};
  chassisDef.shape = ShapeDef::Box(1, Real(0.25));
  const BodyId chassis = w.CreateBody(chassisDef);
  JointId motor{};
  for (Real x : {Real(-0.8), Real(0.8)}) {
    const BodyId wheel = Ball(w, {x, 1}, Real(0.4));
    WheelJointDef j;
    j.bodyA = chassis;
    j.bodyB = wheel;
    j.localAnchorA = w.GetLocalPoint(chassis, {x, 1});
    j.localAxisA = {0, 1};
    j.hertz = 4;
    j.dampingRatio = Real(0.7);
    j.enableMotor = true;
    j.motorSpeed = -4;  // clockwise: rolls to +x
    j.maxMotorTorque = 20;
    motor = w.CreateWheelJoint(j);
  }
  for (int s = 0; s < 240; ++s) w.Step(kDt);
  EXPECT_GT(w.GetPosition(chassis).x, Real(3)) << "the car drove off to +x";
  EXPECT_GT(w.GetPosition(chassis).y, Real(1.2)) << "carried by the springs";
  EXPECT_LT(std::abs(w.GetAngle(chassis)), Real(0.2));
  EXPECT_LT(std::abs(w.GetJointLength(motor)), Real(0.5)) << "the suspension's travel stays small";
}

// A motor joint carries a body to its target offset with a bounded force; a mouse joint pulls a
// body to a point.
TEST(JointTest, MotorAndMouseJointsReachTheirTargets) {
  WorldDef def;
  def.gravity = {0, 0};
  World w(def);
  const BodyId ground = Anchor(w, {0, 0});
  BodyDef box;
  box.type = BodyType::kDynamic;
  box.position = {0, 0};
  box.shape = ShapeDef::Box(Real(0.5), Real(0.5));
  const BodyId mover = w.CreateBody(box);
  MotorJointDef m;
  m.bodyA = ground;
  m.bodyB = mover;
  m.localAnchorA = {3, 1};  // the target: bodyB's origin at (3, 1), turned by 0.5 rad
  m.referenceAngle = Real(0.5);
  m.maxForce = 50;
  m.maxTorque = 20;
  const JointId mj = w.CreateMotorJoint(m);
  for (int s = 0; s < 240; ++s) w.Step(kDt);
  EXPECT_NEAR(w.GetPosition(mover).x, Real(3), Real(0.01));
  EXPECT_NEAR(w.GetPosition(mover).y, Real(1), Real(0.01));
  EXPECT_NEAR(w.GetJointAngle(mj), Real(0), Real(0.01));
  // A force limit: with maxForce 1 N a 1 kg box is still on its way after 0.5 s (it accelerates
  // at most 1 m/s^2: at most 0.125 m from rest).
  const BodyId slow = w.CreateBody(box);
  m.bodyB = slow;
  m.maxForce = 1;
  w.CreateMotorJoint(m);
  for (int s = 0; s < 30; ++s) w.Step(kDt);
  EXPECT_LT(Length(w.GetPosition(slow)), Real(0.13));
  EXPECT_GT(Length(w.GetPosition(slow)), Real(0.05));

  const BodyId ball = Ball(w, {-5, 0}, Real(0.5));
  MouseJointDef mouse;
  mouse.bodyA = ground;
  mouse.bodyB = ball;
  mouse.target = {-5, 4};
  mouse.maxForce = 500;
  const JointId mo = w.CreateMouseJoint(mouse);
  for (int s = 0; s < 120; ++s) w.Step(kDt);
  EXPECT_NEAR(w.GetPosition(ball).y, Real(4), Real(0.02));
  w.SetJointTarget(mo, {-8, 4});
  for (int s = 0; s < 120; ++s) w.Step(kDt);
  EXPECT_NEAR(w.GetPosition(ball).x, Real(-8), Real(0.02));
  EXPECT_THROW(w.SetJointTarget(mo, {INFINITY, 0}), Error);
  EXPECT_THROW(w.SetJointTarget(mj, {0, 0}), Error) << "not a mouse joint";
}

TEST(JointTest, JoinedBodiesCollideOnlyWhenAsked) {
  for (bool collide : {false, true}) {
    WorldDef def;
    def.gravity = {0, 0};
    World w(def);
    const BodyId a = Ball(w, {0, 0}, Real(0.5));
    const BodyId b = Ball(w, {Real(0.8), 0}, Real(0.5));  // overlapping by 0.2 m
    RevoluteJointDef j = Pin(w, a, b, {Real(0.4), 0});
    j.collideConnected = collide;
    w.CreateRevoluteJoint(j);
    w.Step(kDt);
    EXPECT_EQ(w.GetContacts().size(), collide ? 1u : 0u) << "collideConnected " << collide;
  }
}

uint64_t GridHash(int threads) {
  WorldDef def;
  def.threadCount = threads;
  def.minParallelItems = 1;
  World w(def);
  const int n = 16;
  std::vector<BodyId> ids(size_t(n * n));
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < n; ++k) {
      BodyDef d;
      d.type = (i == 0 && (k == 0 || k == n - 1)) ? BodyType::kStatic : BodyType::kDynamic;
      d.position = {Real(k), Real(-i)};
      d.shape = ShapeDef::MakeCircle(Real(0.4));
      ids[size_t(i * n + k)] = w.CreateBody(d);
    }
  }
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < n; ++k) {
      const BodyId b = ids[size_t(i * n + k)];
      if (k > 0) w.CreateRevoluteJoint(Pin(w, ids[size_t(i * n + k - 1)], b, {Real(k) - Real(0.5), Real(-i)}));
      if (i > 0) w.CreateRevoluteJoint(Pin(w, ids[size_t((i - 1) * n + k)], b, {Real(k), Real(-i) + Real(0.5)}));
    }
  }
  for (int s = 0; s < 120; ++s) w.Step(kDt);
  return w.StateHash();
}

// The joint colouring is kept from step to step while the joints and their moving ends stay the
// same. A twin world that forces a new colouring every step (a joint added and removed between
// steps bumps the joints' version; the joint order is unchanged) ends with the same bits, also
// after a body's type changes (its joints' ends change) half way.
TEST(JointTest, KeptColouringGivesTheSameBitsAsANewOne) {
  uint64_t hashes[2];
  for (int forced = 0; forced < 2; ++forced) {
    WorldDef def;
    def.threadCount = 2;
    def.minParallelItems = 1;
    World w(def);
    const int n = 8;
    std::vector<BodyId> ids;
    for (int i = 0; i < n; ++i) {
      for (int k = 0; k < n; ++k) {
        BodyDef d;
        d.type = i == 0 && k == 0 ? BodyType::kStatic : BodyType::kDynamic;
        d.position = {Real(k), Real(-i)};
        d.shape = ShapeDef::MakeCircle(Real(0.4));
        ids.push_back(w.CreateBody(d));
      }
    }
    for (int i = 0; i < n; ++i) {
      for (int k = 0; k < n; ++k) {
        const BodyId b = ids[size_t(i * n + k)];
        if (k > 0) w.CreateRevoluteJoint(Pin(w, ids[size_t(i * n + k - 1)], b, {Real(k) - Real(0.5), Real(-i)}));
        if (i > 0) w.CreateRevoluteJoint(Pin(w, ids[size_t((i - 1) * n + k)], b, {Real(k), Real(-i) + Real(0.5)}));
      }
    }
    const BodyId far1 = Anchor(w, {100, 100}), far2 = Anchor(w, {102, 100});
    int kept = 0;
    for (int s = 0; s < 120; ++s) {
      if (s == 60) w.SetType(ids[size_t(n - 1)], BodyType::kStatic);
      if (forced) {
        RevoluteJointDef dummy;
        dummy.bodyA = far1;
        dummy.bodyB = far2;
        w.DestroyJoint(w.CreateRevoluteJoint(dummy));
      }
      w.Step(kDt);
      kept += w.GetCounters().jointColoringKept ? 1 : 0;
      // The steps that must colour again: the first, and the one after a body became static.
      if (s == 0 || s == 60 || forced) {
        EXPECT_FALSE(w.GetCounters().jointColoringKept) << "step " << s;
      }
    }
    // Every other step keeps it: the twin that never does must end with the same bits.
    EXPECT_EQ(kept, forced ? 0 : 118);
    hashes[forced] = w.StateHash();
  }
  EXPECT_EQ(hashes[0], hashes[1]);
}

TEST(JointTest, JointGridIsBitIdenticalAcrossThreadCounts) {
  const uint64_t one = GridHash(1);
  EXPECT_EQ(GridHash(2), one);
  EXPECT_EQ(GridHash(4), one);
}

TEST(JointTest, DestroyingABodyDestroysItsJoints) {
  World w;
  const BodyId pivot = Anchor(w, {0, 10});
  const BodyId a = Ball(w, {1, 10});
  const BodyId b = Ball(w, {2, 10});
  const JointId ja = w.CreateRevoluteJoint(Pin(w, pivot, a, {0, 10}));
  const JointId jb = w.CreateRevoluteJoint(Pin(w, a, b, {Real(1.5), 10}));
  const JointId jc = w.CreateRevoluteJoint(Pin(w, pivot, b, {0, 10}));
  w.DestroyBody(a);
  EXPECT_FALSE(w.IsValid(ja));
  EXPECT_FALSE(w.IsValid(jb));
  EXPECT_TRUE(w.IsValid(jc));
  EXPECT_EQ(w.GetJointCount(), 1);
  EXPECT_EQ(w.GetJointBodyB(jc), b);
  for (int s = 0; s < 60; ++s) w.Step(kDt);
  // b's anchor (2 m to its left) stays on the pivot: b swings at 2 m from it.
  EXPECT_NEAR(Length(w.GetPosition(b) - Vec2{0, 10}), Real(2), Real(0.01));
  EXPECT_THROW(w.DestroyJoint(ja), Error);
  w.DestroyJoint(jc);
  EXPECT_EQ(w.GetJointCount(), 0);
}

TEST(JointTest, JoinedBodiesSleepAndWakeTogether) {
  WorldDef def;
  def.effects.sleep = true;
  World w(def);
  AddGround(w, 20, Real(0.5));
  const BodyId a = Ball(w, {0, Real(0.75)});
  const BodyId b = Ball(w, {3, Real(0.75)});
  DistanceJointDef d;
  d.bodyA = a;
  d.bodyB = b;
  d.length = 3;
  w.CreateDistanceJoint(d);
  for (int s = 0; s < 240; ++s) w.Step(kDt);
  ASSERT_FALSE(w.IsAwake(a));
  ASSERT_FALSE(w.IsAwake(b));
  w.ApplyLinearImpulse(a, {1, 0}, w.GetWorldCenter(a));  // wakes a's island, b with it
  EXPECT_TRUE(w.IsAwake(b));
  w.Step(kDt);
  EXPECT_GT(w.GetLinearVelocity(b).x, Real(0.1)) << "the rod pulls b along";
}

TEST(JointTest, BadJointsAreRefusedWithTheWorldUnchanged) {
  World w;
  const BodyId a = Ball(w, {0, 0});
  const BodyId b = Ball(w, {1, 0});
  const BodyId gone = Ball(w, {2, 0});
  w.DestroyBody(gone);
  const uint64_t before = w.StateHash();
  auto refused = [&](auto&& make, const char* expect) {
    try {
      make();
      ADD_FAILURE() << "accepted: " << expect;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(expect), std::string::npos) << e.what();
    }
    EXPECT_EQ(w.GetJointCount(), 0);
    EXPECT_EQ(w.StateHash(), before);
  };
  RevoluteJointDef r;
  r.bodyA = a;
  r.bodyB = b;
  refused([&] { RevoluteJointDef x = r; x.bodyB = gone; w.CreateRevoluteJoint(x); }, "bodyB is a stale");
  refused([&] { RevoluteJointDef x = r; x.bodyA = BodyId{}; w.CreateRevoluteJoint(x); }, "must be set");
  refused([&] { RevoluteJointDef x = r; x.bodyB = a; w.CreateRevoluteJoint(x); }, "same body");
  refused([&] { RevoluteJointDef x = r; x.localAnchorA.x = std::nanf(""); w.CreateRevoluteJoint(x); }, "localAnchorA");
  refused([&] { RevoluteJointDef x = r; x.localAnchorB.y = INFINITY; w.CreateRevoluteJoint(x); }, "localAnchorB");
  refused([&] { RevoluteJointDef x = r; x.lowerAngle = 1; x.upperAngle = -1; w.CreateRevoluteJoint(x); }, "lowerAngle must be <=");
  refused([&] { RevoluteJointDef x = r; x.upperAngle = 4; w.CreateRevoluteJoint(x); }, "within [-pi, pi]");
  refused([&] { RevoluteJointDef x = r; x.maxMotorTorque = -1; w.CreateRevoluteJoint(x); }, "maxMotorTorque");
  refused([&] { RevoluteJointDef x = r; x.hertz = -1; w.CreateRevoluteJoint(x); }, "hertz");
  refused([&] { RevoluteJointDef x = r; x.motorSpeed = std::nanf(""); w.CreateRevoluteJoint(x); }, "motorSpeed");
  DistanceJointDef d;
  d.bodyA = a;
  d.bodyB = b;
  refused([&] { DistanceJointDef x = d; x.length = -1; w.CreateDistanceJoint(x); }, "length must be");
  refused([&] { DistanceJointDef x = d; x.length = 0; w.CreateDistanceJoint(x); }, "length must be");
  refused([&] { DistanceJointDef x = d; x.minLength = 2; x.maxLength = 1; w.CreateDistanceJoint(x); }, "minLength must be <=");
  refused([&] { DistanceJointDef x = d; x.dampingRatio = -1; w.CreateDistanceJoint(x); }, "dampingRatio");
  WeldJointDef wd;
  wd.bodyA = a;
  wd.bodyB = b;
  refused([&] { WeldJointDef x = wd; x.angularHertz = std::nanf(""); w.CreateWeldJoint(x); }, "angularhertz");
  refused([&] { WeldJointDef x = wd; x.referenceAngle = 7; w.CreateWeldJoint(x); }, "referenceAngle");
  PrismaticJointDef pd;
  pd.bodyA = a;
  pd.bodyB = b;
  refused([&] { PrismaticJointDef x = pd; x.localAxisA = {0, 0}; w.CreatePrismaticJoint(x); }, "localAxisA must not be zero");
  refused([&] { PrismaticJointDef x = pd; x.localAxisA.y = std::nanf(""); w.CreatePrismaticJoint(x); }, "localAxisA must be finite");
  refused([&] { PrismaticJointDef x = pd; x.lowerTranslation = 1; w.CreatePrismaticJoint(x); }, "lowerTranslation must be <=");
  refused([&] { PrismaticJointDef x = pd; x.maxMotorForce = -1; w.CreatePrismaticJoint(x); }, "maxMotorForce");
  WheelJointDef wh;
  wh.bodyA = a;
  wh.bodyB = b;
  refused([&] { WheelJointDef x = wh; x.hertz = -2; w.CreateWheelJoint(x); }, "hertz");
  refused([&] { WheelJointDef x = wh; x.upperTranslation = INFINITY; w.CreateWheelJoint(x); }, "upperTranslation");
  MotorJointDef md;
  md.bodyA = a;
  md.bodyB = b;
  refused([&] { MotorJointDef x = md; x.correctionFactor = 2; w.CreateMotorJoint(x); }, "correctionFactor");
  refused([&] { MotorJointDef x = md; x.maxForce = -1; w.CreateMotorJoint(x); }, "maxForce");
  MouseJointDef mo;
  mo.bodyA = a;
  mo.bodyB = b;
  refused([&] { MouseJointDef x = mo; x.hertz = 0; w.CreateMouseJoint(x); }, "hertz must be finite and > 0");
  refused([&] { MouseJointDef x = mo; x.target = {2e6f, 0}; w.CreateMouseJoint(x); }, "target");
  // Read-backs and writes on the wrong joint type, or on a stale joint.
  const JointId rod = w.CreateDistanceJoint(d);
  EXPECT_THROW(w.GetJointAngle(rod), Error);
  EXPECT_THROW(w.SetMotorSpeed(rod, 1), Error);
  w.DestroyJoint(rod);
  EXPECT_THROW(w.GetJointLength(rod), Error);
  EXPECT_THROW(w.DestroyJoint(JointId{}), Error);
  EXPECT_FALSE(w.IsValid(JointId{}));
  // Solvers and schemes that do not solve joints.
  for (SolverType solver : {SolverType::kPgs, SolverType::kThesis, SolverType::kJacobi}) {
    WorldDef def;
    def.solver = solver;
    World other(def);
    RevoluteJointDef x;
    x.bodyA = Ball(other, {0, 0});
    x.bodyB = Ball(other, {1, 0});
    EXPECT_THROW(other.CreateRevoluteJoint(x), Error);
    EXPECT_EQ(other.GetJointCount(), 0);
  }
  WorldDef quads;
  quads.scheme = ParallelScheme::kQuadrants;
  quads.threadCount = 2;
  World q(quads);
  RevoluteJointDef x;
  x.bodyA = Ball(q, {0, 0});
  x.bodyB = Ball(q, {1, 0});
  EXPECT_THROW(q.CreateRevoluteJoint(x), Error);
  WorldDef bad;
  bad.jointHertz = 0;
  EXPECT_THROW(World{bad}, Error);
  bad = WorldDef{};
  bad.jointDampingRatio = -1;
  EXPECT_THROW(World{bad}, Error);
}

}  // namespace
}  // namespace quadrant
