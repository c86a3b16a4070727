// The engine-neutral scene description: built once, loaded into any engine by an adapter.
//
// A scene says everything an engine needs to simulate it the same way as every other engine:
// the world settings, the effects it calls for, and its bodies. Adapters translate it at load
// time; nothing of it is consulted per step.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "quadrant/math.h"
#include "quadrant/world.h"  // Effects

namespace quadrant::scene {

/// kSegment: a two-sided line segment (vertices: its 2 points); kChainSegment: one segment of a
/// chain (vertices: ghost1, point1, point2, ghost2; one-sided, colliding on the right of point1 ->
/// point2, quadrant::ChainSegment's convention, which Box2D 2.4.1's one-sided b2EdgeShape shares).
/// Both have no area: static and kinematic bodies only (MakeChainBodyDescs builds a chain).
enum class ShapeKind : uint8_t { kCircle, kPolygon, kCapsule, kSegment, kChainSegment };

/// Effects a scene calls for: the engine's own type (quadrant/world.h), so the scene API and the
/// engine cannot drift (scene.h had a copy). An adapter whose engine cannot honour one that is on
/// (or cannot switch one off) reports the scene as unsupported. A scene's defaults differ from
/// the engine's WorldDef in one field: continuous collision is off (SceneEffects), as in the
/// stress scenes and most cases, and Chipmunk cannot run it; a scene that needs it says so.
using Effects = quadrant::Effects;

/// The effects of a scene that sets none: the engine's defaults with continuous collision off.
inline Effects SceneEffects() {
  Effects e;
  e.continuous = false;
  return e;
}

/// One more shape of a body (BodyDesc::extraShapes): BodyDesc's shape fields, and a circle's
/// centre (the body's own circle is centred on its origin).
struct ShapeDesc {
  ShapeKind shape = ShapeKind::kPolygon;
  Real radius = Real(0.5);   ///< circles, capsules (m)
  Vec2 center;               ///< circles: body coordinates
  std::vector<Vec2> vertices;  ///< as BodyDesc::vertices
  Real density = 1;
  Real friction = Real(0.6);
  Real restitution = 0;
};

struct BodyDesc {
  bool dynamic = true;
  /// With dynamic = false: a kinematic body, moved by its velocity (set at load and by drivers
  /// through Adapter::SetVelocity), not by contacts or gravity; infinite mass. Its origin should
  /// be its centroid (engines differ in which point of a kinematic body the velocity is of).
  /// Adapters of engines without kinematic bodies report the scene as unsupported.
  bool kinematic = false;
  ShapeKind shape = ShapeKind::kCircle;
  Real radius = Real(0.5);          ///< circles (m), centred on the body origin; capsules' radius
  /// Polygons: convex, counter-clockwise, body coordinates. Capsules: the two centres.
  /// Segments: the two points. Chain segments: ghost1, point1, point2, ghost2.
  std::vector<Vec2> vertices;
  Vec2 position;                    ///< body origin (m)
  Real angle = 0;                   ///< rad
  Vec2 velocity;                    ///< m/s
  Real angularVelocity = 0;         ///< rad/s
  Real density = 1;                 ///< kg/m^2
  Real friction = Real(0.6);
  Real restitution = 0;
  /// Damping rates (1/s, >= 0), acting only when the scene's damping effect is on. Box2D 2.4's
  /// meaning: each step multiplies the velocity by 1 / (1 + dt c). Adapters of engines with
  /// another law (Bullet, Chipmunk) convert the rate so one step gives that same factor.
  Real linearDamping = 0;
  Real angularDamping = 0;
  /// false: created asleep (a dynamic body in a scene with the sleep effect), as Box2D 3's
  /// isAwake; it wakes when an awake body touches it.
  bool awake = true;
  /// Collision filter, Box2D's rule (quadrant::Filter): two bodies collide when each one's
  /// category is in the other's mask. Box2D 2.4.1 holds 16 bits: an adapter refuses wider ones.
  uint32_t categoryBits = 1;
  uint32_t maskBits = 0xFFFFFFFFu;
  /// More shapes on the same body (a compound body: quadrant::BodyDef::extraShapes; Box2D's
  /// several fixtures, Chipmunk's several shapes on one body). Mass, centre and inertia are the
  /// exact sum of all shapes' (ComputeMassProperties). Empty for a one-shape body.
  std::vector<ShapeDesc> extraShapes;
};

/// Every shape of a body: its own (from BodyDesc's shape fields, a circle at the origin), then
/// BodyDesc::extraShapes. Adapters load a body's shapes from this list.
std::vector<ShapeDesc> ShapesOf(const BodyDesc& body);

enum class JointKind : uint8_t { kRevolute, kPrismatic, kDistance, kWeld, kWheel };

/// A joint between scene bodies bodyA and bodyB (indices). `anchor` is a world point at load: the
/// revolute pin, the weld point, the prismatic and wheel joints' point on bodyB (the hub) sliding
/// along `axis` (a world direction at load, fixed in bodyA), and the distance joint's anchor on
/// bodyA (anchorB on bodyB). Angles are bodyB's relative to bodyA's, from their angles at load.
///   revolute: limit (lowerAngle, upperAngle), motor (motorSpeed rad/s, maxMotorTorque), angular spring;
///   prismatic: limit (lowerTranslation, upperTranslation), motor (motorSpeed m/s, maxMotorForce);
///   distance: a rod of `length` (0: the anchors' distance at load), or with enableSpring a spring
///             (hertz 0: none) between minLength and maxLength when enableLimit (a rope);
///   weld: rigid, or springs: linear of hertz, angular of angularHertz (0: rigid);
///   wheel: a suspension spring along the axis (hertz, dampingRatio), limits, a motor on the turn.
/// Engines load it as their nearest joint (Box2D 2.4.1's b2*Joint, Chipmunk's pivot, groove, pin,
/// slide, rotary limit, simple motor and damped springs); an adapter that cannot honour a part
/// reports the scene unsupported, with the reason.
struct JointDesc {
  int bodyA = 0, bodyB = 1;
  Vec2 anchor;
  bool collideConnected = false;
  bool enableLimit = false;
  Real lowerAngle = 0, upperAngle = 0;  ///< rad (revolute)
  bool enableMotor = false;
  Real motorSpeed = 0, maxMotorTorque = 0;  ///< rad/s or m/s; N m (revolute, wheel)
  bool enableSpring = false;
  Real hertz = 0, dampingRatio = 0;
  JointKind kind = JointKind::kRevolute;
  Vec2 axis{1, 0};                                   ///< prismatic, wheel
  Real lowerTranslation = 0, upperTranslation = 0;   ///< m (prismatic, wheel)
  Real maxMotorForce = 0;                            ///< N (prismatic)
  Vec2 anchorB{};                                    ///< distance: bodyB's world anchor
  Real length = 0, minLength = Real(0.005), maxLength = Real(1e6);  ///< m (distance)
  Real angularHertz = 0, angularDampingRatio = 0;    ///< weld
  /// Revolute, prismatic and weld: added to bodyB's angle minus bodyA's at load to give the angle where the joint
  /// angle (its limits' and spring's) is zero (Box2D 3's rotated local frame A).
  Real referenceAngle = 0;
};

/// Bodies and joints a scene's driver adds during a run (Adapter::AddGroup) and removes as one
/// (Adapter::RemoveGroup): Box2D 3's rain spawns ragdolls this way. Joint body indices are the
/// group's own (0 .. bodies.size() - 1); a group cannot join a scene body.
struct BodyGroup {
  std::vector<BodyDesc> bodies;
  std::vector<JointDesc> joints;
};

class Adapter;

/// Called before every step with the step index (0-based); may push, add and remove nothing else
/// than what the Adapter interface offers (SetVelocity, AddGroup, RemoveGroup). Used by scenes
/// that drive bodies. Each Load takes its own copy, so state a driver keeps (the group ids it
/// was given) starts afresh with every Load.
using Driver = std::function<void(int step, Adapter& adapter)>;

struct Scene {
  std::string name;
  Vec2 gravity{0, Real(-10)};
  Real timeStep = Real(1.0 / 60.0);   ///< s, fixed
  int pipelineRepeats = 1;            ///< Quadrant: whole-pipeline repeats per step (World::StepRepeated)
  int velocityIterations = 8;         ///< Box2D 2.4 and Quadrant pgs
  int positionIterations = 3;
  Real restitutionThreshold = Real(1);///< m/s; approach speeds below it do not bounce
  Effects effects = SceneEffects();
  AABB bounds;                        ///< region that holds every body (the box of stress scenes)
  std::vector<BodyDesc> bodies;
  std::vector<JointDesc> joints;      ///< loaded after the bodies
  Driver driver;                      ///< optional
  /// Every kind of group the driver adds (one sample of each): Load validates them and refuses,
  /// as Unsupported, a scene whose groups the engine cannot run, so that no refusal comes mid-run.
  std::vector<BodyGroup> groupSamples;
  /// The most dynamic bodies the driver's groups hold at once (rain: its ragdolls' bodies), counted
  /// with the scene's own where a body count is reported (the suite's N).
  int groupBodies = 0;
  uint64_t seed = 0;                  ///< the seed it was generated with (0 = hand-built)
};

/// A circle body of `radius` at `position` (other fields at their defaults).
BodyDesc MakeCircleBody(Vec2 position, Real radius, bool dynamic = true);
/// An axis-aligned box body of half-widths hx, hy at `position`, vertices counter-clockwise
/// (other fields at their defaults).
BodyDesc MakeBoxBody(Vec2 position, Real hx, Real hy, bool dynamic = true);

/// A capsule body: centres (-halfLength, 0) and (halfLength, 0), `radius`, at `position`.
BodyDesc MakeCapsuleBody(Vec2 position, Real halfLength, Real radius, bool dynamic = true);

/// A segment body (static, or kinematic with `kinematic`) from p1 to p2, body coordinates, at
/// `position`.
BodyDesc MakeSegmentBody(Vec2 position, Vec2 p1, Vec2 p2, bool kinematic = false);

/// A chain (quadrant::ChainDef's rules: an open chain of 4 or more points collides on points 1 to
/// count - 2, a loop of 3 or more all round) as static chain-segment bodies at the origin, world
/// points as their vertices. Throws quadrant::Error for a chain MakeChainBodies refuses.
std::vector<BodyDesc> MakeChainBodyDescs(const std::vector<Vec2>& points, bool isLoop = false,
                                         Real friction = Real(0.6));

/// Exact mass (kg) and rotational inertia about the centre of mass (kg m^2) of a body as the
/// scene defines it; every adapter gives its engine these values where the engine lets it.
struct MassProperties {
  Real mass = 0;
  Real inertia = 0;
  Vec2 localCenter;
};
MassProperties ComputeMassProperties(const BodyDesc& body);

/// The engine's definition of a scene body (the Quadrant adapter loads these; other adapters
/// translate the BodyDesc themselves). Polygons are copied vertex for vertex, not validated:
/// CheckBodyDef and CreateBody do that. Throws quadrant::Error for more than 8 vertices, which a
/// Polygon cannot hold.
BodyDef ToBodyDef(const BodyDesc& body);

/// Validates a whole scene; throws quadrant::Error naming the first bad body or field. The
/// world settings are checked here (time step > 0, iterations >= 1, ...); each body is checked
/// by the engine's own rules (quadrant::CheckBodyDef on ToBodyDef, so the scene API and the
/// engine refuse the same bodies, message prefixed with "scene body <i>: "; a segment or chain
/// segment on a dynamic body among them), plus what only a
/// scene can get wrong: dynamic and kinematic both set, polygon vertices not in
/// counter-clockwise convex order (the engine re-orders them; other engines need the order).
/// Joints: body indices in range and distinct, finite values, lowerAngle <= upperAngle within
/// [-pi, pi], maxMotorTorque, hertz and dampingRatio >= 0 ("scene joint <j>: ..."), the engine's
/// own rules (quadrant::MakeJoint's) for the rest.
void ValidateScene(const Scene& scene);

/// Validates a group to be added to a world of `scene`'s settings by the rules of ValidateScene
/// (messages "group body <i>: ..." and "group joint <j>: ...", joint indices the group's own).
/// Throws quadrant::Error; an empty group is refused too.
void ValidateGroup(const Scene& scene, const BodyGroup& group);

}  // namespace quadrant::scene
