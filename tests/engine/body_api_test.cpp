// The body API of issue #29 item 9: forces, torques and angular impulses; per-body gravity
// scale, fixed rotation and bullet flags; SetType, SetGravity and the material setters. Each
// call does what world.h says, refuses bad input without changing the world, and keeps the
// state the same for any thread count.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "quadrant/error.h"
#include "quadrant/world.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

using namespace test;  // the small-world builders of test_helpers.h

constexpr Real kNaN = std::numeric_limits<Real>::quiet_NaN();
constexpr Real kInf = std::numeric_limits<Real>::infinity();
constexpr SolverType kSolvers[] = {SolverType::kThesis, SolverType::kPgs, SolverType::kSoftStep, SolverType::kJacobi};

const char* SolverName(SolverType s) {
  switch (s) {
    case SolverType::kThesis: return "thesis";
    case SolverType::kPgs: return "pgs";
    case SolverType::kSoftStep: return "soft_step";
    case SolverType::kJacobi: return "jacobi";
  }
  return "?";
}

/// Expects `call` to throw quadrant::Error containing `message` and to change neither the hash
/// nor the body count nor the world's next step.
void ExpectRefusedWith(World& world, const std::function<void()>& call, const std::string& message,
                       const std::string& what) {
  SCOPED_TRACE(what);
  const uint64_t hash = world.StateHash();
  const int count = world.GetBodyCount();
  ExpectError(call, message, what);
  EXPECT_EQ(world.StateHash(), hash);
  EXPECT_EQ(world.GetBodyCount(), count);
}

BodyId AddKinematic(World& world, Vec2 position, Vec2 velocity = {}) {
  BodyDef def;
  def.type = BodyType::kKinematic;
  def.position = position;
  def.linearVelocity = velocity;
  def.shape = ShapeDef::Box(Real(0.5), Real(0.5));
  return world.CreateBody(def);
}

// --- Forces, torques, impulses ---

TEST(BodyForceTest, ForcesAndTorquesActInTheNextStepOnlyAsDtOverMass) {
  for (SolverType solver : {SolverType::kPgs, SolverType::kSoftStep}) {
    SCOPED_TRACE(SolverName(solver));
    World world(NoGravityDef(solver));
    const BodyId box = AddBox(world, {0, 0});  // m = 1 kg, I = 1/6 kg m^2
    const Real inertia = world.GetRotationalInertia(box);
    world.ApplyForceToCenter(box, {6, 0});
    world.ApplyForceToCenter(box, {6, -3});  // summed: (12, -3) N
    world.ApplyTorque(box, Real(0.5));
    world.Step(kDt);
    EXPECT_TRUE(VecNear(world.GetLinearVelocity(box), Vec2{12 * kDt, -3 * kDt}, 1e-6));
    EXPECT_NEAR(world.GetAngularVelocity(box), 0.5 * kDt / inertia, 1e-5);
    // Cleared: the next step keeps the velocity.
    const Vec2 v = world.GetLinearVelocity(box);
    const Real w = world.GetAngularVelocity(box);
    world.Step(kDt);
    EXPECT_TRUE(VecNear(world.GetLinearVelocity(box), v, 1e-7));
    EXPECT_NEAR(world.GetAngularVelocity(box), w, 1e-6);
  }
}

TEST(BodyForceTest, AnOffCentreForceAddsItsTorque) {
  World world(NoGravityDef());
  const BodyId box = AddBox(world, {1, 2});
  const Real inertia = world.GetRotationalInertia(box);
  // r = (0.5, 0) from the centre, F = (0, 2): torque r x F = 1 N m.
  world.ApplyForce(box, {0, 2}, {Real(1.5), 2});
  world.Step(kDt);
  EXPECT_TRUE(VecNear(world.GetLinearVelocity(box), Vec2{0, 2 * kDt}, 1e-6));
  EXPECT_NEAR(world.GetAngularVelocity(box), kDt / inertia, 1e-5);
}

TEST(BodyForceTest, AngularImpulseActsAtOnce) {
  World world(NoGravityDef());
  const BodyId box = AddBox(world, {0, 0});
  const Real inertia = world.GetRotationalInertia(box);
  world.ApplyAngularImpulse(box, Real(0.25));
  EXPECT_NEAR(world.GetAngularVelocity(box), 0.25 / inertia, 1e-5);
}

TEST(BodyForceTest, StepRepeatedAppliesThemInItsFirstRepeatLikeCallsOfStep) {
  auto run = [](bool repeated) {
    World world;
    AddGround(world);
    const BodyId box = AddBox(world, {0, 3});
    world.ApplyForce(box, {40, 5}, {Real(0.3), Real(3.2)});
    world.ApplyTorque(box, 2);
    if (repeated) {
      world.StepRepeated(kDt, 3);
    } else {
      for (int k = 0; k < 3; ++k) world.Step(kDt / 3);
    }
    StepN(world, 20);
    return world.StateHash();
  };
  EXPECT_EQ(run(true), run(false));
}

