// The world: body storage, validation, and the step pipeline
//   broad phase -> narrow phase -> persistence -> solver (velocities, contacts, positions).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <limits>
#include <string>

#include "collision/broad_phase.h"
#include "collision/contact_cache.h"
#include "collision/contact_sort.h"
#include "dynamics/integrate.h"
#include "dynamics/islands.h"
#include "collision/narrow_phase.h"
#include "collision/pair_cache.h"
#include "collision/queries.h"
#include "quadrant/task_system.h"
#include "world/quadrants_scheme.h"
#include "quadrant/world.h"
#include "dynamics/solver.h"
#include "parallel/stage_clock.h"
#include "world/joint_set.h"
#include "world/validation.h"
#include "world/world_internal.h"

namespace quadrant {

uint64_t HashBodies(const Bodies& bodies);  // state_hash.cpp

namespace {

using Clock = StageClock;

}  // namespace

ShapeDef ShapeDef::MakeCircle(Real radius, Vec2 center) {
  ShapeDef s;
  s.type = ShapeType::kCircle;
  s.circle = Circle{center, radius};
  ValidateCircle(s.circle);
  return s;
}

ShapeDef ShapeDef::Box(Real hx, Real hy, Vec2 center, Real angle) {
  ShapeDef s;
  s.type = ShapeType::kPolygon;
  s.polygon = MakeBox(hx, hy, center, angle);
  return s;
}

ShapeDef ShapeDef::MakeCapsule(Vec2 center1, Vec2 center2, Real radius) {
  ShapeDef s;
  s.type = ShapeType::kCapsule;
  s.capsule = Capsule{center1, center2, radius};
  ValidateCapsule(s.capsule);
  return s;
}

ShapeDef ShapeDef::MakeSegment(Vec2 p1, Vec2 p2) {
  ShapeDef s;
  s.type = ShapeType::kSegment;
  s.segment = Segment{p1, p2};
  ValidateSegment(s.segment);
  return s;
}

ShapeDef ShapeDef::MakeChainSegment(Vec2 ghost1, Vec2 p1, Vec2 p2, Vec2 ghost2) {
  ShapeDef s;
  s.type = ShapeType::kChainSegment;
  s.chainSegment = ChainSegment{ghost1, Segment{p1, p2}, ghost2};
  ValidateChainSegment(s.chainSegment);
  return s;
}

std::vector<BodyDef> MakeChainBodies(const ChainDef& def) {
  const std::vector<Vec2>& p = def.points;
  const int n = static_cast<int>(p.size());
  Require(def.isLoop ? n >= 3 : n >= 4, std::string("ChainDef: ") + (def.isLoop ? "a loop needs at least 3 points" :
                                                                                   "an open chain needs at least 4 points") +
                                            ", got " + std::to_string(n));
  // A repeated point is the likely mistake: named as such (the segments' checks cover the rest).
  for (int k = 0; k + (def.isLoop ? 0 : 1) < n; ++k) {
    const Vec2 a = p[size_t(k)], b = p[size_t((k + 1) % n)];
    const Real gap = Length(b - a);
    Require(!IsFinite(a) || !IsFinite(b) || gap >= kMinFeatureSize || !IsFinite(gap),
            "ChainDef: points " + std::to_string(k) + " and " + std::to_string((k + 1) % n) + " are " +
                std::to_string(gap) + " m apart (at least 0.005 m)");
  }
  // A loop: a segment from every point to the next, wrapping. An open chain: its first and last
  // segments are only the ghosts of their neighbours (Box2D 3's rule), n - 3 segments.
  const int first = def.isLoop ? 0 : 1, count = def.isLoop ? n : n - 3;
  const auto at = [&](int k) { return p[size_t((k % n + n) % n)]; };
  std::vector<BodyDef> bodies;
  bodies.reserve(size_t(count));
  for (int k = first; k < first + count; ++k) {
    BodyDef body;
    body.type = BodyType::kStatic;
    body.filter = def.filter;
    try {
      body.shape = ShapeDef::MakeChainSegment(at(k - 1), at(k), at(k + 1), at(k + 2));
    } catch (const Error& e) {
      throw Error("ChainDef: segment " + std::to_string(k - first) + " (points " + std::to_string(k) + " to " +
                  std::to_string((k + 1) % n) + "): " + e.what());
    }
    body.shape.friction = def.friction;
    body.shape.restitution = def.restitution;
    CheckBodyDef(body);
    bodies.push_back(body);
  }
  return bodies;
}

ShapeDef ShapeDef::FromPolygon(const Polygon& polygon) {
  ShapeDef s;
  s.type = ShapeType::kPolygon;
  s.polygon = polygon;
  return s;
}

struct World::Impl {
  WorldDef def;
  Bodies bodies;
  // Id slots: generation per slot (odd bumps on free keep stale ids stale), dense index or -1.
  std::vector<uint32_t> generation;
  std::vector<int32_t> denseOf;
  std::vector<uint32_t> freeSlots;

  std::unique_ptr<TaskSystem> tasks;
  std::unique_ptr<StageRunner> run;
  std::unique_ptr<BroadPhase> broadPhase;
  PairCache pairCache;  // the broad phase's pairs reused while the bodies rest (WorldDef::reusePairs)
  bool pairsReused = false;  // this step's FindPairs was served by pairCache (Counters::pairsReused)
  std::unique_ptr<Solver> solver;
  std::unique_ptr<QuadrantsScheme> quadrants;  // only for ParallelScheme::kQuadrants
  WorkerLists<Contact> workerContacts;  // the narrow phase's output, per worker
  ContactCache cache;
  // Contact recycling (PrepareRecycling): valid for this step's narrow phases when `recycling`.
  std::vector<int32_t> recycleFirst;
  RecycleSource recycleSource;
  bool recycling = false;
  Islands islands;  // only used when def.effects.sleep is on
  JointSet joints;
  std::vector<CandidatePair> pairs;
  std::vector<Contact> contacts;
  ContactSorter sorter;
  bool contactsIncreasing = true;  // the sorter's check of `contacts` (ContactCache::Keep)
  Profile profile;
  Counters counters;
  std::vector<std::pair<int, int>> countParts;  // CountContacts: per worker, points and touching contacts
  int customFilters = 0;  // bodies whose Filter is not the default: the pair filter runs while > 0
  int sensorCount = 0;    // bodies whose shape is a sensor: the sensor passes run while > 0

  // Queries (world.h): their own broad-phase instance on a one-thread runner (so they never wake
  // the pool nor touch the step's profile), rebuilt when a query follows a change.
  std::unique_ptr<TaskSystem> queryTasks;
  std::unique_ptr<StageRunner> queryRun;
  std::unique_ptr<BroadPhase> queryIndex;
  std::vector<AABB> queryBoxes;
  std::vector<int> queryFound;
  bool queryStale = true;

  // Contact events (def.contactEvents, or effects.sleep for the touching counter): touching pairs
  // after this step and the last one.
  std::vector<ContactEvent> touching, touchingBefore, beginEvents, endEvents;

  // Forces and torques applied since the last Step (ApplyForce, ApplyForceToCenter, ApplyTorque):
  // one entry per body, in the order of its first call, summed in double; pendingOf maps an id
  // slot to its entry (-1: none; grown on demand). Applied and cleared by the pre-solve pass.
  struct PendingForce {
    uint32_t slot = 0;
    bool live = true;  // false once the body is destroyed
    double fx = 0, fy = 0, torque = 0;
  };
  std::vector<PendingForce> pendingForces;
  std::vector<int32_t> pendingOf;
  int gravityScaled = 0;  // bodies whose gravity scale is not 1: the pre-solve pass runs while > 0
  // Sensors (while sensorCount > 0): the broad phase's pairs of a sensor and a body that is not
  // one (FindPairs moves them out of `pairs`), the overlapping ones as (sensor, visitor) ids
  // (FindSensorOverlaps), and the overlaps after this step and the last one with their events.
  std::vector<CandidatePair> sensorPairs;
  std::vector<SensorEvent> sensorFound, overlaps, overlapsBefore, sensorBeginEvents, sensorEndEvents;

  // Hit events (def.hitEvents): this step's candidates from every pipeline repeat (FindHits),
  // the per-worker lists they are gathered in, and the events kept (SelectHits).
  WorkerLists<ContactHitEvent> hitParts;
  std::vector<ContactHitEvent> hitCandidates, hitEvents;

  int Dense(BodyId id) const {
    if (id.generation == 0 || id.index >= generation.size() || generation[id.index] != id.generation ||
        denseOf[id.index] < 0) {
      throw Error("stale or invalid BodyId (index " + std::to_string(id.index) + ", generation " +
                  std::to_string(id.generation) + ")");
    }
    return denseOf[id.index];
  }

  // The broad-phase box (world_internal.h, BroadPhaseBox: shared with the distributed world).
  // Always inlined into the box update's loop, as BroadPhaseBox is.
  [[gnu::always_inline]] void UpdateAABB(int i, Real dt) { bodies.aabb[i] = BroadPhaseBox(bodies, i, def, dt); }

  // Sleep (effects.sleep on only): wakes the islands of sleeping bodies that body i's box
  // overlaps, and body i's own island.
  void WakeAround(int i) {
    if (!def.effects.sleep) return;
    islands.WakeIslandOf(bodies, i);
    islands.WakeOverlapping(bodies, bodies.aabb[i]);
  }

  void RunPipeline(Real dt);
  /// solverScalesGravity: the solver applies the gravity scales itself (StepContext::gravityScaled).
  void PreSolve(Real dt, bool solverScalesGravity = false);
  void FindPairs(const BroadPhase::BoxUpdate* update = nullptr);
  void SplitSensorPairs();
  void FindSensorOverlaps();
  void UpdateContactEvents();
  void UpdateSensorEvents();
  void FindHits(Real dt);
  void SelectHits();
  // Whether id names a live body that is not simulated (static or asleep).
  bool Idle(BodyId id) const {
    if (id.index >= generation.size() || generation[id.index] != id.generation || denseOf[id.index] < 0) return false;
    return bodies.awake[denseOf[id.index]] == 0;
  }
  void PrepareQueries();
  BodyId IdOf(int i) const { return BodyId{bodies.slot[i], generation[bodies.slot[i]]}; }  // one pass of every stage
  void CountContacts(int candidatePairs);
  void PrepareRecycling(bool persist);
  void NarrowPhase(Real dt);
  // Sorts the narrow phase's contacts and restores last step's impulses into them (warm starting).
  void SortContacts() {
    const bool persist = def.solver != SolverType::kThesis && def.effects.warmStarting;
    sorter.Sort(*run, bodies.Count(), workerContacts, contacts, persist ? &cache : nullptr);
    contactsIncreasing = sorter.StrictlyIncreasing();
  }

