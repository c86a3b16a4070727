// The causes of large differences in the random campaign (benchmarks/scenes/random_hit_causes.h,
// issue #31): one reproducer per cause, each a hit of the committed 10-seed campaign where a
// Box2D-compatible setting differs from Box2D by more than 5 % and the rules name that cause; the
// ambiguity rule on a hit it sets apart and on one it does not; the perturbations and the mirror
// the rules rely on. A change to a solver or to the rules that moves one of these hits to another
// cause, or below 5 %, fails here; the report (tools/quadrant validate --random 200) lists them all.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "quadrant/error.h"
#include "random_hit_causes.h"

namespace quadrant::scene {
namespace {

// The settings named Box2D-compatible before issue #31's contact switches: the reproducers below
// are their differences, and the hits that the switches took below 5 % are checked further down.
constexpr const char* kPgs = "quadrant:pgs+b2rest+b2skin";
constexpr const char* kSoftStep = "quadrant:soft_step+b2rest+b2skin+relax4+relaxfriction";
// The Box2D-compatible settings (CompatibleRuns): those with Box2D 2.4.1's contacts, touching
// points only (nospec) and its polygon clip (b2clip), and with its position pass's geometry
// (b2possolve); the thesis's with its two-point block (block), soft_step's with 32 relax passes
// (kSoftStepContacts and kSoftStepPositions are its steps there).
constexpr const char* kPgsCompatible = "quadrant:pgs+b2rest+b2skin+nospec+b2clip+b2possolve";
constexpr const char* kSoftStepContacts = "quadrant:soft_step+b2rest+b2skin+relax4+relaxfriction+nospec+b2clip";
constexpr const char* kSoftStepPositions = "quadrant:soft_step+b2rest+b2skin+relax4+relaxfriction+nospec+b2clip+b2possolve";
constexpr const char* kSoftStepCompatible = "quadrant:soft_step+b2rest+b2skin+relax32+relaxfriction+nospec+b2clip+b2possolve";
constexpr const char* kThesisContacts = "quadrant:thesis+coupled+points+b2skin+b2pos+accum+passes8+nospec+b2clip";

struct Reproducer {
  HitCause cause;
  uint64_t seed;
  int index;
  const char* engine;
};

// The first hit of each cause in the campaign (pgs's where it has one).
constexpr Reproducer kReproducers[] = {
    {HitCause::kRestitutionThreshold, 22, 148, kPgs},  // polygon-polygon e=0.5, a second point at ~1 m/s
    {HitCause::kRecontact, 19, 45, kPgs},              // polygon-polygon e=0, a second impact
    {HitCause::kSpeculative, 17, 187, kPgs},           // circle-polygon e=1, a graze Box2D never touches
    {HitCause::kSkin, 17, 101, kPgs},                  // polygon-polygon e=1, 1 point in Box2D, 2 in pgs
    {HitCause::kPointOrder, 24, 120, kSoftStep},       // polygon-polygon e=0.5
    {HitCause::kSimultaneous, 17, 71, kPgs},           // polygon-polygon e=1, two points in both
    {HitCause::kSolver, 19, 169, kPgs},                // circle-polygon e=1, one point throughout
};

TEST(RandomHitCauses, EachCauseHasAReproducer) {
  for (HitCause cause : kAllCauses) {
    bool found = false;
    for (const Reproducer& r : kReproducers) found = found || r.cause == cause;
    EXPECT_TRUE(found) << CauseName(cause);
  }
}

TEST(RandomHitCauses, ReproducersDifferAboveFivePercentForTheirCause) {
  for (const Reproducer& r : kReproducers) {
    SCOPED_TRACE("seed " + std::to_string(r.seed) + " hit " + std::to_string(r.index) + " " + r.engine);
    const RandomHit hit = MakeRandomHit(r.seed, r.index);
    const CauseDiagnosis d = DiagnoseHit(hit, r.engine);
    EXPECT_GT(d.difference, kCauseThreshold);
    EXPECT_EQ(CauseName(d.cause), CauseName(r.cause));
    // The same difference the campaign measures.
    EXPECT_NEAR(d.difference, VelocityDifference(hit, RunRandomHit(hit, r.engine).final, RunRandomHit(hit, "box2d").final),
                1e-12);
  }
}

// The causes that remain in the compatible settings, one hit each (speculative contact, skin and
// order of points have none left in the 10-seed campaign).
constexpr Reproducer kCompatibleReproducers[] = {
    {HitCause::kRestitutionThreshold, 19, 119, kSoftStepCompatible},  // polygon-polygon e=0.5
    {HitCause::kRecontact, 19, 45, kPgsCompatible},                   // polygon-polygon e=0, a second impact
    {HitCause::kSimultaneous, 22, 122, kSoftStepCompatible},          // polygon-polygon e=1
    {HitCause::kSolver, 19, 169, kPgsCompatible},                     // circle-polygon e=1, one point throughout
};

TEST(RandomHitCauses, CompatibleSettingsReproducersDifferAboveFivePercentForTheirCause) {
  for (const Reproducer& r : kCompatibleReproducers) {
    SCOPED_TRACE("seed " + std::to_string(r.seed) + " hit " + std::to_string(r.index) + " " + r.engine);
    const CauseDiagnosis d = DiagnoseHit(MakeRandomHit(r.seed, r.index), r.engine);
    EXPECT_GT(d.difference, kCauseThreshold);
    EXPECT_EQ(CauseName(d.cause), CauseName(r.cause));
  }
}

// Each contact switch's effect, one hit per behaviour: a difference above 5 % in the earlier
// setting that the switch alone takes below 1 % (the campaign's figures, issue #31).
struct SwitchReproducer {
  uint64_t seed;
  int index;
  const char* before;
  const char* after;
};
constexpr SwitchReproducer kSwitchReproducers[] = {
    // b2clip: Box2D holds the mover's vertex alone; clipped at the face's end, pgs also held the
    // incident edge's far end 1.6 cm off the face (the old "skin" cause, 12.7 %).
    {17, 101, "quadrant:pgs+b2rest+b2skin", "quadrant:pgs+b2rest+b2skin+b2clip"},
    // b2clip: two points in both, the second one 0.02 m further along the edge in Box2D (the old
    // "simultaneous points" cause, 6.8 %).
    {17, 71, "quadrant:pgs+b2rest+b2skin", "quadrant:pgs+b2rest+b2skin+b2clip"},
    // nospec: a speculative point beyond the circle's reach pushed a step before Box2D's contact
    // existed (the old "speculative contact" cause, 8.5 %).
    {22, 182, "quadrant:pgs+b2rest+b2skin", "quadrant:pgs+b2rest+b2skin+nospec"},
    // nospec: a spinning corner's graze, 23.2 % (named "solver difference" before: one point in both).
    {22, 129, "quadrant:pgs+b2rest+b2skin", "quadrant:pgs+b2rest+b2skin+nospec"},
    // b2possolve: a circle sets the polygon spinning at 33 rad/s; Box2D's position pass measures
    // the circle against the face turned with the polygon and turns it back by 0.16 rad, where the
    // fixed normal did not (the old "skin" cause, 33.5 %).
    {34, 47, "quadrant:pgs+b2rest+b2skin+nospec+b2clip", "quadrant:pgs+b2rest+b2skin+nospec+b2clip+b2possolve"},
    // block: two points in both; one after the other, the thesis split the impulse unlike Box2D's
    // block solver (the old "simultaneous points" cause, 30.9 % and 32.2 %).
    {17, 71, kThesisContacts, "quadrant:thesis+coupled+points+b2skin+b2pos+accum+passes8+nospec+b2clip+block"},
    {18, 39, kThesisContacts, "quadrant:thesis+coupled+points+b2skin+b2pos+accum+passes8+nospec+b2clip+block"},
    // b2possolve on soft_step: a polygon spun up by the first contact meets the circle again; the
    // soft rows' push had left it 1 cm further on than Box2D's position pass, which measures the
    // circle against the turned face (the "re-contact" cause, 18.1 %).
    {23, 25, kSoftStepContacts, kSoftStepPositions},
    // relax32: two points in both; four relax passes one point after the other did not reach the
    // split of Box2D's block solver (the "simultaneous points" cause, 8.4 %).
    {17, 71, kSoftStepPositions, kSoftStepCompatible},
};

TEST(RandomHitCauses, ContactSwitchesTakeTheirHitsBelowOnePercent) {
  for (const SwitchReproducer& r : kSwitchReproducers) {
    SCOPED_TRACE("seed " + std::to_string(r.seed) + " hit " + std::to_string(r.index) + " " + r.after);
    const RandomHit hit = MakeRandomHit(r.seed, r.index);
    const std::vector<BodyState> box2d = RunRandomHit(hit, "box2d").final;
    EXPECT_GT(VelocityDifference(hit, RunRandomHit(hit, r.before).final, box2d), kCauseThreshold);
    EXPECT_LT(VelocityDifference(hit, RunRandomHit(hit, r.after).final, box2d), 0.01);
  }
}

TEST(RandomHitCauses, ReproducersAreNotAmbiguous) {
  // Box2D answers each of them the same way under the perturbations: the difference is the
  // solver's or the model's, not an accident of the start.
  for (const Reproducer& r : kReproducers) {
    EXPECT_LT(Box2dPerturbationSpread(MakeRandomHit(r.seed, r.index)), kAmbiguityTolerance)
        << "seed " << r.seed << " hit " << r.index;
  }
}

TEST(RandomHitCauses, AmbiguityRuleSetsApartAHitBox2dAnswersTwoWays) {
  // Seed 24, hit 119: Box2D's own response moves by about 8 % under a 1e-4 perturbation.
  EXPECT_GT(Box2dPerturbationSpread(MakeRandomHit(24, 119)), kAmbiguityTolerance);
}

TEST(RandomHitCauses, PerturbationsMoveTheMoverByOneTenThousandth) {
  const RandomHit hit = MakeRandomHit(17, 3);
  const std::vector<RandomHit> copies = PerturbedHits(hit);
  ASSERT_EQ(copies.size(), 6u);
  for (const RandomHit& c : copies) {
    const BodyDesc &a = hit.scene.bodies[0], &b = c.scene.bodies[0];
    const double moved = std::abs(double(b.position.x - a.position.x)) + std::abs(double(b.position.y - a.position.y)) +
                         std::abs(double(b.angle - a.angle));
    EXPECT_NEAR(moved, kPerturbation, 1e-6);
    EXPECT_EQ(c.scene.bodies[1].position, hit.scene.bodies[1].position);  // the target stays
  }
}

TEST(RandomHitCauses, MirroredHitGivesTheSameResponse) {
  // The mirror behind "order of points" changes nothing else: a one-point hit comes back with
  // the same velocities (float rounding aside), on Box2D and on Quadrant.
  const RandomHit hit = MakeRandomHit(17, 187);
  for (const char* engine : {"box2d", kPgs}) {
    const HitTrace plain = TraceRandomHit(hit, engine), mirrored = TraceRandomHit(hit, engine, true);
    EXPECT_LT(VelocityDifference(hit, mirrored.states.back(), plain.states.back()), 1e-4) << engine;
    EXPECT_GT(plain.touching[0], 0) << engine;  // they touch in the first step
  }
}

TEST(RandomHitCauses, CompatibleRunsAreTheThreeSolvers) {
  const std::vector<CampaignRun> runs = CompatibleRuns();
  ASSERT_EQ(runs.size(), 3u);
  EXPECT_EQ(runs[0].adapter, kPgsCompatible);
  EXPECT_EQ(runs[1].adapter, kSoftStepCompatible);
  EXPECT_EQ(runs[2].adapter, std::string(kThesisContacts) + "+block+b2possolve");
  EXPECT_THROW(DiagnoseHit(MakeRandomHit(17, 0), "box2d"), Error);
}

}  // namespace
}  // namespace quadrant::scene