TEST(BodyForceTest, DestroyedBodiesDropTheirForcesAndOthersKeepThem) {
  World world(NoGravityDef());
  const BodyId a = AddCircle(world, {0, 0});
  const BodyId b = AddCircle(world, {5, 0});
  const BodyId c = AddCircle(world, {10, 0});
  world.ApplyForceToCenter(a, {100, 0});
  world.ApplyForceToCenter(b, {0, 100});
  world.ApplyForceToCenter(c, {-100, 0});
  world.DestroyBody(a);                          // c moves into a's dense place
  const BodyId d = AddCircle(world, {20, 0});    // reuses a's slot: gets no force
  world.Step(kDt);
  const Real m = world.GetMass(b);
  EXPECT_TRUE(VecNear(world.GetLinearVelocity(b), Vec2{0, 100 * kDt / m}, 1e-4));
  EXPECT_TRUE(VecNear(world.GetLinearVelocity(c), Vec2{-100 * kDt / m, 0}, 1e-4));
  EXPECT_TRUE(VecNear(world.GetLinearVelocity(d), Vec2{0, 0}, 0));
}

TEST(BodyForceTest, ForcesAndImpulsesOnStaticOrKinematicBodiesAreErrors) {
  World world;
  const BodyId ground = AddGround(world);
  const BodyId kin = AddKinematic(world, {0, 5}, {1, 0});
  StepN(world, 3);
  for (BodyId id : {ground, kin}) {
    const std::string kind = id == ground ? "static" : "kinematic";
    const std::string tail = ": the body is " + kind + "; forces, torques and impulses act on dynamic bodies only";
    ExpectRefusedWith(world, [&] { world.ApplyLinearImpulse(id, {1, 0}, {0, 5}); }, "ApplyLinearImpulse" + tail, kind);
    ExpectRefusedWith(world, [&] { world.ApplyAngularImpulse(id, 1); }, "ApplyAngularImpulse" + tail, kind);
    ExpectRefusedWith(world, [&] { world.ApplyForce(id, {1, 0}, {0, 5}); }, "ApplyForce" + tail, kind);
    ExpectRefusedWith(world, [&] { world.ApplyForceToCenter(id, {1, 0}); }, "ApplyForceToCenter" + tail, kind);
    ExpectRefusedWith(world, [&] { world.ApplyTorque(id, 1); }, "ApplyTorque" + tail, kind);
  }
}

TEST(BodyForceTest, BadForcesAndImpulsesAreRefusedAndChangeNothing) {
  World world;
  AddGround(world);
  const BodyId box = AddBox(world, {0, 2});  // 1 kg, I = 1/6
  StepN(world, 5);
  ExpectRefusedWith(world, [&] { world.ApplyForce(box, {kNaN, 0}, {0, 2}); }, "ApplyForce: force or point is not finite", "F NaN");
  ExpectRefusedWith(world, [&] { world.ApplyForce(box, {1, 0}, {kInf, 2}); }, "ApplyForce: force or point is not finite", "p inf");
  ExpectRefusedWith(world, [&] { world.ApplyForce(box, {1, 0}, {Real(2e6), 2}); },
                    "ApplyForce: point is beyond the coordinate limit of 1e6 m", "p 2e6");
  ExpectRefusedWith(world, [&] { world.ApplyForceToCenter(box, {0, -kInf}); }, "ApplyForceToCenter: force is not finite", "F inf");
  ExpectRefusedWith(world, [&] { world.ApplyTorque(box, kNaN); }, "ApplyTorque: torque is not finite", "T NaN");
  ExpectRefusedWith(world, [&] { world.ApplyAngularImpulse(box, kInf); }, "ApplyAngularImpulse: impulse is not finite", "J inf");
  const std::string tooMuch = ": the body's pending force or torque would change its velocity by more than 1e6 m/s (rad/s) in a 1 s step";
  ExpectRefusedWith(world, [&] { world.ApplyForceToCenter(box, {Real(3e38), 0}); }, "ApplyForceToCenter" + tooMuch, "F 3e38");
  ExpectRefusedWith(world, [&] { world.ApplyTorque(box, Real(1e6)); }, "ApplyTorque" + tooMuch, "T 1e6 on I = 1/6");
  ExpectRefusedWith(world, [&] { world.ApplyAngularImpulse(box, Real(1e6)); },
                    "ApplyAngularImpulse: the resulting angular velocity is beyond the limit of 1e6 rad/s", "J 1e6");
  // The pending sum is what is checked: 6e5 N twice on 1 kg is 1.2e6 m/s in a 1 s step.
  world.ApplyForceToCenter(box, {Real(6e5), 0});
  ExpectRefusedWith(world, [&] { world.ApplyForceToCenter(box, {Real(6e5), 0}); }, "ApplyForceToCenter" + tooMuch, "sum");
  ExpectRefusedWith(world, [&] { world.ApplyForce(box, {Real(6e5), 0}, world.GetWorldCenter(box)); }, "ApplyForce" + tooMuch, "sum");
  // Stale ids.
  const BodyId doomed = AddCircle(world, {5, 5});
  world.DestroyBody(doomed);
  const std::string stale = "stale or invalid BodyId";
  ExpectRefusedWith(world, [&] { world.ApplyForce(doomed, {1, 0}, {5, 5}); }, stale, "ApplyForce stale");
  ExpectRefusedWith(world, [&] { world.ApplyForceToCenter(doomed, {1, 0}); }, stale, "ApplyForceToCenter stale");
  ExpectRefusedWith(world, [&] { world.ApplyTorque(doomed, 1); }, stale, "ApplyTorque stale");
  ExpectRefusedWith(world, [&] { world.ApplyAngularImpulse(doomed, 1); }, stale, "ApplyAngularImpulse stale");
}

