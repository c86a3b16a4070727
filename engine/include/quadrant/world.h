// Quadrant's World: create and destroy bodies, step, read back, query. The definitions and
// read-out types it takes and gives are in quadrant/types.h (included here), each default
// documented there.
//
// Ids are values (index + generation), objects are made from definition structs, and one call
// steps the world:
//
//   quadrant::WorldDef def;                      // gravity (0,-10), soft_step, 4 sub-steps
//   quadrant::World world(def);
//   quadrant::BodyDef ground;                    // static by default
//   ground.shape = quadrant::ShapeDef::Box(20, 0.5);
//   world.CreateBody(ground);
//   quadrant::BodyDef ball;
//   ball.type = quadrant::BodyType::kDynamic;
//   ball.position = {0, 4};
//   ball.shape = quadrant::ShapeDef::MakeCircle(0.5);
//   quadrant::BodyId id = world.CreateBody(ball);
//   for (int i = 0; i < 60; ++i) world.Step(1.0f / 60.0f);
//   quadrant::Vec2 p = world.GetPosition(id);   // resting on the ground at y ~ 1.0
#pragma once

#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "quadrant/debug_draw.h"
#include "quadrant/joints.h"
#include "quadrant/types.h"

namespace quadrant {

namespace detail {
/// The world's state behind a pointer that refuses to be followed once moved from: a moved-from
/// World has no state, and every call on it throws quadrant::Error (never a null dereference).
/// Assigning a World to it makes it usable again; destroying it is always fine.
template <class T>
class LiveImpl {
 public:
  explicit LiveImpl(std::unique_ptr<T> p) noexcept : p_(std::move(p)) {}
  T* operator->() const { return &Get(); }
  T& operator*() const { return Get(); }

 private:
  T& Get() const {
    if (!p_) throw Error("World: this World was moved from; assign a World to it before using it");
    return *p_;
  }
  std::unique_ptr<T> p_;
};
}  // namespace detail

class World {
 public:
  /// Throws quadrant::Error if `def` is invalid (non-finite gravity, iterations < 1, ...).
  explicit World(const WorldDef& def = WorldDef{});
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;
  /// Moving leaves the source empty: every call on it then throws quadrant::Error until a World
  /// is assigned to it.
  World(World&&) noexcept;
  World& operator=(World&&) noexcept;

  /// Validates `def` fully before adding anything; throws quadrant::Error on bad input.
  BodyId CreateBody(const BodyDef& def);
  /// A chain as static bodies, one chain segment each (MakeChainBodies), in the chain's order;
  /// validates the whole chain before adding any body. Throws quadrant::Error on bad input.
  std::vector<BodyId> CreateChain(const ChainDef& def);
  /// Throws quadrant::Error for a stale or null id.
  void DestroyBody(BodyId id);
  bool IsValid(BodyId id) const;

  // Joints (quadrant/joints.h). Each Create validates its definition fully before adding anything
  // and throws quadrant::Error on bad input, a stale body id, or a world that cannot solve joints
  // (solver other than soft_step, ParallelScheme::kQuadrants). Creating or destroying a joint wakes
  // both bodies. DestroyBody destroys the body's joints with it (their ids turn stale).
  JointId CreateRevoluteJoint(const RevoluteJointDef& def);
  JointId CreateDistanceJoint(const DistanceJointDef& def);
  JointId CreateWeldJoint(const WeldJointDef& def);
  JointId CreatePrismaticJoint(const PrismaticJointDef& def);
  JointId CreateWheelJoint(const WheelJointDef& def);
  JointId CreateMotorJoint(const MotorJointDef& def);
  JointId CreateMouseJoint(const MouseJointDef& def);
  /// Throws quadrant::Error for a stale or null id.
  void DestroyJoint(JointId id);
  bool IsValid(JointId id) const;
  int GetJointCount() const;
  JointType GetJointType(JointId id) const;
  BodyId GetJointBodyA(JointId id) const;
  BodyId GetJointBodyB(JointId id) const;
  /// A joint's angle: bodyB's angle minus bodyA's minus referenceAngle, in [-pi, pi] (not for
  /// distance and mouse joints). GetJointLength: a distance joint's current length between its
  /// anchors, a prismatic or wheel joint's translation along its axis (m).
  Real GetJointAngle(JointId id) const;
  Real GetJointLength(JointId id) const;
  /// The motor speed of a revolute, wheel (rad/s) or prismatic (m/s) joint; throws for other joint
  /// types or a non-finite speed.
  void SetMotorSpeed(JointId id, Real speed);
  /// A mouse joint's target (a finite world point within 1e6 m); wakes bodyB.
  void SetJointTarget(JointId id, Vec2 target);
  /// The impulses the joint applied to bodyB over the last step (N s and N m s; a distance joint's
  /// along its axis; no angular impulse for distance and mouse joints): divided by the step's dt,
  /// the joint's force and torque.
  Vec2 GetJointLinearImpulse(JointId id) const;
  Real GetJointAngularImpulse(JointId id) const;

