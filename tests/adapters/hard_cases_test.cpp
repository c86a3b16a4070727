// The hard cases on Quadrant: every case's criterion (benchmarks/scenes/hard_case_checks.cpp, the
// same code tools/quadrant hardcases runs, 60 s of simulated time per case) must pass, with the
// default engine (soft_step, all 34) and with pgs (the 13 older cases and the closed box); the
// closed box also with thesis and jacobi (issue #26: every solver comes to rest). The soak runs 3600 steps
// here (60 s, as every other case) instead of the tool's 100000, to keep the suite, which CI
// also runs under ASan, fast. Also: the scene builders' contracts (body counts, order, materials) and
// the penetration measure the criteria rely on.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <tuple>
#include <vector>

#include "hard_case_checks.h"
#include "quadrant/error.h"
#include "scenes.h"

namespace quadrant::scene {
namespace {

constexpr int kTestSoakSteps = 3600;

std::string Describe(const HardCaseResult& r) {
  std::string out = r.name + " on " + r.engine + ": " + r.criterion + "\n  measured:";
  for (const Measured& m : r.measured) out += " " + m.name + "=" + std::to_string(m.value);
  if (!r.supported) out += " unsupported: " + r.unsupported;
  return out;
}

double Figure(const HardCaseResult& r, const std::string& name) {
  for (const Measured& m : r.measured) {
    if (m.name == name) return m.value;
  }
  ADD_FAILURE() << r.name << " reports no " << name;
  return 0;
}

void ExpectPasses(const std::string& name, const std::string& engine) {
  HardCaseOptions options;
  options.soakSteps = kTestSoakSteps;
  const HardCaseResult r = RunHardCase(name, engine, options);
  EXPECT_TRUE(r.supported) << r.unsupported;
  EXPECT_FALSE(r.measured.empty());
  EXPECT_TRUE(r.pass) << Describe(r);
}

// Every case, the tall stacks included (issue #26 item 3: they toppled over the 60-s window until
// soft_step recycled its manifolds, kept loaded points soft past contactPushMaxDepth and
// alternated the order of a row's two points; docs/soft_step.md).
std::vector<std::string> DefaultCases() { return HardCaseNames(); }

void ExpectFails(const std::string& name, const std::string& engine) {
  HardCaseOptions options;
  options.soakSteps = kTestSoakSteps;
  const HardCaseResult r = RunHardCase(name, engine, options);
  EXPECT_TRUE(r.supported) << r.unsupported;
  EXPECT_FALSE(r.pass) << "now passes (move it back to the passing list): " << Describe(r);
}

// Issue #13's heavy cases are among them; the default engine (soft_step with two relax passes and
// the mass-ratio limit) holds all 32 over 60 s (issue #27's four joint cases and Solver2D's ten
// too).
class QuadrantHardCase : public ::testing::TestWithParam<std::string> {};

TEST_P(QuadrantHardCase, Passes) { ExpectPasses(GetParam(), "quadrant"); }

INSTANTIATE_TEST_SUITE_P(All, QuadrantHardCase, ::testing::ValuesIn(DefaultCases()),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });

// pgs (Box2D 2.4's method, the default engine before issue #13) on the older cases and the closed
// box, which it passes; issue #13's three it does not hold at the default budget (it topples the
// 30-box stack, the 1000 kg box sinks 0.197 m into its supports), nor, over 60 s, mass_ratio_400
// (the plank's penetration reaches 0.037 m, 0.02 allowed; it passed the old 10-s window).
// Issue #26 item 2's cases (Solver2D's contact scenes) are required of the default engine only.
bool IsSolver2dCase(const std::string& name) {
  for (const char* c : {"single_box", "warm_start_energy", "high_mass_ratio_1", "high_mass_ratio_2", "high_mass_ratio_3",
                        "rush", "double_domino", "circle_stack", "far_stack", "far_recovery"}) {
    if (name == c) return true;
  }
  return false;
}

std::vector<std::string> PgsCases() {
  std::vector<std::string> out;
  for (const std::string& name : HardCaseNames()) {
    if (name != "tall_stack" && name != "tall_stack_50" && name != "heavy_on_supports" && name != "heavy_on_slab" &&
        name != "mass_ratio_400" && name != "heavy_chain" && name != "ragdoll_pile" && name != "prismatic_stop" &&
        name != "weld_beam" && name != "wheel_terrain" && name != "hanging_grid" && !IsSolver2dCase(name)) {
      out.push_back(name);
    }
  }
  return out;
}

// Issue #26's "at its default budget": four scenes state a larger budget than the default engine's
// (vertical_stack and the mass ratios 16 or 32 velocity iterations, overlap_recovery 20 position
// iterations), which the adapter turns into more sub-steps. Forced to the engine's own 4 sub-steps
// they must pass too (at stop 34 vertical_stack and mass_ratio_100 did not: 0.145 and 0.106 m).
TEST(HardCases, CasesWithALargerStatedBudgetPassAtTheDefaultFourSubSteps) {
  for (const char* name : {"vertical_stack", "mass_ratio_100", "mass_ratio_400", "overlap_recovery"}) {
    ExpectPasses(name, "quadrant:sub4");
  }
}

TEST(HardCases, PgsKnownFailureOver60sStillFails) { ExpectFails("mass_ratio_400", "quadrant:pgs"); }

// Issue #27's joint cases: pgs solves no joints and says so; Box2D 2.4.1, Chipmunk and Bullet let
// the heavy chain fly apart (stretch 407, 185 and 234 times its length); Bullet's prismatic joint
// holds its stop.
TEST(HardCases, JointCasesOnPgsAreUnsupportedAndThePeersDropTheHeavyChain) {
  EXPECT_FALSE(RunHardCase("heavy_chain", "quadrant:pgs").supported);
  EXPECT_FALSE(RunHardCase("ragdoll_pile", "quadrant:pgs").supported);
  EXPECT_FALSE(RunHardCase("weld_beam", "quadrant:pgs").supported);
  EXPECT_FALSE(RunHardCase("weld_beam", "box2d").pass);
  EXPECT_FALSE(RunHardCase("weld_beam", "quadrant:soft_step+nochain").pass) << "joint by joint the beam droops";
  EXPECT_FALSE(RunHardCase("heavy_chain", "box2d").pass);
  EXPECT_FALSE(RunHardCase("heavy_chain", "chipmunk").pass);
  const auto bulletChain = RunHardCase("heavy_chain", "bullet");
  EXPECT_TRUE(bulletChain.supported);
  EXPECT_FALSE(bulletChain.pass);
  EXPECT_TRUE(RunHardCase("prismatic_stop", "bullet").pass);
  EXPECT_FALSE(RunHardCase("wheel_terrain", "quadrant:pgs").supported);
  EXPECT_FALSE(RunHardCase("wheel_terrain", "bullet").supported);
}

// Issue #27's joint grid that sags and settles. Joint by joint (`nochain`) the top joints, which
// hold the whole net of 0.5 kg circles, open by up to 0.056 m while it falls (0.05 allowed), and
// more sub-steps do not close them (0.054 m at 6 and 8); the default engine cuts the net into its
// rows and columns and solves each as a chain (WorldDef::jointChainSolve), and passes (DefaultCases).
TEST(HardCases, HangingGridOpensItsJointsWithoutTheLineSolve) {
  const HardCaseResult r = RunHardCase("hanging_grid", "quadrant:nochain");
  ASSERT_TRUE(r.supported) << r.unsupported;
  EXPECT_FALSE(r.pass) << Describe(r);
  EXPECT_GT(Figure(r, "max_joint_gap_m"), 0.05);
  EXPECT_LT(Figure(r, "ke_fraction_at_60s"), 0.01) << "it still comes to rest";
}

class QuadrantPgsHardCase : public ::testing::TestWithParam<std::string> {};

TEST_P(QuadrantPgsHardCase, Passes) { ExpectPasses(GetParam(), "quadrant:pgs"); }

INSTANTIATE_TEST_SUITE_P(All, QuadrantPgsHardCase, ::testing::ValuesIn(PgsCases()),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });


// soft_step with Box2D 3's settings (b3soft) at its default 4 sub-steps (not the larger budget the mass-ratio scenes state): the
// mass ratios fail their criteria there (a 30 Hz contact sags under 1000 N, and the plank creeps),
// but the heavy bodies must stay up. With the soft contacts' push-out capped at 0.015 m and no
// rigid rows below it the 100 kg box fell through the pyramid (heavy drift 12.2 m) and
// the plank's boxes sank into the ground (penetration 0.555 m). Measured: with no cap 0.076 m and
// 0.088 m; with rigid rows below 0.01 m 0.097 m and 0.060 m (the plank drifts 0.53 m sideways).
// (The box's penetration does not tell: 0.10 m with no cap, 0.092 m once it has fallen through.)
// Over the old 10-s window the box drifted less than 0.25 m and the plank sank less than 0.2 m.
// Over the 60-s window (issue #26) b3soft's box drifted 0.42 m and the plank reached 0.36 m of
// penetration (it crept sideways off its supports); with contact recycling, loaded points soft
// past the depth cap and the points' order alternated (issue #26 item 3) the box drifts 0.019 m
// and the plank's penetration stays at 0.092 m, within the old 10-s window's bounds again.
TEST(HardCases, SoftStepHoldsHeavyBodiesAtDefaultSubSteps) {
  const HardCaseResult box = RunHardCase("mass_ratio_100", "quadrant:soft_step+b3soft+sub4");
  EXPECT_LT(Figure(box, "heavy_drift_m"), 0.25) << Describe(box);
  const HardCaseResult plank = RunHardCase("mass_ratio_400", "quadrant:soft_step+b3soft+sub4");
  EXPECT_LT(Figure(plank, "max_penetration_m"), 0.2) << Describe(plank);
}

