// Exact shape tests for the world's queries and sensors (queries.h). Computed in double: a query
// is one shape at a time, so the cost is negligible, and a ray grazing a vertex or a box touching
// an edge then gives the same answer the brute-force tests compute.
#include "collision/queries.h"

#include <algorithm>
#include <cmath>

namespace quadrant {
namespace {

struct D2 {
  double x, y;
};
D2 ToD(Vec2 v) { return {v.x, v.y}; }
double DotD(D2 a, D2 b) { return a.x * b.x + a.y * b.y; }
D2 RotD(Rot q, D2 v) { return {double(q.c) * v.x - double(q.s) * v.y, double(q.s) * v.x + double(q.c) * v.y}; }
D2 PointD(const Transform& xf, Vec2 v) {
  const D2 r = RotD(xf.q, ToD(v));
  return {r.x + xf.p.x, r.y + xf.p.y};
}

// Squared distance from p to the segment a-b.
double PointSegmentSquared(D2 a, D2 b, D2 p) {
  const D2 e{b.x - a.x, b.y - a.y};
  const double ee = DotD(e, e);
  const double u = ee > 0 ? std::clamp(DotD(D2{p.x - a.x, p.y - a.y}, e) / ee, 0.0, 1.0) : 0.0;
  const D2 q{p.x - a.x - u * e.x, p.y - a.y - u * e.y};
  return DotD(q, q);
}

// Squared distance between the segments a-b and c-d: 0 where they cross, else the nearest of
// the four ends to the other segment.
double SegmentsSquared(D2 a, D2 b, D2 c, D2 d) {
  auto orient = [](D2 p, D2 q, D2 r) { return (q.x - p.x) * (r.y - p.y) - (q.y - p.y) * (r.x - p.x); };
  const double o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a), o4 = orient(c, d, b);
  if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0))) return 0;
  return std::min(std::min(PointSegmentSquared(c, d, a), PointSegmentSquared(c, d, b)),
                  std::min(PointSegmentSquared(a, b, c), PointSegmentSquared(a, b, d)));
}

// A capsule's segment core in world coordinates, its two sides' outward normals, its radius.
struct CapsuleD {
  D2 v[2];
  D2 n[2];
  double radius;
};
CapsuleD CapsuleWorld(const Capsule& c, const Transform& xf) {
  CapsuleD w;
  w.v[0] = PointD(xf, c.center1), w.v[1] = PointD(xf, c.center2);
  const D2 e{w.v[1].x - w.v[0].x, w.v[1].y - w.v[0].y};
  const double len = std::sqrt(DotD(e, e));
  w.n[0] = {e.y / len, -e.x / len};
  w.n[1] = {-w.n[0].x, -w.n[0].y};
  w.radius = c.radius;
  return w;
}

// A segment of either kind is a capsule of radius 0 for every test but the ray cast (and
// contains no point: it has no area). A chain segment's overlaps are two-sided, as Box2D 3's.
const Segment& SegmentOf(const ShapeDef& shape) {
  return shape.type == ShapeType::kSegment ? shape.segment : shape.chainSegment.segment;
}
bool IsRoundCore(ShapeType t) { return t == ShapeType::kCapsule || IsSegmentType(t); }
CapsuleD RoundCoreWorld(const ShapeDef& shape, const Transform& xf) {
  if (shape.type == ShapeType::kCapsule) return CapsuleWorld(shape.capsule, xf);
  const Segment& seg = SegmentOf(shape);
  return CapsuleWorld(Capsule{seg.point1, seg.point2, 0}, xf);
}