  /// A world point in body `id`'s frame (relative to its origin), for joint anchors, and back.
  Vec2 GetLocalPoint(BodyId id, Vec2 worldPoint) const;
  Vec2 GetWorldPoint(BodyId id, Vec2 localPoint) const;

  /// Advances by dt seconds: one pass of the whole pipeline (broad phase, narrow phase, solver,
  /// integration). The solver's own sub-steps are a setting of the world
  /// (WorldDef::softSubSteps for soft_step, velocityIterations for pgs), not of this call, so
  /// there is no Box2D-3-style `Step(dt, subStepCount)` here on purpose.
  /// Throws quadrant::Error for dt <= 0, dt > 1 s or non-finite.
  void Step(Real dt);

  /// Advances by dt seconds as `pipelineRepeats` whole steps of dt / pipelineRepeats each (the
  /// broad phase, narrow phase, solver and integration all rerun per repeat): the state is bit
  /// for bit that of calling Step(dt / pipelineRepeats) that many times; the profile and
  /// counters cover the whole call. Not solver sub-steps (see Step).
  /// Throws quadrant::Error as Step does, or for pipelineRepeats outside [1, 1000].
  void StepRepeated(Real dt, int pipelineRepeats);

  // Read-back (all throw quadrant::Error on a stale id).
  Vec2 GetPosition(BodyId id) const;
  Real GetAngle(BodyId id) const;
  Rot GetRotation(BodyId id) const;
  Vec2 GetLinearVelocity(BodyId id) const;
  Real GetAngularVelocity(BodyId id) const;
  Vec2 GetWorldCenter(BodyId id) const;
  Real GetMass(BodyId id) const;                ///< kg; 0 for static and kinematic bodies
  /// kg m^2 about the centre of mass; 0 for static, kinematic and fixed-rotation bodies.
  Real GetRotationalInertia(BodyId id) const;
  BodyType GetType(BodyId id) const;
  AABB GetAABB(BodyId id) const;
  /// The body's first shape (BodyDef::shape, canonical: polygons re-hulled).
  const ShapeDef& GetShape(BodyId id) const;
  /// Shape `index` of the body: 0 is BodyDef::shape, 1.. BodyDef::extraShapes in order; an index
  /// outside [0, GetShapeCount) is refused.
  const ShapeDef& GetShape(BodyId id, int index) const;
  /// 1 for a body made of BodyDef::shape alone, 1 + extraShapes.size() for a compound body.
  int GetShapeCount(BodyId id) const;

  // Writes (validated; throw quadrant::Error and change nothing on bad input, a stale id included).
  void SetLinearVelocity(BodyId id, Vec2 v);  ///< m/s of the centre of mass; ignored on a static body
  /// rad/s; ignored on a static body and where effects.rotation is off. Refuses anything but 0 on
  /// a fixed-rotation body (SetFixedRotation).
  void SetAngularVelocity(BodyId id, Real w);
  void SetTransform(BodyId id, Vec2 position, Real angle);

