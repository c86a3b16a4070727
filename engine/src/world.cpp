// The world: body storage, validation, and the step pipeline
//   broad phase -> narrow phase -> persistence -> solver (velocities, contacts, positions).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "broad_phase.h"
#include "contact_cache.h"
#include "integrate.h"
#include "islands.h"
#include "narrow_phase.h"
#include "quadrant/task_system.h"
#include "quadrants_scheme.h"
#include "quadrant/world.h"
#include "solver.h"
#include "world_internal.h"

namespace quadrant {

uint64_t HashBodies(const Bodies& bodies);  // state_hash.cpp

namespace {

using Clock = std::chrono::steady_clock;
double Ms(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }

constexpr int kMaxThreads = 64;

void Require(bool ok, const std::string& message) {
  if (!ok) throw Error(message);
}

void ValidateWorldDef(const WorldDef& d) {
  Require(IsFinite(d.gravity), "WorldDef.gravity is not finite");
  Require(d.solver == SolverType::kThesis || d.solver == SolverType::kPgs || d.solver == SolverType::kSoftStep,
          "WorldDef.solver is unknown");
  Require(d.softSubSteps >= 1, "WorldDef.softSubSteps must be >= 1");
  Require(d.softSubSteps <= kMaxIterations, "WorldDef.softSubSteps must be <= 1000");
  Require(IsFinite(d.contactHertz) && d.contactHertz > 0, "WorldDef.contactHertz must be > 0");
  Require(IsFinite(d.contactDampingRatio) && d.contactDampingRatio >= 0, "WorldDef.contactDampingRatio must be >= 0");
  Require(IsFinite(d.contactPushMaxVelocity) && d.contactPushMaxVelocity > 0,
          "WorldDef.contactPushMaxVelocity must be > 0");
  Require(IsFinite(d.contactPushMaxDepth) && d.contactPushMaxDepth > 0, "WorldDef.contactPushMaxDepth must be > 0");
  Require(IsFinite(d.softMassRatioLimit) && (d.softMassRatioLimit == 0 || d.softMassRatioLimit >= 1),
          "WorldDef.softMassRatioLimit must be 0 (off) or >= 1");
  Require(d.broadPhase == BroadPhaseType::kQuadTree || d.broadPhase == BroadPhaseType::kUniformGrid,
          "WorldDef.broadPhase is unknown");
  Require(d.velocityIterations >= 1, "WorldDef.velocityIterations must be >= 1");
  Require(d.velocityIterations <= kMaxIterations, "WorldDef.velocityIterations must be <= 1000");
  Require(d.positionIterations >= 0, "WorldDef.positionIterations must be >= 0");
  Require(d.positionIterations <= kMaxIterations, "WorldDef.positionIterations must be <= 1000");
  Require(d.restitutionIterations >= 1, "WorldDef.restitutionIterations must be >= 1");
  Require(d.restitutionIterations <= kMaxIterations, "WorldDef.restitutionIterations must be <= 1000");
  Require(IsFinite(d.linearSlop) && d.linearSlop >= 0, "WorldDef.linearSlop must be finite and >= 0");
  Require(IsFinite(d.baumgarte) && d.baumgarte >= 0 && d.baumgarte <= 1, "WorldDef.baumgarte must be in [0, 1]");
  Require(IsFinite(d.maxLinearCorrection) && d.maxLinearCorrection > 0, "WorldDef.maxLinearCorrection must be > 0");
  Require(IsFinite(d.speculativeDistance) && d.speculativeDistance >= 0,
          "WorldDef.speculativeDistance must be finite and >= 0");
  Require(IsFinite(d.restitutionThreshold) && d.restitutionThreshold >= 0,
          "WorldDef.restitutionThreshold must be finite and >= 0");
  Require(IsFinite(d.maxLinearSpeed) && d.maxLinearSpeed > 0, "WorldDef.maxLinearSpeed must be > 0");
  Require(IsFinite(d.maxRotation) && d.maxRotation > 0, "WorldDef.maxRotation must be > 0");
  Require(d.threadCount >= 1 && d.threadCount <= kMaxThreads, "WorldDef.threadCount must be in [1, 64]");
  Require(d.quadTreeMaxDepth >= 1 && d.quadTreeMaxDepth <= 12, "WorldDef.quadTreeMaxDepth must be in [1, 12]");
  Require(d.minParallelItems >= 1, "WorldDef.minParallelItems must be >= 1");
  Require(d.scheme == ParallelScheme::kDeterministic || d.scheme == ParallelScheme::kQuadrants,
          "WorldDef.scheme is unknown");
  Require(IsFinite(d.linearSleepTolerance) && d.linearSleepTolerance >= 0,
          "WorldDef.linearSleepTolerance must be finite and >= 0");
  Require(IsFinite(d.angularSleepTolerance) && d.angularSleepTolerance >= 0,
          "WorldDef.angularSleepTolerance must be finite and >= 0");
  Require(IsFinite(d.timeToSleep) && d.timeToSleep > 0, "WorldDef.timeToSleep must be finite and > 0");
  // The quadrants scheme solves private copies of its regions' bodies (quadrants_scheme.cpp)
  // that carry no sleep state, and its results depend on the thread count anyway; sleeping is
  // refused there rather than half supported.
  Require(!(d.effects.sleep && d.scheme == ParallelScheme::kQuadrants),
          "WorldDef.effects.sleep is not supported with ParallelScheme::kQuadrants (use kDeterministic)");
}

// std::to_string prints 1e-40 as 0.000000; %g keeps the exponent.
std::string DensityText(Real density) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", double(density));
  return buffer;
}

// Validates a body definition and returns its shape in canonical form (polygons re-hulled).
ShapeDef ValidateBodyDef(const BodyDef& def) {
  Require(def.type == BodyType::kStatic || def.type == BodyType::kKinematic || def.type == BodyType::kDynamic,
          "BodyDef.type is unknown");
  Require(IsFinite(def.position) && IsFinite(def.angle), "BodyDef position or angle is not finite");
  Require(std::abs(def.position.x) <= kMaxCoordinate && std::abs(def.position.y) <= kMaxCoordinate,
          "BodyDef.position is beyond the coordinate limit of 1e6 m");
  Require(IsFinite(def.linearVelocity) && IsFinite(def.angularVelocity), "BodyDef velocity is not finite");
  Require(std::abs(def.linearVelocity.x) <= kMaxInputSpeed && std::abs(def.linearVelocity.y) <= kMaxInputSpeed &&
              std::abs(def.angularVelocity) <= kMaxInputSpeed,
          "BodyDef velocity is beyond the limit of 1e6 m/s (rad/s)");
  Require(IsFinite(def.linearDamping) && def.linearDamping >= 0, "BodyDef.linearDamping must be finite and >= 0");
  Require(IsFinite(def.angularDamping) && def.angularDamping >= 0, "BodyDef.angularDamping must be finite and >= 0");
  ShapeDef shape = def.shape;
  Require(IsFinite(shape.density) && shape.density >= 0, "ShapeDef.density must be finite and >= 0");
  Require(def.type != BodyType::kDynamic || shape.density > 0, "a dynamic body needs ShapeDef.density > 0");
  Require(IsFinite(shape.friction) && shape.friction >= 0, "ShapeDef.friction must be finite and >= 0");
  Require(IsFinite(shape.restitution) && shape.restitution >= 0 && shape.restitution <= 1,
          "ShapeDef.restitution must be in [0, 1]");
  if (shape.type == ShapeType::kCircle) {
    ValidateCircle(shape.circle);
  } else if (shape.type == ShapeType::kPolygon) {
    const int count = shape.polygon.count;
    Require(count >= 3 && count <= kMaxPolygonVertices, "polygon vertex count must be in [3, 8], got " + std::to_string(count));
    shape.polygon = MakePolygon(std::span<const Vec2>(shape.polygon.vertices.data(), size_t(count)));
  } else {
    throw Error("ShapeDef.type is unknown");
  }
  return shape;
}

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
  std::unique_ptr<Solver> solver;
  std::unique_ptr<QuadrantsScheme> quadrants;  // only for ParallelScheme::kQuadrants
  std::vector<std::vector<Contact>> workerContacts;
  ContactCache cache;
  Islands islands;  // only used when def.effects.sleep is on
  std::vector<CandidatePair> pairs;
  std::vector<Contact> contacts;
  struct SortKey {
    uint64_t key;
    uint32_t index;
  };
  // One per worker: the radix sort's buffers and the worker's contacts in key order.
  struct SortPart {
    std::vector<SortKey> keys, keyScratch;
    std::vector<uint32_t> radixCounts;
    std::vector<Contact> sorted;
  };
  std::vector<SortPart> sortParts;
  Profile profile;
  Counters counters;

