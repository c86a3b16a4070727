// The world's data, shared by the stages. Dense arrays indexed by body (no per-body heap
// objects), split by who touches them: the solver reads and writes only `vel` and `inv`,
// integration `center`, `xf`, `vel`, and the broad phase only `aabb` and `dynamic`.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "collision/narrow_phase.h"
#include "dynamics/joint.h"
#include "quadrant/types.h"
#include "parallel/stage_runner.h"

namespace quadrant {

struct BodyVelocity {
  Vec2 v;
  Real w = 0;
};

struct BodyInverseMass {
  Real invMass = 0;
  Real invInertia = 0;
};

/// What the box update reads of a body's shape: its type, and a circle's centre and radius (the
/// other shapes' boxes read their ShapeDef). 16 bytes beside ShapeDef's 236: reading a circle's
/// fields from `shape` cost a cache line a body, and the box update was 20 % of the step of
/// circle stress 64000 at 1 thread, most of it waiting on that load (perf).
struct BoxShape {
  Vec2 center;
  Real radius = 0;
  ShapeType type = ShapeType::kCircle;
};
inline BoxShape BoxShapeOf(const ShapeDef& s) {
  return s.type == ShapeType::kCircle ? BoxShape{s.circle.center, s.circle.radius, s.type} : BoxShape{{}, 0, s.type};
}

/// Dense body arrays. Index i is a body's dense index; ids map to it through the world's slots.
struct Bodies {
  std::vector<BodyType> type;
  std::vector<Transform> xf;           ///< body origin and rotation
  std::vector<Vec2> center;            ///< world centre of mass
  std::vector<Vec2> localCenter;       ///< centre of mass in body coordinates
  std::vector<BodyVelocity> vel;
  std::vector<BodyInverseMass> inv;
  std::vector<Real> mass;
  std::vector<Real> inertia;
  std::vector<Real> linearDamping;
  std::vector<Real> angularDamping;
  std::vector<ShapeDef> shape;
  std::vector<BoxShape> boxShape;      ///< what the box update reads of `shape` (BoxShape says why)
  std::vector<Real> boundRadius;       ///< farthest shape point from the centre of mass
  std::vector<AABB> aabb;
  std::vector<uint8_t> dynamic;        ///< 1 for dynamic bodies: pairs need at least one
  std::vector<uint32_t> slot;          ///< dense index -> id slot
  // Sleep (islands.cpp; read and written only when effects.sleep is on). A sleeping dynamic
  // body has awake 0, dynamic 0, velocity 0 and inverse mass 0, so every stage treats it as
  // static without a sleep test of its own; waking restores them from mass and inertia.
  std::vector<uint8_t> awake;          ///< 1 for simulated bodies: kinematic and awake dynamic
  std::vector<Real> sleepTime;         ///< seconds the body has been below the sleep tolerances
  std::vector<uint32_t> islandOf;      ///< while asleep: the id of the island it fell asleep with
  // Cold: read only by the pair filter (when some body has a non-default filter), the queries
  // and the user.
  std::vector<Filter> filter;
  std::vector<uint64_t> userData;
  // Cold per-body settings (World::SetGravityScale, SetFixedRotation, SetBullet). Read by the
  // world's pre-solve pass while some body's gravity scale is not 1, and by the broad-phase box
  // and the narrow phase's point filter while bulletCount > 0 with effects.continuous off. The
  // solvers never read them: a fixed-rotation body has inertia and inverse inertia 0 instead.
  std::vector<Real> gravityScale;
  std::vector<uint8_t> fixedRotation;
  std::vector<uint8_t> bullet;
  int bulletCount = 0;  ///< bodies with bullet 1 (not an array: kept by AppendBody and the World)
  // Compound bodies (BodyDef::extraShapes; the design is in narrow_phase_compound.cpp): all of the
  // body's shapes, canonical, first shape first; empty for a one-shape body. Such a body's `shape`
  // is a stand-in of type kCompoundShape whose polygon is the box around all its shapes in body
  // coordinates (the broad-phase box) and whose materials are the first shape's. No hot loop reads
  // this array: the stand-in's type sends the body down the rare-shape paths.
  std::vector<std::vector<ShapeDef>> compound;
  std::vector<std::vector<AABB>> compoundBoxes;  ///< each of `compound`'s shapes' box, body coordinates
  int compoundCount = 0;  ///< bodies with shapes in `compound`

  int Count() const { return static_cast<int>(type.size()); }

