// Quadrant's debug drawing: World::Draw hands every body's shape (and, if asked, its box and the
// contact points) to a DebugDraw the caller implements with whatever renderer it has. The engine
// draws nothing itself and keeps no state for it: a call costs only what the callbacks cost.
#pragma once

#include <cstdint>
#include <span>

#include "quadrant/math.h"

namespace quadrant {

/// An RGBA colour, each channel in [0, 1].
struct Color {
  float r = 1, g = 1, b = 1, a = 1;
  friend constexpr bool operator==(Color x, Color y) = default;
};

// The colours World::Draw gives shapes by what the body is (a sensor first, then by type, a
// sleeping dynamic body apart), and boxes.
inline constexpr Color kStaticColor{0.5f, 0.9f, 0.5f, 1};
inline constexpr Color kKinematicColor{0.5f, 0.5f, 0.9f, 1};
inline constexpr Color kDynamicColor{0.9f, 0.7f, 0.7f, 1};
inline constexpr Color kSleepingColor{0.6f, 0.6f, 0.6f, 1};
inline constexpr Color kSensorColor{0.9f, 0.9f, 0.3f, 1};
inline constexpr Color kAABBColor{0.9f, 0.3f, 0.9f, 1};

/// What World::Draw draws (bits, combined with |).
inline constexpr uint32_t kDrawShapes = 1u << 0;    ///< every body's shape (DrawCircle, DrawPolygon)
inline constexpr uint32_t kDrawAABBs = 1u << 1;     ///< every body's shape box (DrawAABB)
inline constexpr uint32_t kDrawContacts = 1u << 2;  ///< every contact point of the last Step (DrawContact)
inline constexpr uint32_t kDrawAll = kDrawShapes | kDrawAABBs | kDrawContacts;

/// The callbacks of World::Draw, in world coordinates (m, rad). Implement the two shape calls;
/// the others do nothing unless overridden. A callback must not change the World that is drawing
/// (no Step, CreateBody, DestroyBody or setter; reading it is fine).
class DebugDraw {
 public:
  virtual ~DebugDraw() = default;
  /// A circle of `radius` at `center`; `angle` is its body's angle, for a line from the centre
  /// that shows the body turning.
  virtual void DrawCircle(Vec2 center, Real radius, Real angle, Color color) = 0;
  /// A convex polygon, its 3 to 8 vertices counter-clockwise (the span lives for the call only);
  /// 2 vertices only from DrawSegment's default, a line.
  virtual void DrawPolygon(std::span<const Vec2> vertices, Color color) = 0;
  /// A capsule: the points within `radius` of the segment p1-p2. By default its rectangle as a
  /// polygon and its two end discs as circles.
  virtual void DrawCapsule(Vec2 p1, Vec2 p2, Real radius, Color color) {
    const Vec2 axis = p2 - p1;
    const Real length = Length(axis);
    const Vec2 side = length > 0 ? (radius / length) * Vec2{-axis.y, axis.x} : Vec2{0, radius};
    const Vec2 rect[4] = {p1 - side, p2 - side, p2 + side, p1 + side};
    DrawPolygon(std::span<const Vec2>(rect, 4), color);
    DrawCircle(p1, radius, 0, color);
    DrawCircle(p2, radius, 0, color);
  }
  /// A segment or chain segment, a line from p1 to p2 (a chain segment's solid side is on the
  /// left of p1 -> p2). By default a polygon of the two vertices p1, p2: the one DrawPolygon call
  /// with fewer than 3 vertices, which a renderer that draws outlines draws as the line.
  virtual void DrawSegment(Vec2 p1, Vec2 p2, Color color) {
    const Vec2 line[2] = {p1, p2};
    DrawPolygon(std::span<const Vec2>(line, 2), color);
  }
  /// A contact point and its unit normal (from the contact's first body to its second).
  virtual void DrawContact(Vec2 point, Vec2 normal) { (void)point, (void)normal; }
  /// A shape's axis-aligned bounding box.
  virtual void DrawAABB(const AABB& box, Color color) { (void)box, (void)color; }
};

}  // namespace quadrant
