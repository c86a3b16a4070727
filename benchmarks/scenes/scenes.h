// Scenes, defined once and used by every adapter, test and benchmark.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "scene.h"

namespace quadrant::scene {

/// The thesis's stress scenes (its Figures 14 and 15) as anchors.md fixes them: N bodies with
/// random speeds in random directions in a closed square box sized for a given area fraction,
/// no gravity, restitution 1, friction 0, no sleeping, dt = 1/60.
struct StressParams {
  int count = 1000;                 ///< N > 0
  ShapeKind shape = ShapeKind::kCircle;
  Real radius = Real(0.5);          ///< circles (m)
  Real minCircumradius = Real(0.35);///< polygons (m)
  Real maxCircumradius = Real(0.5);
  Real areaFraction = Real(0.25);   ///< body area / box area, in (0, 0.9)
  Real minSpeed = 1;                ///< m/s
  Real maxSpeed = 5;
  bool clumped = false;             ///< all bodies in one quadrant of the box (load-imbalance case)
  uint64_t seed = 42;
};

/// Throws quadrant::Error on malformed parameters (N <= 0, non-positive sizes, area fraction
/// outside (0, 0.9), min > max, non-finite values).
Scene MakeStressScene(const StressParams& params);

/// Scene names known to the suite: "circle_stress", "polygon_stress" (and later more).
std::vector<std::string> SceneNames();

/// Builds a named scene with `count` bodies (ignored by fixed-size scenes) and a seed.
/// Throws quadrant::Error for unknown names or bad counts.
Scene MakeScene(std::string_view name, int count, uint64_t seed = 42);

/// A small deterministic random source (splitmix64), so a seed gives the same scene with any
/// standard library.
class Random {
 public:
  explicit Random(uint64_t seed) : state_(seed) {}
  uint64_t Next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  /// Uniform in [lo, hi).
  double Uniform(double lo, double hi) { return lo + (hi - lo) * double(Next() >> 11) * 0x1.0p-53; }
  int UniformInt(int lo, int hiInclusive) { return lo + int(Next() % uint64_t(hiInclusive - lo + 1)); }

 private:
  uint64_t state_;
};

}  // namespace quadrant::scene