  /// Calls fn on every array above: the one list of them (adding and removing a body use it,
  /// so an array added here is grown and shrunk with the rest).
  template <class Fn>
  void ForEachArray(Fn&& fn) {
    fn(type), fn(xf), fn(center), fn(localCenter), fn(vel), fn(inv), fn(mass), fn(inertia);
    fn(linearDamping), fn(angularDamping), fn(shape), fn(boxShape), fn(boundRadius), fn(aabb), fn(dynamic);
    fn(slot), fn(awake), fn(sleepTime), fn(islandOf), fn(filter), fn(userData), fn(gravityScale);
    fn(fixedRotation), fn(bullet), fn(compound), fn(compoundBoxes);
  }
};

/// The type of a compound body's stand-in shape (Bodies::compound). Not a ShapeType a user may
/// give (validation refuses it): bit 3, so the pair loop's test of (type A | type B) for the rare
/// shapes (> kPolygon) takes it there, and a test of bit 3 tells it from capsules and segments.
inline constexpr ShapeType kCompoundShape = ShapeType(8);
inline constexpr bool IsCompoundType(ShapeType t) { return (uint8_t(t) & uint8_t(kCompoundShape)) != 0; }

/// Body i's shapes: its one `shape`, or a compound body's list.
inline std::span<const ShapeDef> BodyShapes(const Bodies& bodies, int i) {
  if (IsCompoundType(bodies.shape[size_t(i)].type)) [[unlikely]] return bodies.compound[size_t(i)];
  return {&bodies.shape[size_t(i)], 1};
}

/// A touching or speculative contact between two bodies (dense indices, a < b).
struct Contact {
  int32_t a = 0;
  int32_t b = 0;
  Real friction = 0;
  Real restitution = 0;
  Manifold manifold;
  /// Where the manifold was computed (with WorldDef::contactRecycleDistance): both bodies'
  /// rotations and B's centre in A's frame relative to A's centre. {0, 0} (no rotation) where it
  /// was computed without recycling on: its turn test fails, so it is never recycled.
  Rot recycleQA{0, 0}, recycleQB{0, 0};
  Vec2 recycleRel;