TEST(BodyForceTest, ForcesWakeASleepingBody) {
  WorldDef def;
  def.effects.sleep = true;
  World world(def);
  AddGround(world);
  const BodyId box = AddBox(world, {0, 1});
  StepN(world, 120);
  ASSERT_FALSE(world.IsAwake(box));
  world.ApplyForceToCenter(box, {300, 0});
  EXPECT_TRUE(world.IsAwake(box));
  world.Step(kDt);
  EXPECT_GT(world.GetLinearVelocity(box).x, 1);
  world.SetAwake(box, false);
  world.ApplyAngularImpulse(box, 1);
  EXPECT_TRUE(world.IsAwake(box));
  EXPECT_GT(world.GetAngularVelocity(box), 1);
}

// --- Gravity scale ---

TEST(GravityScaleTest, ScaleZeroFloatsAndScaleTwoFallsTwiceAsFastUnderPgs) {
  WorldDef def;
  def.solver = SolverType::kPgs;
  World world(def);
  BodyDef bd;
  bd.type = BodyType::kDynamic;
  bd.shape = ShapeDef::MakeCircle(Real(0.5));
  bd.position = {0, 10};
  bd.gravityScale = 0;
  const BodyId floating = world.CreateBody(bd);
  bd.position = {5, 10};
  bd.gravityScale = 2;
  const BodyId heavy = world.CreateBody(bd);
  const BodyId plain = AddCircle(world, {10, 10});
  EXPECT_EQ(world.GetGravityScale(floating), 0);
  EXPECT_EQ(world.GetGravityScale(plain), 1);
  StepN(world, 30);
  EXPECT_EQ(world.GetPosition(floating), (Vec2{0, 10}));
  EXPECT_EQ(world.GetLinearVelocity(floating), (Vec2{0, 0}));
  EXPECT_NEAR(world.GetLinearVelocity(heavy).y, 2 * world.GetLinearVelocity(plain).y, 1e-4);
  EXPECT_NEAR(10 - world.GetPosition(heavy).y, 2 * (10 - world.GetPosition(plain).y), 1e-4);
  // Back to 1: falls as the plain one does from here on.
  world.SetGravityScale(heavy, 1);
  const Real v0 = world.GetLinearVelocity(heavy).y;
  world.Step(kDt);
  EXPECT_NEAR(world.GetLinearVelocity(heavy).y - v0, -10 * kDt, 1e-5);
}

TEST(GravityScaleTest, UnderSoftStepScaleZeroFloatsAndScaleTwoFallsTwiceAsFar) {
  // soft_step scales gravity in each sub-step: scale 0 stays put, scale 2 falls exactly as a body
  // under 2 g does.
  WorldDef def;  // soft_step, 4 sub-steps, g = (0, -10)
  World world(def);
  BodyDef bd;
  bd.type = BodyType::kDynamic;
  bd.shape = ShapeDef::MakeCircle(Real(0.5));
  bd.position = {0, 10};
  bd.gravityScale = 0;
  const BodyId floating = world.CreateBody(bd);
  const int steps = 60;
  StepN(world, steps);
  EXPECT_EQ(world.GetPosition(floating).y, Real(10));
  EXPECT_EQ(world.GetLinearVelocity(floating).y, Real(0));
  // Scale 2 against a world whose gravity is 2 g: the same motion (within float rounding).
  WorldDef doubled;
  doubled.gravity = {0, -20};
  World reference(doubled);
  bd.gravityScale = 1;
  const BodyId ref = reference.CreateBody(bd);
  world.SetGravityScale(floating, 2);
  const Real y0 = world.GetPosition(floating).y;
  StepN(world, steps);
  StepN(reference, steps);
  EXPECT_NEAR(world.GetPosition(floating).y - y0, reference.GetPosition(ref).y - 10, 1e-3);
  EXPECT_NEAR(world.GetLinearVelocity(floating).y, reference.GetLinearVelocity(ref).y, 1e-3);
}