  int Dense(BodyId id) const {
    if (id.generation == 0 || id.index >= generation.size() || generation[id.index] != id.generation ||
        denseOf[id.index] < 0) {
      throw Error("stale or invalid BodyId (index " + std::to_string(id.index) + ", generation " +
                  std::to_string(id.generation) + ")");
    }
    return denseOf[id.index];
  }

  // The broad-phase box of a body: its shape's AABB grown by half the speculative distance on
  // every side (so two shapes closer than that distance pair up), and for moving bodies swept
  // by this step's displacement, so a pair that can meet within the step is found before it
  // touches and the speculative contact stops it at the surface.
  void UpdateAABB(int i, Real dt) {
    const ShapeDef& s = bodies.shape[i];
    AABB box = s.type == ShapeType::kCircle ? ComputeAABB(s.circle, bodies.xf[i]) : ComputeAABB(s.polygon, bodies.xf[i]);
    const BodyVelocity& bv = bodies.vel[i];
    // Without continuous collision the box is not swept (dt 0 below): only the base margin.
    const Real sweep = def.effects.continuous ? dt : Real(0);
    const Real margin = Real(0.5) * def.speculativeDistance + sweep * std::abs(bv.w) * bodies.boundRadius[i];
    const Vec2 d = sweep * bv.v;
    box.lower = box.lower + Vec2{std::min(d.x, Real(0)) - margin, std::min(d.y, Real(0)) - margin};
    box.upper = box.upper + Vec2{std::max(d.x, Real(0)) + margin, std::max(d.y, Real(0)) + margin};
    bodies.aabb[i] = box;
  }