  uint64_t Key() const { return (uint64_t(uint32_t(a)) << 32) | uint32_t(b); }
};

struct CandidatePair;

/// Validates `def` (throws quadrant::Error and adds nothing on bad input), computes its mass
/// data and appends the body to `bodies` with id slot `slot`; returns its dense index. The one
/// place a body row is made: World::CreateBody and the distributed world both use it.
int AppendBody(Bodies& bodies, const BodyDef& def, const WorldDef& worldDef, uint32_t slot);

/// What a compound body's shapes make (world.cpp): the exact mass data, the farthest shape point
/// from the centre of mass, and the stand-in `shape` (Bodies::compound).
struct CompoundProperties {
  MassData mass;
  Real boundRadius = 0;
  ShapeDef standIn;
};
CompoundProperties MakeCompoundProperties(std::span<const ShapeDef> shapes);

// The shape's box, out of the hot loops (queries, drawing, GetAABB).
// A compound body's stand-in (kCompoundShape) gives the box around its body-frame bounding box.
inline AABB ComputeShapeAABB(const ShapeDef& s, const Transform& xf) {
  if (IsCompoundType(s.type)) return ComputeAABB(s.polygon, xf);
  switch (s.type) {
    case ShapeType::kCircle: return ComputeAABB(s.circle, xf);
    case ShapeType::kCapsule: return ComputeAABB(s.capsule, xf);
    case ShapeType::kSegment: return ComputeAABB(s.segment, xf);
    case ShapeType::kChainSegment: return ComputeAABB(s.chainSegment.segment, xf);
    case ShapeType::kPolygon: break;
  }
  return ComputeAABB(s.polygon, xf);
}

// The broad-phase box of a body: its shape's AABB grown by half the speculative distance on
// every side (so two shapes closer than that distance pair up), and for moving bodies swept
// by this step's displacement, so a pair that can meet within the step is found before it
// touches and the speculative contact stops it at the surface. Shared with the distributed
// world, which must find exactly the World's pairs.
//
// The shape's box is computed here, inline, with exactly ComputeAABB's arithmetic (mass.cpp),
// instead of calling it: the out-of-line call takes the Transform in two registers that the
// callee spills as two 8-byte stores and reloads as one 16-byte load, which cannot be forwarded
// from the stores and stalls. perf put 44 % of ComputeAABB's samples on that load, and
// ComputeAABB at 18 % of all cycles of circle stress 16000 at 1 thread, 2-core VM.
// A circle's box: its centre moved to the world, out by the radius (ShapeBox's and
// BroadPhaseBox's, from the ShapeDef or the 16-byte BoxShape).
[[gnu::always_inline]] inline AABB CircleBox(const Transform& xf, Vec2 center, Real radius) {
  const Vec2 p = TransformPoint(xf, center);
  const Vec2 r{radius, radius};
  return {p - r, p + r};
}
[[gnu::always_inline]] inline AABB ShapeBox(const ShapeDef& s, const Transform& xf) {
  if (s.type == ShapeType::kCircle) return CircleBox(xf, s.circle.center, s.circle.radius);
  // Capsules and segments after the polygons: one compare for all of them.
  if (uint8_t(s.type) > uint8_t(ShapeType::kPolygon)) [[unlikely]] return ComputeShapeAABB(s, xf);
  const Polygon& poly = s.polygon;
  Vec2 lower = TransformPoint(xf, poly.vertices[0]);
  Vec2 upper = lower;
  for (int k = 1; k < poly.count; ++k) {
    const Vec2 v = TransformPoint(xf, poly.vertices[k]);
    lower = Min(lower, v);
    upper = Max(upper, v);
  }
  return {lower, upper};
}


// `sweep` is the time the box is swept over: the step's dt, or 0 for only the base margin.
[[gnu::always_inline]] inline AABB SweepBox(AABB box, const BodyVelocity& bv, Real boundRadius, Real speculativeDistance,
                                            Real sweep) {
  const Real margin = Real(0.5) * speculativeDistance + sweep * std::abs(bv.w) * boundRadius;
  const Vec2 d = sweep * bv.v;
  box.lower = box.lower + Vec2{std::min(d.x, Real(0)) - margin, std::min(d.y, Real(0)) - margin};
  box.upper = box.upper + Vec2{std::max(d.x, Real(0)) + margin, std::max(d.y, Real(0)) + margin};
  return box;
}

[[gnu::always_inline]] inline AABB SweptBoxOver(const ShapeDef& s, const Transform& xf, const BodyVelocity& bv, Real boundRadius,
                                                Real speculativeDistance, Real sweep) {
  return SweepBox(ShapeBox(s, xf), bv, boundRadius, speculativeDistance, sweep);
}

// Without continuous collision the box is not swept (sweep 0): only the base margin.
inline AABB SweptBox(const ShapeDef& s, const Transform& xf, const BodyVelocity& bv, Real boundRadius,
                     const WorldDef& def, Real dt) {
  return SweptBoxOver(s, xf, bv, boundRadius, def.speculativeDistance, def.effects.continuous ? dt : Real(0));
}

/// The same for body i of `bodies`; a bullet body (Bodies::bullet) is swept even with
/// effects.continuous off. With it on, or while no body is a bullet, the bullet flags are not read.
/// Always inlined, as are SweptBoxOver and ShapeBox: where GCC left any of them out of line, the
/// call cost up to 16 instructions a body in the box update (circle_stress 1000: 2.6 % of the
/// step, callgrind).
[[gnu::always_inline]] inline AABB BroadPhaseBox(const Bodies& bodies, int i, const WorldDef& def, Real dt) {
  const bool sweep = def.effects.continuous || (bodies.bulletCount > 0 && bodies.bullet[i] != 0);
  const BoxShape& k = bodies.boxShape[i];
  const Transform& xf = bodies.xf[i];
  const AABB box = k.type == ShapeType::kCircle ? CircleBox(xf, k.center, k.radius) : ShapeBox(bodies.shape[i], xf);
  return SweepBox(box, bodies.vel[i], bodies.boundRadius[i], def.speculativeDistance, sweep ? dt : Real(0));
}


/// Narrow phase for a list of pairs: manifolds with material mixing, speculative points kept
/// only where the gap can close within the step. Appends to `out` in pair order.
/// Last step's contacts, from which the pair loop may recycle manifolds (contactRecycleDistance):
/// `contacts` in strictly increasing key order, `first[a]` the index of body a's first contact as
/// body a (-1: none; one entry per body).
struct RecycleSource {
  const Contact* contacts = nullptr;
  int count = 0;
  const int32_t* first = nullptr;  ///< per body: its first contact as body a, where that contact starts a's run
  Real distance = 0;  ///< WorldDef::contactRecycleDistance (> 0)
};

void CollidePairs(const Bodies& bodies, const WorldDef& def, Real dt, std::span<const CandidatePair> pairs,
                  std::vector<Contact>& out, const RecycleSource* recycle = nullptr);

/// CollidePairs for pairs of one-shape bodies only (the pair loops, narrow_pair_loop.inc).
void CollideSimplePairs(const Bodies& bodies, const WorldDef& def, Real dt, std::span<const CandidatePair> pairs,
                        std::vector<Contact>& out, const RecycleSource* recycle);

/// CollidePairs in a world with compound bodies (Bodies::compound; narrow_phase_compound.cpp): runs
/// of pairs without a compound body go to CollideSimplePairs; a pair with one gets a contact for
/// each pair of shapes whose manifold keeps a point, in a fixed shape order.
void CollidePairsWithCompounds(const Bodies& bodies, const WorldDef& def, Real dt, std::span<const CandidatePair> pairs,
                               std::vector<Contact>& out, const RecycleSource* recycle);

/// What a solver needs for one (sub-)step.
struct StepContext {
  Real dt = 0;
  const WorldDef* def = nullptr;
  Bodies* bodies = nullptr;
  std::span<Contact> contacts;
  /// The world's joints (soft_step solves them; the world refuses joints with the other solvers),
  /// their dense body indices current.
  std::span<Joint> joints;
  /// Changes whenever a joint is added or removed or the bodies' dense indices move (JointSet):
  /// with the same version and the same moving ends, last step's joint colouring holds.
  uint64_t jointsVersion = 0;
  Profile* profile = nullptr;
  StageRunner* run = nullptr;
  /// Some body's gravity scale is not 1 (Bodies::gravityScale) and the solver applies the scales
  /// itself (soft_step, per sub-step); otherwise World's pre-solve pass has applied them.
  bool gravityScaled = false;
};

}  // namespace quadrant
