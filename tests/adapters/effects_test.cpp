// Effects switched through the scene API, on every engine that accepts them:
//   - damping acts by the scene's law, v *= 1 / (1 + dt c) per step, on all four engines (Bullet
//     and Chipmunk have other laws; their adapters convert the rates);
//   - an effect switched off gives the same motion as a scene that does not need it (the values
//     it would act on set to zero), so "off" really removes the effect and nothing else.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "adapter.h"
#include "quadrant/error.h"
#include "scenes.h"

namespace quadrant::scene {
namespace {

constexpr double kDt = 1.0 / 60.0;

BodyDesc Box(Vec2 position, Real half, bool dynamic) { return MakeBoxBody(position, half, half, dynamic); }

std::vector<BodyState> RunScene(const std::string& engine, const Scene& s, int steps) {
  auto a = MakeAdapter(engine);
  a->Load(s, 1);
  for (int i = 0; i < steps; ++i) a->Step();
  std::vector<BodyState> out;
  a->ReadBodies(out);
  return out;
}

class EngineEffects : public ::testing::TestWithParam<std::string> {};

// A free box in zero gravity, moving and spinning: after n steps its speeds are the start
// speeds times (1 / (1 + dt c))^n. Linear and angular rates are equal because Chipmunk has one
// rate for both.
TEST_P(EngineEffects, DampingFollowsTheSceneLaw) {
  Scene s;
  s.name = "damped";
  s.gravity = {0, 0};
  s.effects.gravity = false;
  s.effects.damping = true;
  BodyDesc b = Box({0, 0}, Real(0.5), true);
  b.velocity = {3, -1};
  b.angularVelocity = 2;
  b.linearDamping = Real(0.7);
  b.angularDamping = Real(0.7);
  s.bodies = {b};
  s.bounds = AABB{{-100, -100}, {100, 100}};
  const int n = 60;
  const std::vector<BodyState> st = RunScene(GetParam(), s, n);
  const double f = std::pow(1.0 / (1.0 + kDt * 0.7), n);  // 0.50: a clear effect
  // 1e-4 relative: float32 rounding of 60 multiplications (and Bullet's pow).
  EXPECT_NEAR(st[0].velocity.x, 3 * f, 3e-4) << GetParam();
  EXPECT_NEAR(st[0].velocity.y, -1 * f, 1e-4) << GetParam();
  EXPECT_NEAR(st[0].angularVelocity, 2 * f, 2e-4) << GetParam();
  // And the same scene with the flag off keeps the speeds: the values alone do nothing.
  s.effects.damping = false;
  const std::vector<BodyState> off = RunScene(GetParam(), s, n);
  EXPECT_NEAR(off[0].velocity.x, 3, 1e-5) << GetParam();
  EXPECT_NEAR(off[0].angularVelocity, 2, 1e-5) << GetParam();
}

// A small pile (boxes dropped on a ramp of ground) that exercises contacts, friction, bounces
// and rotation. Each row switches one effect off in scene A and removes what the effect would
// act on in scene B (with the effect on); both must move identically.
struct OffCase {
  const char* name;
  void (*off)(Scene&);     // scene A: the effect's flag off
  void (*absent)(Scene&);  // scene B: flag on, nothing for it to act on
};

Scene Pile() {
  Scene s;
  s.name = "pile";
  s.effects.continuous = false;
  s.restitutionThreshold = Real(0.5);
  BodyDesc ground = Box({0, -1}, 1, false);
  ground.angle = Real(0.2);
  ground.friction = Real(0.4);
  s.bodies.push_back(ground);
  for (int k = 0; k < 6; ++k) {
    BodyDesc b = Box({Real(-0.6 + 0.25 * k), Real(1.0 + 1.1 * k)}, Real(0.3), true);
    b.angle = Real(0.1 * k);
    b.velocity = {Real(0.5), Real(-2)};  // moving even where gravity is off
    b.friction = Real(0.5);
    b.restitution = Real(0.3);
    b.linearDamping = Real(0.2);
    b.angularDamping = Real(0.2);
    s.bodies.push_back(b);
  }
  s.bounds = AABB{{-20, -20}, {20, 20}};
  return s;
}

const OffCase kOffCases[] = {
    {"gravity", [](Scene& s) { s.effects.gravity = false; }, [](Scene& s) { s.gravity = {0, 0}; }},
    {"friction", [](Scene& s) { s.effects.friction = false; },
     [](Scene& s) {
       for (BodyDesc& b : s.bodies) b.friction = 0;
     }},
    {"restitution", [](Scene& s) { s.effects.restitution = false; },
     [](Scene& s) {
       for (BodyDesc& b : s.bodies) b.restitution = 0;
     }},
    {"damping", [](Scene& s) { s.effects.damping = false; },
     [](Scene& s) {
       for (BodyDesc& b : s.bodies) b.linearDamping = b.angularDamping = 0;
     }},
};

// The two scenes of a row: A with the effect's flag off, B with nothing for it to act on.
struct OffPair {
  Scene base, a, b;
};
OffPair MakeOffPair(const OffCase& c) {
  OffPair p;
  p.base = Pile();
  p.base.effects.damping = true;
  p.a = p.base;
  p.b = p.base;
  c.off(p.a);
  c.absent(p.b);
  return p;
}

TEST_P(EngineEffects, EffectOffEqualsSceneWithoutIt) {
  const std::string engine = GetParam();
  for (const OffCase& c : kOffCases) {
    const auto [base, a, b] = MakeOffPair(c);
    std::vector<BodyState> sa, sb;
    try {
      sa = RunScene(engine, a, 90);
      sb = RunScene(engine, b, 90);
    } catch (const Unsupported& e) {
      // Chipmunk: the pile's ground is static, its boxes share one rate, so damping is
      // accepted; nothing here should be refused.
      ADD_FAILURE() << engine << " refused " << c.name << ": " << e.what();
      continue;
    }
    ASSERT_EQ(sa.size(), sb.size());
    // The pile moved (so the comparison is not of two bodies at rest).
    EXPECT_GT(std::abs(double(sa[6].position.y) - double(base.bodies[6].position.y)), 0.5) << engine << " " << c.name;
    for (size_t i = 0; i < sa.size(); ++i) {
      // Same operations on the same numbers: equal to round-off (peers may compute a zero
      // term where the flag skips it; 1e-5 m is float32 round-off at these sizes).
      EXPECT_NEAR(sa[i].position.x, sb[i].position.x, 1e-5) << engine << " " << c.name << " body " << i;
      EXPECT_NEAR(sa[i].position.y, sb[i].position.y, 1e-5) << engine << " " << c.name << " body " << i;
      EXPECT_NEAR(sa[i].angle, sb[i].angle, 1e-5) << engine << " " << c.name << " body " << i;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(All, EngineEffects, ::testing::Values("quadrant", "box2d", "bullet", "chipmunk"),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });

// Quadrant: an effect off runs a path without it, yet lands on the same bits as the same
// world with nothing for the effect to act on.
TEST(QuadrantEffects, EffectOffIsBitIdenticalToSceneWithoutIt) {
  for (const OffCase& c : kOffCases) {
    const OffPair p = MakeOffPair(c);
    auto qa = MakeAdapter("quadrant"), qb = MakeAdapter("quadrant");
    qa->Load(p.a, 1);
    qb->Load(p.b, 1);
    for (int i = 0; i < 90; ++i) {
      qa->Step();
      qb->Step();
    }
    EXPECT_EQ(qa->StateHash(), qb->StateHash()) << c.name;
  }
}

TEST(QuadrantEffects, NegativeOrNanDampingIsRefused) {
  for (Real bad : {Real(-1), Real(std::nan(""))}) {
    Scene s = Pile();
    s.bodies[1].linearDamping = bad;
    auto q = MakeAdapter("quadrant");
    EXPECT_THROW(q->Load(s, 1), quadrant::Error);
    s.bodies[1].linearDamping = 0;
    s.bodies[2].angularDamping = bad;
    EXPECT_THROW(q->Load(s, 1), quadrant::Error);
  }
}

TEST(ChipmunkEffects, UnequalDampingIsUnsupported) {
  Scene s = Pile();
  s.effects.damping = true;
  s.bodies[3].linearDamping = Real(0.9);
  EXPECT_THROW(MakeAdapter("chipmunk")->Load(s, 1), Unsupported);
}

}  // namespace
}  // namespace quadrant::scene