  // Forces, torques and impulses, as Box2D's. They act on dynamic bodies only: on a static or
  // kinematic body each throws quadrant::Error ("...: the body is kinematic; forces, torques and
  // impulses act on dynamic bodies only"; move a kinematic body by its velocity). Each wakes the
  // body's island, and a sleeping body takes them with its awake mass. A torque or the angular
  // part of an off-centre force or impulse does nothing on a fixed-rotation body (inverse inertia
  // 0) or where effects.rotation is off. Also refused: non-finite values, a point beyond 1e6 m, and
  // a change of velocity beyond 1e6 m/s (rad/s): for forces, the body's pending sum over a 1 s step.

  /// An impulse (N s) at `worldPoint` (m): v += J / m, w += (r x J) / I now, r from the centre of
  /// mass.
  void ApplyLinearImpulse(BodyId id, Vec2 impulse, Vec2 worldPoint);
  /// An angular impulse (N m s): w += impulse / I now.
  void ApplyAngularImpulse(BodyId id, Real impulse);
  /// A force (N) at `worldPoint` (m), for the next Step only: the body's forces and torques are
  /// summed until then (a force off the centre of mass adds the torque r x F, r measured at the
  /// call), applied in that Step as v += dt F / m and w += dt T / I before the solver runs, and
  /// cleared (call it every step for a steady force). Under StepRepeated they act in its first
  /// repeat only, as with as many calls of Step. Applied once before the solver, not spread over
  /// soft_step's sub-steps as Box2D 3 does: the velocity at the end of the step is the same, but in
  /// free flight the step moves the body dt^2 (F / m) (n - 1) / (2 n) further along F for n
  /// sub-steps (0.1 mm a step for F / m = 1 m/s^2 at 60 Hz and 4 sub-steps: a body held up against
  /// gravity by F = -m g rises 6.25 cm/s). pgs, thesis and jacobi apply gravity once per step
  /// too, and move the body exactly as if the force were added to it. A body made static or
  /// kinematic, or put to sleep, before the Step does not get them; one destroyed drops them.
  void ApplyForce(BodyId id, Vec2 force, Vec2 worldPoint);
  /// ApplyForce at the centre of mass (no torque).
  void ApplyForceToCenter(BodyId id, Vec2 force);
  /// A torque (N m) for the next Step, summed and applied as ApplyForce's: w += dt T / I.
  void ApplyTorque(BodyId id, Real torque);

  // Per-body settings (BodyDef documents each; stale ids and bad values throw quadrant::Error).

  /// BodyDef::gravityScale: the body feels scale * g. soft_step applies it in each sub-step (a
  /// body of scale 0 floats exactly); pgs, thesis and jacobi, which apply gravity once a step, get
  /// dt (scale - 1) g added to the velocity before they run, which is the same motion. Under the
  /// quadrants scheme soft_step gets it that way too, so a free body there moves
  /// (scale - 1) g dt^2 (n - 1) / (2 n) a step further along g (1.04 mm at 60 Hz, 4 sub-steps,
  /// scale 0). Static and kinematic bodies keep their scale and ignore it. While every body has
  /// scale 1 this costs nothing (no pass over the bodies). Wakes the body.
  Real GetGravityScale(BodyId id) const;
  void SetGravityScale(BodyId id, Real scale);
  /// BodyDef::fixedRotation: true sets the inertia and inverse inertia to 0 and the angular
  /// velocity to 0; false restores the inertia of the shape and density. Wakes the body.
  bool IsFixedRotation(BodyId id) const;
  void SetFixedRotation(BodyId id, bool fixedRotation);
  /// BodyDef::isBullet: continuous collision for this body where effects.continuous is off (with
  /// it on, the default, every body has it already). Takes effect at the next Step.
  bool IsBullet(BodyId id) const;
  void SetBullet(BodyId id, bool bullet);
  /// Static, kinematic or dynamic, as if created so: dynamic gets the mass and inertia of its
  /// shape and density (refused, as CreateBody refuses, for density 0 or a mass that is not a
  /// positive finite number), the others mass 0; static also velocity 0. The velocity is kept
  /// otherwise. The body, its island and the sleeping bodies its box overlaps wake; its pairs are
  /// found anew at the next Step. Refuses an unknown type.
  void SetType(BodyId id, BodyType type);
  /// The shape's material (ShapeDef documents each; GetShape reads them back). Friction >= 0 and
  /// restitution in [0, 1], as CreateBody: contacts mix them anew at the next Step. Density
  /// (kg/m^2, finite, >= 0; > 0 on a dynamic body, whose mass must stay a positive finite number):
  /// recomputes a dynamic body's mass and inertia (not its centre of mass: the density is
  /// uniform) and wakes it; a static or kinematic body keeps it for SetType. On a compound body
  /// (BodyDef::extraShapes) each sets every shape's value, and SetDensity recomputes the centre of
  /// mass too (the shapes' densities may have differed before); the body's origin stays.
  void SetFriction(BodyId id, Real friction);
  void SetRestitution(BodyId id, Real restitution);
  void SetDensity(BodyId id, Real density);