// Issue #26 item 4: every solver brings the closed box to rest; soft_step and pgs in their lists
// above, thesis and jacobi here. Both gained energy beyond the spawn's (at 60 s thesis 8.2 m/s and
// 15 % of the peak kinetic energy, jacobi 15.6 m/s and 35 %) until shock propagation stopped
// treating a lower body that moves toward an equal or heavier upper one as immovable (thesis) and
// penetration went to split impulses instead of a bias in the warm-started rows (jacobi);
// docs/solvers.md gives the figures since.
TEST(HardCases, ClosedBoxComesToRestOnThesisAndJacobi) {
  ExpectPasses("closed_box", "quadrant:thesis");
  ExpectPasses("closed_box", "quadrant:jacobi");
}

// Issue #26 item 2, found with Solver2D's high mass ratio 1 (400, 800 and 1200 kg boxes dropped on
// base-10 pyramids of 4 kg boxes): softMassRatioLimit used to act only where the light body touched
// a static one, so the pyramids' top boxes were "unsupported", their contacts with the heavy box
// went without warm start every step, and all three pyramids toppled within 35 s (a box drifted
// 5697 m; 16 sub-steps still 0.09 m). With support carried through the pile (PropagateSupport) the
// boxes move 0.0017 m. Without the limit (quadrant:ratio1000, warm start kept) the pile holds too but
// the heavy boxes sink 0.087 m into it (0.05 allowed), and Box2D 3's settings (b3soft) drift 0.11 m.
TEST(HardCases, HighMassRatio1NeedsSupportThroughThePile) {
  const HardCaseResult limitOff = RunHardCase("high_mass_ratio_1", "quadrant:ratio1000");
  EXPECT_FALSE(limitOff.pass) << Describe(limitOff);
  EXPECT_GT(Figure(limitOff, "max_penetration_m"), 0.05) << Describe(limitOff);
  EXPECT_LT(Figure(limitOff, "max_box_drift_m"), 0.05) << Describe(limitOff);
}

// The support carried through a pile is computed in a serial pass: the same state for any thread
// count.
TEST(HardCases, HighMassRatio1SameForAnyThreadCount) {
  const Scene scene = MakeHighMassRatio(1);
  uint64_t hashes[2] = {0, 0};
  for (int t = 0; t < 2; ++t) {
    auto adapter = MakeAdapter("quadrant");
    adapter->Load(scene, t + 1);
    for (int k = 0; k < 240; ++k) adapter->Step();
    hashes[t] = adapter->StateHash();
  }
  EXPECT_EQ(hashes[0], hashes[1]);
}