TEST(GravityScaleTest, AHeavierScaledBodyStillRestsOnTheGround) {
  for (SolverType solver : kSolvers) {
    SCOPED_TRACE(SolverName(solver));
    WorldDef def;
    def.solver = solver;
    World world(def);
    AddGround(world);
    const BodyId box = AddBox(world, {0, 1});
    world.SetGravityScale(box, 3);
    StepN(world, 120);
    EXPECT_NEAR(world.GetPosition(box).y, 1, 0.03);
    EXPECT_NEAR(world.GetLinearVelocity(box).y, 0, 0.05);
  }
}

TEST(GravityScaleTest, BadScalesAreRefused) {
  World world;
  const BodyId box = AddBox(world, {0, 2});
  for (Real bad : {kNaN, kInf, -kInf, Real(2e6), Real(-1.5e6)}) {
    ExpectRefusedWith(world, [&] { world.SetGravityScale(box, bad); },
                      "SetGravityScale: the scale must be finite and in [-1e6, 1e6]", "SetGravityScale");
    BodyDef bd;
    bd.type = BodyType::kDynamic;
    bd.shape = ShapeDef::MakeCircle(Real(0.5));
    bd.gravityScale = bad;
    ExpectRefusedWith(world, [&] { world.CreateBody(bd); }, "BodyDef.gravityScale must be finite and in [-1e6, 1e6]",
                      "CreateBody");
  }
  EXPECT_EQ(world.GetGravityScale(box), 1);
  world.SetGravityScale(box, Real(-1e6));  // the limit itself is accepted
  EXPECT_EQ(world.GetGravityScale(box), Real(-1e6));
}

// --- Determinism ---

TEST(BodyApiDeterminismTest, ForcesAndGravityScalesGiveTheSameStateForOneAndTwoThreads) {
  auto run = [](int threads) {
    WorldDef def;
    def.threadCount = threads;
    def.minParallelItems = 4;  // split every pass of these bodies
    World world(def);
    AddGround(world, 30);
    std::vector<BodyId> bodies;
    for (int k = 0; k < 160; ++k) {
      const Vec2 p{Real(-15 + (k % 20) * 1.5), Real(1 + (k / 20) * 1.2)};
      const BodyId id = k % 2 ? AddBox(world, p, Real(0.4), Real(0.4)) : AddCircle(world, p, Real(0.45));
      if (k % 3 == 0) world.SetGravityScale(id, Real(0.25) * Real(k % 7));
      bodies.push_back(id);
    }
    for (int step = 0; step < 90; ++step) {
      for (size_t k = 0; k < bodies.size(); k += 5) {
        const Real s = Real((step + int(k)) % 9) - 4;
        world.ApplyForce(bodies[k], {3 * s, 2 * s + 12}, world.GetWorldCenter(bodies[k]) + Vec2{Real(0.2), Real(0.1)});
        if (k % 10 == 0) world.ApplyTorque(bodies[k], s * Real(0.3));
      }
      world.Step(kDt);
    }
    return world.StateHash();
  };
  EXPECT_EQ(run(1), run(2));
}

// --- Fixed rotation ---

TEST(FixedRotationTest, NoSolverTurnsAFixedRotationBody) {
  for (SolverType solver : kSolvers) {
    SCOPED_TRACE(SolverName(solver));
    WorldDef def;
    def.solver = solver;
    World world(def);
    AddGround(world);
    BodyDef bd;
    bd.type = BodyType::kDynamic;
    bd.position = {0, 2};
    bd.angle = Real(0.4);  // lands on a corner
    bd.shape = ShapeDef::Box(Real(0.5), Real(0.5));
    bd.fixedRotation = true;
    const BodyId box = world.CreateBody(bd);
    const Real angle = world.GetAngle(box);
    EXPECT_EQ(world.GetRotationalInertia(box), 0);
    EXPECT_TRUE(world.IsFixedRotation(box));
    // A ball hits it off centre, and forces and impulses try to turn it.
    AddCircle(world, {-3, Real(2.6)}, Real(0.3), {12, 0});
    for (int k = 0; k < 90; ++k) {
      world.ApplyForce(box, {0, 5}, world.GetWorldCenter(box) + Vec2{Real(0.4), 0});
      world.ApplyTorque(box, 3);
      world.ApplyLinearImpulse(box, {0, Real(0.01)}, world.GetWorldCenter(box) + Vec2{Real(0.4), 0});
      world.ApplyAngularImpulse(box, 1);
      world.Step(kDt);
      ASSERT_EQ(world.GetAngularVelocity(box), 0) << "step " << k;
    }
    EXPECT_EQ(world.GetAngle(box), angle);
    EXPECT_LT(world.GetPosition(box).y, 1.2);  // it fell and rests on its corner
  }
}