  // Sleep (effects.sleep on only): wakes the islands of sleeping bodies that body i's box
  // overlaps, and body i's own island.
  void WakeAround(int i) {
    if (!def.effects.sleep) return;
    islands.WakeIslandOf(bodies, i);
    islands.WakeOverlapping(bodies, bodies.aabb[i]);
  }

  void SubStep(Real dt);
  void CountContacts(int candidatePairs);
  void NarrowPhase(Real dt);
  void SortContacts();
  void SortPartContacts(const std::vector<Contact>& in, SortPart& part) const;
  void MergeSortedParts(int ranges);
};

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

BodyId World::CreateBody(const BodyDef& def) {
  Impl& w = *impl_;
  const ShapeDef shape = ValidateBodyDef(def);  // throws before anything changes

  MassData md{};
  Real boundRadius = 0;
  if (shape.type == ShapeType::kCircle) {
    md = ComputeMass(shape.circle, shape.density);
    boundRadius = shape.circle.radius;
  } else {
    md = ComputeMass(shape.polygon, shape.density);
    for (int k = 0; k < shape.polygon.count; ++k) {
      boundRadius = std::max(boundRadius, Length(shape.polygon.vertices[k] - md.center));
    }
  }
  const bool dynamic = def.type == BodyType::kDynamic;
  // Density times area can overflow (or underflow) float: a mass or inertia that is not a
  // positive finite number would poison the solver, so the body is refused.
  // Subnormal values count as underflow: they lose precision and make 1/m overflow.
  constexpr Real kSmallest = std::numeric_limits<Real>::min();
  Require(!dynamic || (IsFinite(md.mass) && md.mass >= kSmallest && IsFinite(md.rotationalInertia) &&
                       md.rotationalInertia >= kSmallest && IsFinite(Real(1) / md.mass) &&
                       IsFinite(Real(1) / md.rotationalInertia)),
          "the body's mass or rotational inertia is not a positive finite number (density " +
              DensityText(shape.density) + ")");

  uint32_t slot;
  if (!w.freeSlots.empty()) {
    slot = w.freeSlots.back();
    w.freeSlots.pop_back();
  } else {
    slot = static_cast<uint32_t>(w.generation.size());
    w.generation.push_back(1);
    w.denseOf.push_back(-1);
  }
  const int i = w.bodies.Count();
  w.denseOf[slot] = i;

  Bodies& b = w.bodies;
  const Transform xf{def.position, MakeRot(def.angle)};
  b.type.push_back(def.type);
  b.xf.push_back(xf);
  b.center.push_back(TransformPoint(xf, md.center));
  b.localCenter.push_back(md.center);
  const bool moves = def.type != BodyType::kStatic;
  b.vel.push_back(moves ? BodyVelocity{def.linearVelocity, w.def.effects.rotation ? def.angularVelocity : Real(0)}
                        : BodyVelocity{});
  b.inv.push_back(dynamic ? BodyInverseMass{Real(1) / md.mass, md.rotationalInertia > 0 ? Real(1) / md.rotationalInertia : Real(0)}
                          : BodyInverseMass{});
  b.mass.push_back(dynamic ? md.mass : Real(0));
  b.inertia.push_back(dynamic ? md.rotationalInertia : Real(0));
  b.linearDamping.push_back(def.linearDamping);
  b.angularDamping.push_back(def.angularDamping);
  b.shape.push_back(shape);
  b.boundRadius.push_back(boundRadius);
  b.aabb.push_back({});
  b.dynamic.push_back(dynamic ? 1 : 0);
  b.slot.push_back(slot);
  b.awake.push_back(def.type == BodyType::kStatic ? 0 : 1);
  b.sleepTime.push_back(0);
  b.islandOf.push_back(0);
  w.UpdateAABB(i, 0);
  w.WakeAround(i);  // a body created touching a sleeping pile wakes it
  return BodyId{slot, w.generation[slot]};
}