// What the new cases tell apart (measured at their making): Box2D 2.4.1 lets the 400 kg box of
// high mass ratio 2 and 3 crush its supports (its bottom 0.47 m below their top); Bullet, which has
// no segment, reports high_mass_ratio_2 unsupported; warm_start_energy's light balls fall through
// Bullet's ground under the 100:1 load.
TEST(HardCases, Solver2dCasesOnThePeers) {
  EXPECT_FALSE(RunHardCase("high_mass_ratio_2", "bullet").supported);
  EXPECT_FALSE(RunHardCase("high_mass_ratio_3", "box2d").pass);
  EXPECT_FALSE(RunHardCase("warm_start_energy", "bullet").pass);
  EXPECT_TRUE(RunHardCase("double_domino", "box2d").pass);
}

TEST(HardCases, NamesAndRegistry) {
  const std::vector<std::string> cases = HardCaseNames();
  EXPECT_EQ(cases.size(), 34u);
  // Every hard-case scene is in the registry under its case name (the soak is polygon_stress).
  const std::vector<std::string> scenes = SceneNames();
  for (const std::string& c : cases) {
    if (c == "soak") continue;
    EXPECT_NE(std::find(scenes.begin(), scenes.end(), c), scenes.end()) << c;
    const Scene s = MakeScene(c, 210, 42);
    EXPECT_EQ(s.name, c);
    EXPECT_NO_THROW(ValidateScene(s)) << c;
  }
  EXPECT_THROW(RunHardCase("no_such_case", "quadrant"), Error);
  EXPECT_THROW(RunHardCase("pyramid", "no_such_engine"), Error);
}

TEST(HardCases, ScenesAreValidUnderBothMixingRules) {
  for (Mixing m : {Mixing::kBox2d, Mixing::kProduct}) {
    for (const Scene& s : {MakeVerticalStack(15, m), MakePyramid(20, {}, m), MakeMassRatio(100, m),
                           MakeMassRatio(400, m), MakeArch(m), MakeCardHouse(5, m), MakeFrictionRamp(m),
                           MakeRestitutionDrop(m), MakeOverlapRecovery(10, m), MakeConfined(25, 42, m),
                           MakeFarFromOrigin(m), MakeNewtonsCradle(m), MakeTallStack(30, m), MakeTallStack(50, m),
                           MakeHeavyOnSupports(m), MakeHeavyOnSlab(m), MakeClosedBox(2000, 42, m), MakeSingleBox(m),
                           MakeWarmStartEnergy(m), MakeHighMassRatio(1, m), MakeHighMassRatio(2, m),
                           MakeHighMassRatio(3, m), MakeRush(m), MakeDoubleDomino(m), MakeCircleStack(m),
                           MakeFarStack(kFarStackOrigin, m), MakeFarStack({0, 0}, m),
                           MakeFarRecovery(kFarRecoveryOrigin, m), MakeFarRecovery({0, 0}, m), MakeWheelTerrain(m),
                           MakeHangingGrid(m)}) {
      EXPECT_NO_THROW(ValidateScene(s)) << s.name;
      EXPECT_EQ(s.timeStep, Real(1.0 / 60.0)) << s.name;
      // Box2D 2.4's defaults (8/3), except the cases that state the solver budget they need
      // (the same for every engine; see hard_cases.cpp and accuracy.md).
      const int velocity = s.name == "vertical_stack" || s.name == "mass_ratio_100" ? 16
                           : s.name == "mass_ratio_400"                              ? 32
                                                                                     : 8;
      EXPECT_EQ(s.velocityIterations, velocity) << s.name;
      EXPECT_EQ(s.positionIterations, s.name == "overlap_recovery" ? 20 : 3) << s.name;
      EXPECT_FALSE(s.effects.sleep) << s.name;
    }
  }
}