TEST(FixedRotationTest, SetFixedRotationTogglesInertiaAndStopsTheSpin) {
  World world(NoGravityDef());
  const BodyId box = AddBox(world, {0, 0});
  const Real inertia = world.GetRotationalInertia(box);
  world.SetAngularVelocity(box, 2);
  world.SetFixedRotation(box, true);
  EXPECT_EQ(world.GetAngularVelocity(box), 0);
  EXPECT_EQ(world.GetRotationalInertia(box), 0);
  ExpectRefusedWith(world, [&] { world.SetAngularVelocity(box, 1); },
                    "SetAngularVelocity: the body has fixed rotation (its angular velocity stays 0)", "w on fixed");
  world.SetAngularVelocity(box, 0);  // 0 is fine
  world.SetFixedRotation(box, false);
  EXPECT_EQ(world.GetRotationalInertia(box), inertia);
  world.ApplyAngularImpulse(box, 1);
  EXPECT_NEAR(world.GetAngularVelocity(box), 1 / inertia, 1e-4);
  BodyDef bd;
  bd.type = BodyType::kDynamic;
  bd.shape = ShapeDef::MakeCircle(Real(0.5));
  bd.fixedRotation = true;
  bd.angularVelocity = 1;
  ExpectRefusedWith(world, [&] { world.CreateBody(bd); }, "BodyDef.angularVelocity must be 0 with fixedRotation", "def");
}

TEST(FixedRotationTest, StaysFixedThroughSleepAndWaking) {
  WorldDef def;
  def.effects.sleep = true;
  World world(def);
  AddGround(world);
  BodyDef bd;
  bd.type = BodyType::kDynamic;
  bd.position = {0, 1};
  bd.shape = ShapeDef::Box(Real(0.5), Real(0.5));
  bd.fixedRotation = true;
  const BodyId box = world.CreateBody(bd);
  StepN(world, 120);
  ASSERT_FALSE(world.IsAwake(box));
  world.SetAwake(box, true);
  world.ApplyLinearImpulse(box, {0, 1}, world.GetWorldCenter(box) + Vec2{Real(0.5), 0});
  EXPECT_EQ(world.GetAngularVelocity(box), 0);
  StepN(world, 10);
  EXPECT_EQ(world.GetAngle(box), 0);
}

// --- Bullets ---

// A thin static wall at x = 5 and a small ball fired at it at 300 m/s (5 m a step at 60 Hz).
struct WallShot {
  World world;
  BodyId ball;
  explicit WallShot(const WorldDef& def, bool bullet) : world(def) {
    BodyDef wall;
    wall.position = {5, 0};
    wall.shape = ShapeDef::Box(Real(0.05), 3);
    world.CreateBody(wall);
    BodyDef b;
    b.type = BodyType::kDynamic;
    b.position = {0, 0};
    b.linearVelocity = {300, 0};
    b.shape = ShapeDef::MakeCircle(Real(0.1));
    b.isBullet = bullet;
    ball = world.CreateBody(b);
  }
};

TEST(BulletTest, ABulletDoesNotTunnelWhereContinuousCollisionIsOff) {
  WorldDef def = NoGravityDef(SolverType::kSoftStep);
  def.effects.continuous = false;
  {
    WallShot plain(def, false);
    StepN(plain.world, 5);
    EXPECT_GT(plain.world.GetPosition(plain.ball).x, 6);  // through the wall
  }
  {
    WallShot shot(def, true);
    EXPECT_TRUE(shot.world.IsBullet(shot.ball));
    StepN(shot.world, 5);
    EXPECT_LT(shot.world.GetPosition(shot.ball).x, 5);  // stopped by the wall
  }
  {
    WallShot later(def, false);
    later.world.SetBullet(later.ball, true);
    StepN(later.world, 5);
    EXPECT_LT(later.world.GetPosition(later.ball).x, 5);
    later.world.SetBullet(later.ball, false);
    EXPECT_FALSE(later.world.IsBullet(later.ball));
  }
}

TEST(BulletTest, WithContinuousCollisionOnTheFlagChangesNothing) {
  const WorldDef def = NoGravityDef(SolverType::kSoftStep);  // effects.continuous on
  WallShot plain(def, false), bullet(def, true);
  for (int k = 0; k < 10; ++k) {
    plain.world.Step(kDt);
    bullet.world.Step(kDt);
    ASSERT_EQ(plain.world.StateHash(), bullet.world.StateHash());
  }
  EXPECT_LT(plain.world.GetPosition(plain.ball).x, 5);
}