// Where the ray p + t d, t in [0, 1], crosses the segment a-b: true, the fraction and the
// segment's normal facing the ray's start. A ray along the segment's line, or one starting on
// it, does not cross it. `oneSided`: only from the right of a -> b (a chain segment's face).
bool RaySegment(D2 a, D2 b, D2 p, D2 d, bool oneSided, double& tOut, D2& normal) {
  const D2 e{b.x - a.x, b.y - a.y};
  const double len = std::sqrt(DotD(e, e));
  D2 n{e.y / len, -e.x / len};  // right of a -> b
  const D2 ap{p.x - a.x, p.y - a.y};
  const double side = DotD(n, ap);  // > 0: the start is on the right
  const double den = DotD(n, d);
  if (side == 0 || den == 0 || (side > 0) == (den > 0)) return false;  // on the line, parallel, or away
  if (oneSided && side < 0) return false;
  const double t = -side / den;
  if (t > 1) return false;
  const double u = DotD(D2{ap.x + t * d.x, ap.y + t * d.y}, e);
  if (u < 0 || u > DotD(e, e)) return false;
  if (side < 0) n = {-n.x, -n.y};
  tOut = t;
  normal = n;
  return true;
}

bool RayRoundedPolygon(const D2* v, const D2* n, int count, double radius, D2 p, D2 d, double& tOut, D2& normal);

}  // namespace

bool ShapeOverlapsBox(const ShapeDef& shape, const Transform& xf, const AABB& box) {
  if (IsRoundCore(shape.type)) {
    // The segment within the radius of the box: an end inside, or the nearest of the box's edges.
    const CapsuleD c = RoundCoreWorld(shape, xf);
    const D2 lo{box.lower.x, box.lower.y}, hi{box.upper.x, box.upper.y};
    for (const D2& v : c.v) {
      if (v.x >= lo.x && v.x <= hi.x && v.y >= lo.y && v.y <= hi.y) return true;
    }
    const D2 corners[4] = {lo, {hi.x, lo.y}, hi, {lo.x, hi.y}};
    double best = INFINITY;
    for (int k = 0; k < 4; ++k) best = std::min(best, SegmentsSquared(c.v[0], c.v[1], corners[k], corners[(k + 1) % 4]));
    return best <= c.radius * c.radius;
  }
  if (shape.type == ShapeType::kCircle) {
    const D2 c = PointD(xf, shape.circle.center);
    const double qx = std::clamp(c.x, double(box.lower.x), double(box.upper.x));
    const double qy = std::clamp(c.y, double(box.lower.y), double(box.upper.y));
    const double r = shape.circle.radius;
    return (c.x - qx) * (c.x - qx) + (c.y - qy) * (c.y - qy) <= r * r;
  }
  const Polygon& p = shape.polygon;
  D2 v[kMaxPolygonVertices];
  double lx = INFINITY, ly = INFINITY, ux = -INFINITY, uy = -INFINITY;
  for (int k = 0; k < p.count; ++k) {
    v[k] = PointD(xf, p.vertices[k]);
    lx = std::min(lx, v[k].x), ly = std::min(ly, v[k].y), ux = std::max(ux, v[k].x), uy = std::max(uy, v[k].y);
  }
  // The box's axes.
  if (lx > box.upper.x || ux < box.lower.x || ly > box.upper.y || uy < box.lower.y) return false;
  // The polygon's normals: the box's nearest corner along -n must lie beyond the edge.
  const D2 centre{0.5 * (double(box.lower.x) + box.upper.x), 0.5 * (double(box.lower.y) + box.upper.y)};
  const double hx = 0.5 * (double(box.upper.x) - box.lower.x), hy = 0.5 * (double(box.upper.y) - box.lower.y);
  for (int k = 0; k < p.count; ++k) {
    const D2 n = RotD(xf.q, ToD(p.normals[k]));
    const double nearest = DotD(n, centre) - (std::abs(n.x) * hx + std::abs(n.y) * hy);
    if (nearest > DotD(n, v[k])) return false;
  }
  return true;
}