TEST(HardCases, BuildersKeepTheirContracts) {
  EXPECT_EQ(MakeVerticalStack().bodies.size(), 16u);
  EXPECT_EQ(MakePyramid(20).bodies.size(), 1u + 210u);
  EXPECT_EQ(MakePyramid(100).bodies.size(), 1u + 5050u);
  EXPECT_EQ(MakeScene("pyramid", 5050).bodies.size(), 1u + 5050u);  // count = boxes
  EXPECT_EQ(MakeScene("pyramid", 5100).bodies.size(), 1u + 5050u);  // rounds down to a full base
  EXPECT_EQ(MakeArch().bodies.size(), 1u + 17u);
  EXPECT_EQ(MakeCardHouse(5).bodies.size(), 1u + 40u);
  EXPECT_EQ(MakeConfined().bodies.size(), 4u + 625u);
  EXPECT_EQ(MakeClosedBox().bodies.size(), 4u + 2000u);
  EXPECT_EQ(MakeNewtonsCradle().bodies.size(), 5u);
  EXPECT_THROW(MakeMassRatio(7), Error);
  EXPECT_THROW(MakePyramid(0), Error);
  EXPECT_THROW(MakeScene("pyramid", 0), Error);
  // The apex is the last body of a pyramid; far from origin is the same pyramid shifted.
  const Scene near = MakePyramid(20), far = MakeFarFromOrigin();
  ASSERT_EQ(near.bodies.size(), far.bodies.size());
  EXPECT_NEAR(far.bodies.back().position.x - near.bodies.back().position.x, 1e5, 0.01);
  EXPECT_NEAR(far.bodies.back().position.y - near.bodies.back().position.y, -8e4, 0.01);
  EXPECT_NEAR(near.bodies.back().position.y, 19.5, 1e-4);
  // Mass ratios: 100 kg on 1 kg boxes, 400 kg on two 1 kg boxes.
  EXPECT_NEAR(ComputeMassProperties(MakeMassRatio(100).bodies.back()).mass, 100, 1e-3);
  EXPECT_NEAR(ComputeMassProperties(MakeMassRatio(400).bodies.back()).mass, 400, 1e-2);
  // Issue #13's cases: 30 aligned boxes, the top last; 1000 kg on 1 kg bodies.
  const Scene tall = MakeTallStack();
  ASSERT_EQ(tall.bodies.size(), 1u + 30u);
  EXPECT_EQ(tall.bodies.back().position.x, 0);
  EXPECT_NEAR(tall.bodies.back().position.y, 29.5, 1e-5);
  EXPECT_EQ(tall.name, "tall_stack");
  const Scene tall50 = MakeTallStack(50);
  ASSERT_EQ(tall50.bodies.size(), 1u + 50u);
  EXPECT_EQ(tall50.name, "tall_stack_50");
  EXPECT_NEAR(tall50.bodies.back().position.y, 49.5, 1e-5);
  const Scene supports = MakeHeavyOnSupports();
  ASSERT_EQ(supports.bodies.size(), 1u + 3u + 1u);
  EXPECT_NEAR(ComputeMassProperties(supports.bodies.back()).mass, 1000, 1e-2);
  EXPECT_NEAR(ComputeMassProperties(supports.bodies[1]).mass, 1, 1e-5);
  // Solver2D's scenes: body counts and the bodies the criteria name.
  EXPECT_EQ(MakeSingleBox().bodies.size(), 2u);
  const Scene warm = MakeWarmStartEnergy();
  ASSERT_EQ(warm.bodies.size(), 4u);
  EXPECT_NEAR(ComputeMassProperties(warm.bodies[3]).mass, 100 * ComputeMassProperties(warm.bodies[1]).mass, 1e-2);
  EXPECT_TRUE(bool(warm.driver));
  const Scene hmr1 = MakeHighMassRatio(1);
  ASSERT_EQ(hmr1.bodies.size(), 1u + 3 * 55u);
  for (int j = 0; j < 3; ++j) {
    EXPECT_NEAR(ComputeMassProperties(hmr1.bodies[size_t(55 * (j + 1))]).mass, 400 * (j + 1), 1e-2);
    EXPECT_NEAR(hmr1.bodies[size_t(55 * (j + 1))].position.y, 21, 1e-5);  // 2 m above its place
  }
  EXPECT_EQ(MakeHighMassRatio(2).bodies[0].shape, ShapeKind::kSegment);
  EXPECT_EQ(MakeHighMassRatio(3).bodies[0].shape, ShapeKind::kPolygon);
  EXPECT_NEAR(ComputeMassProperties(MakeHighMassRatio(3).bodies[3]).mass, 400, 1e-2);
  EXPECT_THROW(MakeHighMassRatio(4), Error);
  const Scene rush = MakeRush();
  EXPECT_EQ(rush.bodies.size(), 1u + size_t(kRushCount));
  EXPECT_FALSE(rush.bodies[0].dynamic);
  EXPECT_TRUE(bool(rush.driver));
  EXPECT_EQ(MakeDoubleDomino().bodies.size(), 1u + size_t(kDominoCount));
  EXPECT_GT(MakeDoubleDomino().bodies[1].velocity.x, 0);
  EXPECT_EQ(MakeCircleStack().bodies.size(), 1u + size_t(kCircleStackCount));
  // The far scenes are the near ones shifted.
  for (const auto& [nearScene, farScene, origin] :
       {std::tuple{MakeFarStack({0, 0}), MakeFarStack(kFarStackOrigin), kFarStackOrigin},
        std::tuple{MakeFarRecovery({0, 0}), MakeFarRecovery(kFarRecoveryOrigin), kFarRecoveryOrigin}}) {
    ASSERT_EQ(nearScene.bodies.size(), farScene.bodies.size());
    for (size_t i = 0; i < nearScene.bodies.size(); ++i) {
      EXPECT_NEAR(farScene.bodies[i].position.x - origin.x, nearScene.bodies[i].position.x, 0.01);
      EXPECT_NEAR(farScene.bodies[i].position.y - origin.y, nearScene.bodies[i].position.y, 0.01);
    }
  }
  EXPECT_EQ(MakeFarRecovery({0, 0}).bodies.size(), 1u + 10u);
  EXPECT_THROW(MakeFarStack({Real(INFINITY), 0}), Error);
  const Scene slab = MakeHeavyOnSlab();
  ASSERT_EQ(slab.bodies.size(), 3u);
  EXPECT_NEAR(ComputeMassProperties(slab.bodies[1]).mass, 1, 1e-5);
  EXPECT_NEAR(ComputeMassProperties(slab.bodies[2]).mass, 1000, 1e-2);
}

