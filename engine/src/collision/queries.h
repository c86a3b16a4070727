// World queries: the exact shape tests behind World::QueryAABB, RayCastClosest and RayCastAll,
// and the sensors' overlap test. The broad phase (broad_phase.h, BuildForQueries) narrows the
// bodies down; these decide.
#pragma once

#include "quadrant/types.h"

namespace quadrant {

/// Whether the shape at `xf` overlaps `box` (touching counts). Exact up to rounding: circles by
/// the box's closest point, polygons by separating axes (the box's two and the polygon's normals).
bool ShapeOverlapsBox(const ShapeDef& shape, const Transform& xf, const AABB& box);

/// Where the segment p1 + t (p2 - p1), t in [0, 1], enters the shape at `xf`: true and the hit
/// (fraction, point, normal; not body) if it does. A shape that contains p1 is not entered.
bool RayCastShape(const ShapeDef& shape, const Transform& xf, Vec2 p1, Vec2 p2, RayHit& hit);

/// Whether two shapes overlap (touching counts): circles by their centres' distance, a polygon
/// and a circle by the centre's distance to the polygon, two polygons by separating axes (both
/// polygons' normals). For sensors (world.cpp, FindSensorOverlaps).
bool ShapesOverlap(const ShapeDef& a, const Transform& xfA, const ShapeDef& b, const Transform& xfB);

}  // namespace quadrant