bool RayCastShape(const ShapeDef& shape, const Transform& xf, Vec2 p1, Vec2 p2, RayHit& hit) {
  const D2 d{double(p2.x) - p1.x, double(p2.y) - p1.y};
  if (IsSegmentType(shape.type)) {
    const CapsuleD c = RoundCoreWorld(shape, xf);
    double t = 0;
    D2 normal{0, 0};
    if (!RaySegment(c.v[0], c.v[1], ToD(p1), d, shape.type == ShapeType::kChainSegment, t, normal)) return false;
    hit.fraction = Real(t);
    hit.point = {Real(p1.x + t * d.x), Real(p1.y + t * d.y)};
    hit.normal = {Real(normal.x), Real(normal.y)};
    return true;
  }
  if (shape.type == ShapeType::kCapsule) {
    const CapsuleD c = CapsuleWorld(shape.capsule, xf);
    double t = 0;
    D2 normal{0, 0};
    if (!RayRoundedPolygon(c.v, c.n, 2, c.radius, ToD(p1), d, t, normal)) return false;
    hit.fraction = Real(t);
    hit.point = {Real(p1.x + t * d.x), Real(p1.y + t * d.y)};
    hit.normal = {Real(normal.x), Real(normal.y)};
    return true;
  }
  if (shape.type == ShapeType::kCircle) {
    // |s + t d|^2 = r^2 with s = p1 - centre: the smaller root, if in [0, 1].
    const D2 c = PointD(xf, shape.circle.center);
    const D2 s{double(p1.x) - c.x, double(p1.y) - c.y};
    const double r = shape.circle.radius;
    const double ss = DotD(s, s) - r * r;
    if (ss < 0) return false;  // the origin is inside
    const double dd = DotD(d, d), sd = DotD(s, d);
    const double disc = sd * sd - dd * ss;
    if (disc < 0 || dd == 0) return false;
    const double t = (-sd - std::sqrt(disc)) / dd;
    if (t < 0 || t > 1) return false;
    const D2 n{s.x + t * d.x, s.y + t * d.y};
    const double len = std::sqrt(DotD(n, n));
    hit.fraction = Real(t);
    hit.point = {Real(p1.x + t * d.x), Real(p1.y + t * d.y)};
    hit.normal = len > 0 ? Vec2{Real(n.x / len), Real(n.y / len)} : Vec2{};
    return true;
  }
  // Clipping the segment by each edge's half-plane (Cyrus-Beck): it enters at the largest
  // entering parameter and must not leave before it. No entering edge: the origin is inside.
  const Polygon& p = shape.polygon;
  double lower = 0, upper = 1;
  int entered = -1;
  for (int k = 0; k < p.count; ++k) {
    const D2 n = RotD(xf.q, ToD(p.normals[k]));
    const D2 v = PointD(xf, p.vertices[k]);
    const double num = DotD(n, D2{v.x - p1.x, v.y - p1.y});  // > 0: p1 inside this edge
    const double den = DotD(n, d);
    if (den == 0) {
      if (num < 0) return false;  // parallel and outside
    } else if (den < 0 && num < lower * den) {
      lower = num / den;  // entering
      entered = k;
    } else if (den > 0 && num < upper * den) {
      upper = num / den;  // leaving
    }
    if (upper < lower) return false;
  }
  if (entered < 0) return false;
  const D2 n = RotD(xf.q, ToD(p.normals[entered]));
  hit.fraction = Real(lower);
  hit.point = {Real(p1.x + lower * d.x), Real(p1.y + lower * d.y)};
  hit.normal = {Real(n.x), Real(n.y)};
  return true;
}