// --- SetType ---

TEST(SetTypeTest, EveryChangeAsIfCreatedSo) {
  World world;
  AddGround(world);
  const BodyId box = AddBox(world, {0, 5});
  const Real mass = world.GetMass(box), inertia = world.GetRotationalInertia(box);
  StepN(world, 10);
  // Dynamic -> static: no mass, no velocity, stays put.
  world.SetType(box, BodyType::kStatic);
  EXPECT_EQ(world.GetType(box), BodyType::kStatic);
  EXPECT_EQ(world.GetMass(box), 0);
  EXPECT_EQ(world.GetRotationalInertia(box), 0);
  EXPECT_EQ(world.GetLinearVelocity(box), (Vec2{0, 0}));
  EXPECT_FALSE(world.IsAwake(box));
  const Vec2 p = world.GetPosition(box);
  StepN(world, 10);
  EXPECT_EQ(world.GetPosition(box), p);
  // Static -> kinematic: moves by its velocity, ignores gravity.
  world.SetType(box, BodyType::kKinematic);
  EXPECT_TRUE(world.IsAwake(box));
  world.SetLinearVelocity(box, {1, 0});
  StepN(world, 6);
  EXPECT_TRUE(VecNear(world.GetPosition(box), p + Vec2{Real(0.1), 0}, 1e-5));
  // Kinematic -> dynamic: the mass back, the velocity kept, gravity acts.
  world.SetType(box, BodyType::kDynamic);
  EXPECT_EQ(world.GetMass(box), mass);
  EXPECT_EQ(world.GetRotationalInertia(box), inertia);
  EXPECT_TRUE(VecNear(world.GetLinearVelocity(box), Vec2{1, 0}, 0));
  world.Step(kDt);
  EXPECT_NEAR(world.GetLinearVelocity(box).y, -10 * kDt, 1e-5);
  StepN(world, 120);
  EXPECT_NEAR(world.GetPosition(box).y, 1, 0.03);  // landed on the ground
  world.SetType(box, BodyType::kDynamic);  // no change
  EXPECT_EQ(world.GetMass(box), mass);
}

TEST(SetTypeTest, ABodyMadeStaticHoldsWhatLandsOnItAndOneMadeDynamicFalls) {
  World world;
  const BodyId ground = AddGround(world);
  const BodyId shelf = AddBox(world, {0, 3}, 2, Real(0.25));
  world.SetType(shelf, BodyType::kStatic);
  const BodyId box = AddBox(world, {0, 5});
  StepN(world, 120);
  EXPECT_NEAR(world.GetPosition(box).y, Real(3.75), 0.03);
  world.SetType(shelf, BodyType::kDynamic);
  StepN(world, 120);
  EXPECT_NEAR(world.GetPosition(shelf).y, Real(0.75), 0.03);
  EXPECT_NEAR(world.GetPosition(box).y, Real(1.5), 0.05);
  world.SetType(ground, BodyType::kKinematic);  // a kinematic ground still holds them
  StepN(world, 30);
  EXPECT_NEAR(world.GetPosition(box).y, Real(1.5), 0.05);
}

TEST(SetTypeTest, WakesWhatRestsOnIt) {
  WorldDef def;
  def.effects.sleep = true;
  def.contactEvents = true;
  World world(def);
  const BodyId ground = AddGround(world);
  const BodyId shelf = world.CreateBody([] {
    BodyDef d;
    d.position = {0, 3};
    d.shape = ShapeDef::Box(2, Real(0.25));
    return d;
  }());
  const BodyId box = AddBox(world, {0, Real(3.75)});
  StepN(world, 120);
  ASSERT_FALSE(world.IsAwake(box));
  world.SetType(shelf, BodyType::kDynamic);
  EXPECT_TRUE(world.IsAwake(box));
  EXPECT_TRUE(world.IsAwake(shelf));
  StepN(world, 120);
  EXPECT_NEAR(world.GetPosition(box).y, Real(1.5), 0.05);
  // The shelf made static on the ground: it touches no dynamic body there; its touch with the
  // ground ends instead of lasting forever as a static pair.
  world.SetAwake(box, true);
  world.SetType(shelf, BodyType::kStatic);
  bool ended = false;
  for (int k = 0; k < 3; ++k) {
    world.Step(kDt);
    for (const ContactEvent& e : world.GetContactEndEvents()) {
      ended = ended || ((e.bodyA == ground || e.bodyB == ground) && (e.bodyA == shelf || e.bodyB == shelf));
    }
  }
  EXPECT_TRUE(ended);
}