  // Forces, torques and impulses act on dynamic bodies only: a clear refusal for the others.
  void RequireDynamic(int i, const char* call) const {
    const BodyType t = bodies.type[i];
    if (t == BodyType::kDynamic) return;
    throw Error(std::string(call) + ": the body is " + (t == BodyType::kStatic ? "static" : "kinematic") +
                "; forces, torques and impulses act on dynamic bodies only");
  }
  // The inverse mass a force or impulse acts on: a sleeping body's stored one is 0.
  BodyInverseMass ActiveInverseMass(int i) const {
    return def.effects.sleep ? Islands::AwakeInverseMass(bodies, i) : bodies.inv[i];
  }
  void AddForce(int i, const char* call, double fx, double fy, double torque);

  // Joints: the world's checks (a solver that solves them, live and distinct bodies), then added.
  JointId AddJoint(const Joint& j, const std::string& call) {
    Require(def.solver == SolverType::kSoftStep,
            call + ": joints need SolverType::kSoftStep (the pgs, thesis and jacobi solvers do not solve joints)");
    Require(def.scheme == ParallelScheme::kDeterministic, call + ": joints need ParallelScheme::kDeterministic");
    Require(IsLive(j.idA), call + ": bodyA is a stale or invalid BodyId");
    Require(IsLive(j.idB), call + ": bodyB is a stale or invalid BodyId");
    if (def.effects.sleep) {
      islands.WakeIslandOf(bodies, denseOf[j.idA.index]);
      islands.WakeIslandOf(bodies, denseOf[j.idB.index]);
    }
    return joints.Add(j);
  }
  bool IsLive(BodyId id) const {
    return id.generation != 0 && id.index < generation.size() && generation[id.index] == id.generation &&
           denseOf[id.index] >= 0;
  }
  // Joint j's two bodies' current dense indices (the joint's own are refreshed only per step).
  std::pair<int, int> JointBodies(const Joint& j) const { return {denseOf[j.idA.index], denseOf[j.idB.index]}; }
};

namespace {

// Mass, inertia and inverse mass of body i from its type, shape (density) and fixed-rotation flag,
// with AppendBody's expressions. A sleeping body keeps inverse mass 0: waking restores it from
// the mass and inertia set here (Islands::AwakeInverseMass).
void UpdateMassData(Bodies& b, int i) {
  if (b.type[i] != BodyType::kDynamic) {
    b.mass[i] = b.inertia[i] = 0;
    b.inv[i] = BodyInverseMass{};
    return;
  }
  const MassData md = b.compound[i].empty() ? ShapeMass(b.shape[i]) : CompoundMass(b.compound[i]);
  b.mass[i] = md.mass;
  b.inertia[i] = b.fixedRotation[i] ? Real(0) : md.rotationalInertia;
  if (b.awake[i]) b.inv[i] = BodyInverseMass{Real(1) / md.mass, b.inertia[i] > 0 ? Real(1) / b.inertia[i] : Real(0)};
}

}  // namespace

World::World(const WorldDef& def) : impl_(std::make_unique<Impl>()) {
  ValidateWorldDef(def);
  impl_->def = def;
  impl_->tasks = MakeThreadPool(def.threadCount);
  impl_->run = std::make_unique<StageRunner>(*impl_->tasks, def.minParallelItems);
  impl_->broadPhase = MakeBroadPhase(def.broadPhase, def.quadTreeMaxDepth);
  impl_->solver = MakeSolver(def.solver);
  if (def.scheme == ParallelScheme::kQuadrants) impl_->quadrants = std::make_unique<QuadrantsScheme>(def, def.threadCount);
}

World::~World() = default;
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;

namespace {

// The farthest point of shape s from `center` (body coordinates).
Real FarthestFrom(const ShapeDef& s, Vec2 center) {
  switch (s.type) {
    case ShapeType::kCircle: return Length(s.circle.center - center) + s.circle.radius;
    case ShapeType::kCapsule:
      return std::max(Length(s.capsule.center1 - center), Length(s.capsule.center2 - center)) + s.capsule.radius;
    case ShapeType::kSegment: return std::max(Length(s.segment.point1 - center), Length(s.segment.point2 - center));
    case ShapeType::kChainSegment: {
      const Segment& seg = s.chainSegment.segment;
      return std::max(Length(seg.point1 - center), Length(seg.point2 - center));
    }
    case ShapeType::kPolygon: break;
  }
  Real r = 0;
  for (int k = 0; k < s.polygon.count; ++k) r = std::max(r, Length(s.polygon.vertices[k] - center));
  return r;
}

}  // namespace

// A compound body's mass data, bound radius and stand-in shape (Bodies::compound): the stand-in's
// polygon is the box around every shape in body coordinates, so the broad-phase box (its box
// turned with the body) covers them all; its materials are the first shape's (GetShape reads
// the real shapes).
CompoundProperties MakeCompoundProperties(std::span<const ShapeDef> shapes) {
  CompoundProperties out;
  out.mass = CompoundMass(shapes);
  AABB box = ComputeShapeAABB(shapes[0], Transform{});
  for (const ShapeDef& s : shapes) {
    out.boundRadius = std::max(out.boundRadius, FarthestFrom(s, out.mass.center));
    const AABB sb = ComputeShapeAABB(s, Transform{});
    box.lower = Min(box.lower, sb.lower);
    box.upper = Max(box.upper, sb.upper);
  }
  ShapeDef standIn = shapes[0];
  standIn.type = kCompoundShape;
  standIn.isSensor = false;
  Polygon& p = standIn.polygon;
  p = Polygon{};
  p.count = 4;
  p.vertices[0] = box.lower;
  p.vertices[1] = {box.upper.x, box.lower.y};
  p.vertices[2] = box.upper;
  p.vertices[3] = {box.lower.x, box.upper.y};
  p.normals[0] = {0, -1};
  p.normals[1] = {1, 0};
  p.normals[2] = {0, 1};
  p.normals[3] = {-1, 0};
  p.centroid = Real(0.5) * (box.lower + box.upper);
  out.standIn = standIn;
  return out;
}

int AppendBody(Bodies& b, const BodyDef& def, const WorldDef& worldDef, uint32_t slot) {
  std::vector<ShapeDef> compound;
  const ShapeDef first = ValidateBodyDef(def, &compound);  // throws before anything changes
  Require(worldDef.scheme != ParallelScheme::kQuadrants || compound.empty(),
          "CreateBody: a compound body (BodyDef.extraShapes) needs ParallelScheme::kDeterministic");
  const CompoundProperties props = compound.empty() ? CompoundProperties{} : MakeCompoundProperties(compound);
  const ShapeDef& shape = compound.empty() ? first : props.standIn;
  Require(worldDef.scheme != ParallelScheme::kQuadrants || def.filter == Filter{},
          "CreateBody: a non-default collision filter needs ParallelScheme::kDeterministic");
  Require(worldDef.scheme != ParallelScheme::kQuadrants || !def.shape.isSensor,
          "CreateBody: a sensor shape needs ParallelScheme::kDeterministic");

  MassData md{};
  Real boundRadius = 0;
  Require(worldDef.scheme != ParallelScheme::kQuadrants || shape.type != ShapeType::kCapsule,
          "CreateBody: a capsule needs ParallelScheme::kDeterministic");
  Require(worldDef.scheme != ParallelScheme::kQuadrants || !IsSegmentType(shape.type),
          "CreateBody: a segment needs ParallelScheme::kDeterministic");
  Require(def.isAwake || (def.type == BodyType::kDynamic && worldDef.effects.sleep),
          "CreateBody: BodyDef.isAwake = false needs a dynamic body and WorldDef.effects.sleep");
  if (!compound.empty()) {
    md = props.mass;
    boundRadius = props.boundRadius;
  } else if (shape.type == ShapeType::kCircle) {
    md = ComputeMass(shape.circle, shape.density);
    boundRadius = shape.circle.radius;
  } else if (shape.type == ShapeType::kCapsule) {
    md = ComputeMass(shape.capsule, shape.density);
    boundRadius = Real(0.5) * Length(shape.capsule.center2 - shape.capsule.center1) + shape.capsule.radius;
  } else if (IsSegmentType(shape.type)) {
    const Segment& seg = shape.type == ShapeType::kSegment ? shape.segment : shape.chainSegment.segment;
    md = ComputeMass(seg);
    boundRadius = Real(0.5) * Length(seg.point2 - seg.point1);
  } else {
    md = ComputeMass(shape.polygon, shape.density);
    for (int k = 0; k < shape.polygon.count; ++k) {
      boundRadius = std::max(boundRadius, Length(shape.polygon.vertices[k] - md.center));
    }
  }
  const bool dynamic = def.type == BodyType::kDynamic;  // its mass was checked by ValidateBodyDef

  const int i = b.Count();
  b.ForEachArray([](auto& v) { v.emplace_back(); });
  const Transform xf{def.position, MakeRot(def.angle)};
  b.type[i] = def.type;
  b.xf[i] = xf;
  b.center[i] = TransformPoint(xf, md.center);
  b.localCenter[i] = md.center;
  const bool moves = def.type != BodyType::kStatic;
  b.vel[i] = moves ? BodyVelocity{def.linearVelocity, worldDef.effects.rotation ? def.angularVelocity : Real(0)}
                   : BodyVelocity{};
  // Fixed rotation: inertia and inverse inertia 0 (Box2D's rule), angular velocity 0 (validated).
  const bool turns = !def.fixedRotation;
  b.inv[i] = dynamic ? BodyInverseMass{Real(1) / md.mass, turns && md.rotationalInertia > 0
                                                              ? Real(1) / md.rotationalInertia
                                                              : Real(0)}
                     : BodyInverseMass{};
  b.mass[i] = dynamic ? md.mass : Real(0);
  b.inertia[i] = dynamic && turns ? md.rotationalInertia : Real(0);
  b.linearDamping[i] = def.linearDamping;
  b.angularDamping[i] = def.angularDamping;
  b.shape[i] = shape;
  b.boxShape[i] = BoxShapeOf(shape);
  b.boundRadius[i] = boundRadius;
  b.aabb[i] = {};
  b.dynamic[i] = dynamic ? 1 : 0;
  b.slot[i] = slot;
  b.awake[i] = def.type == BodyType::kStatic ? 0 : 1;
  b.sleepTime[i] = 0;
  b.islandOf[i] = 0;
  b.filter[i] = def.filter;
  b.userData[i] = def.userData;
  b.gravityScale[i] = def.gravityScale;
  b.fixedRotation[i] = def.fixedRotation ? 1 : 0;
  b.bullet[i] = def.isBullet ? 1 : 0;
  b.bulletCount += def.isBullet ? 1 : 0;
  b.compoundCount += compound.empty() ? 0 : 1;
  for (const ShapeDef& s : compound) b.compoundBoxes[i].push_back(ComputeShapeAABB(s, Transform{}));
  b.compound[i] = std::move(compound);
  b.aabb[i] = BroadPhaseBox(b, i, worldDef, 0);
  return i;
}

BodyId World::CreateBody(const BodyDef& def) {
  Impl& w = *impl_;
  // The slot is taken only once the body is accepted (AppendBody validates before it adds).
  const uint32_t slot = w.freeSlots.empty() ? static_cast<uint32_t>(w.generation.size()) : w.freeSlots.back();
  const int i = AppendBody(w.bodies, def, w.def, slot);
  if (!w.freeSlots.empty()) {
    w.freeSlots.pop_back();
  } else {
    w.generation.push_back(1);
    w.denseOf.push_back(-1);
  }
  w.denseOf[slot] = i;
  w.customFilters += def.filter == Filter{} ? 0 : 1;
  w.gravityScaled += def.gravityScale == 1 ? 0 : 1;
  w.sensorCount += def.shape.isSensor ? 1 : 0;
  w.queryStale = true;
  if (def.isAwake) {
    w.WakeAround(i);  // a body created touching a sleeping pile wakes it
  } else {
    Islands::Sleep(w.bodies, i, slot);  // an island of its own, until something awake touches it
    w.UpdateAABB(i, 0);
  }
  return BodyId{slot, w.generation[slot]};
}

std::vector<BodyId> World::CreateChain(const ChainDef& def) {
  const std::vector<BodyDef> bodies = MakeChainBodies(def);  // throws before anything changes
  // What CreateBody checks beyond CheckBodyDef depends on the world alone, the same for every
  // segment: the first body is refused or none is.
  std::vector<BodyId> ids;
  ids.reserve(bodies.size());
  for (const BodyDef& body : bodies) ids.push_back(CreateBody(body));
  return ids;
}

void World::DestroyBody(BodyId id) {
  Impl& w = *impl_;
  const int i = w.Dense(id);
  w.WakeAround(i);  // what rested on the body falls again
  // Its joints go with it, from the last one down (RemoveAt moves the last joint into the gap).
  const std::vector<int> onBody = w.joints.OnBody(id.index);
  for (auto it = onBody.rbegin(); it != onBody.rend(); ++it) {
    const Joint& j = w.joints.All()[size_t(*it)];
    if (w.def.effects.sleep) w.islands.WakeIslandOf(w.bodies, w.denseOf[(j.idA.index == id.index ? j.idB : j.idA).index]);
    w.joints.RemoveAt(*it);
  }
  w.joints.MarkStale();  // dense indices move below
  const int last = w.bodies.Count() - 1;
  Bodies& b = w.bodies;
  w.customFilters -= b.filter[i] == Filter{} ? 0 : 1;
  w.gravityScaled -= b.gravityScale[i] == 1 ? 0 : 1;
  b.bulletCount -= b.bullet[i];
  b.compoundCount -= b.compound[i].empty() ? 0 : 1;
  if (id.index < w.pendingOf.size() && w.pendingOf[id.index] >= 0) {
    w.pendingForces[size_t(w.pendingOf[id.index])].live = false;
    w.pendingOf[id.index] = -1;
  }
  w.sensorCount -= b.shape[i].isSensor ? 1 : 0;
  w.queryStale = true;
  auto moveLast = [&](auto& v) {
    v[i] = v[last];
    v.pop_back();
  };
  b.ForEachArray(moveLast);
  if (i != last) w.denseOf[b.slot[i]] = i;
  w.denseOf[id.index] = -1;
  // Generation 0 means null, so skip it when the counter wraps.
  w.generation[id.index] = w.generation[id.index] + 1 == 0 ? 1 : w.generation[id.index] + 1;
  w.freeSlots.push_back(id.index);
  // Dense indices moved, so last step's contacts no longer name the right bodies.
  w.cache.Clear();
  w.contacts.clear();
}

bool World::IsValid(BodyId id) const {
  const Impl& w = *impl_;
  return id.generation != 0 && id.index < w.generation.size() && w.generation[id.index] == id.generation &&
         w.denseOf[id.index] >= 0;
}

void World::Step(Real dt) { StepRepeated(dt, 1); }

void World::StepRepeated(Real dt, int pipelineRepeats) {
  Require(IsFinite(dt) && dt > 0, "Step: dt must be finite and > 0");
  Require(dt <= kMaxTimeStep, "Step: dt must be <= 1 s");
  Require(pipelineRepeats >= 1, "StepRepeated: pipelineRepeats must be >= 1");
  Require(pipelineRepeats <= kMaxIterations, "StepRepeated: pipelineRepeats must be <= 1000");
  Impl& w = *impl_;
  w.queryStale = true;
  w.profile = Profile{};
  w.run->Reset();
  w.run->BeginStep();
  const auto start = Clock::now();
  const Real h = dt / Real(pipelineRepeats);
  if (w.def.hitEvents) w.hitCandidates.clear();
  for (int s = 0; s < pipelineRepeats; ++s) w.RunPipeline(h);
  w.profile.total = Ms(start, Clock::now());
  w.profile.balance = w.run->Balance();
  w.profile.aloneSteps = w.run->Alone() ? 1 : 0;
  w.profile.smallSteps = w.run->SmallStep() ? 1 : 0;
  // With sleep on, the touching pairs are tracked even without events: a sleeping island's
  // contacts are not in `contacts` (it gets no pairs), yet it still touches, so the counter counts
  // the tracked pairs (as Box2D, Bullet and Chipmunk count a sleeping pile's contacts). Hit events
  // need last step's touching pairs too.
  if (w.def.contactEvents || w.def.hitEvents || w.def.effects.sleep) {
    if (w.def.hitEvents) w.SelectHits();  // before `touching` becomes this step's
    w.UpdateContactEvents();
    w.counters.touchingContacts = static_cast<int>(w.touching.size());
  }
  // Also once more after the last sensor is gone: its overlaps end, and then its events clear.
  if (w.sensorCount > 0 || !w.overlaps.empty() || !w.sensorEndEvents.empty()) w.UpdateSensorEvents();
}

void World::Impl::FindPairs(const BroadPhase::BoxUpdate* update) {
  pairsReused = false;
  if (update && def.reusePairs && !def.effects.sleep) {
    pairsReused = pairCache.UpdateAndFindPairs(*broadPhase, bodies.aabb, bodies.dynamic, pairs, *run, *update);
  } else if (update) {
    broadPhase->UpdateAndFindPairs(bodies.aabb, bodies.dynamic, pairs, *run, *update);
  } else {
    broadPhase->FindPairs(bodies.aabb, bodies.dynamic, pairs, *run);
  }
  // While every body collides with everything, nothing is dropped and this is skipped.
  if (customFilters > 0) {
    // Box2D's rule (types.h, ShouldCollide). Compacting in place keeps the pairs' deterministic order.
    run->Serial(Stage::kBroadPhase, [&] {
      const std::vector<Filter>& f = bodies.filter;
      pairs.erase(std::remove_if(pairs.begin(), pairs.end(),
                                 [&](const CandidatePair& p) { return !ShouldCollide(f[p.a], f[p.b]); }),
                  pairs.end());
    });
  }
  if (joints.Filters()) run->Serial(Stage::kBroadPhase, [&] { joints.FilterPairs(pairs); });
  if (sensorCount > 0) SplitSensorPairs();
}

// A sensor's pairs make no contact: they leave `pairs` (which keeps its order) for `sensorPairs`.
// Two sensors do not sense each other, and their pair is dropped.
void World::Impl::SplitSensorPairs() {
  run->Serial(Stage::kBroadPhase, [&] {
    sensorPairs.clear();
    const ShapeDef* shape = bodies.shape.data();
    size_t kept = 0;
    for (const CandidatePair& p : pairs) {
      const bool a = shape[p.a].isSensor, b = shape[p.b].isSensor;
      if (!a && !b) {
        pairs[kept++] = p;
      } else if (a != b) {
        sensorPairs.push_back(p);
      }
    }
    pairs.resize(kept);
  });
}

// The sensor pairs whose shapes overlap (touching counts) where the bodies are now, at the start
// of the step's solve: exact tests in double (queries.cpp, ShapesOverlap), as (sensor, visitor).
void World::Impl::FindSensorOverlaps() {
  run->Serial(Stage::kPersistence, [&] {
    sensorFound.clear();
    for (const CandidatePair& p : sensorPairs) {
      // A visitor may be a compound body (a sensor never is): any of its shapes counts.
      bool overlap = false;
      for (const ShapeDef& sa : BodyShapes(bodies, p.a)) {
        for (const ShapeDef& sb : BodyShapes(bodies, p.b)) overlap = overlap || ShapesOverlap(sa, bodies.xf[p.a], sb, bodies.xf[p.b]);
      }
      if (!overlap) continue;
      const bool aSenses = bodies.shape[p.a].isSensor;
      sensorFound.push_back({IdOf(aSenses ? p.a : p.b), IdOf(aSenses ? p.b : p.a)});
    }
  });
}

// Hit candidates: contacts with a point approaching faster than the threshold that reaches the
// other shape within this step (separation <= approach speed * dt, so a speculative point about
// to close counts, and a point already touching does), with the velocities before the solver. Per
// contact the fastest such point. SelectHits keeps those of pairs that were not touching.
void World::Impl::FindHits(Real dt) {
  hitParts.Reset(run->Workers());
  const Real threshold = def.hitEventThreshold;
  run->For(Stage::kPersistence, static_cast<int>(contacts.size()), run->MinHeavyItems(),
           [&](int begin, int end, int worker) {
             std::vector<ContactHitEvent>& out = hitParts[worker];
             for (int i = begin; i < end; ++i) {
               const Contact& c = contacts[size_t(i)];
               const Manifold& m = c.manifold;
               const BodyVelocity& va = bodies.vel[c.a];
               const BodyVelocity& vb = bodies.vel[c.b];
               ContactHitEvent e;
               e.approachSpeed = threshold;
               bool hit = false;
               for (int k = 0; k < m.pointCount; ++k) {
                 const ManifoldPoint& mp = m.points[k];
                 const Vec2 rA = mp.point - bodies.center[c.a];
                 const Vec2 rB = mp.point - bodies.center[c.b];
                 const Vec2 dv = vb.v + Cross(vb.w, rB) - va.v - Cross(va.w, rA);
                 const Real approach = -Dot(dv, m.normal);
                 if (approach > e.approachSpeed && mp.separation <= approach * dt) {
                   e.approachSpeed = approach;
                   e.point = mp.point;
                   hit = true;
                 }
               }
               if (!hit) continue;
               e.bodyA = IdOf(c.a);
               e.bodyB = IdOf(c.b);
               e.normal = m.normal;
               if (e.bodyB.index < e.bodyA.index) {
                 std::swap(e.bodyA, e.bodyB);
                 e.normal = -e.normal;
               }
               out.push_back(e);
             }
           });
  for (int k = 0; k < hitParts.Count(); ++k) hitCandidates.insert(hitCandidates.end(), hitParts[k].begin(), hitParts[k].end());
}

namespace {
bool IdPairLess(BodyId a1, BodyId b1, BodyId a2, BodyId b2) {
  if (a1.index != a2.index) return a1.index < a2.index;
  if (b1.index != b2.index) return b1.index < b2.index;
  if (a1.generation != a2.generation) return a1.generation < a2.generation;
  return b1.generation < b2.generation;
}
bool EventLess(const ContactEvent& x, const ContactEvent& y) { return IdPairLess(x.bodyA, x.bodyB, y.bodyA, y.bodyB); }
bool SensorLess(const SensorEvent& x, const SensorEvent& y) { return IdPairLess(x.sensor, x.visitor, y.sensor, y.visitor); }
bool HitLess(const ContactHitEvent& x, const ContactHitEvent& y) { return IdPairLess(x.bodyA, x.bodyB, y.bodyA, y.bodyB); }
}  // namespace

// The hit events of the step: the candidates (FindHits) of pairs that were not touching after the
// last Step (`touching` still holds that step's pairs), one per pair (its first pipeline repeat's),
// sorted by ids as the contact events.
void World::Impl::SelectHits() {
  std::stable_sort(hitCandidates.begin(), hitCandidates.end(), HitLess);
  hitEvents.clear();
  for (size_t k = 0; k < hitCandidates.size(); ++k) {
    const ContactHitEvent& e = hitCandidates[k];
    if (k > 0 && !HitLess(hitCandidates[k - 1], e)) continue;  // a later repeat's hit of the same pair
    if (std::binary_search(touching.begin(), touching.end(), ContactEvent{e.bodyA, e.bodyB}, EventLess)) continue;
    hitEvents.push_back(e);
  }
}

// Sensor begin and end events as the difference of two sorted lists of overlaps, as the contact
// events are made (below).
void World::Impl::UpdateSensorEvents() {
  std::swap(overlaps, overlapsBefore);
  overlaps.clear();
  if (sensorCount > 0) overlaps.assign(sensorFound.begin(), sensorFound.end());
  if (def.effects.sleep) {
    // A pair of which neither body is simulated has no broad-phase pair: it keeps its overlap.
    for (const SensorEvent& e : overlapsBefore) {
      if (Idle(e.sensor) && Idle(e.visitor)) overlaps.push_back(e);
    }
  }
  std::sort(overlaps.begin(), overlaps.end(), SensorLess);
  overlaps.erase(std::unique(overlaps.begin(), overlaps.end()), overlaps.end());
  sensorBeginEvents.clear();
  sensorEndEvents.clear();
  std::set_difference(overlaps.begin(), overlaps.end(), overlapsBefore.begin(), overlapsBefore.end(),
                      std::back_inserter(sensorBeginEvents), SensorLess);
  std::set_difference(overlapsBefore.begin(), overlapsBefore.end(), overlaps.begin(), overlaps.end(),
                      std::back_inserter(sensorEndEvents), SensorLess);
}

// Begin and end events as the difference of two sorted lists of touching pairs, named by id
// (not by dense index, which destroying a body changes): the order depends on ids only, so it is
// the same for any thread count whenever the contacts are.
void World::Impl::UpdateContactEvents() {
  std::swap(touching, touchingBefore);
  touching.clear();
  for (const Contact& c : contacts) {
    bool touches = false;
    for (int k = 0; k < c.manifold.pointCount; ++k) touches = touches || c.manifold.points[k].separation <= 0;
    if (!touches) continue;
    BodyId a = IdOf(c.a), b = IdOf(c.b);
    if (b.index < a.index) std::swap(a, b);
    touching.push_back({a, b});
  }
  if (def.effects.sleep) {
    // Sleeping bodies get no pairs (among themselves or with statics), so their contacts are not
    // in `contacts`; a pile that falls asleep has not stopped touching. A pair of bodies that are
    // both still there and neither simulated (asleep or static) keeps its touch from last step.
    // At least one of them must be asleep: a body made static (SetType) beside a static one
    // no longer touches it.
    auto asleep = [&](BodyId id) { return Islands::IsSleeping(bodies, denseOf[id.index]); };
    for (const ContactEvent& e : touchingBefore) {
      if (Idle(e.bodyA) && Idle(e.bodyB) && (asleep(e.bodyA) || asleep(e.bodyB))) touching.push_back(e);
    }
  }
  std::sort(touching.begin(), touching.end(), EventLess);
  // The step an island falls asleep its pairs are both in `contacts` and carried over: once each.
  touching.erase(std::unique(touching.begin(), touching.end()), touching.end());
  beginEvents.clear();
  endEvents.clear();
  std::set_difference(touching.begin(), touching.end(), touchingBefore.begin(), touchingBefore.end(),
                      std::back_inserter(beginEvents), EventLess);
  std::set_difference(touchingBefore.begin(), touchingBefore.end(), touching.begin(), touching.end(),
                      std::back_inserter(endEvents), EventLess);
}

// The query structure over every body's current shape box, grown a little (1 mm, and 1e-6 of
// the coordinate far out) so float rounding in the box never hides a shape the exact double
// tests (queries.cpp) would report.
void World::Impl::PrepareQueries() {
  if (!queryStale) return;
  if (!queryIndex) {
    queryTasks = MakeThreadPool(1);
    queryRun = std::make_unique<StageRunner>(*queryTasks, def.minParallelItems);
    queryIndex = MakeBroadPhase(def.broadPhase, def.quadTreeMaxDepth);
  }
  const int n = bodies.Count();
  queryBoxes.resize(n);
  for (int i = 0; i < n; ++i) {
    const ShapeDef& s = bodies.shape[i];
    AABB box = ComputeShapeAABB(s, bodies.xf[i]);
    const Real far = std::max(std::max(std::abs(box.lower.x), std::abs(box.lower.y)),
                              std::max(std::abs(box.upper.x), std::abs(box.upper.y)));
    const Real m = Real(1e-3) + Real(1e-6) * far;
    box.lower = box.lower - Vec2{m, m};
    box.upper = box.upper + Vec2{m, m};
    queryBoxes[i] = box;
  }
  queryIndex->BuildForQueries(queryBoxes, *queryRun);
  queryStale = false;
}

void World::Impl::RunPipeline(Real dt) {
  const int n = bodies.Count();
  if (joints.Count() > 0) joints.Prepare(denseOf, n);
  auto t0 = Clock::now();
  const bool sleepOn = def.effects.sleep;
  // The boxes of [begin, end): sleeping bodies keep the box they fell asleep with (awake is 0
  // for them and for statics).
  struct Update {
    Impl* w;
    Real dt;
    static void Run(const void* ctx, int begin, int end) {
      const Update& u = *static_cast<const Update*>(ctx);
      Bodies& bodies = u.w->bodies;
      if (u.w->def.effects.sleep) {
        for (int i = begin; i < end; ++i) {
          if (bodies.awake[i]) u.w->UpdateAABB(i, u.dt);
        }
      } else {
        for (int i = begin; i < end; ++i) {
          if (bodies.type[i] != BodyType::kStatic) u.w->UpdateAABB(i, u.dt);
        }
      }
    }
  };
  const Update update{this, dt};
  const BroadPhase::BoxUpdate boxUpdate{&Update::Run, &update};
  if (quadrants) {
    run->For(Stage::kBroadPhase, n, run->MinItems(), [&](int begin, int end, int) { boxUpdate(begin, end); });
    int pairCount = 0;
    profile.broadPhase += Ms(t0, Clock::now());  // the AABB update; the scheme times the rest
    PreSolve(dt);
    quadrants->Step(dt, def, bodies, *run, cache, contacts, pairCount, profile);
    CountContacts(pairCount);
    return;
  }
  FindPairs(&boxUpdate);  // the boxes are updated inside (UpdateAndFindPairs)
  auto t1 = Clock::now();
  const bool persist = def.solver != SolverType::kThesis && def.effects.warmStarting;
  // Last step's solved contacts become the cache (ContactCache::Keep): nothing is copied at the
  // end of the step, and `contacts` stays readable (GetContacts) until this step refills it. Kept
  // before the narrow phase, which may recycle their manifolds (PrepareRecycling).
  if (persist) cache.Keep(contacts, contactsIncreasing);
  PrepareRecycling(persist);
  NarrowPhase(dt);
  auto t2 = Clock::now();
  SortContacts();  // times itself (kPersistence); the narrow phase's contacts, restored, are in `contacts` after it
  if (sleepOn) {
    // An awake body touches a sleeping island: the island wakes in this step. Its bodies' pairs
    // (among themselves and with the ground) were not searched, so the broad and narrow phases
    // run again with them awake; repeated while that wakes further islands. (Timed with
    // persistence: it is rare and short.)
    while (islands.WakeTouched(bodies, contacts) > 0) {
      for (int i : islands.Changed()) UpdateAABB(i, dt);
      FindPairs();
      NarrowPhase(dt);
      SortContacts();
    }
  }
  // Timed with persistence, as the rewaking above: they read the contacts and pairs found so far.
  if (sensorCount > 0) FindSensorOverlaps();
  if (def.hitEvents) FindHits(dt);
  auto t3 = Clock::now();

  // soft_step applies gravity per sub-step, so it scales it there: added once a step here, a
  // scale would move a free body by (scale - 1) g dt^2 (n - 1) / (2 n) too far.
  const bool solverScalesGravity = def.solver == SolverType::kSoftStep && gravityScaled > 0 && def.effects.gravity;
  PreSolve(dt, solverScalesGravity);
  StepContext ctx;
  ctx.dt = dt;
  ctx.def = &def;
  ctx.bodies = &bodies;
  ctx.contacts = contacts;
  ctx.joints = joints.All();
  ctx.jointsVersion = joints.Version();
  ctx.profile = &profile;
  ctx.run = run.get();
  ctx.gravityScaled = solverScalesGravity;
  solver->Step(ctx);
  if (sleepOn) {
    // Timed as part of the solve: Box2D 2.4 also builds its islands in the solve.
    const auto ts = Clock::now();
    run->Serial(Stage::kSolve, [&] {
      islands.Update(bodies, contacts, joints.All(), def, dt);
      // A sleeping body keeps its box until it wakes: the tight one at rest, not this step's sweep.
      for (int i : islands.Changed()) UpdateAABB(i, 0);
    });
    profile.solve += Ms(ts, Clock::now());
  }

  profile.broadPhase += Ms(t0, t1);
  profile.narrowPhase += Ms(t1, t2);
  profile.persistence += Ms(t2, t3);

  CountContacts(static_cast<int>(pairs.size()));
  counters.jointColoringKept = solver->JointColoringKept();
  counters.rowBundles = solver->RowBundles();
}

// The pre-solve pass: what the solvers do not know of, as velocity changes before they run (so no
// solver is touched). Pending forces and torques, v += dt F / m and w += dt T / I, then cleared
// (in the first pipeline repeat of a StepRepeated, as with calls of Step); and the part of gravity
// that a scale other than 1 adds, v += dt (scale - 1) g, every repeat. Only awake dynamic bodies
// (`dynamic` 1): a body made static or kinematic, or put to sleep, since its force was applied
// does not get it. Serial over the forces' list, in parallel blocks over the bodies for gravity
// (each body's own arithmetic): the same bits for any thread count. Nothing runs, not even a test
// per body, while no force is pending and every body's gravity scale is 1.
void World::Impl::PreSolve(Real dt, bool solverScalesGravity) {
  if (pendingForces.empty() && (gravityScaled == 0 || solverScalesGravity)) return;
  const auto t0 = Clock::now();
  run->Serial(Stage::kIntegrate, [&] {
    const bool rotation = def.effects.rotation;
    const double limit = double(kMaxInputSpeed);
    for (const PendingForce& f : pendingForces) {
      if (!f.live) continue;
      pendingOf[f.slot] = -1;
      const int i = denseOf[f.slot];
      if (bodies.dynamic[i] == 0) continue;
      const BodyInverseMass inv = bodies.inv[i];
      BodyVelocity& bv = bodies.vel[i];
      // The calls checked the velocity change against the mass at that time; clamping guards a
      // mass made smaller since (SetDensity) from overflowing the velocity.
      const double h = double(dt);
      bv.v.x = Real(std::clamp(double(bv.v.x) + h * f.fx * double(inv.invMass), -limit, limit));
      bv.v.y = Real(std::clamp(double(bv.v.y) + h * f.fy * double(inv.invMass), -limit, limit));
      if (rotation) bv.w = Real(std::clamp(double(bv.w) + h * f.torque * double(inv.invInertia), -limit, limit));
    }
    pendingForces.clear();
  });
  if (gravityScaled > 0 && def.effects.gravity && !solverScalesGravity) {
    const Vec2 g = def.gravity;
    run->For(Stage::kIntegrate, bodies.Count(), run->MinItems(), [&](int begin, int end, int) {
      for (int i = begin; i < end; ++i) {
        const Real scale = bodies.gravityScale[i];
        if (scale == 1 || bodies.dynamic[i] == 0) continue;
        bodies.vel[i].v += (dt * (scale - Real(1))) * g;
      }
    });
  }
  profile.integrate += Ms(t0, Clock::now());
}

void World::Impl::CountContacts(int candidatePairs) {
  counters = Counters{};
  counters.bodies = bodies.Count();
  counters.candidatePairs = candidatePairs;
  counters.pairsReused = pairsReused;
  counters.contacts = static_cast<int>(contacts.size());
  // In parallel (sums of integers: any split gives the same counts). Serial, it was 0.7 % of the
  // base-100 pyramid's instructions a step, all of it on one thread at any thread count.
  countParts.assign(size_t(run->Workers()), {0, 0});
  run->For(Stage::kPersistence, static_cast<int>(contacts.size()), run->MinHeavyItems(), [&](int begin, int end, int worker) {
    int points = 0, touchingContacts = 0;
    for (int i = begin; i < end; ++i) {
      const Manifold& m = contacts[i].manifold;
      points += m.pointCount;
      bool touching = false;
      for (int k = 0; k < m.pointCount; ++k) touching = touching || m.points[k].separation <= 0;
      touchingContacts += touching ? 1 : 0;
    }
    countParts[size_t(worker)].first += points;
    countParts[size_t(worker)].second += touchingContacts;
  });
  for (const auto& [points, touchingContacts] : countParts) {
    counters.contactPoints += points;
    counters.touchingContacts += touchingContacts;
  }
}

// The recycling source for this step's narrow phase (soft_step with contactRecycleDistance > 0
// and warm starting): last step's contacts, kept by the cache in key order, and the index of each
// body's first contact as body a, so the pair loop finds a pair's old contact in a few compares.
// In parallel, each body's entry written by the thread that holds the start of its run; entries
// of bodies without a contact now are left as they were: the pair loop takes an entry only where
// it is the start of that body's run (narrow_pair_loop.inc). Serial, with a reset of last step's
// entries, this was 0.28-0.37 ms a step on many_pyramids 22000 (2 % of one thread's step, 11 % of
// the model's 16-thread step).
void World::Impl::PrepareRecycling(bool persist) {
  recycling = false;
  if (!persist || def.solver != SolverType::kSoftStep || def.contactRecycleDistance <= 0) return;
  const std::vector<Contact>* kept = cache.Kept();
  if (kept == nullptr) return;
  const int n = bodies.Count(), count = static_cast<int>(kept->size());
  if (recycleFirst.size() < size_t(n)) recycleFirst.resize(size_t(n), -1);
  const Contact* old = kept->data();
  int32_t* first = recycleFirst.data();
  run->For(Stage::kNarrowPhase, count, run->MinItems(), [old, first](int begin, int end, int) {
    for (int i = begin; i < end; ++i) {
      if (i == 0 || old[i - 1].a != old[i].a) first[old[i].a] = i;
    }
  });
  recycleSource = {old, count, first, def.contactRecycleDistance};
  recycling = true;
}

void World::Impl::NarrowPhase(Real dt) {
  workerContacts.Reset(run->Workers());
  const RecycleSource* recycle = recycling ? &recycleSource : nullptr;
  run->For(Stage::kNarrowPhase, static_cast<int>(pairs.size()), run->MinHeavyItems(),
           [&](int begin, int end, int worker) {
             CollidePairs(bodies, def, dt, std::span<const CandidatePair>(pairs).subspan(begin, end - begin),
                          workerContacts[worker], recycle);
           });
  // The workers' contacts are put in key order and merged by SortContacts.
}

Vec2 World::GetPosition(BodyId id) const { return impl_->bodies.xf[impl_->Dense(id)].p; }
Real World::GetAngle(BodyId id) const { return quadrant::GetAngle(impl_->bodies.xf[impl_->Dense(id)].q); }
Rot World::GetRotation(BodyId id) const { return impl_->bodies.xf[impl_->Dense(id)].q; }
Vec2 World::GetLinearVelocity(BodyId id) const { return impl_->bodies.vel[impl_->Dense(id)].v; }
Real World::GetAngularVelocity(BodyId id) const { return impl_->bodies.vel[impl_->Dense(id)].w; }
Vec2 World::GetWorldCenter(BodyId id) const { return impl_->bodies.center[impl_->Dense(id)]; }
Real World::GetMass(BodyId id) const { return impl_->bodies.mass[impl_->Dense(id)]; }
Real World::GetRotationalInertia(BodyId id) const { return impl_->bodies.inertia[impl_->Dense(id)]; }
BodyType World::GetType(BodyId id) const { return impl_->bodies.type[impl_->Dense(id)]; }
AABB World::GetAABB(BodyId id) const {
  const int i = impl_->Dense(id);
  const Transform& xf = impl_->bodies.xf[i];
  const std::span<const ShapeDef> shapes = BodyShapes(impl_->bodies, i);
  AABB box = ComputeShapeAABB(shapes[0], xf);
  for (size_t k = 1; k < shapes.size(); ++k) {
    const AABB sb = ComputeShapeAABB(shapes[k], xf);
    box.lower = Min(box.lower, sb.lower);
    box.upper = Max(box.upper, sb.upper);
  }
  return box;
}
const ShapeDef& World::GetShape(BodyId id) const { return BodyShapes(impl_->bodies, impl_->Dense(id))[0]; }
const ShapeDef& World::GetShape(BodyId id, int index) const {
  const std::span<const ShapeDef> shapes = BodyShapes(impl_->bodies, impl_->Dense(id));
  Require(index >= 0 && size_t(index) < shapes.size(),
          "GetShape: shape index " + std::to_string(index) + " is outside [0, " + std::to_string(shapes.size()) + ")");
  return shapes[size_t(index)];
}
int World::GetShapeCount(BodyId id) const { return static_cast<int>(BodyShapes(impl_->bodies, impl_->Dense(id)).size()); }

void World::SetLinearVelocity(BodyId id, Vec2 v) {
  const int i = impl_->Dense(id);
  Require(IsFinite(v), "SetLinearVelocity: velocity is not finite");
  Require(std::abs(v.x) <= kMaxInputSpeed && std::abs(v.y) <= kMaxInputSpeed,
          "SetLinearVelocity: velocity is beyond the limit of 1e6 m/s");
  if (impl_->bodies.type[i] == BodyType::kStatic) return;  // static bodies have no velocity
  if (impl_->def.effects.sleep) impl_->islands.WakeIslandOf(impl_->bodies, i);
  impl_->bodies.vel[i].v = v;
}

void World::SetAngularVelocity(BodyId id, Real w) {
  const int i = impl_->Dense(id);
  Require(IsFinite(w), "SetAngularVelocity: angular velocity is not finite");
  Require(std::abs(w) <= kMaxInputSpeed, "SetAngularVelocity: angular velocity is beyond the limit of 1e6 rad/s");
  Require(w == 0 || !impl_->bodies.fixedRotation[i], "SetAngularVelocity: the body has fixed rotation (its angular velocity stays 0)");
  if (impl_->bodies.type[i] == BodyType::kStatic || !impl_->def.effects.rotation) return;
  if (impl_->def.effects.sleep) impl_->islands.WakeIslandOf(impl_->bodies, i);
  impl_->bodies.vel[i].w = w;
}

void World::SetTransform(BodyId id, Vec2 position, Real angle) {
  Impl& w = *impl_;
  const int i = w.Dense(id);
  Require(IsFinite(position) && IsFinite(angle), "SetTransform: position or angle is not finite");
  Require(std::abs(position.x) <= kMaxCoordinate && std::abs(position.y) <= kMaxCoordinate,
          "SetTransform: position is beyond the coordinate limit of 1e6 m");
  w.WakeAround(i);  // the body and what rested on it at its old place
  w.bodies.xf[i] = Transform{position, MakeRot(angle)};
  w.bodies.center[i] = TransformPoint(w.bodies.xf[i], w.bodies.localCenter[i]);
  w.UpdateAABB(i, 0);
  w.queryStale = true;
  w.WakeAround(i);  // what it lands on
}

void World::ApplyLinearImpulse(BodyId id, Vec2 impulse, Vec2 worldPoint) {
  Impl& w = *impl_;
  const int i = w.Dense(id);
  Require(IsFinite(impulse) && IsFinite(worldPoint), "ApplyLinearImpulse: impulse or point is not finite");
  Require(std::abs(worldPoint.x) <= kMaxCoordinate && std::abs(worldPoint.y) <= kMaxCoordinate,
          "ApplyLinearImpulse: point is beyond the coordinate limit of 1e6 m");
  w.RequireDynamic(i, "ApplyLinearImpulse");
  // Compute in double and check before writing: the world must stay as it was if refused.
  // A sleeping body's stored inverse mass is 0; the impulse acts on its awake one.
  const BodyInverseMass inv = w.ActiveInverseMass(i);
  const double vx = double(w.bodies.vel[i].v.x) + double(inv.invMass) * impulse.x;
  const double vy = double(w.bodies.vel[i].v.y) + double(inv.invMass) * impulse.y;
  const Vec2 r = worldPoint - w.bodies.center[i];
  const double wz = double(w.bodies.vel[i].w) +
                    (w.def.effects.rotation ? double(inv.invInertia) * (double(r.x) * impulse.y - double(r.y) * impulse.x) : 0.0);
  Require(std::abs(vx) <= kMaxInputSpeed && std::abs(vy) <= kMaxInputSpeed && std::abs(wz) <= kMaxInputSpeed,
          "ApplyLinearImpulse: the resulting velocity is beyond the limit of 1e6 m/s (rad/s)");
  if (w.def.effects.sleep) w.islands.WakeIslandOf(w.bodies, i);
  w.bodies.vel[i].v = {Real(vx), Real(vy)};
  w.bodies.vel[i].w = Real(wz);
}

void World::ApplyAngularImpulse(BodyId id, Real impulse) {
  Impl& w = *impl_;
  const int i = w.Dense(id);
  Require(IsFinite(impulse), "ApplyAngularImpulse: impulse is not finite");
  w.RequireDynamic(i, "ApplyAngularImpulse");
  const double invI = w.def.effects.rotation ? double(w.ActiveInverseMass(i).invInertia) : 0.0;
  const double wz = double(w.bodies.vel[i].w) + invI * double(impulse);
  Require(std::abs(wz) <= kMaxInputSpeed, "ApplyAngularImpulse: the resulting angular velocity is beyond the limit of 1e6 rad/s");
  if (w.def.effects.sleep) w.islands.WakeIslandOf(w.bodies, i);
  w.bodies.vel[i].w = Real(wz);
}

// Adds to body i's pending force and torque after checking the sums: applied over the longest
// step (1 s) they must not change the velocity by more than 1e6 m/s (rad/s), the limit of every
// velocity input.
void World::Impl::AddForce(int i, const char* call, double fx, double fy, double torque) {
  const uint32_t slot = bodies.slot[i];
  const int32_t k = slot < pendingOf.size() ? pendingOf[slot] : -1;
  if (k >= 0) {
    const PendingForce& f = pendingForces[size_t(k)];
    fx += f.fx, fy += f.fy, torque += f.torque;
  }
  const BodyInverseMass inv = ActiveInverseMass(i);
  const double invI = def.effects.rotation ? double(inv.invInertia) : 0.0;
  const double limit = double(kMaxInputSpeed) / double(kMaxTimeStep);
  Require(std::abs(fx * double(inv.invMass)) <= limit && std::abs(fy * double(inv.invMass)) <= limit &&
              std::abs(torque * invI) <= limit,
          std::string(call) + ": the body's pending force or torque would change its velocity by more than 1e6 m/s "
                              "(rad/s) in a 1 s step");
  if (def.effects.sleep) islands.WakeIslandOf(bodies, i);
  if (k >= 0) {
    PendingForce& f = pendingForces[size_t(k)];
    f.fx = fx, f.fy = fy, f.torque = torque;
    return;
  }
  if (pendingOf.size() < generation.size()) pendingOf.resize(generation.size(), -1);
  pendingOf[slot] = static_cast<int32_t>(pendingForces.size());
  pendingForces.push_back(PendingForce{slot, true, fx, fy, torque});
}

namespace {
void CheckForce(const char* call, Vec2 force) {
  Require(IsFinite(force), std::string(call) + ": force is not finite");
}
}  // namespace

void World::ApplyForce(BodyId id, Vec2 force, Vec2 worldPoint) {
  Impl& w = *impl_;
  const int i = w.Dense(id);
  Require(IsFinite(force) && IsFinite(worldPoint), "ApplyForce: force or point is not finite");
  Require(std::abs(worldPoint.x) <= kMaxCoordinate && std::abs(worldPoint.y) <= kMaxCoordinate,
          "ApplyForce: point is beyond the coordinate limit of 1e6 m");
  w.RequireDynamic(i, "ApplyForce");
  const Vec2 c = w.bodies.center[i];
  const double rx = double(worldPoint.x) - double(c.x), ry = double(worldPoint.y) - double(c.y);
  w.AddForce(i, "ApplyForce", force.x, force.y, rx * double(force.y) - ry * double(force.x));
}

void World::ApplyForceToCenter(BodyId id, Vec2 force) {
  Impl& w = *impl_;
  const int i = w.Dense(id);
  CheckForce("ApplyForceToCenter", force);
  w.RequireDynamic(i, "ApplyForceToCenter");
  w.AddForce(i, "ApplyForceToCenter", force.x, force.y, 0.0);
}

void World::ApplyTorque(BodyId id, Real torque) {
  Impl& w = *impl_;
  const int i = w.Dense(id);
  Require(IsFinite(torque), "ApplyTorque: torque is not finite");
  w.RequireDynamic(i, "ApplyTorque");
  w.AddForce(i, "ApplyTorque", 0.0, 0.0, torque);
}

Real World::GetGravityScale(BodyId id) const { return impl_->bodies.gravityScale[impl_->Dense(id)]; }

void World::SetGravityScale(BodyId id, Real scale) {
  Impl& w = *impl_;
  const int i = w.Dense(id);
  Require(GravityScaleOk(scale), "SetGravityScale: the scale must be finite and in [-1e6, 1e6]");
  Real& s = w.bodies.gravityScale[i];
  if (s == scale) return;
  w.gravityScaled += (scale == 1 ? 0 : 1) - (s == 1 ? 0 : 1);
  s = scale;
  if (w.def.effects.sleep) w.islands.WakeIslandOf(w.bodies, i);
}

bool World::IsFixedRotation(BodyId id) const { return impl_->bodies.fixedRotation[impl_->Dense(id)] != 0; }

void World::SetFixedRotation(BodyId id, bool fixed) {
  Impl& w = *impl_;
  const int i = w.Dense(id);
  Bodies& b = w.bodies;
  if ((b.fixedRotation[i] != 0) == fixed) return;
  if (w.def.effects.sleep) w.islands.WakeIslandOf(b, i);
  b.fixedRotation[i] = fixed ? 1 : 0;
  if (fixed) b.vel[i].w = 0;
  UpdateMassData(b, i);
}

bool World::IsBullet(BodyId id) const { return impl_->bodies.bullet[impl_->Dense(id)] != 0; }

void World::SetBullet(BodyId id, bool bullet) {
  Impl& w = *impl_;
  const int i = w.Dense(id);
  Bodies& b = w.bodies;
  if ((b.bullet[i] != 0) == bullet) return;
  b.bullet[i] = bullet ? 1 : 0;
  b.bulletCount += bullet ? 1 : -1;
}

void World::SetType(BodyId id, BodyType type) {
  Impl& w = *impl_;
  const int i = w.Dense(id);
  Require(type == BodyType::kStatic || type == BodyType::kKinematic || type == BodyType::kDynamic,
          "SetType: the type is unknown");
  Bodies& b = w.bodies;
  if (b.type[i] == type) return;
  if (type == BodyType::kDynamic && !b.compound[i].empty()) {
    for (const ShapeDef& s : b.compound[i]) {
      Require(!IsSegmentType(s.type), "SetType: a segment has no area (mass 0): only a static or kinematic body may carry it");
    }
    RequireDynamicMass(std::span<const ShapeDef>(b.compound[i]), "SetType: ");
  } else if (type == BodyType::kDynamic) {
    Require(b.shape[i].density > 0, "SetType: a dynamic body needs ShapeDef.density > 0 (SetDensity first)");
    RequireDynamicMass(b.shape[i], "SetType: ");
  }
  w.WakeAround(i);  // its island, and what rests on it, wake before it changes
  b.type[i] = type;
  if (type == BodyType::kStatic) b.vel[i] = BodyVelocity{};
  b.dynamic[i] = type == BodyType::kDynamic ? 1 : 0;
  b.awake[i] = type == BodyType::kStatic ? 0 : 1;
  b.sleepTime[i] = 0;
  b.islandOf[i] = 0;
  UpdateMassData(b, i);
  w.UpdateAABB(i, 0);
  w.pairCache.Invalidate();
  w.WakeAround(i);
}

void World::SetFriction(BodyId id, Real friction) {
  Impl& w = *impl_;
  const int i = w.Dense(id);
  Require(IsFinite(friction) && friction >= 0, "SetFriction: friction must be finite and >= 0");
  w.bodies.shape[i].friction = friction;
  for (ShapeDef& s : w.bodies.compound[i]) s.friction = friction;
}

void World::SetRestitution(BodyId id, Real restitution) {
  Impl& w = *impl_;
  const int i = w.Dense(id);
  Require(IsFinite(restitution) && restitution >= 0 && restitution <= 1, "SetRestitution: restitution must be in [0, 1]");
  w.bodies.shape[i].restitution = restitution;
  for (ShapeDef& s : w.bodies.compound[i]) s.restitution = restitution;
}

void World::SetDensity(BodyId id, Real density) {
  Impl& w = *impl_;
  const int i = w.Dense(id);
  Bodies& b = w.bodies;
  Require(IsFinite(density) && density >= 0, "SetDensity: density must be finite and >= 0");
  if (!b.compound[i].empty()) {  // every shape's, and the centre of mass with it
    std::vector<ShapeDef> shapes = b.compound[i];
    for (ShapeDef& s : shapes) s.density = density;
    if (b.type[i] == BodyType::kDynamic) {
      Require(density > 0, "SetDensity: a dynamic body needs density > 0");
      RequireDynamicMass(std::span<const ShapeDef>(shapes), "SetDensity: ");
    }
    if (w.def.effects.sleep) w.islands.WakeIslandOf(b, i);
    const CompoundProperties props = MakeCompoundProperties(shapes);
    b.compound[i] = std::move(shapes);
    b.shape[i].density = density;
    b.localCenter[i] = props.mass.center;
    b.center[i] = TransformPoint(b.xf[i], props.mass.center);
    b.boundRadius[i] = props.boundRadius;
    UpdateMassData(b, i);
    return;
  }
  ShapeDef shape = b.shape[i];
  shape.density = density;
  if (b.type[i] == BodyType::kDynamic) {
    Require(density > 0, "SetDensity: a dynamic body needs density > 0");
    RequireDynamicMass(shape, "SetDensity: ");
  }
  if (w.def.effects.sleep) w.islands.WakeIslandOf(b, i);
  b.shape[i].density = density;
  UpdateMassData(b, i);
}

Vec2 World::GetGravity() const { return impl_->def.gravity; }

void World::SetGravity(Vec2 gravity) {
  Impl& w = *impl_;
  Require(IsFinite(gravity), "SetGravity: gravity is not finite");
  if (w.def.gravity == gravity) return;
  w.def.gravity = gravity;
  if (w.def.effects.sleep) {
    constexpr Real kFar = std::numeric_limits<Real>::max();
    w.islands.WakeOverlapping(w.bodies, AABB{{-kFar, -kFar}, {kFar, kFar}});  // every sleeping body
  }
}

bool World::IsAwake(BodyId id) const { return impl_->bodies.awake[impl_->Dense(id)] != 0; }

void World::SetAwake(BodyId id, bool awake) {
  Impl& w = *impl_;
  const int i = w.Dense(id);
  if (w.bodies.type[i] != BodyType::kDynamic || !w.def.effects.sleep) return;
  if (awake) {
    w.islands.WakeIslandOf(w.bodies, i);
  } else if (w.bodies.awake[i]) {
    Islands::Sleep(w.bodies, i, w.bodies.slot[i]);  // an island of its own
    w.UpdateAABB(i, 0);
  }
}

uint64_t World::GetUserData(BodyId id) const { return impl_->bodies.userData[impl_->Dense(id)]; }
void World::SetUserData(BodyId id, uint64_t userData) { impl_->bodies.userData[impl_->Dense(id)] = userData; }
Filter World::GetFilter(BodyId id) const { return impl_->bodies.filter[impl_->Dense(id)]; }

void World::SetFilter(BodyId id, Filter filter) {
  Impl& w = *impl_;
  const int i = w.Dense(id);
  Require(w.def.scheme != ParallelScheme::kQuadrants || filter == Filter{},
          "SetFilter: a non-default collision filter needs ParallelScheme::kDeterministic");
  w.customFilters += (filter == Filter{} ? 0 : 1) - (w.bodies.filter[i] == Filter{} ? 0 : 1);
  w.bodies.filter[i] = filter;
}

namespace {

// Whether test(shape) holds for any of body i's shapes (queries on compound bodies).
template <class Test>
bool AnyShape(const Bodies& b, int i, Test&& test) {
  for (const ShapeDef& s : BodyShapes(b, i)) {
    if (test(s)) return true;
  }
  return false;
}

// The closest hit of cast(shape, hit) over body i's shapes (the first shape's on a tie).
template <class Cast>
bool ClosestOverShapes(const Bodies& b, int i, RayHit& hit, Cast&& cast) {
  bool found = false;
  for (const ShapeDef& s : BodyShapes(b, i)) {
    RayHit h = hit;
    if (!cast(s, h)) continue;
    if (!found || h.fraction < hit.fraction) hit = h;
    found = true;
  }
  return found;
}

}  // namespace

void World::QueryAABB(const AABB& box, std::vector<BodyId>& out, uint32_t categoryMask) const {
  Require(IsFinite(box.lower) && IsFinite(box.upper), "QueryAABB: the box is not finite");
  Require(box.lower.x <= box.upper.x && box.lower.y <= box.upper.y,
          "QueryAABB: the box's lower corner is above or right of its upper corner");
  Impl& w = *impl_;
  w.PrepareQueries();
  w.queryFound.clear();
  w.queryIndex->QueryBox(box, w.queryBoxes, w.queryFound);
  std::sort(w.queryFound.begin(), w.queryFound.end());  // GetBodyIds order
  out.clear();
  for (int i : w.queryFound) {
    if ((w.bodies.filter[i].categoryBits & categoryMask) != 0 && AnyShape(w.bodies, i, [&](const ShapeDef& s) { return ShapeOverlapsBox(s, w.bodies.xf[i], box); })) {
      out.push_back(w.IdOf(i));
    }
  }
}

namespace {
void CheckRay(const char* call, Vec2 origin, Vec2 translation) {
  const std::string c = call;
  Require(IsFinite(origin) && IsFinite(translation), c + ": origin or translation is not finite");
  Require(translation.x != 0 || translation.y != 0, c + ": the translation is zero (a ray needs a direction)");
  const Vec2 end = origin + translation;
  Require(IsFinite(end) && std::abs(origin.x) <= kMaxCoordinate && std::abs(origin.y) <= kMaxCoordinate &&
              std::abs(end.x) <= kMaxCoordinate && std::abs(end.y) <= kMaxCoordinate,
          c + ": origin or end is beyond the coordinate limit of 1e6 m");
}
}  // namespace

void World::RayCastAll(Vec2 origin, Vec2 translation, std::vector<RayHit>& out, uint32_t categoryMask) const {
  CheckRay("RayCastAll", origin, translation);
  Impl& w = *impl_;
  w.PrepareQueries();
  w.queryFound.clear();
  const Vec2 end = origin + translation;
  w.queryIndex->QuerySegment(origin, end, w.queryBoxes, w.queryFound);
  std::sort(w.queryFound.begin(), w.queryFound.end());
  out.clear();
  for (int i : w.queryFound) {
    RayHit hit;
    if ((w.bodies.filter[i].categoryBits & categoryMask) == 0) continue;
    if (!ClosestOverShapes(w.bodies, i, hit, [&](const ShapeDef& s, RayHit& h) { return RayCastShape(s, w.bodies.xf[i], origin, end, h); })) continue;
    hit.body = w.IdOf(i);
    out.push_back(hit);
  }
  // Stable: equal fractions stay in GetBodyIds order.
  std::stable_sort(out.begin(), out.end(), [](const RayHit& a, const RayHit& b) { return a.fraction < b.fraction; });
}

std::optional<RayHit> World::RayCastClosest(Vec2 origin, Vec2 translation, uint32_t categoryMask) const {
  CheckRay("RayCastClosest", origin, translation);
  Impl& w = *impl_;
  w.PrepareQueries();
  w.queryFound.clear();
  const Vec2 end = origin + translation;
  w.queryIndex->QuerySegment(origin, end, w.queryBoxes, w.queryFound);
  std::optional<RayHit> best;
  int bestIndex = -1;
  for (int i : w.queryFound) {
    RayHit hit;
    if ((w.bodies.filter[i].categoryBits & categoryMask) == 0) continue;
    if (!ClosestOverShapes(w.bodies, i, hit, [&](const ShapeDef& s, RayHit& h) { return RayCastShape(s, w.bodies.xf[i], origin, end, h); })) continue;
    if (best && (hit.fraction > best->fraction || (hit.fraction == best->fraction && i > bestIndex))) continue;
    hit.body = w.IdOf(i);
    best = hit;
    bestIndex = i;
  }
  return best;
}

void World::QueryPoint(Vec2 point, std::vector<BodyId>& out, uint32_t categoryMask) const {
  Require(IsFinite(point), "QueryPoint: the point is not finite");
  Impl& w = *impl_;
  w.PrepareQueries();
  w.queryFound.clear();
  w.queryIndex->QueryBox(AABB{point, point}, w.queryBoxes, w.queryFound);
  std::sort(w.queryFound.begin(), w.queryFound.end());  // GetBodyIds order
  out.clear();
  for (int i : w.queryFound) {
    if ((w.bodies.filter[i].categoryBits & categoryMask) != 0 && AnyShape(w.bodies, i, [&](const ShapeDef& s) { return ShapeContainsPoint(s, w.bodies.xf[i], point); })) {
      out.push_back(w.IdOf(i));
    }
  }
}

namespace {
// The closest hit of `cast` (a shape cast: true and the hit for body i) over the bodies whose
// query boxes overlap `box` (the swept shape's box), ties to the body earlier in GetBodyIds order.
template <class Cast>
std::optional<RayHit> CastClosest(World::Impl& w, const AABB& box, uint32_t categoryMask, const Cast& cast) {
  w.PrepareQueries();
  w.queryFound.clear();
  w.queryIndex->QueryBox(box, w.queryBoxes, w.queryFound);
  std::optional<RayHit> best;
  int bestIndex = -1;
  for (int i : w.queryFound) {
    RayHit hit;
    if ((w.bodies.filter[i].categoryBits & categoryMask) == 0) continue;
    if (!cast(i, hit)) continue;
    if (best && (hit.fraction > best->fraction || (hit.fraction == best->fraction && i > bestIndex))) continue;
    hit.body = w.IdOf(i);
    best = hit;
    bestIndex = i;
  }
  return best;
}
}  // namespace

std::optional<RayHit> World::CastCircle(Vec2 origin, Real radius, Vec2 translation, uint32_t categoryMask) const {
  CheckRay("CastCircle", origin, translation);
  Require(IsFinite(radius) && radius > 0 && radius <= kMaxCoordinate, "CastCircle: the radius must be > 0 and <= 1e6 m");
  Impl& w = *impl_;
  const Vec2 end = origin + translation;
  const Vec2 r{radius, radius};
  const AABB box{Min(origin, end) - r, Max(origin, end) + r};
  return CastClosest(w, box, categoryMask, [&](int i, RayHit& hit) {
    return ClosestOverShapes(w.bodies, i, hit, [&](const ShapeDef& s, RayHit& h) {
      return CastCircleShape(s, w.bodies.xf[i], origin, end, radius, h);
    });
  });
}

std::optional<RayHit> World::CastPolygon(std::span<const Vec2> vertices, Vec2 translation, uint32_t categoryMask) const {
  Require(vertices.size() >= 3 && vertices.size() <= size_t(kMaxPolygonVertices),
          "CastPolygon: the polygon needs 3 to 8 vertices, got " + std::to_string(vertices.size()));
  Polygon moving;
  try {
    moving = MakePolygon(vertices);
  } catch (const Error& e) {
    throw Error(std::string("CastPolygon: ") + e.what());
  }
  Require(IsFinite(translation), "CastPolygon: the translation is not finite");
  Require(translation.x != 0 || translation.y != 0, "CastPolygon: the translation is zero (a cast needs a direction)");
  AABB box{moving.vertices[0], moving.vertices[0]};
  for (int k = 0; k < moving.count; ++k) {
    const Vec2 v = moving.vertices[k], end = v + translation;
    Require(IsFinite(end) && std::abs(end.x) <= kMaxCoordinate && std::abs(end.y) <= kMaxCoordinate,
            "CastPolygon: a vertex's end is beyond the coordinate limit of 1e6 m");
    box.lower = Min(box.lower, Min(v, end));
    box.upper = Max(box.upper, Max(v, end));
  }
  Impl& w = *impl_;
  return CastClosest(w, box, categoryMask, [&](int i, RayHit& hit) {
    return ClosestOverShapes(w.bodies, i, hit, [&](const ShapeDef& s, RayHit& h) {
      return CastPolygonShape(s, w.bodies.xf[i], moving, translation, h);
    });
  });
}

std::span<const ContactEvent> World::GetContactBeginEvents() const {
  Require(impl_->def.contactEvents, "GetContactBeginEvents: contact events are off (WorldDef::contactEvents)");
  return impl_->beginEvents;
}

std::span<const ContactEvent> World::GetContactEndEvents() const {
  Require(impl_->def.contactEvents, "GetContactEndEvents: contact events are off (WorldDef::contactEvents)");
  return impl_->endEvents;
}

std::span<const SensorEvent> World::GetSensorBeginEvents() const { return impl_->sensorBeginEvents; }
std::span<const SensorEvent> World::GetSensorEndEvents() const { return impl_->sensorEndEvents; }

std::span<const ContactHitEvent> World::GetContactHitEvents() const {
  Require(impl_->def.hitEvents, "GetContactHitEvents: hit events are off (WorldDef::hitEvents)");
  return impl_->hitEvents;
}

void World::Draw(DebugDraw& draw, uint32_t flags) const {
  Require((flags & ~kDrawAll) == 0, "Draw: unknown flag bits (use kDrawShapes, kDrawAABBs, kDrawContacts)");
  const Impl& w = *impl_;
  const Bodies& b = w.bodies;
  const int n = b.Count();
  if (flags & kDrawShapes) {
    for (int i = 0; i < n; ++i) {
      for (const ShapeDef& s : BodyShapes(b, i)) {
        const Color color = s.isSensor                        ? kSensorColor
                            : b.type[i] == BodyType::kStatic    ? kStaticColor
                            : b.type[i] == BodyType::kKinematic ? kKinematicColor
                            : b.awake[i]                        ? kDynamicColor
                                                                : kSleepingColor;
        const Transform& xf = b.xf[i];
        if (s.type == ShapeType::kCircle) {
          draw.DrawCircle(TransformPoint(xf, s.circle.center), s.circle.radius, quadrant::GetAngle(xf.q), color);
        } else if (s.type == ShapeType::kCapsule) {
          draw.DrawCapsule(TransformPoint(xf, s.capsule.center1), TransformPoint(xf, s.capsule.center2), s.capsule.radius, color);
        } else if (IsSegmentType(s.type)) {
          const Segment& seg = s.type == ShapeType::kSegment ? s.segment : s.chainSegment.segment;
          draw.DrawSegment(TransformPoint(xf, seg.point1), TransformPoint(xf, seg.point2), color);
        } else {
          Vec2 v[kMaxPolygonVertices];
          for (int k = 0; k < s.polygon.count; ++k) v[k] = TransformPoint(xf, s.polygon.vertices[k]);
          draw.DrawPolygon(std::span<const Vec2>(v, size_t(s.polygon.count)), color);
        }
      }
    }
  }
  if (flags & kDrawAABBs) {
    for (int i = 0; i < n; ++i) {
      // A compound body's box: the one around all its shapes (GetAABB).
      draw.DrawAABB(b.compound[i].empty() ? ComputeShapeAABB(b.shape[i], b.xf[i]) : GetAABB(w.IdOf(i)), kAABBColor);
    }
  }
  if (flags & kDrawContacts) {
    for (const Contact& c : w.contacts) {
      for (int k = 0; k < c.manifold.pointCount; ++k) draw.DrawContact(c.manifold.points[k].point, c.manifold.normal);
    }
  }
}

int World::GetBodyCount() const { return impl_->bodies.Count(); }

std::vector<BodyId> World::GetBodyIds() const {
  std::vector<BodyId> ids;
  ids.reserve(impl_->bodies.Count());
  for (uint32_t slot : impl_->bodies.slot) ids.push_back(BodyId{slot, impl_->generation[slot]});
  return ids;
}

const WorldDef& World::GetDef() const { return impl_->def; }
const Profile& World::GetProfile() const { return impl_->profile; }
const Counters& World::GetCounters() const { return impl_->counters; }

std::vector<ContactInfo> World::GetContacts() const {
  const Impl& w = *impl_;
  std::vector<ContactInfo> out;
  out.reserve(w.contacts.size());
  for (const Contact& c : w.contacts) {
    ContactInfo info;
    const uint32_t sa = w.bodies.slot[c.a], sb = w.bodies.slot[c.b];
    info.bodyA = BodyId{sa, w.generation[sa]};
    info.bodyB = BodyId{sb, w.generation[sb]};
    info.normal = c.manifold.normal;
    info.pointCount = c.manifold.pointCount;
    for (int k = 0; k < c.manifold.pointCount; ++k) {
      info.points[k] = c.manifold.points[k].point;
      info.separations[k] = c.manifold.points[k].separation;
      info.normalImpulses[k] = c.manifold.points[k].normalImpulse;
      info.tangentImpulses[k] = c.manifold.points[k].tangentImpulse;
    }
    out.push_back(info);
  }
  return out;
}

uint64_t World::StateHash() const { return HashBodies(impl_->bodies); }

std::vector<int> World::GetOwners() const {
  if (!impl_->quadrants) return {};
  std::vector<int> owners = impl_->quadrants->Owners();
  owners.resize(impl_->bodies.Count(), 0);  // bodies created since the last step: not yet assigned
  return owners;
}

JointId World::CreateRevoluteJoint(const RevoluteJointDef& def) {
  return impl_->AddJoint(MakeJoint(def), "CreateRevoluteJoint");
}
JointId World::CreateDistanceJoint(const DistanceJointDef& def) {
  return impl_->AddJoint(MakeJoint(def), "CreateDistanceJoint");
}
JointId World::CreateWeldJoint(const WeldJointDef& def) { return impl_->AddJoint(MakeJoint(def), "CreateWeldJoint"); }
JointId World::CreatePrismaticJoint(const PrismaticJointDef& def) {
  return impl_->AddJoint(MakeJoint(def), "CreatePrismaticJoint");
}
JointId World::CreateWheelJoint(const WheelJointDef& def) { return impl_->AddJoint(MakeJoint(def), "CreateWheelJoint"); }
JointId World::CreateMotorJoint(const MotorJointDef& def) { return impl_->AddJoint(MakeJoint(def), "CreateMotorJoint"); }
JointId World::CreateMouseJoint(const MouseJointDef& def) { return impl_->AddJoint(MakeJoint(def), "CreateMouseJoint"); }

void World::DestroyJoint(JointId id) {
  Impl& w = *impl_;
  const int j = w.joints.Dense(id);
  if (w.def.effects.sleep) {
    const auto [a, b] = w.JointBodies(w.joints.All()[size_t(j)]);
    w.islands.WakeIslandOf(w.bodies, a);
    w.islands.WakeIslandOf(w.bodies, b);
  }
  w.joints.RemoveAt(j);
}

bool World::IsValid(JointId id) const { return impl_->joints.IsValid(id); }
int World::GetJointCount() const { return impl_->joints.Count(); }
JointType World::GetJointType(JointId id) const { return impl_->joints.All()[size_t(impl_->joints.Dense(id))].type; }
BodyId World::GetJointBodyA(JointId id) const { return impl_->joints.All()[size_t(impl_->joints.Dense(id))].idA; }
BodyId World::GetJointBodyB(JointId id) const { return impl_->joints.All()[size_t(impl_->joints.Dense(id))].idB; }

Real World::GetJointAngle(JointId id) const {
  const Impl& w = *impl_;
  const Joint& j = w.joints.All()[size_t(w.joints.Dense(id))];
  Require(j.type != JointType::kDistance && j.type != JointType::kMouse,
          "GetJointAngle: distance and mouse joints have no angle");
  const auto [a, b] = w.JointBodies(j);
  const Rot qa = w.bodies.xf[a].q, qb = w.bodies.xf[b].q;
  Real angle = std::atan2(qa.c * qb.s - qa.s * qb.c, qa.c * qb.c + qa.s * qb.s) - j.referenceAngle;
  const Real pi = Real(3.14159265358979323846);
  if (angle > pi) angle -= 2 * pi;
  if (angle < -pi) angle += 2 * pi;
  return angle;
}

Real World::GetJointLength(JointId id) const {
  const Impl& w = *impl_;
  const Joint& j = w.joints.All()[size_t(w.joints.Dense(id))];
  Require(j.type == JointType::kDistance || j.type == JointType::kPrismatic || j.type == JointType::kWheel,
          "GetJointLength: only distance, prismatic and wheel joints have a length");
  const auto [a, b] = w.JointBodies(j);
  const Vec2 d = TransformPoint(w.bodies.xf[b], j.localAnchorB) - TransformPoint(w.bodies.xf[a], j.localAnchorA);
  if (j.type == JointType::kDistance) return Length(d);
  return Dot(Rotate(w.bodies.xf[a].q, j.localAxisA), d);
}

void World::SetMotorSpeed(JointId id, Real speed) {
  Impl& w = *impl_;
  const int d = w.joints.Dense(id);
  Joint& j = w.joints.All()[size_t(d)];
  Require(j.type == JointType::kRevolute || j.type == JointType::kPrismatic || j.type == JointType::kWheel,
          "SetMotorSpeed: only revolute, prismatic and wheel joints have a motor");
  Require(IsFinite(speed), "SetMotorSpeed: speed must be finite");
  j.motorSpeed = speed;
  if (w.def.effects.sleep) {
    const auto [a, b] = w.JointBodies(j);
    w.islands.WakeIslandOf(w.bodies, a);
    w.islands.WakeIslandOf(w.bodies, b);
  }
}

void World::SetJointTarget(JointId id, Vec2 target) {
  Impl& w = *impl_;
  Joint& j = w.joints.All()[size_t(w.joints.Dense(id))];
  Require(j.type == JointType::kMouse, "SetJointTarget: only a mouse joint has a target");
  Require(IsFinite(target) && std::abs(target.x) <= kMaxCoordinate && std::abs(target.y) <= kMaxCoordinate,
          "SetJointTarget: target must be finite and within 1e6 m");
  j.target = target;
  if (w.def.effects.sleep) w.islands.WakeIslandOf(w.bodies, w.JointBodies(j).second);
}

// The solver keeps a joint's impulses per sub-step (each sub-step re-applies them): the step's
// impulse is softSubSteps times that.
Vec2 World::GetJointLinearImpulse(JointId id) const {
  const Impl& w = *impl_;
  const Joint& j = w.joints.All()[size_t(w.joints.Dense(id))];
  const Real n = Real(w.def.softSubSteps);
  const auto [a, b] = w.JointBodies(j);
  switch (j.type) {
    case JointType::kDistance: {
      const Vec2 d = TransformPoint(w.bodies.xf[b], j.localAnchorB) - TransformPoint(w.bodies.xf[a], j.localAnchorA);
      return (n * (j.angularImpulse + j.springImpulse + j.lowerImpulse - j.upperImpulse)) * Normalize(d);
    }
    case JointType::kPrismatic:
    case JointType::kWheel: {
      const Vec2 axis = Rotate(w.bodies.xf[a].q, j.localAxisA);
      const Real along = j.springImpulse + j.lowerImpulse - j.upperImpulse + (j.type == JointType::kPrismatic ? j.motorImpulse : 0);
      return n * (along * axis + j.perpImpulse * Vec2{-axis.y, axis.x});
    }
    default: return n * j.linearImpulse;
  }
}

Real World::GetJointAngularImpulse(JointId id) const {
  const Impl& w = *impl_;
  const Joint& j = w.joints.All()[size_t(w.joints.Dense(id))];
  const Real n = Real(w.def.softSubSteps);
  switch (j.type) {
    case JointType::kRevolute: return n * (j.springImpulse + j.motorImpulse + j.lowerImpulse - j.upperImpulse);
    case JointType::kWheel: return n * j.motorImpulse;
    case JointType::kDistance:
    case JointType::kMouse: return 0;
    case JointType::kWeld:
    case JointType::kPrismatic:
    case JointType::kMotor: break;
  }
  return n * j.angularImpulse;
}

Vec2 World::GetLocalPoint(BodyId id, Vec2 worldPoint) const {
  Require(IsFinite(worldPoint), "GetLocalPoint: worldPoint must be finite");
  return InvTransformPoint(impl_->bodies.xf[impl_->Dense(id)], worldPoint);
}

Vec2 World::GetWorldPoint(BodyId id, Vec2 localPoint) const {
  Require(IsFinite(localPoint), "GetWorldPoint: localPoint must be finite");
  return TransformPoint(impl_->bodies.xf[impl_->Dense(id)], localPoint);
}

AABB World::GetPartitionRegion() const { return impl_->quadrants ? impl_->quadrants->Region() : AABB{}; }

}  // namespace quadrant
