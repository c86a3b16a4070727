// Quadrant's value types: body ids, the definitions a world and its bodies are made from
// (WorldDef, BodyDef, ShapeDef, Filter, Effects, with every default documented here), and what
// a step reports (Profile, Counters, ContactInfo, RayHit, ContactEvent). No behaviour: the
// engine's stages include this header, not world.h; users include world.h, which includes it.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "quadrant/error.h"
#include "quadrant/math.h"
#include "quadrant/shapes.h"

namespace quadrant {


/// A body handle. A value type: index into the world's slots plus a generation that is
/// bumped when the slot is freed, so a stale id is detected instead of aliasing a new body.
/// The default (generation 0) is the null id; live ids have generation >= 1.
struct BodyId {
  uint32_t index = 0;
  uint32_t generation = 0;
  constexpr bool IsNull() const { return generation == 0; }
  friend constexpr bool operator==(BodyId a, BodyId b) = default;
};

enum class BodyType : uint8_t {
  kStatic,     ///< never moves, infinite mass
  kKinematic,  ///< moves by its velocity, infinite mass, not pushed by contacts
  kDynamic,    ///< moved by gravity and contacts
};

/// The hot loops test circles and polygons first; every later type is rarer and goes out of line.
enum class ShapeType : uint8_t { kCircle, kPolygon, kCapsule, kSegment, kChainSegment };

/// A segment or a chain segment: no area, static and kinematic bodies only.
constexpr bool IsSegmentType(ShapeType t) { return t == ShapeType::kSegment || t == ShapeType::kChainSegment; }

/// Most shapes one body may carry (BodyDef::shape and BodyDef::extraShapes together): a contact
/// point's feature id names the shape on each side in 6 bits (narrow_phase.h, kCompoundFeature).
inline constexpr int kMaxBodyShapes = 64;

/// One shape of a body. Most bodies carry one (BodyDef::shape), which the hot loops read with no
/// shape list; a compound body adds more (BodyDef::extraShapes) and takes an out-of-line path.
struct ShapeDef {
  ShapeType type = ShapeType::kCircle;
  /// A sensor senses the bodies its shape overlaps and pushes none: its pairs make no contact,
  /// only overlap events (World::GetSensorBeginEvents). Any body type may carry one: a static or
  /// kinematic sensor senses dynamic bodies, a dynamic one every body whose pair the broad phase
  /// finds (a pair needs an awake dynamic body; World::GetSensorBeginEvents has the rules). A
  /// dynamic sensor body still has mass (from density) and falls, through everything. Two sensors
  /// do not sense each other. Needs ParallelScheme::kDeterministic (CreateBody refuses it under
  /// kQuadrants; DistributedWorld refuses it). Default false. (Kept here, beside `type`, where it
  /// fills padding: the narrow phase reads shapes in whole cache lines.)
  bool isSensor = false;
  Circle circle;
  Polygon polygon;
  Capsule capsule;
  Real density = 1;       ///< kg/m^2, > 0 for dynamic bodies
  Real friction = Real(0.6);   ///< Coulomb coefficient, >= 0; mixed as sqrt(fa*fb) like Box2D
  Real restitution = 0;   ///< 0..1 (values above 1 are refused); mixed as max(ea, eb) like Box2D
  // The zero-area shapes, after the materials so that the fields the hot loops read keep their
  // offsets (the narrow phase reads shapes in whole cache lines).
  Segment segment;            ///< ShapeType::kSegment
  ChainSegment chainSegment;  ///< ShapeType::kChainSegment