void World::DestroyBody(BodyId id) {
  Impl& w = *impl_;
  const int i = w.Dense(id);
  w.WakeAround(i);  // what rested on the body falls again
  const int last = w.bodies.Count() - 1;
  Bodies& b = w.bodies;
  auto moveLast = [&](auto& v) {
    v[i] = v[last];
    v.pop_back();
  };
  moveLast(b.type); moveLast(b.xf); moveLast(b.center); moveLast(b.localCenter); moveLast(b.vel);
  moveLast(b.inv); moveLast(b.mass); moveLast(b.inertia); moveLast(b.linearDamping);
  moveLast(b.angularDamping); moveLast(b.shape); moveLast(b.boundRadius); moveLast(b.aabb);
  moveLast(b.dynamic); moveLast(b.slot); moveLast(b.awake); moveLast(b.sleepTime); moveLast(b.islandOf);
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

void World::Step(Real dt, int subSteps) {
  Require(IsFinite(dt) && dt > 0, "Step: dt must be finite and > 0");
  Require(dt <= kMaxTimeStep, "Step: dt must be <= 1 s");
  Require(subSteps >= 1, "Step: subSteps must be >= 1");
  Require(subSteps <= kMaxIterations, "Step: subSteps must be <= 1000");
  Impl& w = *impl_;
  w.profile = Profile{};
  w.run->Reset();
  const auto start = Clock::now();
  const Real h = dt / Real(subSteps);
  for (int s = 0; s < subSteps; ++s) w.SubStep(h);
  w.profile.total = Ms(start, Clock::now());
  w.profile.balance = w.run->Balance();
}

void World::Impl::SubStep(Real dt) {
  const int n = bodies.Count();
  auto t0 = Clock::now();
  const bool sleepOn = def.effects.sleep;
  if (sleepOn) {
    // Sleeping bodies keep the box they fell asleep with (awake is 0 for them and for statics).
    run->For(Stage::kBroadPhase, n, run->MinItems(), [&](int begin, int end, int) {
      for (int i = begin; i < end; ++i) {
        if (bodies.awake[i]) UpdateAABB(i, dt);
      }
    });
  } else {
    run->For(Stage::kBroadPhase, n, run->MinItems(), [&](int begin, int end, int) {
      for (int i = begin; i < end; ++i) {
        if (bodies.type[i] != BodyType::kStatic) UpdateAABB(i, dt);
      }
    });
  }
  if (quadrants) {
    int pairCount = 0;
    profile.broadPhase += Ms(t0, Clock::now());  // the AABB update; the scheme times the rest
    quadrants->Step(dt, def, bodies, *run, cache, contacts, pairCount, profile);
    CountContacts(pairCount);
    return;
  }
  broadPhase->FindPairs(bodies.aabb, bodies.dynamic, pairs, *run);
  auto t1 = Clock::now();
  NarrowPhase(dt);
  auto t2 = Clock::now();
  SortContacts();  // times itself (kPersistence); the narrow phase's contacts are in `contacts` after it
  if (sleepOn) {
    // An awake body touches a sleeping island: the island wakes in this step. Its bodies' pairs
    // (among themselves and with the ground) were not searched, so the broad and narrow phases
    // run again with them awake; repeated while that wakes further islands. (Timed with
    // persistence: it is rare and short.)
    while (islands.WakeTouched(bodies, contacts) > 0) {
      for (int i : islands.Changed()) UpdateAABB(i, dt);
      broadPhase->FindPairs(bodies.aabb, bodies.dynamic, pairs, *run);
      NarrowPhase(dt);
      SortContacts();
    }
  }
  const bool persist = def.solver != SolverType::kThesis && def.effects.warmStarting;
  if (persist) {
    run->For(Stage::kPersistence, static_cast<int>(contacts.size()), run->MinHeavyItems(),
             [&](int begin, int end, int) { cache.Restore(std::span<Contact>(contacts).subspan(begin, end - begin)); });
  }
  auto t3 = Clock::now();

  StepContext ctx;
  ctx.dt = dt;
  ctx.def = &def;
  ctx.bodies = &bodies;
  ctx.contacts = contacts;
  ctx.profile = &profile;
  ctx.run = run.get();
  solver->Step(ctx);
  if (sleepOn) {
    // Timed as part of the solve: Box2D 2.4 also builds its islands in the solve.
    const auto ts = Clock::now();
    run->Serial(Stage::kSolve, [&] {
      islands.Update(bodies, contacts, def, dt);
      // A sleeping body keeps its box until it wakes: the tight one at rest, not this step's sweep.
      for (int i : islands.Changed()) UpdateAABB(i, 0);
    });
    profile.solve += Ms(ts, Clock::now());
  }

  auto t4 = Clock::now();
  if (persist) cache.Store(contacts, *run);
  auto t5 = Clock::now();

  profile.broadPhase += Ms(t0, t1);
  profile.narrowPhase += Ms(t1, t2);
  profile.persistence += Ms(t2, t3) + Ms(t4, t5);

  CountContacts(static_cast<int>(pairs.size()));
}

void World::Impl::CountContacts(int candidatePairs) {
  counters = Counters{};
  counters.bodies = bodies.Count();
  counters.candidatePairs = candidatePairs;
  counters.contacts = static_cast<int>(contacts.size());
  for (const Contact& c : contacts) {
    counters.contactPoints += c.manifold.pointCount;
    bool touching = false;
    for (int k = 0; k < c.manifold.pointCount; ++k) touching = touching || c.manifold.points[k].separation <= 0;
    counters.touchingContacts += touching ? 1 : 0;
  }
}

void World::Impl::NarrowPhase(Real dt) {
  workerContacts.resize(run->Workers());
  for (std::vector<Contact>& part : workerContacts) part.clear();
  run->For(Stage::kNarrowPhase, static_cast<int>(pairs.size()), run->MinHeavyItems(),
           [&](int begin, int end, int worker) {
             CollidePairs(bodies, def, dt, std::span<const CandidatePair>(pairs).subspan(begin, end - begin),
                          workerContacts[worker]);
           });
  // The workers' contacts are put in key order and merged by SortContacts.
}

void CollidePairs(const Bodies& bodies, const WorldDef& def, Real dt, std::span<const CandidatePair> pairs,
                  std::vector<Contact>& out) {
  for (const CandidatePair& p : pairs) {
    const int a = p.a, b = p.b;
    // Two bodies that cannot be moved by contacts (kinematic vs kinematic) need no manifold.
    if (!(bodies.dynamic[a] | bodies.dynamic[b])) continue;
    // How far the two surfaces can approach each other this step, plus the base distance: points
    // closer than this become speculative constraints (the solver lets the gap close, no more).
    const BodyVelocity& va = bodies.vel[a];
    const BodyVelocity& vb = bodies.vel[b];
    const Real sweep = def.effects.continuous ? dt : Real(0);
    const Real spec = def.speculativeDistance +
                      sweep * (Length(vb.v - va.v) + std::abs(va.w) * bodies.boundRadius[a] + std::abs(vb.w) * bodies.boundRadius[b]);
    // Bounding circles reject most AABB-overlapping pairs before any shape test.
    const Real reach = bodies.boundRadius[a] + bodies.boundRadius[b] + spec;
    if (LengthSquared(bodies.center[b] - bodies.center[a]) > reach * reach) continue;
    Manifold m = Collide(bodies.shape[a], bodies.xf[a], bodies.shape[b], bodies.xf[b], spec);
    if (m.pointCount == 0) continue;
    // Keep a point that is still apart only if it can close within the step at its current
    // approach speed (plus the base distance for gravity and other contacts' pushes). The rest
    // are far more numerous in sparse scenes (99 % at the stress scenes' density) and would
    // only cost solver iterations.
    int kept = 0;
    for (int k = 0; k < m.pointCount; ++k) {
      const ManifoldPoint& mp = m.points[k];
      if (mp.separation > def.speculativeDistance) {
        const Vec2 rA = mp.point - bodies.center[a];
        const Vec2 rB = mp.point - bodies.center[b];
        const Vec2 dv = vb.v + Cross(vb.w, rB) - va.v - Cross(va.w, rA);
        const Real approach = -Dot(dv, m.normal);
        if (mp.separation > def.speculativeDistance + sweep * approach) continue;
      }
      m.points[kept++] = mp;
    }
    m.pointCount = kept;
    if (kept == 0) continue;
    Contact c;
    c.a = a;
    c.b = b;
    // Mixing as Box2D: friction geometric mean, restitution the larger.
    c.friction = std::sqrt(bodies.shape[a].friction * bodies.shape[b].friction);
    c.restitution = std::max(bodies.shape[a].restitution, bodies.shape[b].restitution);
    c.manifold = m;
    out.push_back(c);
  }
}

// Contacts are solved in pair-key order, not broad-phase order, so the result does not depend
// on which broad phase found them or on how threads split the work. Keys are unique (the
// broad phase reports a pair once), so the order is the same whichever way it is reached:
// every worker sorts its own contacts (in parallel), then the sorted parts are merged in
// parallel, each worker producing one range of keys.
void World::Impl::SortContacts() {
  const int parts = static_cast<int>(workerContacts.size());
  sortParts.resize(parts);
  size_t total = 0;
  for (const std::vector<Contact>& part : workerContacts) total += part.size();
  // Few contacts: one thread does it all (a parallel-for would cost more than it saves).
  const bool parallel = total >= size_t(run->MinHeavyItems());
  run->For(Stage::kPersistence, parts, parallel ? 1 : parts + 1, [&](int begin, int end, int) {
    for (int p = begin; p < end; ++p) SortPartContacts(workerContacts[p], sortParts[p]);
  });
  MergeSortedParts(parallel ? run->Workers() : 1);
}

// The key a*n+b fits 32 bits for up to 65536 bodies; an LSD radix sort of (key, index) in
// 11-bit digits, then one gather of the contacts, keeps it linear and moves each contact once.
void World::Impl::SortPartContacts(const std::vector<Contact>& in, SortPart& part) const {
  const size_t count = in.size();
  part.sorted.resize(count);
  if (count < 2) {
    std::copy(in.begin(), in.end(), part.sorted.begin());
    return;
  }
  const uint64_t n = uint64_t(bodies.Count());
  std::vector<SortKey>& keys = part.keys;
  std::vector<SortKey>& keyScratch = part.keyScratch;
  keys.resize(count);
  keyScratch.resize(count);
  uint64_t maxKey = 0;
  for (size_t i = 0; i < count; ++i) {
    const uint64_t key = uint64_t(in[i].a) * n + uint64_t(in[i].b);
    keys[i] = {key, uint32_t(i)};
    maxKey = std::max(maxKey, key);
  }
  constexpr int kDigitBits = 11;
  constexpr size_t kBuckets = size_t(1) << kDigitBits;
  std::vector<uint32_t>& radixCounts = part.radixCounts;
  radixCounts.resize(kBuckets + 1);
  for (int shift = 0; shift < 64 && (maxKey >> shift) != 0; shift += kDigitBits) {
    std::fill(radixCounts.begin(), radixCounts.end(), 0u);
    for (const SortKey& k : keys) ++radixCounts[((k.key >> shift) & (kBuckets - 1)) + 1];
    for (size_t b = 0; b < kBuckets; ++b) radixCounts[b + 1] += radixCounts[b];
    for (const SortKey& k : keys) keyScratch[radixCounts[(k.key >> shift) & (kBuckets - 1)]++] = k;
    keys.swap(keyScratch);
  }
  for (size_t i = 0; i < count; ++i) part.sorted[i] = in[keys[i].index];
}

// Merges the sorted parts into `contacts`. The key space is cut into `ranges` ranges at evenly
// spaced keys of the largest part (the parts are samples of the same scene, so the ranges hold
// similar numbers of contacts); each range finds its start in every part by binary search, its
// place in the output by adding those starts, and merges its share on its own.
void World::Impl::MergeSortedParts(int ranges) {
  int live = 0, largest = -1;
  size_t total = 0;
  for (int p = 0; p < static_cast<int>(sortParts.size()); ++p) {
    const size_t size = sortParts[p].sorted.size();
    total += size;
    if (size == 0) continue;
    ++live;
    if (largest < 0 || size > sortParts[largest].sorted.size()) largest = p;
  }
  if (live <= 1) {  // one thread's case: the sorted part is the result
    if (live == 0) contacts.clear();
    else contacts.swap(sortParts[largest].sorted);
    return;
  }
  contacts.resize(total);
  const std::vector<Contact>& sample = sortParts[largest].sorted;
  auto split = [&](int r) -> uint64_t {  // the first key of range r
    if (r <= 0) return 0;
    if (r >= ranges) return ~uint64_t(0);
    return sample[sample.size() * size_t(r) / size_t(ranges)].Key();
  };
  auto lowerBound = [](const std::vector<Contact>& v, uint64_t key) -> size_t {
    if (key == ~uint64_t(0)) return v.size();
    return size_t(std::partition_point(v.begin(), v.end(), [&](const Contact& c) { return c.Key() < key; }) - v.begin());
  };
  const int parts = static_cast<int>(sortParts.size());
  run->For(Stage::kPersistence, ranges, ranges > 1 ? 1 : 2, [&](int r0, int r1, int) {
    size_t head[kMaxThreads], end[kMaxThreads];
    for (int r = r0; r < r1; ++r) {
      const uint64_t lo = split(r), hi = split(r + 1);
      size_t out = 0;
      for (int p = 0; p < parts; ++p) {
        const std::vector<Contact>& v = sortParts[p].sorted;
        head[p] = lowerBound(v, lo);
        end[p] = lowerBound(v, hi);
        out += head[p];
      }
      for (;;) {
        int best = -1;
        uint64_t bestKey = 0;
        for (int p = 0; p < parts; ++p) {
          if (head[p] == end[p]) continue;
          const uint64_t key = sortParts[p].sorted[head[p]].Key();
          if (best < 0 || key < bestKey) {
            best = p;
            bestKey = key;
          }
        }
        if (best < 0) break;
        contacts[out++] = sortParts[best].sorted[head[best]++];
      }
    }
  });
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
  const ShapeDef& s = impl_->bodies.shape[i];
  const Transform& xf = impl_->bodies.xf[i];
  return s.type == ShapeType::kCircle ? ComputeAABB(s.circle, xf) : ComputeAABB(s.polygon, xf);
}
const ShapeDef& World::GetShape(BodyId id) const { return impl_->bodies.shape[impl_->Dense(id)]; }

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
  w.WakeAround(i);  // what it lands on
}

void World::ApplyLinearImpulse(BodyId id, Vec2 impulse, Vec2 worldPoint) {
  Impl& w = *impl_;
  const int i = w.Dense(id);
  Require(IsFinite(impulse) && IsFinite(worldPoint), "ApplyLinearImpulse: impulse or point is not finite");
  Require(std::abs(worldPoint.x) <= kMaxCoordinate && std::abs(worldPoint.y) <= kMaxCoordinate,
          "ApplyLinearImpulse: point is beyond the coordinate limit of 1e6 m");
  if (w.bodies.type[i] != BodyType::kDynamic) return;
  // Compute in double and check before writing: the world must stay as it was if refused.
  // A sleeping body's stored inverse mass is 0; the impulse acts on its awake one.
  const BodyInverseMass inv = w.def.effects.sleep ? Islands::AwakeInverseMass(w.bodies, i) : w.bodies.inv[i];
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

AABB World::GetPartitionRegion() const { return impl_->quadrants ? impl_->quadrants->Region() : AABB{}; }

}  // namespace quadrant