  /// The world's gravity (m/s^2; WorldDef::gravity at creation). SetGravity: finite, else
  /// quadrant::Error; GetDef().gravity reads it too. A change wakes every sleeping body.
  Vec2 GetGravity() const;
  void SetGravity(Vec2 gravity);

  /// Whether the body is simulated. Static bodies are never awake (they are not simulated);
  /// kinematic bodies always are; a dynamic body is asleep only when effects.sleep is on and
  /// its island fell asleep (or SetAwake(false)). A sleeping body reads back velocity 0.
  /// Throws quadrant::Error on a stale id.
  bool IsAwake(BodyId id) const;
  /// Wakes a sleeping dynamic body and its whole island (true), or puts the body to sleep with
  /// velocity 0 (false; it wakes again at the next step if an awake body touches it). No effect
  /// on static or kinematic bodies, and SetAwake(false) has none when effects.sleep is off.
  /// SetLinearVelocity, SetAngularVelocity, SetTransform, the forces and impulses, SetType,
  /// SetDensity, SetGravityScale and SetFixedRotation wake the body too, and creating,
  /// destroying, moving or retyping a body wakes the sleeping bodies its box overlaps.
  /// Throws quadrant::Error on a stale id.
  void SetAwake(BodyId id, bool awake);

  // Per-body user data and collision filter (throw quadrant::Error on a stale id).
  uint64_t GetUserData(BodyId id) const;
  void SetUserData(BodyId id, uint64_t userData);
  Filter GetFilter(BodyId id) const;
  /// Takes effect at the next Step. Throws quadrant::Error on a stale id, and for a
  /// non-default filter under ParallelScheme::kQuadrants.
  void SetFilter(BodyId id, Filter filter);

  // Queries, on the bodies where they are now (after the last Step, SetTransform, CreateBody).
  // They run through a broad-phase structure of the world's type (WorldDef::broadPhase), rebuilt
  // from every body's current box at the first query after a change (O(bodies): about 40 ns per
  // body of CPU on the 2-core VM, 1.3 ms for 32000 circles, quadrant_queries'
  // aabb_after_move; then each query reads only the cells or nodes it touches). Shapes are tested exactly. A body is reported
  // only if (its categoryBits & categoryMask) != 0; sensors are reported as any body (give them a
  // category of their own to leave them out). Queries are const but not safe to run
  // concurrently with each other or with any other call on the same World.