  static ShapeDef MakeCircle(Real radius, Vec2 center = {});
  static ShapeDef Box(Real hx, Real hy, Vec2 center = {}, Real angle = 0);
  static ShapeDef FromPolygon(const Polygon& polygon);
  /// A capsule from center1 to center2 (body coordinates) of the given radius; validated
  /// (ValidateCapsule). Not under ParallelScheme::kQuadrants or in a DistributedWorld.
  static ShapeDef MakeCapsule(Vec2 center1, Vec2 center2, Real radius);
  /// A two-sided segment from p1 to p2 (body coordinates); validated (ValidateSegment). Static
  /// and kinematic bodies only (CreateBody refuses a dynamic one: no area, no mass). Not under
  /// ParallelScheme::kQuadrants or in a DistributedWorld.
  static ShapeDef MakeSegment(Vec2 p1, Vec2 p2);
  /// One segment p1 -> p2 of a chain whose neighbouring vertices are ghost1 (before p1) and
  /// ghost2 (after p2): one-sided, solid on the left, colliding on the right (ChainSegment has the
  /// convention); validated (ValidateChainSegment). Static and kinematic bodies only.
  /// MakeChainBodies builds a whole chain.
  static ShapeDef MakeChainSegment(Vec2 ghost1, Vec2 p1, Vec2 p2, Vec2 ghost2);
};

/// Every category bit: the default mask of bodies and queries.
inline constexpr uint32_t kAllCategories = 0xFFFFFFFFu;

/// Collision filtering with Box2D's rule (ShouldCollide): two bodies of the same non-zero
/// groupIndex always collide when it is positive and never when it is negative, whatever their
/// bits; otherwise they collide only if (a.maskBits & b.categoryBits) != 0 and
/// (b.maskBits & a.categoryBits) != 0. A pair that fails it gets no contact at all (it is dropped
/// after the broad phase; a sensor's pair that fails it has no overlap either). The default
/// (category 1, every mask bit, group 0) collides with everything; while every body has it, the
/// step does no filtering work at all. Needs ParallelScheme::kDeterministic (World refuses a
/// non-default filter under kQuadrants, whose threads find pairs on their own).
struct Filter {
  uint32_t categoryBits = 1;              ///< what the body is (usually one bit)
  uint32_t maskBits = kAllCategories;     ///< the categories it collides with
  /// 0: no group (the bits decide). Bodies sharing a positive group always collide, a negative
  /// one never (a ragdoll's limbs: one negative group), whatever their bits.
  int32_t groupIndex = 0;
  friend constexpr bool operator==(Filter a, Filter b) = default;
};

/// Box2D's filter rule (Filter): whether bodies with filters a and b may collide.
constexpr bool ShouldCollide(Filter a, Filter b) {
  if (a.groupIndex == b.groupIndex && a.groupIndex != 0) return a.groupIndex > 0;
  return (a.maskBits & b.categoryBits) != 0 && (b.maskBits & a.categoryBits) != 0;
}

struct BodyDef {
  BodyType type = BodyType::kStatic;
  Vec2 position;            ///< world position of the body origin (m)
  Real angle = 0;           ///< radians
  Vec2 linearVelocity;      ///< m/s, of the centre of mass
  Real angularVelocity = 0; ///< rad/s
  Real linearDamping = 0;   ///< 1/s, >= 0 (applied only when the world enables damping)
  Real angularDamping = 0;  ///< 1/s, >= 0
  ShapeDef shape;
  /// More shapes on the same body (a compound body, as Box2D's several fixtures or shapes per
  /// body): empty by default. With any, the body's mass is the sum of its shapes' masses, its
  /// centre of mass their mass-weighted centre and its inertia the sum of theirs about that centre
  /// (parallel axes): exact. Each shape keeps its own friction, restitution and density (0 is
  /// allowed for some shapes of a dynamic body as long as the total mass is positive). At most
  /// kMaxBodyShapes - 1; no sensors; a segment only on a static or kinematic body, as for `shape`.
  /// Contacts are made per pair of touching shapes (several per pair of bodies). Needs
  /// ParallelScheme::kDeterministic; not in a DistributedWorld.
  std::vector<ShapeDef> extraShapes;
  Filter filter;            ///< collision filtering (Filter), default: collides with everything
  /// Yours: the engine stores it and never reads it (World::GetUserData). A game keeps an entity
  /// index or a pointer here (reinterpret_cast<uintptr_t>).
  uint64_t userData = 0;
  /// Multiplies the world's gravity for this body (dimensionless; default 1; 0 floats, -1 falls
  /// up): finite, in [-1e6, 1e6]. Only dynamic bodies feel gravity. World::SetGravityScale says
  /// how a scale other than 1 is applied.
  Real gravityScale = 1;
  /// Never turns: the body's rotational inertia and inverse inertia are 0 (no contact, force or
  /// impulse changes its angular velocity, which stays 0; World::GetRotationalInertia reads 0).
  /// angularVelocity must then be 0. Default false.
  bool fixedRotation = false;
  /// false: the body is created asleep (Box2D 3's isAwake), as a settled pile or a wall of boxes
  /// waiting to be hit is; it wakes like any sleeping body when an awake one touches it. Needs a
  /// dynamic body in a world with effects.sleep. Default true.
  bool isAwake = true;
  /// Continuous collision for this body where the world's effects.continuous is off: its
  /// broad-phase box is swept over the step and its speculative contacts kept as far as it can
  /// close within the step, as every body's are with continuous on, so a fast bullet does not pass
  /// through a thin wall. With effects.continuous on (the default) every body already gets this
  /// and the flag changes nothing. Default false.
  bool isBullet = false;
};

/// A chain of segments without ghost collisions (Box2D 3's b2ChainDef): terrain a box slides over
/// without catching at the joins. Each segment is one-sided (ChainSegment: it collides on its
/// right, so a counter-clockwise loop faces outwards and a ground runs right to left) and knows its
/// neighbours' far ends as ghost vertices. Quadrant bodies carry one shape, so a chain is one
/// static body per segment (MakeChainBodies, World::CreateChain).
struct ChainDef {
  /// World coordinates, in order; consecutive points at least 0.005 m apart. An open chain needs
  /// 4 or more and, as in Box2D 3, its first and last segments are only ghosts (no collision):
  /// points 1 to count - 2 are the ground. A loop needs 3 or more and closes back to the first.
  std::vector<Vec2> points;
  bool isLoop = false;
  Real friction = Real(0.6);  ///< every segment's, as ShapeDef::friction
  Real restitution = 0;       ///< every segment's, as ShapeDef::restitution
  Filter filter;              ///< every segment body's
};

/// The static bodies of a chain, one ShapeDef::MakeChainSegment each, at the origin with the
/// points as their shapes' coordinates (so neighbours share their vertices bit for bit).
/// Validated; throws quadrant::Error naming the bad segment.
std::vector<BodyDef> MakeChainBodies(const ChainDef& def);

/// Throws quadrant::Error, with the message CreateBody would give, for a definition that
/// World::CreateBody refuses whatever the world (bad numbers, shapes, densities, a mass that
/// overflows). What depends on the world is not checked (a non-default filter under
/// ParallelScheme::kQuadrants). For tools that check a description before they have a World:
/// the scene API's ValidateScene runs every scene body through it.
void CheckBodyDef(const BodyDef& def);

/// The mass data of validated shapes as one rigid body (a compound body's: BodyDef::extraShapes),
/// each at its own density: the summed mass, the mass-weighted centre (body coordinates) and the
/// inertia about it (parallel axes), summed in double; exactly what CreateBody gives the body.
MassData ComputeBodyMass(std::span<const ShapeDef> shapes);

enum class SolverType : uint8_t {
  kThesis,  ///< the 2013 thesis: mass-ratio separation + one impulse per contact, no iterations
  kPgs,     ///< sequential impulses, warm starting, velocity iterations, position pass (Box2D 2.4)
  kSoftStep,  ///< sub-steps with soft contacts and a relax pass (Box2D 3)
  /// Jacobi velocity iterations with mass splitting (engine/src/dynamics/jacobi_solve.h): every contact
  /// solved from the velocities at the start of the iteration, each body's changes summed in
  /// contact-key order, penetration removed by a Baumgarte velocity bias (no position pass),
  /// restitution as a velocity bias (kBox2d's, also for speculative points closing within the
  /// step). velocityIterations applies; positionIterations and restitutionIterations do not.
  /// Its result does not depend on how bodies are split
  /// among processes: it is the solver of quadrant::DistributedWorld, whose state equals a
  /// World's with this solver. Softer than pgs on stacks (docs/distributed.md).
  kJacobi,
};

enum class BroadPhaseType : uint8_t {
  kQuadTree,     ///< the thesis's region quad-tree (body in the smallest node holding its AABB)
  kUniformGrid,  ///< a uniform grid rebuilt each step, cells sized by the bodies (see uniform_grid.cpp)
};

/// Effects a world simulates. A disabled effect's work is not done at all: the step picks a
/// specialised path, it does not multiply by zero.
struct Effects {
  bool gravity = true;
  bool friction = true;
  bool restitution = true;
  bool rotation = true;       ///< false: angular velocity stays 0 and no angular terms are solved
  bool warmStarting = true;   ///< pgs only: start from last step's impulses
  bool damping = false;       ///< apply per-body linear/angular damping
  /// Continuous collision: a body's broad-phase box is swept by its motion over the step and a
  /// contact is created wherever the gap can close within the step, so nothing tunnels. Off:
  /// contacts are created only within speculativeDistance (a fast body can pass through a
  /// thin one).
  bool continuous = true;
  /// Sleeping (islands.cpp): a group of dynamic bodies connected by contacts that has been slow
  /// for WorldDef::timeToSleep stops being simulated (no integration, no AABB update, no pairs
  /// among sleeping or with static bodies) until something touches or moves it. Off: no island
  /// bookkeeping at all, every body is simulated every step.
  bool sleep = false;
};

/// How the pgs and soft_step solvers apply restitution (WorldDef::restitution).
enum class RestitutionPolicy : uint8_t {
  /// Pairwise collisions before the velocity iterations or sub-steps (contact_constraints.h, ApplyCollisions): each
  /// approaching contact gets the impulse of a collision of its two bodies alone, sequentially, so
  /// a row of touching balls passes the impulse on as Newton's cradle does. The default.
  kCollisions,
  /// Box2D 2.4.1's way, to reproduce its responses: each point's normal approach speed vn is
  /// captured before the solve (after gravity, before warm starting); where vn < -threshold the
  /// normal row's target becomes -e vn (a velocity bias) inside the velocity iterations, solved
  /// simultaneously with friction and the other rows. soft_step: vn is captured before the step's
  /// sub-steps (before their gravity), and rigid rows with that target and friction act after the
  /// first sub-step's relax pass, the bodies moving as if they had from its start
  /// (engine/src/dynamics/soft_step_restitution.cpp). pgs and soft_step (World refuses it with thesis). docs/validation.md
  /// gives what it changes against Box2D and the analytic answer.
  kBox2d,
};

/// How a world with threadCount > 1 splits its work.
enum class ParallelScheme : uint8_t {
  /// Every stage parallel over static blocks, per-thread buffers merged in block order, and the
  /// solver parallel over constraint-graph colours: the state is bit-identical for any thread
  /// count (the state hash is a test).
  kDeterministic,
  /// The thesis's data partition: the quad-tree's top nodes are the threads' regions; each
  /// thread detects, resolves and integrates the bodies it owns; bodies straddling a region
  /// boundary belong to the master. Results depend on the thread count.
  kQuadrants,
};

struct WorldDef {
  Vec2 gravity{0, Real(-10)};           ///< m/s^2
  /// The default is soft_step with two relax passes and a mass-ratio limit of 10 (below), chosen
  /// by measurement (issue #13; docs/solvers.md): it holds all 16 hard cases at the default budget,
  /// pgs 13, and the base-100 pyramid costs it 43.2M instructions a step against pgs's 58.4M.
  SolverType solver = SolverType::kSoftStep;
  BroadPhaseType broadPhase = BroadPhaseType::kUniformGrid;
  int velocityIterations = 8;           ///< pgs, >= 1 (Box2D 2.4 default 8)
  int positionIterations = 3;           ///< pgs position pass, >= 0 (Box2D 2.4 default 3)
  /// Restitution passes, >= 1. pgs: most passes of pairwise collisions before the velocity
  /// iterations (they stop early once no contact collides; a row of k touching bodies needs
  /// about k / 2). soft_step: the same, before its sub-steps.
  int restitutionIterations = 4;
  int softSubSteps = 4;                 ///< soft_step sub-steps per step, >= 1 (Box2D 3 default 4)
  Real contactHertz = 30;               ///< soft_step contact stiffness (Hz), > 0 (Box2D 3: 30)
  /// soft_step contact damping ratio, >= 0 (Box2D 3: 10). 5 pushes overlap out twice as fast
  /// (bias rate 17.5/s instead of 9.1/s at 4 sub-steps): with two relax passes and 10 the confined
  /// circles were still spreading at 1 s and gained 2.05 J (3 %) when they reached the walls; with 5
  /// they are done by then (rise 0.008 J of 247 J) and the tall stack still holds (top 0.035 m).
  /// The stack and the confined circles are both near their limits around it (docs/soft_step.md).
  Real contactDampingRatio = 5;
  /// soft_step joint stiffness (Hz, > 0) and damping ratio (>= 0) of the joints' rigid rows
  /// (joints.h), as Box2D 3.0's defaults; the stiffness is capped at a quarter of the sub-step rate
  /// as the contacts' is.
  Real jointHertz = 60;
  Real jointDampingRatio = 2;
  /// soft_step: solve joints in chains exactly, as one block-tridiagonal system per chain in each
  /// sub-step's solve pass, instead of one joint after another: revolute joints' point rows, or
  /// rigid welds' point and angle rows. Chains are cut through bodies of any number of joints
  /// (a net into its rows and columns; docs/solvers.md). A 30-link chain holding a body 1000 times
  /// a link's mass then stretches 5e-6 instead of 0.59, a 10 m welded cantilever sags 7e-5 m
  /// instead of 3.6 m, a 30 x 30 net hung from seven pins opens its joints 0.017 m instead of
  /// 0.056 m; joint_grid 9993 costs 1.46x. The relax pass, and chains' limits, motors and springs,
  /// are solved one by one.
  bool jointChainSolve = true;
  Real contactPushMaxVelocity = 3;      ///< soft_step fastest push-out of penetration (m/s), > 0
  /// soft_step: the deepest penetration at which its contacts are soft (m), > 0, beyond twice the
  /// compression a point's soft spring needs for the load it carries (its normal impulse), so a
  /// stack's loaded contacts stay soft; deeper points are rigid rows pushing out at the rate they
  /// have at this depth, and the rest of the overlap is moved out by a position pass
  /// (positionIterations) that adds no velocity.
  Real contactPushMaxDepth = Real(0.01);
  /// soft_step: solve four contact rows at a time (SSE2, in float builds on x86-64) instead of one.
  /// The state is the same bit for bit either way (a test checks it); false exists for that test
  /// and to measure what the four-wide path gains.
  bool softSimd = true;
  /// soft_step: with softSimd, solve eight contact rows at a time with AVX when the CPU has it
  /// (checked at run time): the same operations per row, fewer instructions, the same state bit
  /// for bit (a test checks it); false keeps the four-wide SSE2 kernels (for that test and to
  /// measure).
  bool softVex = true;
  /// soft_step: relax passes per sub-step, >= 1 (Box2D 3: 1). The second one held the 30-box tall
  /// stack at 4 sub-steps before contact recycling (top 0.035 m; with one 0.083 m, 0.05 allowed);
  /// since, one holds it too (50 boxes: 0.026 m, against 0.0004 m with two; docs/soft_step.md), at
  /// the cost of one pass over the rows per sub-step (friction is solved in the last one only;
  /// base-100 pyramid: +4.3M instructions a step).
  int softRelaxIterations = 2;
  /// soft_step: solve friction in every relax pass, not only the last. Where a lever arm couples
  /// friction and the normal row (an oblique corner hit), the passes then converge both as Box2D
  /// 2.4.1's iterations do; part of soft_step's Box2D-compatible setting (docs/validation.md).
  bool softFrictionEveryRelaxPass = false;
  /// soft_step: 0 (off) or the largest mass ratio a contact between two dynamic bodies sees, >= 1.
  /// Where two bodies' masses differ by more, the lighter one takes part in their contact as if it
  /// were only this many times lighter (inverse mass and inertia scaled alike): a heavy body then
  /// rests on a light one (a 1000 kg box on a 1 kg slab holds at 4 sub-steps with 10) at the price
  /// of momentum in those contacts (a light body striking a heavy one pushes it harder than it
  /// should; bounces, solved apart, are not affected). 10 by default: it holds issue #13's heavy
  /// boxes on supports and on a slab at the default budget, which nothing else measured does.
  Real softMassRatioLimit = 10;
  /// soft_step (deterministic scheme, warm starting on): 0 (off) or how far (m) two bodies may move
  /// relative to each other since their two-point manifold was computed before it is computed
  /// again (Box2D 3's contact recycling, its default 10 x its 0.005 m slop). Until then the
  /// manifold is kept: its normal, its points' lever arms, and separations moved with the bodies
  /// as rigid points (turning either body by more than about 11 degrees also recomputes it). A
  /// stack's contacts then stay put while it sways, instead of following each sub-millimetre
  /// offset: without it the 30-box stack topples after 13 s, and Box2D 3 without its recycling
  /// topples it after 3 s (docs/soft_step.md).
  Real contactRecycleDistance = Real(0.05);
  Real linearSlop = Real(0.005);        ///< allowed penetration (m), as Box2D
  Real baumgarte = Real(0.2);           ///< fraction of penetration removed per position iteration
  Real maxLinearCorrection = Real(0.2); ///< most a position iteration moves a contact (m)
  Real speculativeDistance = Real(0.02);///< contacts are created this far before touching (m)
  Real restitutionThreshold = Real(1);  ///< approach speed (m/s) below which no bounce is added
  RestitutionPolicy restitution = RestitutionPolicy::kCollisions;  ///< pgs's and soft_step's restitution model
  /// Skin (m) around every polygon as the solvers see contacts, 0..speculativeDistance/2:
  /// a point is solved as if its separation were smaller by the skins of the pair's polygons, so
  /// points within them are touching rows and bodies rest that far apart. 0 (the default): shapes
  /// are exactly their vertices. Box2D 2.4.1's b2_polygonRadius is 0.01; with it and
  /// RestitutionPolicy::kBox2d Quadrant reproduces Box2D's responses (docs/validation.md).
  /// Deterministic scheme only (World refuses it with kQuadrants).
  Real polygonSkin = 0;
  /// Speculative contact points: a manifold point still apart (beyond the pair's polygonSkin) is
  /// a row that lets the gap close within the step, no more. false: only touching points (within
  /// the skin) reach the solvers, as in Box2D 2.4.1, whose manifolds hold no point beyond its
  /// polygon radius; a pair that is still apart gets its contact in the first step its shapes
  /// overlap, as there. true (the default): the engine's own contacts. docs/validation.md
  /// (the random campaign) gives what it changes.
  bool speculativeContacts = true;
  /// Polygon pairs' manifolds as Box2D 2.4.1 computes them: the incident edge is clipped to the
  /// reference face's side planes moved out by the pair's polygonSkin (Box2D extends them by its
  /// polygon radii), and only touching points are kept. A vertex hitting a face then keeps the
  /// incident edge's far end only where Box2D does. false (the default): side planes through the
  /// face's ends. docs/validation.md (the random campaign) gives what it changes.
  bool box2dPolygonClip = false;
  /// pgs's position pass, and the thesis solver's with thesisPositionPass, as Box2D 2.4.1's: a
  /// point's reference normal and plane turn with the reference body and the incident point (a
  /// circle's centre, the clipped vertex) with its own, two circles are measured centre to
  /// centre, and the pass stops after the first iteration with no point deeper than 3
  /// linearSlop. false (the default): the normal fixed, the anchors turned, until nothing moves.
  /// soft_step with it: that pass on the bodies after the sub-steps, in place of the soft rows'
  /// push (which then pushes nothing) and of its own position pass.
  /// engine/src/dynamics/box2d_position.h says why; docs/validation.md what it changes.
  bool box2dPositionSolve = false;
  /// thesis solver: solve its one impulse per contact with the normal and friction parts coupled
  /// (the 2x2 effective mass and the Coulomb cone) instead of by two separate formulas. Off (the
  /// default): the thesis's method. docs/validation.md gives what it changes.
  bool thesisCoupledImpulse = false;
  /// thesis solver: one impulse at each touching point of a contact, in turn, instead of the
  /// thesis's one impulse at their centroid. Off (the default): the thesis's method.
  /// docs/validation.md gives what it changes.
  bool thesisPointImpulses = false;
  /// thesis solver: passes over the contacts per step, >= 1. 1 (the default): the thesis's one
  /// pass; more let the impulses of a contact's two points, or of neighbouring contacts, settle
  /// as an iterative solver's do. docs/validation.md gives what it changes.
  int thesisPasses = 1;
  /// thesis solver: each point's impulse is a total accumulated over the step's passes and
  /// clamped as a total (normal >= 0, friction within mu times it), as Box2D 2.4.1's iterations
  /// do, instead of a fresh impulse per pass that only pushes. Only matters with thesisPasses > 1.
  /// Off (the default): the thesis's method. docs/validation.md gives what it changes.
  bool thesisAccumulatedImpulse = false;
  /// thesis solver, with thesisPointImpulses and thesisAccumulatedImpulse: a contact's two
  /// touching points take their normal impulses together, as the 2x2 complementarity problem
  /// Box2D 2.4.1's block solver solves (friction first, each point's row clamped by its normal
  /// total), and both restitution targets are read before either point's impulse. Off (the
  /// default): one point after the other, the second point's target read after the first's
  /// impulse. docs/validation.md gives what it changes.
  bool thesisBlockImpulse = false;
  /// thesis solver: remove penetration after the positions are integrated, by positionIterations
  /// passes of non-linear Gauss-Seidel at the touching points (Box2D 2.4.1's and pgs's position
  /// pass, which turns the bodies too), instead of the thesis's translation push before the
  /// impulses. Off (the default): the thesis's method. docs/validation.md gives what it changes.
  bool thesisPositionPass = false;
  Real maxLinearSpeed = Real(400);      ///< m/s; a numerical guard, as Box2D 3's default
  /// Most a body turns in one step (rad), as Box2D 3's 0.25 pi: a numerical guard. Speculative
  /// contacts see where a corner is, not where a fast spin takes it within the step; without
  /// the limit, triangles of the elastic polygon stress scene spun up to 160 rad/s and left
  /// the box. At 60 Hz it allows 47 rad/s.
  Real maxRotation = Real(0.25 * 3.14159265358979);
  int threadCount = 1;                  ///< worker threads, 1..64 (1 = no threading at all)
  ParallelScheme scheme = ParallelScheme::kDeterministic;
  /// Sections with fewer items (bodies, pairs; an eighth as many constraints) run on the calling
  /// thread. A parallel-for costs about 3.4 us at 2 threads (benchmarks/task_overhead.cpp) and a
  /// body or pair about 10-20 ns, so below a few thousand items splitting does not pay. Lower it
  /// only to exercise threading on small scenes (the tests do). A whole step whose last step's
  /// work was below this many items at 50 ns runs on the calling thread too
  /// (Profile::smallSteps). >= 1.
  int minParallelItems = 2048;
  int quadTreeMaxDepth = 8;             ///< quad-tree levels below the root, 1..12
  /// Reuse the broad phase's pairs while every body stays within 0.1 m of where they were found
  /// (engine/src/collision/pair_cache.h): the same pairs, so the same results bit for bit, at a fraction of
  /// the broad phase's cost on a resting pile. Off: the broad phase runs every step (for tests
  /// and measurement). Not used with sleep on or the quadrants scheme.
  bool reusePairs = true;
  // Sleep settings (used only when effects.sleep is on), Box2D 2.4's defaults. A body is slow
  // while its speed is at most linearSleepTolerance and its angular speed at most
  // angularSleepTolerance; an island sleeps once all its bodies have been slow for timeToSleep.
  Real linearSleepTolerance = Real(0.01);                       ///< m/s, finite, >= 0
  Real angularSleepTolerance = Real(2.0 / 180.0 * 3.14159265358979);  ///< rad/s (2 deg/s), finite, >= 0
  Real timeToSleep = Real(0.5);                                 ///< s, finite, > 0
  Effects effects;
  /// Record begin/end touch events at each Step (World::GetContactBeginEvents). Off: no event
  /// work at all, and reading the events throws quadrant::Error.
  bool contactEvents = false;
  /// Record hit events at each Step (World::GetContactHitEvents): pairs that begin touching at an
  /// approach speed above hitEventThreshold. Off: no hit work at all (on: one pass over the
  /// contacts a step, and the touching pairs tracked as for contactEvents), and reading them
  /// throws quadrant::Error. Needs ParallelScheme::kDeterministic.
  bool hitEvents = false;
  /// Least approach speed (m/s, finite, >= 0) of a hit event: only faster ones are reported.
  /// Default 1, as Box2D 3's hitEventThreshold.
  Real hitEventThreshold = 1;
};

/// The stages of a step, as timed in Profile and StageBalance.
enum class Stage : uint8_t { kBroadPhase, kNarrowPhase, kPersistence, kSolve, kIntegrate };
inline constexpr size_t kStageCount = 5;
inline constexpr const char* kStageNames[kStageCount] = {"broad_phase", "narrow_phase", "persistence", "solve",
                                                         "integrate"};

/// Load balance of one stage: thread CPU milliseconds of all workers (work) and of the largest
/// worker share of each parallel section plus every serial section (critical). work/critical
/// bounds the stage's speed-up at the world's thread count.
struct StageBalance {
  double workMs = 0;
  double criticalMs = 0;
};

/// Wall-clock milliseconds per stage of the last Step (summed over its sub-steps).
struct Profile {
  double broadPhase = 0;   ///< AABB update and candidate pairs
  double narrowPhase = 0;  ///< manifolds for candidate pairs
  double persistence = 0;  ///< matching manifolds to last step's, warm-start impulses
  double solve = 0;        ///< contact solver (velocity and position passes)
  double integrate = 0;    ///< velocities and positions
  double total = 0;        ///< the whole Step
  std::array<StageBalance, kStageCount> balance{};  ///< per stage, indexed by Stage
  /// Steps on the one-thread path with more than one thread (a busy machine, no worker, or a
  /// step too small to split), and of those the ones too small (the last step's work below
  /// WorldDef::minParallelItems items' worth): 0 or 1 for one Step.
  int aloneSteps = 0;
  int smallSteps = 0;