namespace {

D2 Sub(D2 a, D2 b) { return {a.x - b.x, a.y - b.y}; }
D2 Add(D2 a, D2 b) { return {a.x + b.x, a.y + b.y}; }
D2 Scale(double s, D2 a) { return {s * a.x, s * a.y}; }
double CrossD(D2 a, D2 b) { return a.x * b.y - a.y * b.x; }

// A shape's outline in world coordinates, in double: a polygon's vertices and outward normals,
// a circle's centre and radius, or a capsule's two centres (count 2, its sides' normals) and
// radius.
struct WorldShape {
  bool circle = false;
  bool capsule = false;  // a capsule, or a segment of either kind (radius 0)
  bool segment = false;
  D2 centre{0, 0};
  double radius = 0;
  D2 v[kMaxPolygonVertices];
  D2 n[kMaxPolygonVertices];
  int count = 0;
};

WorldShape ToWorld(const ShapeDef& shape, const Transform& xf) {
  WorldShape w;
  if (shape.type == ShapeType::kCircle) {
    w.circle = true;
    w.centre = PointD(xf, shape.circle.center);
    w.radius = shape.circle.radius;
    return w;
  }
  if (IsRoundCore(shape.type)) {
    const CapsuleD c = RoundCoreWorld(shape, xf);
    w.capsule = true;
    w.segment = shape.type != ShapeType::kCapsule;
    w.count = 2;
    w.v[0] = c.v[0], w.v[1] = c.v[1], w.n[0] = c.n[0], w.n[1] = c.n[1];
    w.radius = c.radius;
    return w;
  }
  w.count = shape.polygon.count;
  for (int k = 0; k < w.count; ++k) {
    w.v[k] = PointD(xf, shape.polygon.vertices[k]);
    w.n[k] = RotD(xf.q, ToD(shape.polygon.normals[k]));
  }
  return w;
}

// Largest signed distance of p past the polygon's edge lines: <= 0 inside or on the boundary.
double PolygonSeparation(const D2* v, const D2* n, int count, D2 p) {
  double s = -INFINITY;
  for (int k = 0; k < count; ++k) s = std::max(s, DotD(n[k], Sub(p, v[k])));
  return s;
}

// Squared distance from p to the segment a-b.
double SegmentDistanceSquared(D2 a, D2 b, D2 p) {
  const D2 e = Sub(b, a);
  const double ee = DotD(e, e);
  const double u = ee > 0 ? std::clamp(DotD(Sub(p, a), e) / ee, 0.0, 1.0) : 0.0;
  const D2 q = Sub(p, Add(a, Scale(u, e)));
  return DotD(q, q);
}

// Squared distance from a point outside the polygon to it (the nearest edge).
double OutsideDistanceSquared(const D2* v, int count, D2 p) {
  double best = INFINITY;
  for (int k = 0; k < count; ++k) best = std::min(best, SegmentDistanceSquared(v[k], v[(k + 1) % count], p));
  return best;
}

// Where the ray p + t d, t in [0, 1], enters the circle (c, r): false if p is inside (closer
// than r) or the ray misses it.
bool RayCircle(D2 c, double r, D2 p, D2 d, double& t, D2& normal) {
  const D2 s = Sub(p, c);
  const double ss = DotD(s, s) - r * r;
  if (ss < 0) return false;
  const double dd = DotD(d, d), sd = DotD(s, d);
  const double disc = sd * sd - dd * ss;
  if (disc < 0 || dd == 0) return false;
  t = (-sd - std::sqrt(disc)) / dd;
  if (t < 0 || t > 1) return false;
  const D2 q = Add(s, Scale(t, d));
  const double len = std::sqrt(DotD(q, q));
  normal = len > 0 ? Scale(1 / len, q) : D2{0, 0};
  return true;
}

// Where the ray p + t d, t in [0, 1], enters the polygon (v, n: counter-clockwise, outward unit
// normals) grown by `radius` >= 0: every edge pushed out along its normal plus a circle of that
// radius at every corner. False if p is inside the grown polygon (closer than radius to it, or
// within it when radius is 0; on its boundary moving inwards is a hit at 0) or the ray misses it. The first entry into that union is the
// earliest entry through a pushed edge or into a corner circle.
bool RayRoundedPolygon(const D2* v, const D2* n, int count, double radius, D2 p, D2 d, double& tOut, D2& normal) {
  if (radius == 0) {
    // Clipping by each edge's half-plane (Cyrus-Beck), as RayCastShape, except that a start on
    // the boundary moving inwards enters at 0 (touching at the start is not overlapping).
    double lower = 0, upper = 1;
    int entered = -1;
    for (int k = 0; k < count; ++k) {
      const double num = DotD(n[k], Sub(v[k], p));  // > 0: p inside this edge
      const double den = DotD(n[k], d);
      if (den == 0) {
        if (num < 0) return false;
      } else if (den < 0 && (num < lower * den || (entered < 0 && num == 0))) {
        lower = num / den;  // entering (at 0 from a start on this edge)
        entered = k;
      } else if (den > 0 && num < upper * den) {
        upper = num / den;
      }
      if (upper < lower) return false;
    }
    if (entered < 0) return false;
    tOut = lower;
    normal = n[entered];
    return true;
  }
  const double separation = PolygonSeparation(v, n, count, p);
  if (separation <= 0 || OutsideDistanceSquared(v, count, p) < radius * radius) return false;
  bool hit = false;
  double best = INFINITY;
  for (int k = 0; k < count; ++k) {
    const double den = DotD(n[k], d);
    if (den < 0) {
      const double t = (radius - DotD(n[k], Sub(p, v[k]))) / den;
      if (t >= 0 && t <= 1 && t < best) {
        const D2 e = Sub(v[(k + 1) % count], v[k]);
        const double u = DotD(Sub(Add(p, Scale(t, d)), v[k]), e);
        if (u >= 0 && u <= DotD(e, e)) {
          best = t, normal = n[k], hit = true;
        }
      }
    }
    double t = 0;
    D2 cn{0, 0};
    if (RayCircle(v[k], radius, p, d, t, cn) && t < best) best = t, normal = cn, hit = true;
  }
  if (hit) tOut = best;
  return hit;
}

// The convex hull of `points` (counter-clockwise, no collinear points; Andrew's monotone chain).
int ConvexHull(D2* points, int count, D2* hull) {
  std::sort(points, points + count, [](D2 a, D2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
  int h = 0;
  for (int i = 0; i < count; ++i) {
    while (h >= 2 && CrossD(Sub(hull[h - 1], hull[h - 2]), Sub(points[i], hull[h - 2])) <= 0) --h;
    hull[h++] = points[i];
  }
  for (int i = count - 2, lower = h + 1; i >= 0; --i) {
    while (h >= lower && CrossD(Sub(hull[h - 1], hull[h - 2]), Sub(points[i], hull[h - 2])) <= 0) --h;
    hull[h++] = points[i];
  }
  return h - 1;  // the first point is repeated at the end
}

// The points of a convex outline that lie furthest along `dir` (within a relative tolerance):
// their extent along the perpendicular `tangent`, and their position along `dir`.
struct Support {
  double along = 0;
  double lo = 0, hi = 0;  // along the tangent
};
Support SupportAlong(const D2* v, int count, D2 dir, D2 tangent) {
  double best = -INFINITY, scale = 1;
  for (int k = 0; k < count; ++k) {
    best = std::max(best, DotD(dir, v[k]));
    scale = std::max(scale, std::max(std::abs(v[k].x), std::abs(v[k].y)));
  }
  const double tolerance = 1e-9 * scale;
  Support s{best, INFINITY, -INFINITY};
  for (int k = 0; k < count; ++k) {
    if (DotD(dir, v[k]) < best - tolerance) continue;
    s.lo = std::min(s.lo, DotD(tangent, v[k]));
    s.hi = std::max(s.hi, DotD(tangent, v[k]));
  }
  return s;
}

void SetHit(RayHit& hit, double t, D2 point, D2 normal) {
  hit.fraction = Real(t);
  hit.point = {Real(point.x), Real(point.y)};
  hit.normal = {Real(normal.x), Real(normal.y)};
}

}  // namespace

bool ShapesOverlap(const ShapeDef& a, const Transform& xfA, const ShapeDef& b, const Transform& xfB) {
  const WorldShape sa = ToWorld(a, xfA), sb = ToWorld(b, xfB);
  if (sa.segment && sb.segment) return false;  // as in the narrow phase: segments never meet
  if (sa.capsule || sb.capsule) {
    // The cores' distance against the radii: a circle's core is its centre, a capsule's its
    // segment, a polygon's itself (a core inside it is at distance 0).
    const WorldShape& cap = sa.capsule ? sa : sb;
    const WorldShape& other = sa.capsule ? sb : sa;
    const double reach = cap.radius + other.radius;
    double d2 = 0;
    if (other.circle) {
      d2 = PointSegmentSquared(cap.v[0], cap.v[1], other.centre);
    } else if (other.capsule) {
      d2 = SegmentsSquared(cap.v[0], cap.v[1], other.v[0], other.v[1]);
    } else if (PolygonSeparation(other.v, other.n, other.count, cap.v[0]) > 0 &&
               PolygonSeparation(other.v, other.n, other.count, cap.v[1]) > 0) {
      d2 = INFINITY;
      for (int k = 0; k < other.count; ++k) {
        d2 = std::min(d2, SegmentsSquared(cap.v[0], cap.v[1], other.v[k], other.v[(k + 1) % other.count]));
      }
    }
    return d2 <= reach * reach;
  }
  if (sa.circle && sb.circle) {
    const D2 d = Sub(sb.centre, sa.centre);
    const double r = sa.radius + sb.radius;
    return DotD(d, d) <= r * r;
  }
  if (sa.circle || sb.circle) {
    const WorldShape& poly = sa.circle ? sb : sa;
    const WorldShape& circle = sa.circle ? sa : sb;
    if (PolygonSeparation(poly.v, poly.n, poly.count, circle.centre) <= 0) return true;
    return OutsideDistanceSquared(poly.v, poly.count, circle.centre) <= circle.radius * circle.radius;
  }
  // Separating axes: the two polygons' edge normals.
  for (int side = 0; side < 2; ++side) {
    const WorldShape& p = side == 0 ? sa : sb;
    const WorldShape& q = side == 0 ? sb : sa;
    for (int k = 0; k < p.count; ++k) {
      double nearest = INFINITY;
      for (int j = 0; j < q.count; ++j) nearest = std::min(nearest, DotD(p.n[k], Sub(q.v[j], p.v[k])));
      if (nearest > 0) return false;
    }
  }
  return true;
}

bool ShapeContainsPoint(const ShapeDef& shape, const Transform& xf, Vec2 point) {
  const WorldShape s = ToWorld(shape, xf);
  const D2 p = ToD(point);
  if (s.segment) return false;  // no area (Box2D's rule)
  if (s.capsule) return PointSegmentSquared(s.v[0], s.v[1], p) <= s.radius * s.radius;
  if (s.circle) {
    const D2 d = Sub(p, s.centre);
    return DotD(d, d) <= s.radius * s.radius;
  }
  return PolygonSeparation(s.v, s.n, s.count, p) <= 0;
}

bool CastCircleShape(const ShapeDef& shape, const Transform& xf, Vec2 p1, Vec2 p2, Real radius, RayHit& hit) {
  const WorldShape s = ToWorld(shape, xf);
  const D2 p = ToD(p1), d = Sub(ToD(p2), p);
  const double r = radius;
  double t = 0;
  D2 normal{0, 0};
  if (s.circle) {
    if (!RayCircle(s.centre, s.radius + r, p, d, t, normal)) return false;
  } else if (s.capsule) {
    if (!RayRoundedPolygon(s.v, s.n, 2, s.radius + r, p, d, t, normal)) return false;
  } else if (!RayRoundedPolygon(s.v, s.n, s.count, r, p, d, t, normal)) {
    return false;
  }
  // The circle's centre at the hit, less its radius along the shape's normal.
  SetHit(hit, t, Sub(Add(p, Scale(t, d)), Scale(r, normal)), normal);
  return true;
}

bool CastPolygonShape(const ShapeDef& shape, const Transform& xf, const Polygon& moving, Vec2 translation,
                      RayHit& hit) {
  // The moving polygon P (world vertices) touches the shape S after t of the translation d when
  // t d lies in S + (-P) (Minkowski sum): a ray from the origin against it.
  const WorldShape s = ToWorld(shape, xf);
  const int m = moving.count;
  D2 pv[kMaxPolygonVertices], pn[kMaxPolygonVertices];
  for (int k = 0; k < m; ++k) pv[k] = ToD(moving.vertices[k]), pn[k] = ToD(moving.normals[k]);
  const D2 d = ToD(translation);
  double t = 0;
  D2 normal{0, 0};
  if (s.circle) {
    // S + (-P) is the polygon c - P (counter-clockwise still: a half turn) grown by the radius.
    D2 v[kMaxPolygonVertices], n[kMaxPolygonVertices];
    for (int k = 0; k < m; ++k) v[k] = Sub(s.centre, pv[k]), n[k] = Scale(-1, pn[k]);
    if (!RayRoundedPolygon(v, n, m, s.radius, D2{0, 0}, d, t, normal)) return false;
    SetHit(hit, t, Add(s.centre, Scale(s.radius, normal)), normal);
    return true;
  }
  D2 points[kMaxPolygonVertices * kMaxPolygonVertices];
  D2 hull[kMaxPolygonVertices * kMaxPolygonVertices + 1];
  int count = 0;
  for (int i = 0; i < s.count; ++i) {
    for (int j = 0; j < m; ++j) points[count++] = Sub(s.v[i], pv[j]);
  }
  const int h = ConvexHull(points, count, hull);
  if (h < 3) return false;
  D2 hn[kMaxPolygonVertices * kMaxPolygonVertices];
  for (int k = 0; k < h; ++k) {
    const D2 e = Sub(hull[(k + 1) % h], hull[k]);
    const double len = std::sqrt(DotD(e, e));
    hn[k] = {e.y / len, -e.x / len};
  }
  if (s.capsule) {
    // S + (-P) is the hull of the segment's ends less P's vertices, grown by the radius; the
    // contact is the moved P's point furthest against the normal (the middle of an edge).
    if (!RayRoundedPolygon(hull, hn, h, s.radius, D2{0, 0}, d, t, normal)) return false;
    D2 moved[kMaxPolygonVertices];
    for (int k = 0; k < m; ++k) moved[k] = Add(pv[k], Scale(t, d));
    const D2 tangent{-normal.y, normal.x};
    const Support onP = SupportAlong(moved, m, Scale(-1, normal), tangent);
    SetHit(hit, t, Add(Scale(-onP.along, normal), Scale(0.5 * (onP.lo + onP.hi), tangent)), normal);
    return true;
  }
  if (!RayRoundedPolygon(hull, hn, h, 0, D2{0, 0}, d, t, normal)) return false;
  // The contact: S's points furthest along the normal meet the moved P's furthest against it.
  // A corner of either is the point; two parallel edges meet along their common stretch, whose
  // middle is taken.
  D2 moved[kMaxPolygonVertices];
  for (int k = 0; k < m; ++k) moved[k] = Add(pv[k], Scale(t, d));
  const D2 tangent{-normal.y, normal.x};
  const Support onS = SupportAlong(s.v, s.count, normal, tangent);
  const Support onP = SupportAlong(moved, m, Scale(-1, normal), tangent);
  double across = 0;
  if (onS.lo == onS.hi) {
    across = onS.lo;
  } else if (onP.lo == onP.hi) {
    across = onP.lo;
  } else {
    across = 0.5 * (std::max(onS.lo, onP.lo) + std::min(onS.hi, onP.hi));
  }
  SetHit(hit, t, Add(Scale(onS.along, normal), Scale(across, tangent)), normal);
  return true;
}

}  // namespace quadrant