  /// Writes to `out` (cleared first) every body whose shape overlaps `box` (touching counts), in
  /// GetBodyIds order. Throws quadrant::Error, changing nothing, for a box that is not finite or
  /// whose lower corner is above its upper one.
  void QueryAABB(const AABB& box, std::vector<BodyId>& out, uint32_t categoryMask = kAllCategories) const;
  /// The first shape the segment from `origin` to origin + translation enters; none if it enters
  /// none. Shapes that contain the origin are not reported (as Box2D 2.4). Ties go to the body
  /// earlier in GetBodyIds order. Throws quadrant::Error, changing nothing, for a non-finite or
  /// zero translation, or an origin or end beyond the coordinate limit (1e6 m) or not finite.
  std::optional<RayHit> RayCastClosest(Vec2 origin, Vec2 translation, uint32_t categoryMask = kAllCategories) const;
  /// Every shape the segment enters, into `out` (cleared first) by fraction, ties in GetBodyIds
  /// order. Refuses what RayCastClosest refuses.
  void RayCastAll(Vec2 origin, Vec2 translation, std::vector<RayHit>& out,
                  uint32_t categoryMask = kAllCategories) const;
  /// Writes to `out` (cleared first) every body whose shape contains `point` (its boundary
  /// counts), in GetBodyIds order. Throws quadrant::Error, changing nothing, for a point that is
  /// not finite.
  void QueryPoint(Vec2 point, std::vector<BodyId>& out, uint32_t categoryMask = kAllCategories) const;
  /// The first shape a circle of `radius` (m) touches as its centre moves from `origin` to
  /// origin + translation; none if it touches none. Exact: a ray against each shape grown by the
  /// radius (a circle by the sum of the radii, a polygon to its rounded outline: every edge pushed
  /// out along its normal and a circle at every corner), in double. The hit: `fraction` of the
  /// translation where the circle first touches, `point` where it touches the shape, `normal` the
  /// shape's outward unit normal there (against the motion). A shape the circle overlaps at the
  /// origin is not reported (as a ray starting inside a shape); one it only touches there is, at
  /// fraction 0, if the translation moves into it. Ties go to the body earlier in GetBodyIds
  /// order. Candidates come from the query structure over the swept circle's box. Throws
  /// quadrant::Error, changing nothing, for what RayCastClosest refuses (naming CastCircle) and a
  /// radius that is not finite, <= 0 or above 1e6 m.
  std::optional<RayHit> CastCircle(Vec2 origin, Real radius, Vec2 translation,
                                   uint32_t categoryMask = kAllCategories) const;
  /// CastCircle for a convex polygon moved without turning: `vertices` (3 to 8, world
  /// coordinates, any order; as MakePolygon takes them) where the cast starts, moved by
  /// `translation`. Exact too: a ray against the Minkowski sum of each shape and the reflected
  /// polygon (their convex hull for a polygon, the rounded reflected polygon for a circle), in
  /// double. `point` is where they touch: a corner of either, or the middle of the stretch two
  /// parallel edges share. The same rules for overlaps at the start and ties. To cast a body's
  /// shape, pass its vertices through TransformPoint. Throws quadrant::Error, changing nothing,
  /// for a polygon MakePolygon refuses (its message after "CastPolygon: "), a translation that is
  /// zero or not finite, or a vertex whose end is beyond 1e6 m.
  std::optional<RayHit> CastPolygon(std::span<const Vec2> vertices, Vec2 translation,
                                    uint32_t categoryMask = kAllCategories) const;

  /// Pairs of bodies touching (a contact point at separation <= 0, as Counters::touchingContacts)
  /// after the last Step that did not touch after the Step before it (begin), and the other way
  /// round (end), sorted by (bodyA.index, bodyB.index). Two bodies that touched when their island
  /// fell asleep still touch while it sleeps (no end event, and none begins when it wakes).
  /// Same for any thread count under the
  /// deterministic scheme. An end event may name a body destroyed since (IsValid is then false).
  /// Valid until the next Step. Throw quadrant::Error unless WorldDef::contactEvents is on.
  std::span<const ContactEvent> GetContactBeginEvents() const;
  std::span<const ContactEvent> GetContactEndEvents() const;

