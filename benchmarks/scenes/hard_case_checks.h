// The hard cases' pass criteria, defined once for the hardcases tool and the tests.
//
// Every measurement goes through the scene API's read-back (Adapter::ReadBodies and the shared
// KineticEnergy / LinearMomentum), so every engine is judged by the same code. Penetration is
// computed from the read-back poses and the scene's exact shapes (separating axes for polygon
// pairs, closest points for circles), never from an engine's own contact report.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "adapter.h"
#include "scenes.h"

namespace quadrant::scene {

/// One measured figure; the unit is in the name (_m, _mps, _J, ...).
struct Measured {
  std::string name;
  double value = 0;
};

struct HardCaseResult {
  std::string name;
  std::string engine;
  std::string criterion;    ///< the pass criterion in words, with its numbers
  bool supported = true;
  std::string unsupported;  ///< Adapter::Load's reason when not supported
  bool pass = false;
  std::vector<Measured> measured;
  std::string note;         ///< what a reader needs to interpret the figures
  std::string settings;     ///< the scene's world settings (time step, iterations, effects)
  double seconds = 0;       ///< wall time of the run

  /// The value of a measured figure; throws quadrant::Error if there is none of that name.
  double Get(std::string_view figure) const;
};

struct HardCaseOptions {
  int soakSteps = 100000;  ///< steps of the polygon_stress soak (N = 1000)
  /// Seconds between progress lines on stderr during a case (the soak: steps done, rate, ETA); 0 for none
  /// (the tests). The soaks take minutes (Bullet's 100000 steps: 16 min on the 2-core VM).
  double progressSeconds = 0;
};

/// vertical_stack, pyramid, mass_ratio_100, mass_ratio_400, arch, card_house, friction_ramp,
/// restitution_drop, overlap_recovery, confined, far_from_origin, newtons_cradle, soak, issue
/// #13's tall_stack, heavy_on_supports, heavy_on_slab (default budget), issue #26's tall_stack_50
/// and closed_box, issue #27's joint cases (heavy_chain, ragdoll_pile, prismatic_stop, weld_beam),
/// and Solver2D's contact scenes (single_box, warm_start_energy, high_mass_ratio_1 to _3, rush,
/// double_domino, circle_stack, far_stack, far_recovery). Every case but the soak runs 60 s of simulated time (3600 steps) and checks its
/// criterion at every sample of that window.
std::vector<std::string> HardCaseNames();

/// Runs one case on one engine (1 thread), building the scene with the engine's material mixing
/// (MixingOf). An engine that refuses the scene gives supported = false, pass = false. Throws
/// quadrant::Error for an unknown case or engine name.
HardCaseResult RunHardCase(std::string_view name, std::string_view engine, const HardCaseOptions& options = {});

/// Most negative separation (as a positive depth, 0 if none) over all pairs of bodies that are
/// not both static, from the read-back poses and the scene's shapes.
double MaxPenetration(const Scene& scene, const std::vector<BodyState>& states);

}  // namespace quadrant::scene