  /// Adds another profile field by field (totals over several steps).
  Profile& operator+=(const Profile& o) {
    broadPhase += o.broadPhase, narrowPhase += o.narrowPhase, persistence += o.persistence;
    solve += o.solve, integrate += o.integrate, total += o.total;
    aloneSteps += o.aloneSteps, smallSteps += o.smallSteps;
    for (size_t k = 0; k < kStageCount; ++k) {
      balance[k].workMs += o.balance[k].workMs;
      balance[k].criticalMs += o.balance[k].criticalMs;
    }
    return *this;
  }
};

/// Counts from the last Step.
struct Counters {
  int bodies = 0;
  int candidatePairs = 0;    ///< pairs whose AABBs overlap, from the broad phase
  int contacts = 0;          ///< manifolds with at least one point (touching or speculative)
  int touchingContacts = 0;  ///< manifolds with a point at separation <= 0 (with sleep on, sleeping islands' too)
  int contactPoints = 0;
  bool pairsReused = false;  ///< this step's pairs came from the pair cache (WorldDef::reusePairs)
  /// soft_step with joints: this step kept last step's joint colouring (the joints and which of
  /// their ends move are unchanged) instead of colouring them again.
  bool jointColoringKept = false;
  /// soft_step: the bundles of contact islands this step's rows ran in, each on one thread through
  /// every sub-step (0: colour by colour; bundles need 4 threads or more and a sparse scene).
  int rowBundles = 0;
};

/// A contact as read back for validation and drawing.
struct ContactInfo {
  BodyId bodyA;
  BodyId bodyB;
  Vec2 normal;  ///< unit, from A to B
  int pointCount = 0;
  Vec2 points[2];
  Real separations[2] = {0, 0};
  /// The contact's impulses (N s) at each point as the solver keeps them for warm starting, not
  /// the step's total under the default solver:
  /// - pgs, jacobi: the step's accumulated impulse of the velocity iterations.
  /// - soft_step: the last sub-step's alone (its warm start, soft solve and relax passes), so a
  ///   steady load reads 1 / softSubSteps of what it transmits over the step: a box of mass m
  ///   resting on the ground reads m |g| dt / softSubSteps in all (multiply by softSubSteps for
  ///   the step's total while the load is steady).
  /// - thesis: the last impulse it applied there (with thesisAccumulatedImpulse, the total over
  ///   its passes).
  /// Neither pgs nor soft_step includes the restitution passes (RestitutionPolicy::kCollisions)
  /// nor the position pass (which moves bodies without an impulse). 0 where the solver kept
  /// none (pgs: a contact of a body over maxLinearSpeed).
  Real normalImpulses[2] = {0, 0};
  Real tangentImpulses[2] = {0, 0};
};

/// A ray's hit on a body (World::RayCastClosest, World::RayCastAll).
struct RayHit {
  BodyId body;
  Vec2 point;         ///< where the ray enters the shape (m)
  Vec2 normal;        ///< the shape's outward unit normal there
  Real fraction = 0;  ///< of the translation, in [0, 1]: point = origin + fraction * translation
};

/// Two bodies that began or ended touching in the last Step (World::GetContactBeginEvents).
/// bodyA.index < bodyB.index.
struct ContactEvent {
  BodyId bodyA;
  BodyId bodyB;
  friend constexpr bool operator==(ContactEvent a, ContactEvent b) = default;
};

/// A body that began or stopped overlapping a sensor in the last Step (World::GetSensorBeginEvents).
struct SensorEvent {
  BodyId sensor;   ///< the body whose shape is the sensor (ShapeDef::isSensor)
  BodyId visitor;  ///< the body it senses (never a sensor)
  friend constexpr bool operator==(SensorEvent a, SensorEvent b) = default;
};

/// Two bodies that began touching in the last Step faster than WorldDef::hitEventThreshold
/// (World::GetContactHitEvents). bodyA.index < bodyB.index.
struct ContactHitEvent {
  BodyId bodyA;
  BodyId bodyB;
  Vec2 point;              ///< world, the contact point that approached fastest (m)
  Vec2 normal;             ///< unit, from A to B
  Real approachSpeed = 0;  ///< speed at which the two surfaces closed there before the solver (m/s), > 0
  friend constexpr bool operator==(ContactHitEvent a, ContactHitEvent b) = default;
};

}  // namespace quadrant
