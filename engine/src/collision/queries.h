// World queries: the exact shape tests behind World::QueryAABB, QueryPoint, RayCastClosest,
// RayCastAll, CastCircle and CastPolygon, and the sensors' overlap test. The broad phase (broad_phase.h, BuildForQueries) narrows the
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

/// Whether the shape at `xf` contains `point` (its boundary counts).
bool ShapeContainsPoint(const ShapeDef& shape, const Transform& xf, Vec2 point);

/// Where a circle of `radius` moving from p1 to p2 first touches the shape at `xf`: true and the
/// hit (fraction, point on the shape, the shape's outward normal there; not body). Not if the
/// circle overlaps the shape at p1; touching it there and moving in is a hit at 0.
bool CastCircleShape(const ShapeDef& shape, const Transform& xf, Vec2 p1, Vec2 p2, Real radius, RayHit& hit);

/// The same for the convex polygon `moving` (world vertices and normals, as MakePolygon makes
/// them) moved by `translation` without turning.
bool CastPolygonShape(const ShapeDef& shape, const Transform& xf, const Polygon& moving, Vec2 translation,
                      RayHit& hit);

}  // namespace quadrant
