// Validation of the world's inputs: every definition is checked in full before anything
// changes, and bad input gets a one-line quadrant::Error naming the field.
#pragma once

#include <string>

#include "quadrant/types.h"

namespace quadrant {

inline constexpr int kMaxThreads = 64;

inline void Require(bool ok, const std::string& message) {
  if (!ok) throw Error(message);
}

void ValidateWorldDef(const WorldDef& d);

/// Validates a body definition and returns its shape in canonical form (polygons re-hulled).
ShapeDef ValidateBodyDef(const BodyDef& def);

/// A density as text for error messages (%g: std::to_string prints 1e-40 as 0.000000).
std::string DensityText(Real density);

}  // namespace quadrant
