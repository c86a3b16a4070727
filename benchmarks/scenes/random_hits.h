// The randomised contact-response campaign (issue #17): seeded oblique hits of a moving body on
// a resting one, run on any engine through the scene API, compared with Box2D 2.4.1 and with the
// analytic single-point impact (impact_analytic.h). Shared by tools/quadrant validate --random
// and tests/adapters/random_hits_test.cpp.
//
// A hit: body 0 (the mover) touches body 1 (the target) at one point at the start (0.5 mm into
// it, so float rounding cannot leave them apart): a vertex of a
// polygon, or a circle, against a face of a polygon or a circle, with the mover's support
// direction strictly inside its vertex's normal cone so no other feature touches. Both bodies
// are dynamic; the target rests, the mover moves at 2-8 m/s at up to 60 degrees off the contact
// normal and spins at up to 8 rad/s (redrawn until its contact point approaches at >= 1.25 m/s,
// above the 1 m/s restitution threshold). Shapes: random convex 3- to 8-gons of circumradius
// 0.35-0.5 m and circles of that radius; pairs polygon-polygon, circle-polygon (either moving),
// circle-circle in equal shares. Mass ratio log-uniform in 1-100 (either body the heavier);
// restitution 0, 0.5 or 1 and friction 0 or 0.3, the same on both bodies (so every engine's
// mixing rule gives that value). World: zero gravity, dt 1/60, 8 velocity and 3 position
// iterations, restitution threshold 1 m/s (Box2D 2.4's default), no sleep, no continuous
// collision, 60 steps. Starting exactly in contact removes detection timing (Box2D finds a
// contact only once it overlaps) from the comparison, as the canonical cases do.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "adapter.h"
#include "impact_analytic.h"
#include "scene.h"

namespace quadrant::scene {

inline constexpr int kRandomHitSteps = 60;

struct RandomHit {
  int index = 0;
  std::string pair;      ///< "polygon-polygon", "circle-polygon" or "circle-circle"
  Scene scene;           ///< bodies[0] the mover, bodies[1] the target
  double speed = 0;      ///< the mover's speed (m/s): differences are fractions of it
  double restitution = 0, friction = 0;
  double massRatio = 1;  ///< heavier / lighter
  double moverSpin = 0;  ///< rad/s
  double approachAngle = 0;  ///< rad, between the mover's velocity and the contact normal
  Vec2 point, normal;    ///< contact point and unit normal from mover to target, at the start
  double radius[2] = {0, 0};  ///< circumradius of each body about its centre of mass (m)