TEST(HardCases, MaterialsMixToTheIntendedCoefficients) {
  const Real want[5] = {Real(0.75), Real(0.5), Real(0.35), Real(0.1), 0};
  const Real es[5] = {0, Real(0.25), Real(0.5), Real(0.75), 1};
  for (Mixing m : {Mixing::kBox2d, Mixing::kProduct}) {
    const Scene ramp = MakeFrictionRamp(m);
    for (int k = 0; k < 5; ++k) {
      EXPECT_NEAR(MixFriction(m, ramp.bodies[2 * k + 1].friction, ramp.bodies[2 * k].friction), want[k], 1e-6);
    }
    const Scene drop = MakeRestitutionDrop(m);
    for (int k = 0; k < 5; ++k) {
      EXPECT_NEAR(MixRestitution(m, drop.bodies[k + 1].restitution, drop.bodies[0].restitution), es[k], 1e-6);
    }
    const Scene stack = MakeVerticalStack(15, m);
    EXPECT_NEAR(MixFriction(m, stack.bodies[1].friction, stack.bodies[2].friction), 0.3, 1e-6);
    EXPECT_NEAR(MixFriction(m, stack.bodies[0].friction, stack.bodies[1].friction), 0.3, 1e-6);
  }
  EXPECT_EQ(MixingOf("quadrant:thesis"), Mixing::kBox2d);
  EXPECT_EQ(MixingOf("chipmunk"), Mixing::kProduct);
  EXPECT_THROW(MixingOf("havok"), Error);
}