TEST(SetTypeTest, RefusesWhatCreateBodyRefuses) {
  World world;
  BodyDef def;
  def.position = {0, 1};
  def.shape = ShapeDef::Box(1, 1);
  def.shape.density = 0;
  const BodyId id = world.CreateBody(def);  // static, density 0
  ExpectRefusedWith(world, [&] { world.SetType(id, BodyType::kDynamic); },
                    "SetType: a dynamic body needs ShapeDef.density > 0 (SetDensity first)", "density 0");
  ExpectRefusedWith(world, [&] { world.SetType(id, static_cast<BodyType>(7)); }, "SetType: the type is unknown", "type 7");
  world.SetDensity(id, Real(3e38));  // a static body keeps any finite density
  ExpectRefusedWith(world, [&] { world.SetType(id, BodyType::kDynamic); },
                    "SetType: the body's mass or rotational inertia is not a positive finite number (density 3e+38)",
                    "mass overflows");
  world.SetDensity(id, 2);
  world.SetType(id, BodyType::kDynamic);
  EXPECT_NEAR(world.GetMass(id), 8, 1e-5);
  const BodyId doomed = AddCircle(world, {5, 5});
  world.DestroyBody(doomed);
  ExpectRefusedWith(world, [&] { world.SetType(doomed, BodyType::kStatic); }, "stale or invalid BodyId", "stale");
}

// --- Gravity ---

TEST(WorldGravityTest, SetGravityActsAtTheNextStepAndWakesSleepers) {
  WorldDef def;
  def.effects.sleep = true;
  World world(def);
  AddGround(world);
  const BodyId box = AddBox(world, {0, 1});
  StepN(world, 120);
  ASSERT_FALSE(world.IsAwake(box));
  EXPECT_EQ(world.GetGravity(), (Vec2{0, -10}));
  world.SetGravity({0, 10});
  EXPECT_EQ(world.GetGravity(), (Vec2{0, 10}));
  EXPECT_EQ(world.GetDef().gravity, (Vec2{0, 10}));
  EXPECT_TRUE(world.IsAwake(box));
  StepN(world, 30);
  EXPECT_GT(world.GetPosition(box).y, 2);
  ExpectRefusedWith(world, [&] { world.SetGravity({kNaN, 0}); }, "SetGravity: gravity is not finite", "NaN");
  ExpectRefusedWith(world, [&] { world.SetGravity({0, -kInf}); }, "SetGravity: gravity is not finite", "inf");
  EXPECT_EQ(world.GetGravity(), (Vec2{0, 10}));
}

// --- Materials ---

TEST(MaterialTest, FrictionAndRestitutionTakeEffectAtTheNextStep) {
  WorldDef def;
  World world(def);
  // A slope of 0.3 rad: tan = 0.31, below sqrt(0.6 * 0.6) friction, so the box holds. The box
  // sits on it, 1 cm above its surface.
  BodyDef slope;
  slope.angle = Real(0.3);
  slope.shape = ShapeDef::Box(10, Real(0.5));
  const BodyId ramp = world.CreateBody(slope);
  const Vec2 normal{-std::sin(Real(0.3)), std::cos(Real(0.3))};
  const BodyId box = AddBox(world, Real(1.01) * normal, Real(0.5), Real(0.5), 1, Real(0.3));
  StepN(world, 60);
  const Vec2 held = world.GetPosition(box);
  StepN(world, 30);
  EXPECT_LT(Length(world.GetPosition(box) - held), 0.01);
  world.SetFriction(box, 0);
  world.SetFriction(ramp, 0);
  EXPECT_EQ(world.GetShape(box).friction, 0);
  StepN(world, 60);
  EXPECT_GT(Length(world.GetPosition(box) - held), 0.5);

  World bounce;
  const BodyId floor = AddGround(bounce);
  const BodyId ball = AddCircle(bounce, {0, 3});
  bounce.SetRestitution(ball, 1);
  bounce.SetRestitution(floor, 1);
  EXPECT_EQ(bounce.GetShape(ball).restitution, 1);
  Real highest = 0;
  bool landed = false;
  for (int k = 0; k < 150; ++k) {
    bounce.Step(kDt);
    landed = landed || bounce.GetLinearVelocity(ball).y > 0;
    if (landed) highest = std::max(highest, bounce.GetPosition(ball).y);
  }
  EXPECT_GT(highest, 2.5);  // bounced back up most of the way
}

TEST(MaterialTest, DensityRecomputesMassAndInertia) {
  World world;
  AddGround(world);
  const BodyId box = AddBox(world, {0, 5});
  const Real mass = world.GetMass(box), inertia = world.GetRotationalInertia(box);
  const Vec2 center = world.GetWorldCenter(box);
  world.SetDensity(box, 3);
  EXPECT_NEAR(world.GetMass(box), 3 * mass, 1e-5);
  EXPECT_NEAR(world.GetRotationalInertia(box), 3 * inertia, 1e-5);
  EXPECT_EQ(world.GetWorldCenter(box), center);
  EXPECT_EQ(world.GetShape(box).density, 3);
  world.ApplyLinearImpulse(box, {3, 0}, center);
  EXPECT_NEAR(world.GetLinearVelocity(box).x, 1, 1e-5);
  StepN(world, 120);
  EXPECT_NEAR(world.GetPosition(box).y, 1, 0.03);
}

