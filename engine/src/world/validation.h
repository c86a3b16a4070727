// Validation of the world's inputs: every definition is checked in full before anything
// changes, and bad input gets a one-line quadrant::Error naming the field.
#pragma once

#include <cmath>
#include <span>
#include <string>
#include <vector>

#include "quadrant/types.h"

namespace quadrant {

inline constexpr int kMaxThreads = 64;

inline void Require(bool ok, const std::string& message) {
  if (!ok) throw Error(message);
}

void ValidateWorldDef(const WorldDef& d);

/// Validates a body definition and returns its shape in canonical form (polygons re-hulled). For
/// a compound body (BodyDef::extraShapes) every shape and the total mass are checked, and
/// `shapes`, if given, receives all of them canonical (shape first); for one shape it is cleared.
ShapeDef ValidateBodyDef(const BodyDef& def, std::vector<ShapeDef>* shapes = nullptr);

/// The exact mass data of several validated shapes as one rigid body: the summed mass, the
/// mass-weighted centre and the inertia about it (parallel axes).
MassData CompoundMass(std::span<const ShapeDef> shapes);

/// RequireDynamicMass for a compound body: its total mass and inertia.
void RequireDynamicMass(std::span<const ShapeDef> shapes, const std::string& prefix);

/// A density as text for error messages (%g: std::to_string prints 1e-40 as 0.000000).
std::string DensityText(Real density);

/// The mass data of a validated shape at its density.
MassData ShapeMass(const ShapeDef& shape);

/// Throws quadrant::Error (its message after `prefix`) unless a dynamic body made of `shape` (a
/// validated shape with density finite and > 0) has a positive, finite mass and inertia whose
/// inverses are finite: CreateBody's rule, shared with SetDensity and SetType.
void RequireDynamicMass(const ShapeDef& shape, const std::string& prefix);

/// BodyDef::gravityScale's rule: finite and within [-1e6, 1e6].
inline bool GravityScaleOk(Real scale) { return IsFinite(scale) && std::abs(scale) <= Real(1e6); }

}  // namespace quadrant
