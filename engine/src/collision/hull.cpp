// Polygon construction: convex hull of a few points, with every degenerate case refused.
//
// The narrow phase and the mass computation assume a strictly convex, counter-clockwise
// polygon whose edges are long enough to give stable normals in float32. Rather than repair
// bad input silently (Box2D welds close points and drops collinear ones), Quadrant refuses it
// with a message, so a scene never simulates a shape other than the one its author wrote.
#include <algorithm>
#include <array>
#include <string>

#include "quadrant/error.h"
#include "quadrant/shapes.h"

namespace quadrant {
namespace {

std::string PointText(Vec2 p) { return "(" + std::to_string(p.x) + ", " + std::to_string(p.y) + ")"; }

void ValidatePoint(Vec2 p, int i) {
  if (!IsFinite(p)) throw Error("polygon vertex " + std::to_string(i) + " is not finite");
  if (std::abs(p.x) > kMaxCoordinate || std::abs(p.y) > kMaxCoordinate) {
    throw Error("polygon vertex " + std::to_string(i) + " " + PointText(p) +
                " is beyond the coordinate limit of 1e6 m");
  }
}

Vec2 ComputeCentroid(const std::array<Vec2, kMaxPolygonVertices>& v, int count) {
  // Triangle fan about the first vertex: keeps the numbers small for shapes far from origin.
  Vec2 origin = v[0];
  Real area = 0;
  Vec2 c{0, 0};
  for (int i = 1; i + 1 < count; ++i) {
    Vec2 e1 = v[i] - origin;
    Vec2 e2 = v[i + 1] - origin;
    Real a = Real(0.5) * Cross(e1, e2);
    c += (a / Real(3)) * (e1 + e2);
    area += a;
  }
  return origin + (Real(1) / area) * c;
}

}  // namespace

Polygon MakePolygon(std::span<const Vec2> points, bool requireConvex) {
  const int n = static_cast<int>(points.size());
  if (n < 3) throw Error("a polygon needs at least 3 vertices, got " + std::to_string(n));
  if (n > kMaxPolygonVertices) {
    throw Error("a polygon has at most 8 vertices, got " + std::to_string(n));
  }
  std::array<Vec2, kMaxPolygonVertices> p{};
  for (int i = 0; i < n; ++i) {
    ValidatePoint(points[i], i);
    p[i] = points[i];
  }
  const Real minDist2 = kMinFeatureSize * kMinFeatureSize;
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      if (LengthSquared(p[i] - p[j]) < minDist2) {
        throw Error("polygon vertices " + std::to_string(i) + " and " + std::to_string(j) +
                    " are duplicates (closer than 0.005 m)");
      }
    }
  }

  // Andrew's monotone chain: sort, then a lower and an upper chain. Points on a hull edge are
  // dropped (strictly convex result).
  std::sort(p.begin(), p.begin() + n, [](Vec2 a, Vec2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
  std::array<Vec2, 2 * kMaxPolygonVertices> hull{};
  int h = 0;
  for (int pass = 0; pass < 2; ++pass) {
    const int start = h;
    for (int k = 0; k < n; ++k) {
      Vec2 q = pass == 0 ? p[k] : p[n - 1 - k];
      while (h >= start + 2 && Cross(hull[h - 1] - hull[h - 2], q - hull[h - 2]) <= 0) --h;
      hull[h++] = q;
    }
    --h;  // the last point of each chain starts the other
  }
  if (h < 3) throw Error("polygon vertices are collinear");
  if (requireConvex && h != n) {
    throw Error("polygon is not convex: " + std::to_string(n - h) +
                " of its vertices lie inside the hull or on an edge");
  }

  Polygon poly;
  poly.count = h;
  for (int i = 0; i < h; ++i) poly.vertices[i] = hull[i];
  Real area2 = 0;
  for (int i = 0; i < h; ++i) {
    Vec2 a = poly.vertices[i];
    Vec2 b = poly.vertices[(i + 1) % h];
    Vec2 edge = b - a;
    if (LengthSquared(edge) < minDist2) throw Error("polygon has an edge shorter than 0.005 m");
    poly.normals[i] = Normalize(RightPerp(edge));
    area2 += Cross(a - poly.vertices[0], b - poly.vertices[0]);
  }
  // Thinness: every vertex farther than kMinFeatureSize from the line of at least one edge
  // means the polygon has real width; a sliver would give unstable normals.
  for (int i = 0; i < h; ++i) {
    Real width = 0;
    for (int j = 0; j < h; ++j) {
      width = std::max(width, -Dot(poly.normals[i], poly.vertices[j] - poly.vertices[i]));
    }
    if (width < kMinFeatureSize) throw Error("polygon is nearly collinear (thinner than 0.005 m)");
  }
  if (area2 <= 0) throw Error("polygon has no area");
  poly.centroid = ComputeCentroid(poly.vertices, h);
  return poly;
}

Polygon MakeBox(Real hx, Real hy, Vec2 center, Real angle) {
  if (!IsFinite(hx) || !IsFinite(hy) || hx < Real(0.5) * kMinFeatureSize || hy < Real(0.5) * kMinFeatureSize) {
    throw Error("box half-widths must be finite and at least 0.0025 m");
  }
  if (!IsFinite(center) || !IsFinite(angle)) throw Error("box centre and angle must be finite");
  if (hx > kMaxCoordinate || hy > kMaxCoordinate || std::abs(center.x) > kMaxCoordinate ||
      std::abs(center.y) > kMaxCoordinate) {
    throw Error("box is beyond the coordinate limit of 1e6 m");
  }
  Transform xf{center, MakeRot(angle)};
  const Vec2 corners[4] = {{-hx, -hy}, {hx, -hy}, {hx, hy}, {-hx, hy}};
  const Vec2 normals[4] = {{0, -1}, {1, 0}, {0, 1}, {-1, 0}};
  Polygon poly;
  poly.count = 4;
  for (int i = 0; i < 4; ++i) {
    poly.vertices[i] = TransformPoint(xf, corners[i]);
    poly.normals[i] = Rotate(xf.q, normals[i]);
  }
  poly.centroid = center;
  return poly;
}

void ValidateCircle(const Circle& circle) {
  if (!IsFinite(circle.center)) throw Error("circle centre is not finite");
  if (!IsFinite(circle.radius)) throw Error("circle radius is not finite");
  if (circle.radius < kMinFeatureSize) {
    throw Error("circle radius must be at least 0.005 m, got " + std::to_string(circle.radius));
  }
  if (circle.radius > kMaxCoordinate || std::abs(circle.center.x) > kMaxCoordinate ||
      std::abs(circle.center.y) > kMaxCoordinate) {
    throw Error("circle is beyond the coordinate limit of 1e6 m");
  }
}

void ValidateCapsule(const Capsule& capsule) {
  if (!IsFinite(capsule.center1) || !IsFinite(capsule.center2)) throw Error("capsule centre is not finite");
  if (!IsFinite(capsule.radius)) throw Error("capsule radius is not finite");
  if (capsule.radius < kMinFeatureSize) {
    throw Error("capsule radius must be at least 0.005 m, got " + std::to_string(capsule.radius));
  }
  const Real limit = kMaxCoordinate;
  if (capsule.radius > limit || std::abs(capsule.center1.x) > limit || std::abs(capsule.center1.y) > limit ||
      std::abs(capsule.center2.x) > limit || std::abs(capsule.center2.y) > limit) {
    throw Error("capsule is beyond the coordinate limit of 1e6 m");
  }
  const Real length = Length(capsule.center2 - capsule.center1);
  if (!(length >= kMinFeatureSize)) {
    throw Error("capsule length (centre to centre) must be at least 0.005 m, got " + std::to_string(length) +
                " (a circle is ShapeDef::MakeCircle)");
  }
}

namespace {

bool WithinLimit(Vec2 p) { return std::abs(p.x) <= kMaxCoordinate && std::abs(p.y) <= kMaxCoordinate; }

}  // namespace

void ValidateSegment(const Segment& segment) {
  if (!IsFinite(segment.point1) || !IsFinite(segment.point2)) throw Error("segment point is not finite");
  if (!WithinLimit(segment.point1) || !WithinLimit(segment.point2)) {
    throw Error("segment is beyond the coordinate limit of 1e6 m");
  }
  // Closer than the linear slop, the segment's direction (and so its normal) is noise.
  const Real length = Length(segment.point2 - segment.point1);
  if (!(length >= kMinFeatureSize)) {
    throw Error("segment length must be at least 0.005 m, got " + std::to_string(length));
  }
}

void ValidateChainSegment(const ChainSegment& chainSegment) {
  ValidateSegment(chainSegment.segment);
  if (!IsFinite(chainSegment.ghost1) || !IsFinite(chainSegment.ghost2)) {
    throw Error("chain segment ghost vertex is not finite");
  }
  if (!WithinLimit(chainSegment.ghost1) || !WithinLimit(chainSegment.ghost2)) {
    throw Error("chain segment ghost vertex is beyond the coordinate limit of 1e6 m");
  }
  // The neighbours' directions give the ghost normals: each needs a length too.
  const Real before = Length(chainSegment.segment.point1 - chainSegment.ghost1);
  const Real after = Length(chainSegment.ghost2 - chainSegment.segment.point2);
  if (!(before >= kMinFeatureSize) || !(after >= kMinFeatureSize)) {
    throw Error("chain segment ghost vertex must be at least 0.005 m from its end, got " +
                std::to_string(std::min(before, after)));
  }
}

}  // namespace quadrant
