// The random validation campaign (benchmarks/scenes/random_hits.cpp) on a fixed sample: 300 hits
// of seed 17 (under a second in a release build), the same code tools/quadrant validate --random
// runs. Bounds are the committed campaign's figures on this sample (docs/validation.md) with a
// margin of about a third, so a solver change that moves responses away from Box2D or from the
// analytic impact fails here; the Box2D-compatible settings of pgs, soft_step and thesis must stay
// below 1 % (issue #17).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "quadrant/error.h"
#include "quadrant/world.h"
#include "random_hits.h"

namespace quadrant::scene {
namespace {

const Campaign& Sample() {
  static const Campaign c = RunCampaign(17, 300, DefaultCampaignRuns());
  return c;
}

const CampaignRow& Find(const std::vector<CampaignRow>& rows, const std::string& cls, const std::string& engine,
                        const std::string& setting) {
  for (const CampaignRow& r : rows) {
    if (r.cls == cls && r.engine == engine && r.setting == setting) return r;
  }
  throw Error("no row " + cls + " / " + engine + " / " + setting);
}

TEST(RandomHits, HitsAreSeededAndStartInContactApproaching) {
  for (int i = 0; i < 50; ++i) {
    const RandomHit a = MakeRandomHit(17, i), b = MakeRandomHit(17, i);
    EXPECT_EQ(a.scene.bodies[0].position, b.scene.bodies[0].position);
    EXPECT_GE(a.speed, 2);
    EXPECT_LE(a.speed, 8);
    EXPECT_GE(a.massRatio, 1);
    EXPECT_LE(a.massRatio, 100);
    const ImpactResult r = AnalyticHit(a);
    EXPECT_GE(r.approachSpeed, 1.25 - 1e-4) << "hit " << i << " must approach above the 1 m/s threshold";
  }
  EXPECT_NE(MakeRandomHit(17, 0).scene.bodies[0].position, MakeRandomHit(18, 0).scene.bodies[0].position);
}

TEST(RandomHits, BadCampaignsAreRefused) {
  EXPECT_THROW(RunCampaign(17, 0, DefaultCampaignRuns()), Error);
  EXPECT_THROW(RunCampaign(17, 5, {{"quadrant:pgs", "default", "quadrant:pgs"}}), Error);
}

constexpr const char* kClasses[] = {"polygon-polygon e=0",   "polygon-polygon e=0.5", "polygon-polygon e=1",
                                    "circle-polygon e=0",    "circle-polygon e=0.5",  "circle-polygon e=1",
                                    "circle-circle e=0",     "circle-circle e=0.5",   "circle-circle e=1"};

TEST(RandomHits, Box2dCompatibleSettingStaysBelowOnePercent) {
  const std::vector<CampaignRow> rows = Sample().Box2dRows();
  const CampaignRow& compat = Find(rows, "all", "quadrant:pgs", "box2d_restitution+box2d_skin");
  EXPECT_EQ(compat.n, 300);
  EXPECT_LT(compat.p90, 0.01);
  // Restitution alone already brings the whole campaign below 1 %; the skin removes the polygon
  // classes that stay above 5 % without it.
  EXPECT_LT(Find(rows, "all", "quadrant:pgs", "box2d_restitution").p90, 0.012);
  for (const char* cls : kClasses) {
    // About 33 hits per class here: the 2000-hit campaign has every class below 2.1 %.
    EXPECT_LT(Find(rows, cls, "quadrant:pgs", "box2d_restitution+box2d_skin").p90, 0.1) << cls;
  }
}

TEST(RandomHits, Box2dContactsHoldEveryClassOfPgsBelowFivePercent) {
  // Issue #31: with Box2D 2.4.1's contacts too (touching points only, its polygon clip) pgs's
  // setting has every class below 5 % (the 10-seed campaign: worst class 2.31 % on its worst seed);
  // without them polygon-polygon classes reach 6.8-12.7 % on seed 17's hits 71, 101, 132.
  const std::vector<CampaignRow> rows = Sample().Box2dRows();
  const char* compat = "box2d_restitution+box2d_skin+touching+box2d_clip";
  EXPECT_LT(Find(rows, "all", "quadrant:pgs", compat).p90, 0.01);
  for (const char* cls : kClasses) EXPECT_LT(Find(rows, cls, "quadrant:pgs", compat).p90, 0.05) << cls;
  EXPECT_GT(Find(rows, "polygon-polygon e=1", "quadrant:pgs", "box2d_restitution+box2d_skin").p90, 0.05);
  // The class's largest difference left is hit 39 (6.0 %), the hit Box2D answers two ways (its own
  // response moves by 272 % under a 1e-4 perturbation: ambiguous).
  EXPECT_LT(Find(rows, "polygon-polygon e=1", "quadrant:pgs", compat).max, 0.07);
}

TEST(RandomHits, SoftStepBox2dCompatibleSettingStaysBelowOnePercent) {
  // soft_step's Box2D-compatible setting: Box2D's restitution, its skin and friction in each of four
  // relax passes (0.76 % here, 0.69 % on the 2000 hits; with the default two passes 1.06 % here and
  // 0.82 % there). Each alone leaves it far above (docs/validation.md).
  const std::vector<CampaignRow> rows = Sample().Box2dRows();
  const char* compat = "box2d_restitution+box2d_skin+relax4+relaxfriction";
  EXPECT_LT(Find(rows, "all", "quadrant:soft_step", compat).p90, 0.01);
  EXPECT_GT(Find(rows, "all", "quadrant:soft_step", "box2d_restitution").p90, 0.015);
  EXPECT_GT(Find(rows, "all", "quadrant:soft_step", "box2d_skin").p90, 0.04);
  EXPECT_GT(Find(rows, "all", "quadrant:soft_step", "relaxfriction").p90, 0.04);
  EXPECT_GT(Find(rows, "all", "quadrant:soft_step", "box2d_restitution+box2d_skin").p90, 0.015);
  for (const char* cls : kClasses) {
    // The largest class here is polygon-polygon e=1 at 9.4 % (33 hits; 2000 hits: 2.8 % at most).
    EXPECT_LT(Find(rows, cls, "quadrant:soft_step", compat).p90, 0.125) << cls;
  }
}

TEST(RandomHits, ThesisBox2dCompatibleSettingStaysBelowOnePercent) {
  // The thesis's Box2D-compatible setting: its impulse coupled at each touching point, Box2D's skin,
  // its position pass and impulses accumulated over 8 passes (0.74 % here, 0.64 % on the 2000 hits).
  const std::vector<CampaignRow> rows = Sample().Box2dRows();
  const char* before = "coupled+points+box2d_skin";
  const char* compat = "coupled+points+box2d_skin+box2d_positions+accumulated+passes8";
  EXPECT_LT(Find(rows, "all", "quadrant:thesis", compat).p90, 0.01);
  // polygon-polygon e=0 was the class above 5 % (2000 hits: 7.15 %; 6.75 % on the 38 here). The
  // position pass takes it to 2.73 % here (4.84 % there); accumulating the impulse takes the
  // two-point hits' worst from 21.9 % to 10.0 % here (p90 4.84 -> 2.70 % there).
  const char* cls = "polygon-polygon e=0";
  EXPECT_GT(Find(rows, cls, "quadrant:thesis", before).p90, 0.05);
  EXPECT_LT(Find(rows, cls, "quadrant:thesis", "coupled+points+box2d_skin+box2d_positions").p90, 0.04);
  EXPECT_GT(Find(rows, cls, "quadrant:thesis", "coupled+points+box2d_skin+box2d_positions").max, 0.18);
  EXPECT_LT(Find(rows, cls, "quadrant:thesis", compat).p90, 0.04);
  EXPECT_LT(Find(rows, cls, "quadrant:thesis", compat).max, 0.12);
  for (const char* c : kClasses) {
    // The largest class here is polygon-polygon e=0.5 at 12.4 % (24 hits; 2000 hits: 2.7 % at most).
    EXPECT_LT(Find(rows, c, "quadrant:thesis", compat).p90, 0.15) << c;
  }
}

TEST(RandomHits, Box2dPositionPassAndBlockHoldEveryClassOfPgsAndThesisBelowFivePercent) {
  // Issue #31: the compatible settings of pgs and the thesis also take Box2D's position pass
  // geometry (box2d_position_solve) and the thesis its two-point block (block). Every class stays
  // below 5 % (the 10-seed campaign: worst class 2.31 % on the worst seed, 1.73 % over seeds 27-56
  // that nobody tuned on); without the block the thesis's polygon-polygon e=1 class reaches 31 %
  // on this sample (hits 71 and 132, two points at once).
  const std::vector<CampaignRow> rows = Sample().Box2dRows();
  const std::string contacts = "coupled+points+box2d_skin+box2d_positions+accumulated+passes8+touching+box2d_clip";
  const std::string pgs = "box2d_restitution+box2d_skin+touching+box2d_clip+box2d_position_solve";
  const std::string thesis = contacts + "+block+box2d_position_solve";
  EXPECT_LT(Find(rows, "all", "quadrant:pgs", pgs).p90, 0.01);
  EXPECT_LT(Find(rows, "all", "quadrant:thesis", thesis).p90, 0.01);
  for (const char* cls : kClasses) {
    EXPECT_LT(Find(rows, cls, "quadrant:pgs", pgs).p90, 0.05) << cls;
    EXPECT_LT(Find(rows, cls, "quadrant:thesis", thesis).p90, 0.05) << cls;
  }
  EXPECT_GT(Find(rows, "polygon-polygon e=1", "quadrant:thesis", contacts).max, 0.25);
  EXPECT_LT(Find(rows, "polygon-polygon e=1", "quadrant:thesis", contacts + "+block").max, 0.001);
}

TEST(RandomHits, Box2dPositionPassAndRelaxPassesHoldEveryClassOfSoftStepBelowFivePercent) {
  // Issue #31: soft_step's compatible setting takes Box2D's position pass in place of its soft
  // push (box2d_position_solve) and 32 relax passes. Every class stays below 5 % (the 10-seed
  // campaign: worst class 2.80 % on the worst seed; 4.64 % on the 40 seeds first run after the
  // setting was chosen, docs/notes/random_campaign_contacts.md). With
  // the pass and 4 relax passes, two points at once (hit 71, polygon-polygon e=1) and
  // polygon-polygon e=0's worst hit stay apart from Box2D's block solver.
  const std::vector<CampaignRow> rows = Sample().Box2dRows();
  const std::string contacts = "box2d_restitution+box2d_skin+relax4+relaxfriction+touching+box2d_clip";
  const std::string positions = contacts + "+box2d_position_solve";
  const std::string compatible = "box2d_restitution+box2d_skin+relax32+relaxfriction+touching+box2d_clip+box2d_position_solve";
  EXPECT_LT(Find(rows, "all", "quadrant:soft_step", compatible).p90, 0.01);
  for (const char* cls : kClasses) EXPECT_LT(Find(rows, cls, "quadrant:soft_step", compatible).p90, 0.05) << cls;
  EXPECT_GT(Find(rows, "polygon-polygon e=0", "quadrant:soft_step", contacts).p90, 0.03);
  EXPECT_LT(Find(rows, "polygon-polygon e=0", "quadrant:soft_step", positions).p90, 0.01);
  EXPECT_GT(Find(rows, "polygon-polygon e=0", "quadrant:soft_step", positions).max, 0.10);
  EXPECT_LT(Find(rows, "polygon-polygon e=0", "quadrant:soft_step", compatible).max, 0.01);
}

TEST(RandomHits, EverySolverWithinItsBoundOfBox2d) {
  const std::vector<CampaignRow> rows = Sample().Box2dRows();
  EXPECT_LT(Find(rows, "all", "quadrant:pgs", "default").p90, 0.07);
  EXPECT_LT(Find(rows, "all", "quadrant:soft_step", "default").p90, 0.09);
  EXPECT_LT(Find(rows, "all", "quadrant:thesis", "default").p90, 0.26);
  // The thesis's difference is its separate normal and friction formulas: coupled, it is within
  // 1.5 % of Box2D at p90 (2000 hits: 22.3 % -> 0.89 %).
  EXPECT_LT(Find(rows, "all", "quadrant:thesis", "coupled").p90, 0.015);
  EXPECT_LT(Find(rows, "all", "quadrant:thesis", "coupled+points+box2d_skin").p90, 0.0125);
  // Circle pairs are one point with no skin in either engine: pgs and soft_step agree with Box2D
  // exactly (within float rounding) whatever the restitution. soft_step did not while a sub-step's
  // friction was bounded by the whole step's collision impulse (circle-circle e=0.5: 81 % at most).
  for (const char* cls : {"circle-circle e=0", "circle-circle e=0.5", "circle-circle e=1"}) {
    EXPECT_LT(Find(rows, cls, "quadrant:pgs", "default").max, 1e-4) << cls;
    EXPECT_LT(Find(rows, cls, "quadrant:soft_step", "default").max, 1e-4) << cls;
    EXPECT_LT(Find(rows, cls, "quadrant:soft_step", "box2d_restitution+box2d_skin+relax4+relaxfriction").max, 1e-4) << cls;
  }
}

TEST(RandomHits, AnalyticReferenceAgreesWithBox2dAndTheCompatibleSetting) {
  const Campaign& c = Sample();
  const std::vector<CampaignRow> rows = c.AnalyticRows();
  const CampaignRow& box2d = Find(rows, "all", "box2d", "default");
  EXPECT_GT(box2d.n, 200) << "most hits are single-point";
  EXPECT_LT(box2d.p90, 0.01);
  EXPECT_LT(Find(rows, "all", "quadrant:pgs", "box2d_restitution").p90, 0.01);
  // soft_step's compatible setting is as near the mechanics (0.05 % here, Box2D 0.54 %).
  EXPECT_LT(Find(rows, "all", "quadrant:soft_step", "box2d_restitution+box2d_skin+relax4+relaxfriction").p90, 0.005);
  EXPECT_GT(Find(rows, "all", "quadrant:soft_step", "default").p90, 3 * box2d.p90);
  // Quadrant's default restitution (a frictionless collision before the iterations) is the
  // farther from the mechanics: its p90 distance is several times Box2D's.
  EXPECT_GT(Find(rows, "all", "quadrant:pgs", "default").p90, 3 * box2d.p90);
}

TEST(RandomHits, MomentumIsConservedByEveryRun) {
  const Campaign& c = Sample();
  for (size_t i = 0; i < c.hits.size(); ++i) {
    for (size_t r = 0; r < c.runs.size(); ++r) {
      EXPECT_LT(c.cells[i][r].momentumError, 1e-5) << "hit " << i << " " << c.runs[r].adapter;
    }
  }
}

TEST(RandomHits, Box2dSettingsAreRefusedWhereTheyDoNotApply) {
  WorldDef def;
  def.solver = SolverType::kThesis;
  def.restitution = RestitutionPolicy::kBox2d;
  EXPECT_THROW(World{def}, Error);
  def.solver = SolverType::kSoftStep;
  EXPECT_NO_THROW(World{def});
  def = WorldDef{};
  def.polygonSkin = Real(-0.01);
  EXPECT_THROW(World{def}, Error);
  def.polygonSkin = def.speculativeDistance;  // more than half of it
  EXPECT_THROW(World{def}, Error);
  def.polygonSkin = Real(0.01);
  def.restitution = RestitutionPolicy::kBox2d;
  EXPECT_NO_THROW(World{def});  // the default solver, soft_step, takes kBox2d too
  def.solver = SolverType::kPgs;
  EXPECT_NO_THROW(World{def});
  def.scheme = ParallelScheme::kQuadrants;
  EXPECT_THROW(World{def}, Error);
  // Box2D's position pass geometry: pgs, soft_step, or the thesis with its position pass; not
  // jacobi (no such pass), not the quadrants scheme (its body copies carry no shapes).
  def = WorldDef{};
  def.box2dPositionSolve = true;
  EXPECT_NO_THROW(World{def});  // soft_step: in place of its push
  def.scheme = ParallelScheme::kQuadrants;
  EXPECT_THROW(World{def}, Error);
  def.scheme = ParallelScheme::kDeterministic;
  def.solver = SolverType::kJacobi;
  EXPECT_THROW(World{def}, Error);
  def.solver = SolverType::kThesis;
  EXPECT_THROW(World{def}, Error);
  def.thesisPositionPass = true;
  EXPECT_NO_THROW(World{def});
  def.solver = SolverType::kPgs;
  EXPECT_NO_THROW(World{def});
  def.scheme = ParallelScheme::kQuadrants;
  EXPECT_THROW(World{def}, Error);
  // The thesis's two-point block needs its impulses per point and accumulated.
  def = WorldDef{};
  def.thesisBlockImpulse = true;
  EXPECT_THROW(World{def}, Error);
  def.solver = SolverType::kThesis;
  def.thesisPointImpulses = true;
  EXPECT_THROW(World{def}, Error);
  def.thesisAccumulatedImpulse = true;
  EXPECT_NO_THROW(World{def});
}

}  // namespace
}  // namespace quadrant::scene
