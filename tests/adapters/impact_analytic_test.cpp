// The analytic single-point impact (benchmarks/scenes/impact_analytic.cpp) against textbook
// answers: Newton's 1D collision, a disc that sticks (rolls off with 2/3 of its tangential speed,
// Routh), a disc that slides throughout (the tangential change is mu (1 + e) times the approach
// speed), a slender rod whose slip stops and reverses (Stronge's example), and a brute-force
// integration over the normal impulse in small increments that shares none of the phase logic.
#include <gtest/gtest.h>

#include <cmath>

#include "impact_analytic.h"
#include "scenes.h"

namespace quadrant::scene {
namespace {

ImpactBody Disc(double mass, double radius, double vx, double vy, double w, double rx, double ry) {
  ImpactBody b;
  b.invMass = 1 / mass;
  b.invInertia = 2 / (mass * radius * radius);
  b.vx = vx;
  b.vy = vy;
  b.w = w;
  b.rx = rx;
  b.ry = ry;
  return b;
}

ImpactBody Wall() { return ImpactBody{}; }

// The same impact integrated in 200000 small increments of normal impulse, with friction
// against the current slip (which chatters about zero where the exact answer sticks): a check
// that shares no phase logic with SolveImpact.
ImpactResult BruteForce(const ImpactInput& in) {
  ImpactResult r;
  r.a = in.a;
  r.b = in.b;
  auto contactVelocity = [&](double& un, double& ut) {
    const double ux = (r.b.vx - r.b.w * r.b.ry) - (r.a.vx - r.a.w * r.a.ry);
    const double uy = (r.b.vy + r.b.w * r.b.rx) - (r.a.vy + r.a.w * r.a.rx);
    un = ux * in.nx + uy * in.ny;
    ut = -ux * in.ny + uy * in.nx;
  };
  double un, ut;
  contactVelocity(un, ut);
  const double target = -in.restitution * un;
  const double dp = 1e-5 * std::abs(un) / (in.a.invMass + in.b.invMass);
  for (int i = 0; i < 10000000 && un < target; ++i) {
    const double pt = ut > 0 ? -in.friction * dp : ut < 0 ? in.friction * dp : 0;
    const double Px = dp * in.nx - pt * in.ny, Py = dp * in.ny + pt * in.nx;
    r.a.vx -= in.a.invMass * Px;
    r.a.vy -= in.a.invMass * Py;
    r.a.w -= in.a.invInertia * (in.a.rx * Py - in.a.ry * Px);
    r.b.vx += in.b.invMass * Px;
    r.b.vy += in.b.invMass * Py;
    r.b.w += in.b.invInertia * (in.b.rx * Py - in.b.ry * Px);
    contactVelocity(un, ut);
  }
  r.ok = true;
  return r;
}

TEST(ImpactAnalytic, HeadOnMatchesNewtonsFormula) {
  for (double ratio : {1.0, 3.0, 100.0}) {
    for (double e : {0.0, 0.5, 1.0}) {
      ImpactInput in;
      in.a = Disc(1, 0.5, 2, 0, 0, 0.5, 0);
      in.b = Disc(ratio, 0.5, 0, 0, 0, -0.5, 0);
      in.restitution = e;
      in.friction = 0.3;  // no slip, so no friction
      const ImpactResult r = SolveImpact(in);
      ASSERT_TRUE(r.ok) << r.why;
      const double m1 = 1, m2 = ratio;
      EXPECT_NEAR(r.a.vx, (m1 - e * m2) * 2 / (m1 + m2), 1e-12);
      EXPECT_NEAR(r.b.vx, (1 + e) * m1 * 2 / (m1 + m2), 1e-12);
      EXPECT_NEAR(r.a.w, 0, 1e-12);
      EXPECT_EQ(r.a.vy, 0);
    }
  }
}

// A disc (no spin) hits a wall obliquely with enough friction to stop its slip: the contact
// point ends at rest tangentially, which for a disc (I = m r^2 / 2) leaves 2/3 of the tangential
// speed, as a rolling ball off a cushion.
TEST(ImpactAnalytic, DiscSticksAndKeepsTwoThirds) {
  ImpactInput in;
  in.a = Wall();
  in.b = Disc(2, 0.4, 1.5, -3, 0, 0, -0.4);  // contact below the disc, normal up (from wall to disc)
  in.nx = 0;
  in.ny = 1;
  in.friction = 0.8;
  in.restitution = 0.5;
  const ImpactResult r = SolveImpact(in);
  ASSERT_TRUE(r.ok) << r.why;
  EXPECT_TRUE(r.stuck);
  EXPECT_FALSE(r.reversed);
  EXPECT_NEAR(r.b.vx, 1.0, 1e-12);
  EXPECT_NEAR(r.b.vy, 1.5, 1e-12);
  EXPECT_NEAR(r.finalSlip, 0, 1e-12);
  EXPECT_NEAR(r.b.vx - r.b.w * -0.4 * 1, 0, 1e-12);  // rolling: v = -w r_y ... contact point at rest
  EXPECT_LE(std::abs(r.tangentImpulse), in.friction * r.normalImpulse + 1e-12);
}

// Low friction: the disc slides throughout; its tangential speed drops by mu (1 + e) v_n.
TEST(ImpactAnalytic, DiscSlidesThroughout) {
  ImpactInput in;
  in.a = Wall();
  in.b = Disc(2, 0.4, 3, -2, 0, 0, -0.4);
  in.nx = 0;
  in.ny = 1;
  in.friction = 0.1;
  in.restitution = 1;
  const ImpactResult r = SolveImpact(in);
  ASSERT_TRUE(r.ok) << r.why;
  EXPECT_FALSE(r.stuck);
  EXPECT_NEAR(r.b.vy, 2, 1e-12);
  EXPECT_NEAR(r.b.vx, 3 - 0.1 * 2 * 2, 1e-12);
  // Angular impulse r x P with r = (0, -0.4) and P = (-0.8, 8): 0.4 * -0.8 = -0.32; 1/I = 6.25.
  EXPECT_NEAR(r.b.w, -0.32 * 6.25, 1e-12);
  EXPECT_LT(ImpactKineticEnergy(r.a, r.b), ImpactKineticEnergy(in.a, in.b));
}

// A slender rod (1 kg, 1 m, 45 degrees) strikes the ground with its end while slipping slowly:
// |K_tn| = 1.5 > mu K_tt = 0.75, so the slip stops during compression and restarts backwards.
TEST(ImpactAnalytic, RodSlipReverses) {
  const double c = std::cos(M_PI / 4), s = std::sin(M_PI / 4);
  ImpactInput in;
  in.a = Wall();
  in.b.invMass = 1;
  in.b.invInertia = 12;
  in.b.vx = 0.2;  // slipping towards +x, the way the impact's K_tn slows (slip the other way grows)
  in.b.vy = -1;
  in.b.rx = -0.5 * c;
  in.b.ry = -0.5 * s;
  in.nx = 0;
  in.ny = 1;
  in.friction = 0.3;
  in.restitution = 0.5;
  const ImpactResult r = SolveImpact(in);
  ASSERT_TRUE(r.ok) << r.why;
  EXPECT_TRUE(r.reversed);
  EXPECT_FALSE(r.stuck);
  EXPECT_GE(r.phases, 2);
  const ImpactResult f = BruteForce(in);
  EXPECT_NEAR(r.b.vx, f.b.vx, 1e-4);
  EXPECT_NEAR(r.b.vy, f.b.vy, 1e-4);
  EXPECT_NEAR(r.b.w, f.b.w, 1e-3);
}

// Random two-body impacts: the exact phase integration agrees with the brute-force one, Newton's
// law holds at the end, friction stays in its cone, and an inelastic impact never gains energy.
TEST(ImpactAnalytic, RandomImpactsAgreeWithBruteForce) {
  Random rng(17);
  int reversed = 0, stuck = 0, checked = 0;
  for (int i = 0; i < 200; ++i) {
    ImpactInput in;
    const double angle = rng.Uniform(0, 6.283185307);
    in.nx = std::cos(angle);
    in.ny = std::sin(angle);
    for (ImpactBody* b : {&in.a, &in.b}) {
      b->invMass = 1 / rng.Uniform(0.2, 20);
      b->invInertia = b->invMass / rng.Uniform(0.02, 0.3);
      b->vx = rng.Uniform(-4, 4);
      b->vy = rng.Uniform(-4, 4);
      b->w = rng.Uniform(-8, 8);
      b->rx = rng.Uniform(-0.5, 0.5);
      b->ry = rng.Uniform(-0.5, 0.5);
    }
    in.friction = rng.UniformInt(0, 2) * 0.3;
    in.restitution = rng.UniformInt(0, 2) * 0.5;
    const ImpactResult r = SolveImpact(in);
    if (!r.ok) continue;  // not approaching (about half) or a jam
    ++checked;
    reversed += r.reversed;
    stuck += r.stuck;
    const ImpactResult f = BruteForce(in);
    const double scale = r.approachSpeed + 1;
    EXPECT_NEAR(r.a.vx, f.a.vx, 2e-3 * scale) << i;
    EXPECT_NEAR(r.b.vy, f.b.vy, 2e-3 * scale) << i;
    EXPECT_NEAR(r.b.w, f.b.w, 2e-2 * scale) << i;
    EXPECT_LE(std::abs(r.tangentImpulse), in.friction * r.normalImpulse * (1 + 1e-9) + 1e-12) << i;
    if (in.restitution == 0) {
      EXPECT_LE(ImpactKineticEnergy(r.a, r.b), ImpactKineticEnergy(in.a, in.b) * (1 + 1e-12)) << i;
    }
    if (in.friction == 0 && in.restitution == 1) {
      EXPECT_NEAR(ImpactKineticEnergy(r.a, r.b), ImpactKineticEnergy(in.a, in.b), 1e-9) << i;
    }
  }
  EXPECT_GT(checked, 60);
  EXPECT_GT(stuck, 3);
  EXPECT_GT(reversed, 0);
}

TEST(ImpactAnalytic, RefusesBodiesThatDoNotApproach) {
  ImpactInput in;
  in.a = Wall();
  in.b = Disc(1, 0.5, 0, 1, 0, 0, -0.5);
  in.nx = 0;
  in.ny = 1;
  const ImpactResult r = SolveImpact(in);
  EXPECT_FALSE(r.ok);
  EXPECT_FALSE(r.why.empty());
}

}  // namespace
}  // namespace quadrant::scene