TEST(HardCases, SpawnGeometry) {
  // Touching spawns touch (no overlap), overlapping spawns overlap by what they say.
  auto pen = [](const Scene& s) {
    std::vector<BodyState> st(s.bodies.size());
    for (size_t i = 0; i < s.bodies.size(); ++i) st[i] = {s.bodies[i].position, s.bodies[i].angle, {}, 0};
    return MaxPenetration(s, st);
  };
  EXPECT_LT(pen(MakeVerticalStack()), 1e-5);
  EXPECT_LT(pen(MakePyramid(20)), 1e-5);
  EXPECT_LT(pen(MakeArch()), 1e-5);
  EXPECT_LT(pen(MakeCardHouse(5)), 1e-5);
  EXPECT_LT(pen(MakeFrictionRamp()), 1e-5);
  EXPECT_LT(pen(MakeNewtonsCradle()), 1e-5);
  EXPECT_LT(pen(MakeTallStack()), 1e-5);
  EXPECT_LT(pen(MakeTallStack(50)), 1e-5);
  EXPECT_LT(pen(MakeHeavyOnSupports()), 1e-5);
  EXPECT_LT(pen(MakeHeavyOnSlab()), 1e-5);
  EXPECT_LT(pen(MakeSingleBox()), 1e-5);
  EXPECT_LT(pen(MakeWarmStartEnergy()), 1e-5);
  EXPECT_LT(pen(MakeHighMassRatio(1)), 1e-5);
  EXPECT_LT(pen(MakeHighMassRatio(2)), 1e-5);
  EXPECT_LT(pen(MakeHighMassRatio(3)), 1e-5);
  EXPECT_LT(pen(MakeRush()), 1e-5);
  EXPECT_LT(pen(MakeDoubleDomino()), 1e-5);
  EXPECT_LT(pen(MakeCircleStack()), 1e-5);
  EXPECT_LT(pen(MakeFarStack({0, 0})), 1e-5);
  EXPECT_NEAR(pen(MakeFarRecovery({0, 0})), 0.25, 1e-5);
  EXPECT_NEAR(pen(MakeOverlapRecovery(10)), 0.25, 1e-5);
  EXPECT_NEAR(pen(MakeConfined()), 0.24, 0.01);  // 0.2 m on the grid, up to 0.04 m more from jitter
}

TEST(HardCases, PenetrationMeasure) {
  Scene s;
  BodyDesc box;
  box.shape = ShapeKind::kPolygon;
  box.vertices = {{Real(-0.5), Real(-0.5)}, {Real(0.5), Real(-0.5)}, {Real(0.5), Real(0.5)}, {Real(-0.5), Real(0.5)}};
  BodyDesc ball;
  ball.shape = ShapeKind::kCircle;
  ball.radius = Real(0.5);
  s.bodies = {box, box, ball, ball};
  std::vector<BodyState> st(4);
  st[0].position = {0, 0};
  st[1].position = {Real(0.3), Real(0.9)};   // 0.1 deep from above
  st[2].position = {Real(10), 0};
  st[3].position = {Real(10.7), 0};          // 0.3 deep
  EXPECT_NEAR(MaxPenetration(s, st), 0.3, 1e-5);
  st[3].position = {Real(11.2), 0};
  EXPECT_NEAR(MaxPenetration(s, st), 0.1, 1e-5);
  // A circle poking 0.05 into a box's corner region from the side.
  st[2].position = {Real(0.95), 0};
  st[3].position = {Real(20), 0};
  EXPECT_NEAR(MaxPenetration(s, st), 0.1, 1e-5);  // still the box pair; the circle is 0.05 in
  st[1].position = {Real(5), Real(5)};
  EXPECT_NEAR(MaxPenetration(s, st), 0.05, 1e-5);
  // Rotated: a box at 45 degrees resting on a corner 0.02 into the other box.
  st[2].position = {Real(30), 0};
  st[1].position = {0, Real(0.5 + std::sqrt(0.5) - 0.02)};
  st[1].angle = Real(0.785398163);
  EXPECT_NEAR(MaxPenetration(s, st), 0.02, 1e-5);
}

}  // namespace
}  // namespace quadrant::scene
