// Validation against Box2D 2.4.1: canonical collisions and resting contacts, run through the
// scene API on Quadrant and Box2D with identical settings, defined once for the validate tool
// and the tests.
//
// Settings in every case: dt = 1/60, 8 velocity and 3 position iterations, no sleep, no
// continuous collision, equal friction and restitution on both bodies of a contact (so Box2D's
// sqrt(f1 f2) and max(e1, e2) mixing and Quadrant's give the same value), and bodies that start
// exactly touching or meet exactly at a step boundary, so neither engine's detection timing
// (Box2D finds a contact only once it overlaps) enters the result.
//
// A quantity passes when |quadrant - box2d| <= tolerance and, where physics gives an answer,
// |quadrant - analytic| <= tolerance. Known design differences are accounted for in the Box2D
// value, never by a wider tolerance: Box2D 2.4 keeps a 0.01 m skin around every polygon, so a
// box rests 0.01 m higher per polygon in the contact, and its contact points lie midway between
// skinned surfaces; such quantities carry "minus skin" in their name and reason. The one effect
// that cannot be subtracted (Box2D applies friction at a point half its slop inside a resting
// circle, so a rolling circle runs 0.5 % fast) is held by tolerances whose reasons give its size.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "scene.h"

namespace quadrant::scene {

struct ValidationQuantity {
  std::string name;
  double quadrant = 0;
  double box2d = 0;  ///< after the stated design-difference adjustment, if any
  std::optional<double> analytic;
  double tolerance = 0;
  std::string reason;  ///< why this tolerance, and any adjustment made
  bool pass = false;
};

struct ValidationResult {
  std::string name;
  std::string description;
  bool pass = false;
  std::vector<ValidationQuantity> quantities;

  /// The quantity of that name; throws quadrant::Error if there is none.
  const ValidationQuantity& Get(std::string_view quantity) const;
};

/// Names of the canonical cases, in report order.
/// The world every canonical case and the random campaign run in: dt 1/60, 8 / 3 iterations,
/// friction, restitution, rotation and warm starting on, no sleep, damping or continuous
/// collision, restitution threshold 0; gravity (0, -10 m/s^2) on when asked. No bodies.
Scene ValidationWorld(const char* name, bool gravity);

std::vector<std::string> ValidationCaseNames();

/// Runs one case on Quadrant and Box2D. Throws quadrant::Error for an unknown name.
ValidationResult RunValidationCase(std::string_view name);

}  // namespace quadrant::scene