  /// The class a hit is reported in: pair and restitution, e.g. "circle-polygon e=0.5".
  std::string Class() const;
};

/// Hit number `index` of the campaign seeded `seed` (each hit has its own random stream, so a
/// hit does not depend on how many others are drawn).
RandomHit MakeRandomHit(uint64_t seed, int index);

struct HitRun {
  std::vector<BodyState> final;  ///< after kRandomHitSteps steps
  double momentumError = 0;      ///< |P after - P before| / (mover mass x speed)
  double energyRatio = 0;        ///< kinetic energy after / before
  int maxPoints = 0;             ///< most points of a contact manifold in any step
  int contactSteps = 0;          ///< steps that ended with a touching contact
};

/// Runs the hit on an engine ("box2d", "quadrant", "quadrant:<variant>"). Throws what the
/// adapter throws.
HitRun RunRandomHit(const RandomHit& hit, std::string_view engine);

/// The largest difference between two final states, over both bodies, of the centre velocity
/// and of the angular velocity times the body's circumradius, as a fraction of the hit's speed.
double VelocityDifference(const RandomHit& hit, const std::vector<BodyState>& x, const std::vector<BodyState>& y);

/// The analytic impact of the hit's first contact (ok = false if it jams). Its velocities are
/// those after the impact; with no second contact they are the final ones too.
ImpactResult AnalyticHit(const RandomHit& hit);
/// Whether the bodies, moving freely with the analytic velocities after the impact, would meet
/// again (penetrate 1.5 mm deeper than they start, sampled every quarter step over the
/// campaign's steps): a second impact the single-impact model does not include.
bool AnalyticRecontacts(const RandomHit& hit, const ImpactResult& r);
/// The analytic answer as final body states (positions left at the start: only velocities are
/// compared).
std::vector<BodyState> AnalyticStates(const RandomHit& hit, const ImpactResult& r);

// ---- The campaign ---------------------------------------------------------------------------

/// One engine and setting of the campaign: `adapter` is the adapter name ("box2d",
/// "quadrant:pgs+b2rest", ...), engine and setting the labels the report uses.
struct CampaignRun {
  std::string engine;
  std::string setting;
  std::string adapter;
};

/// A distribution row of the report: differences as fractions of the impact speed.
struct CampaignRow {
  std::string cls, engine, setting;
  int n = 0;
  double median = 0, p90 = 0, max = 0;
};

struct Campaign {
  uint64_t seed = 0;
  std::vector<CampaignRun> runs;  ///< runs[0] is Box2D 2.4.1, the reference
  struct Cell {
    double toBox2d = 0;    ///< VelocityDifference against runs[0]
    double toAnalytic = 0; ///< against the analytic answer; NaN where the hit has none
    double momentumError = 0, energyRatio = 0;
    int maxPoints = 0, contactSteps = 0;
  };
  std::vector<RandomHit> hits;
  std::vector<std::vector<Cell>> cells;   ///< [hit][run]
  std::vector<double> analyticToBox2d;    ///< per hit; NaN where the hit has no analytic answer
  std::vector<double> analyticEnergyRatio;  ///< per hit: kinetic energy after / before the analytic impact; NaN as above
  std::vector<bool> singlePoint;          ///< the analytic answer applies (see RunCampaign)
  int analyticJams = 0;                   ///< hits whose analytic impact jams (no answer)
  int analyticRecontacts = 0;             ///< hits whose bodies would meet again after it

  /// Per class (and "all") and run: the distribution of the difference to Box2D; plus rows of
  /// engine "analytic" (the analytic answer's difference to Box2D on single-point hits).
  std::vector<CampaignRow> Box2dRows() const;
  /// Per class and run: the distribution of each engine's distance from the analytic answer,
  /// over the single-point hits (and Box2D's own).
  std::vector<CampaignRow> AnalyticRows() const;
};

/// The runs of the committed campaign: Box2D; Quadrant's pgs, soft_step and thesis at their
/// defaults; and the single-choice switches that trace each difference (README "validation"):
/// pgs with Box2D 2.4.1's restitution, with its polygon skin, and with both (pgs's
/// Box2D-compatible setting); soft_step with each of those, with friction in every relax pass, with
/// the first two, with all three and that with four relax passes; thesis with its impulse coupled,
/// and that with an impulse per touching point, with the skin, and with both; and that (coupled,
/// points, skin) with Box2D's position pass, with its impulses accumulated over 8 passes, and with
/// both. Last, Box2D 2.4.1's contacts (issue #31): pgs's restitution and skin setting with touching
/// points only (nospec), with Box2D's polygon clip (b2clip), with both; and the fullest setting of
/// each solver with both. Then pgs's with Box2D's position pass geometry (b2possolve), soft_step's
/// with it (in place of its soft push; 4, 16 and 32 relax passes), the thesis's with its two-point
/// impulses solved together (block) and with both. The Box2D-compatible settings
/// (CompatibleRuns) are the fullest of each solver: soft_step's is the one with 32 relax passes.
std::vector<CampaignRun> DefaultCampaignRuns();

/// Runs hits 0..count-1 of the campaign seeded `seed` on every run. A hit is single-point, and
/// carries the analytic answer, when its impact does not jam and the bodies, moving with the
/// analytic velocities, do not meet again (AnalyticRecontacts): the model is one instantaneous
/// impact at one point, and a second contact (a polygon turning onto the face) is a second
/// impact it does not include.
Campaign RunCampaign(uint64_t seed, int count, const std::vector<CampaignRun>& runs);

/// Median, 90th percentile (nearest rank) and maximum of `values` (NaNs dropped; zeros if empty).
CampaignRow Distribution(std::vector<double> values);

}  // namespace quadrant::scene