  /// Pairs that began touching in the last Step faster than WorldDef::hitEventThreshold: a
  /// contact point approaching faster than the threshold (the relative normal velocity of the two
  /// bodies at the point before the solver, with the velocities the Step began with) whose gap
  /// closes within the Step (separation <= speed * dt: a speculative point about to close counts,
  /// so does one already touching), of a pair that was not touching after the Step before (as
  /// GetContactBeginEvents). One event a pair, at its fastest such point; with StepRepeated, its
  /// first repeat's. A body that lands and bounces off without ever resting still hits once.
  /// Sorted by (bodyA.index, bodyB.index), the same for any thread count. Valid until the next
  /// Step. Cost: one pass over the contacts a Step while WorldDef::hitEvents is on. Throws
  /// quadrant::Error unless WorldDef::hitEvents is on.
  std::span<const ContactHitEvent> GetContactHitEvents() const;

  /// Sensor overlaps (ShapeDef::isSensor) that began (and ended) in the last Step: a visitor
  /// overlaps a sensor when their shapes overlap (touching counts) where the Step found them, at
  /// its start (as contact begin events see the bodies), among the broad phase's pairs, and the
  /// pair passes both filters (ShouldCollide). A pair needs one awake dynamic body, so a static or
  /// kinematic sensor senses dynamic bodies and a dynamic one senses every body; a visitor and a
  /// sensor that both stop being simulated (asleep or static) keep overlapping until one wakes.
  /// Sensors do not sense each other, push nothing and wake nothing. Sorted by (sensor.index,
  /// visitor.index), the same for any thread count. An end event may name a body destroyed since
  /// (IsValid is then false). Valid until the next Step. Cost: none while the world has no sensor;
  /// with sensors, the pairs with one are split off after the broad phase and tested exactly.
  std::span<const SensorEvent> GetSensorBeginEvents() const;
  std::span<const SensorEvent> GetSensorEndEvents() const;

  /// Debug drawing (quadrant/debug_draw.h): with kDrawShapes, every body's shape in GetBodyIds
  /// order (DrawCircle or DrawPolygon, world coordinates, coloured by what the body is: kSensorColor,
  /// kStaticColor, kKinematicColor, kDynamicColor or kSleepingColor); then with kDrawAABBs every
  /// body's shape box (GetAABB) in the same order; then with kDrawContacts every point of the last
  /// Step's contacts (GetContacts order, touching and speculative) with its contact's normal.
  /// Reads only; costs the callbacks and one pass over the bodies (and contacts). Throws
  /// quadrant::Error, drawing nothing, for flag bits other than kDrawAll's.
  void Draw(DebugDraw& draw, uint32_t flags = kDrawShapes) const;

  int GetBodyCount() const;
  /// Live ids in the world's dense order, which StateHash, GetOwners and query ties use: creation
  /// order until a body is destroyed; DestroyBody then moves the body that was last into the
  /// destroyed one's place (after DestroyBody(ids[k]), the body that was ids.back() is at k).
  std::vector<BodyId> GetBodyIds() const;
  const WorldDef& GetDef() const;  ///< as created, with SetGravity's gravity
  const Profile& GetProfile() const;
  const Counters& GetCounters() const;
  std::vector<ContactInfo> GetContacts() const;

  /// Under ParallelScheme::kQuadrants: the thread that owned each body (in GetBodyIds order) in
  /// the last step, -1 for the master (a body straddling two threads' regions). Empty under the
  /// deterministic scheme.
  std::vector<int> GetOwners() const;
  /// Under ParallelScheme::kQuadrants: the square split among the threads in the last step.
  AABB GetPartitionRegion() const;

  /// 64-bit FNV-1a over the exact bits of every body's position, rotation and velocities,
  /// in body order. Equal hashes mean bit-identical states.
  uint64_t StateHash() const;

  struct Impl;

 private:
  detail::LiveImpl<Impl> impl_;
};

}  // namespace quadrant
