// Quadrant: collision shapes and their exact mass properties.
#pragma once

#include <array>
#include <cstdint>
#include <span>

#include "quadrant/math.h"

namespace quadrant {

/// Most vertices a polygon may have (as Box2D's default).
inline constexpr int kMaxPolygonVertices = 8;

/// Largest coordinate magnitude accepted for positions and vertices (m). float32 still
/// resolves 1 mm at 1e5 m only roughly (ulp ~ 8 mm), so beyond 1e6 results are meaningless.
inline constexpr Real kMaxCoordinate = Real(1e6);

/// Largest linear speed (m/s) and angular speed (rad/s) accepted as input. Beyond it one step
/// moves a body past the coordinate limit; the simulation itself also guards with
/// WorldDef::maxLinearSpeed and maxRotation.
inline constexpr Real kMaxInputSpeed = Real(1e6);

/// Longest time step accepted (s). Longer steps are outside what a rigid-body step models.
inline constexpr Real kMaxTimeStep = Real(1);

/// Most sub-steps per Step and iterations of any kind accepted. Far beyond any useful accuracy
/// (the accuracy study sweeps to 32); without a bound, one call could run for hours.
inline constexpr int kMaxIterations = 1000;

/// Smallest edge length / circle radius accepted (m). Below this the hull and the narrow
/// phase lose precision in float32.
inline constexpr Real kMinFeatureSize = Real(0.005);

/// A circle centred at `center` in body coordinates.
struct Circle {
  Vec2 center;
  Real radius = Real(0.5);
};

/// A capsule: the points within `radius` of the segment from center1 to center2 (body
/// coordinates), a segment's length of rectangle with a half disc on each end.
struct Capsule {
  Vec2 center1{Real(-0.5), 0};
  Vec2 center2{Real(0.5), 0};
  Real radius = Real(0.25);
};

/// A two-sided line segment from point1 to point2 (body coordinates): no area, so no mass. Only
/// static and kinematic bodies may carry one; it collides with circles, polygons and capsules
/// (exactly as a capsule of radius 0), never with another segment.
struct Segment {
  Vec2 point1{Real(-0.5), 0};
  Vec2 point2{Real(0.5), 0};
};

/// One segment of a chain (Box2D 3's b2ChainSegment): one-sided, it collides only on its right
/// side, the side of its normal (point2 - point1) turned clockwise, so a counter-clockwise loop
/// faces outwards and a ground to stand on runs right to left (x decreasing). The ghost vertices
/// are the neighbours' far ends, ghost1 -> point1 -> point2 -> ghost2: a contact whose normal
/// points into a neighbour's side (the "ghost collision" of a box catching on a join) is
/// skipped or turned to the segment's normal, so bodies slide across the joins smoothly.
struct ChainSegment {
  Vec2 ghost1{Real(-1.5), 0};
  Segment segment;
  Vec2 ghost2{Real(1.5), 0};
};

/// A convex polygon, counter-clockwise, with precomputed outward unit normals.
/// Build it with MakePolygon or MakeBox: they validate the input.
struct Polygon {
  std::array<Vec2, kMaxPolygonVertices> vertices{};
  std::array<Vec2, kMaxPolygonVertices> normals{};
  Vec2 centroid;
  int count = 0;
};

/// Mass properties of a shape at a given density (kg/m^2).
struct MassData {
  Real mass = 0;     ///< kg
  Vec2 center;       ///< centre of mass in body coordinates
  Real rotationalInertia = 0;  ///< about the centre of mass, kg m^2
};

/// Builds the convex hull of 3..8 points (any order) as a counter-clockwise polygon.
/// Throws quadrant::Error for fewer than 3 or more than 8 points, non-finite or huge
/// coordinates, duplicate points, collinear or nearly collinear input (area or an edge below
/// kMinFeatureSize), and input that is not convex when `requireConvex` is true (points that
/// the hull would drop, which means the caller's polygon was not the convex shape it meant).
Polygon MakePolygon(std::span<const Vec2> points, bool requireConvex = true);

/// An axis-aligned box of half-widths hx, hy centred at `center`, rotated by `angle`.
Polygon MakeBox(Real hx, Real hy, Vec2 center = {}, Real angle = 0);

/// Validates a circle (finite centre, radius >= kMinFeatureSize); throws quadrant::Error.
void ValidateCircle(const Circle& circle);

/// Validates a capsule (finite centres, radius and length >= kMinFeatureSize, within the
/// coordinate limit); throws quadrant::Error.
void ValidateCapsule(const Capsule& capsule);
/// Validates a segment (finite points within the coordinate limit, at least kMinFeatureSize
/// apart); throws quadrant::Error.
void ValidateSegment(const Segment& segment);
/// Validates a chain segment: its segment as ValidateSegment, and its ghost vertices finite,
/// within the coordinate limit and at least kMinFeatureSize from their ends; throws quadrant::Error.
void ValidateChainSegment(const ChainSegment& chainSegment);
MassData ComputeMass(const Circle& circle, Real density);
MassData ComputeMass(const Capsule& capsule, Real density);
MassData ComputeMass(const Polygon& polygon, Real density);
/// A segment has no area: mass and inertia 0, its centre the segment's middle.
MassData ComputeMass(const Segment& segment);

/// Signed area of a polygon (positive for counter-clockwise).
Real ComputeArea(const Polygon& polygon);

AABB ComputeAABB(const Circle& circle, Transform xf);
AABB ComputeAABB(const Capsule& capsule, Transform xf);
AABB ComputeAABB(const Polygon& polygon, Transform xf);
AABB ComputeAABB(const Segment& segment, Transform xf);

}  // namespace quadrant
