// Why a random hit's response differs from Box2D's (issue #31): the ambiguity rule and the
// cause of a large difference, shared by quadrant_validate --random and the reproducer tests in
// tests/adapters/random_hit_causes_test.cpp.
//
// Ambiguous: a hit has no single right answer at the campaign's tolerance when Box2D 2.4.1's own
// response moves by more than kAmbiguityTolerance (5 %, the tolerance itself) under a
// perturbation of the mover far below any engine's slop: 1e-4 m along x or y, or 1e-4 rad,
// either sign (six runs). The rule reads Box2D alone, so it sets apart the same hits for every
// engine and solver.
//
// Cause of a difference d > 5 % between a run R and Box2D B (the first rule that holds):
//   restitution threshold - a point arriving after the first step approaches at 0.8-1.25 m/s in
//                           either engine (e > 0): one engine bounces, the other does not;
//   after both first separate, if they still agree then (<= 5 %), at the step the difference
//   first exceeds 5 %:
//     re-contact          - either engine has a touching contact;
//     speculative contact - neither has: a speculative row acted before the shapes touched;
//   otherwise, during the first contact:
//   speculative contact   - R's point beyond the skin pushed where Box2D had no touching point;
//   skin                  - the engines count different touching points (a second point inside
//                           one's skin only);
//   order of points       - both hold two points at once, and R or B moves by more than 5 % when
//                           the scene is mirrored (x -> -x, which reverses the order of the
//                           manifold's points);
//   simultaneous points   - both hold two points at once, insensitive to that order: the split
//                           of the impulse between two points has no single answer;
//   solver difference     - one point throughout in both: the solvers themselves differ.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "random_hits.h"

namespace quadrant::scene {

inline constexpr double kAmbiguityTolerance = 0.05;
inline constexpr double kPerturbation = 1e-4;  ///< m and rad
inline constexpr double kCauseThreshold = 0.05;

/// The six perturbed copies of a hit (mover shifted by +-kPerturbation in x, y, and angle).
std::vector<RandomHit> PerturbedHits(const RandomHit& hit);
/// Largest difference of Box2D's response to the hit's perturbed copies from its response to the
/// hit itself (fractions of the impact speed, as VelocityDifference).
double Box2dPerturbationSpread(const RandomHit& hit);

enum class HitCause { kRestitutionThreshold, kRecontact, kSpeculative, kSkin, kPointOrder, kSimultaneous, kSolver };
inline constexpr HitCause kAllCauses[] = {HitCause::kRestitutionThreshold, HitCause::kRecontact, HitCause::kSpeculative,
                                          HitCause::kSkin,                 HitCause::kPointOrder, HitCause::kSimultaneous,
                                          HitCause::kSolver};
std::string CauseName(HitCause c);

/// One engine's run of a hit, step by step.
struct HitTrace {
  std::vector<std::vector<BodyState>> states;  ///< states[k]: after k steps (k = 0..kRandomHitSteps)
  std::vector<int> touching;                   ///< [k-1]: touching points after step k
  std::vector<int> speculative;                ///< [k-1]: points beyond the skin that pushed in step k
  std::vector<Vec2> normal;                    ///< [k-1]: the contact's normal, from body 0 to body 1
  std::vector<Vec2> point, point2;             ///< [k-1]: its first and second point (the first if one)
};
/// Runs the hit on an engine ("box2d", "quadrant:<variant>"), recording every step. With
/// `mirrored`, the scene is mirrored (x -> -x, polygons wound the other way round, which reverses
/// the order of a manifold's points); states come back mirrored to the hit's frame.
HitTrace TraceRandomHit(const RandomHit& hit, std::string_view engine, bool mirrored = false);

struct CauseDiagnosis {
  HitCause cause = HitCause::kSolver;
  double difference = 0;       ///< final difference of the run to Box2D
  double atSeparation = -1;    ///< difference when both first separate (-1: they do not)
  double recontactSpeed = -1;  ///< approach nearest the threshold of a point arriving after step 1 (m/s; -1: none)
  int maxTouching[2] = {0, 0};  ///< most touching points in the first contact: Box2D, the run
  double orderShift = 0;       ///< largest self-difference of Box2D or the run with the bodies swapped
};
/// The Box2D-compatible setting of each Quadrant solver (README "validation"): the runs whose
/// differences are classified and held to 5 %.
std::vector<CampaignRun> CompatibleRuns();

/// Classifies the difference of `engine` to Box2D on the hit by the rules above.
CauseDiagnosis DiagnoseHit(const RandomHit& hit, std::string_view engine);

}  // namespace quadrant::scene