TEST(MaterialTest, BadMaterialsAreRefused) {
  World world;
  const BodyId ground = AddGround(world);
  const BodyId box = AddBox(world, {0, 2});
  StepN(world, 3);
  for (Real bad : {kNaN, kInf, Real(-0.1)}) {
    ExpectRefusedWith(world, [&] { world.SetFriction(box, bad); }, "SetFriction: friction must be finite and >= 0", "friction");
    ExpectRefusedWith(world, [&] { world.SetDensity(ground, bad); }, "SetDensity: density must be finite and >= 0", "density");
  }
  for (Real bad : {kNaN, Real(-0.1), Real(1.01)}) {
    ExpectRefusedWith(world, [&] { world.SetRestitution(box, bad); }, "SetRestitution: restitution must be in [0, 1]",
                      "restitution");
  }
  ExpectRefusedWith(world, [&] { world.SetDensity(box, 0); }, "SetDensity: a dynamic body needs density > 0", "0 dynamic");
  ExpectRefusedWith(world, [&] { world.SetDensity(box, Real(1e-40)); },
                    "SetDensity: the body's mass or rotational inertia is not a positive finite number", "denormal");
  const BodyId big = AddBox(world, {10, 3}, 2, 2);  // 16 m^2: 3e38 kg/m^2 overflows its mass
  ExpectRefusedWith(world, [&] { world.SetDensity(big, Real(3e38)); },
                    "SetDensity: the body's mass or rotational inertia is not a positive finite number (density 3e+38)",
                    "overflow");
  world.SetDensity(ground, 0);  // a static body may have density 0
  EXPECT_EQ(world.GetMass(ground), 0);
  const BodyId doomed = AddCircle(world, {5, 5});
  world.DestroyBody(doomed);
  const std::string stale = "stale or invalid BodyId";
  ExpectRefusedWith(world, [&] { world.SetFriction(doomed, 1); }, stale, "SetFriction");
  ExpectRefusedWith(world, [&] { world.SetRestitution(doomed, 1); }, stale, "SetRestitution");
  ExpectRefusedWith(world, [&] { world.SetDensity(doomed, 1); }, stale, "SetDensity");
  ExpectRefusedWith(world, [&] { world.SetGravityScale(doomed, 1); }, stale, "SetGravityScale");
  ExpectRefusedWith(world, [&] { (void)world.GetGravityScale(doomed); }, stale, "GetGravityScale");
  ExpectRefusedWith(world, [&] { world.SetFixedRotation(doomed, true); }, stale, "SetFixedRotation");
  ExpectRefusedWith(world, [&] { (void)world.IsFixedRotation(doomed); }, stale, "IsFixedRotation");
  ExpectRefusedWith(world, [&] { world.SetBullet(doomed, true); }, stale, "SetBullet");
  ExpectRefusedWith(world, [&] { (void)world.IsBullet(doomed); }, stale, "IsBullet");
}

// --- Documentation checks: GetBodyIds order, ContactInfo impulses ---

TEST(BodyApiDocsTest, GetBodyIdsMovesTheLastBodyIntoADestroyedOnesPlace) {
  World world;
  std::vector<BodyId> ids;
  for (int k = 0; k < 5; ++k) ids.push_back(AddCircle(world, {Real(2 * k), 0}));
  EXPECT_EQ(world.GetBodyIds(), ids);  // creation order
  world.DestroyBody(ids[1]);
  EXPECT_EQ(world.GetBodyIds(), (std::vector<BodyId>{ids[0], ids[4], ids[2], ids[3]}));
}

TEST(BodyApiDocsTest, ContactImpulsesAreTheLastSubStepsUnderSoftStepAndTheStepsUnderPgs) {
  for (SolverType solver : {SolverType::kPgs, SolverType::kSoftStep}) {
    SCOPED_TRACE(SolverName(solver));
    WorldDef def;
    def.solver = solver;
    World world(def);
    AddGround(world);
    const BodyId box = AddBox(world, {0, 1});  // 1 kg
    StepN(world, 120);
    Real total = 0;
    for (const ContactInfo& c : world.GetContacts()) {
      for (int k = 0; k < c.pointCount; ++k) total += c.normalImpulses[k];
    }
    const double weightOverStep = world.GetMass(box) * 10.0 * kDt;
    const double expected = solver == SolverType::kSoftStep ? weightOverStep / def.softSubSteps : weightOverStep;
    EXPECT_NEAR(total, expected, 0.02 * expected);
  }
}

}  // namespace
}  // namespace quadrant
