// Bullet 3.24 run as a 2D engine: its 2D-constrained mode (linear factor (1,1,0), angular factor
// (0,0,1)) with the 2D convex collision algorithms registered, as Bullet's Planar2D example does.
//
// Everything is translated once in Load; Step is one stepSimulation call. Bullet keeps a body at
// its centre of mass, so shapes are built around the scene's centre of mass and positions are
// converted back to the body origin on read-back. A compound body (or a capsule off its body's x
// axis) is a btCompoundShape of per-shape children. Joints are btGeneric6DofSpring2Constraints
// between frames at the anchor, their z rotation and x translation (the axis) limited, driven or
// sprung as the joint says; distance joints are refused (no 6-dof frame holds a radius).
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <btBulletDynamicsCommon.h>
#include <BulletCollision/CollisionDispatch/btBox2dBox2dCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btConvex2dConvex2dAlgorithm.h>
#include <BulletCollision/CollisionShapes/btConvex2dShape.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpaPenetrationDepthSolver.h>
#include <BulletCollision/NarrowPhaseCollision/btVoronoiSimplexSolver.h>
#include <BulletDynamics/ConstraintSolver/btGeneric6DofSpring2Constraint.h>
#include <LinearMath/btPoolAllocator.h>

#include "adapter.h"
#include "adapter_factories.h"
#include "quadrant/error.h"

namespace quadrant::scene {
namespace {

constexpr const char* kName = "bullet";

// Half-thickness of the slab a polygon is extruded to. An in-plane overlap deeper than this
// makes GJK/EPA pick the z axis as the separating normal, which the linear factor then cancels,
// and the bodies stay stuck; 0.5 m is deeper than any overlap the scenes produce.
constexpr btScalar kHalfThickness = btScalar(0.5);

// Bullet's default convex margin. Keeping it (and moving the hull inward to compensate) means
// shallow contacts are found by GJK on the cores, which is exact, instead of by the
// penetration-depth solver, which is iterative and costlier.
constexpr Real kHullMargin = Real(0.04);
// Below this a polygon is too small for an inset hull; it then keeps its vertices and this
// margin, which makes it at most this much larger than the scene says.
constexpr Real kMinHullMargin = Real(0.001);

constexpr int kMinPoolSize = 4096;

// Moves every edge of a convex counter-clockwise polygon inward by `margin` (each vertex along
// its bisector). Returns false if an edge would collapse or flip, i.e. the polygon is too small
// for that margin.
bool InsetPolygon(const std::vector<Vec2>& in, Real margin, std::vector<Vec2>& out) {
  const size_t n = in.size();
  std::vector<Vec2> normals(n);
  for (size_t i = 0; i < n; ++i) normals[i] = Normalize(RightPerp(in[(i + 1) % n] - in[i]));
  out.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const Vec2 nPrev = normals[(i + n - 1) % n];
    const Vec2 nNext = normals[i];
    const Real denom = Real(1) + Dot(nPrev, nNext);
    if (denom <= Real(1e-6)) return false;
    // The offset d = s (nPrev + nNext) with s chosen so that d.nPrev = d.nNext = margin.
    out[i] = in[i] - (margin / denom) * (nPrev + nNext);
  }
  for (size_t i = 0; i < n; ++i) {
    const Vec2 before = in[(i + 1) % n] - in[i];
    const Vec2 after = out[(i + 1) % n] - out[i];
    if (Dot(before, after) <= Real(1e-6) * Dot(before, before)) return false;
  }
  return true;
}

// Distance from the local origin to the nearest edge line: the largest circle about the centre
// of mass that the shape contains, used as the swept sphere of continuous collision.
Real InnerRadius(const std::vector<Vec2>& vertices) {
  Real best = std::numeric_limits<Real>::max();
  const size_t n = vertices.size();
  for (size_t i = 0; i < n; ++i) {
    const Vec2 normal = Normalize(RightPerp(vertices[(i + 1) % n] - vertices[i]));
    best = std::min(best, Dot(normal, vertices[i]));
  }
  return best;
}

Real NormalizeAngle(double angle) {
  constexpr double kPi = std::numbers::pi;
  while (angle > kPi) angle -= 2 * kPi;
  while (angle <= -kPi) angle += 2 * kPi;
  return Real(angle);
}

// One loaded scene. Members are declared so that the implicit destruction order is the order
// Bullet needs: the world first (its destructor still reads the bodies' broadphase proxies and
// uses the broadphase and dispatcher), then bodies, shapes, solver, broadphase, dispatcher,
// configuration, and last the algorithm factories and solvers the dispatcher pointed to.
struct BulletWorld {
  btVoronoiSimplexSolver simplexSolver;
  // EPA rather than Planar2D's Minkowski sampling solver: with the sampling solver two boxes
  // overlapping by 40 % or more of their width often get no contact point at all and stay
  // stuck inside each other; EPA separates them.
  btGjkEpaPenetrationDepthSolver penetrationSolver;
  std::unique_ptr<btConvex2dConvex2dAlgorithm::CreateFunc> convex2dCreate;
  std::unique_ptr<btBox2dBox2dCollisionAlgorithm::CreateFunc> box2dCreate;
  std::unique_ptr<btDefaultCollisionConfiguration> configuration;
  std::unique_ptr<btCollisionDispatcher> dispatcher;
  std::unique_ptr<btDbvtBroadphase> broadphase;
  std::unique_ptr<btSequentialImpulseConstraintSolver> solver;
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  bool filtered = false;  // some body has a non-default collision filter (AddBody)
  std::vector<std::unique_ptr<btRigidBody>> bodies;
  /// The scene's joints, then each group's, in the order the groups were added.
  std::vector<std::unique_ptr<btTypedConstraint>> constraints;
  std::unique_ptr<btDiscreteDynamicsWorld> world;

  BulletWorld() = default;
  BulletWorld(const BulletWorld&) = delete;
  BulletWorld& operator=(const BulletWorld&) = delete;
  // Constraints leave the world (which drops their references from the bodies) before anything
  // is freed; the members then go in the order above.
  ~BulletWorld() {
    if (world) {
      for (auto& c : constraints) world->removeConstraint(c.get());
    }
  }

  std::vector<Vec2> localCenters;  ///< body origin to centre of mass, body frame, per body
  std::vector<bool> dynamic;
  bool rotation = true;
  btScalar timeStep = 0;
};

class BulletAdapter final : public Adapter {
 public:
  std::string Name() const override { return kName; }

  Capabilities Caps() const override {
    Capabilities caps;
    caps.maxThreads = 1;
    caps.threadLimit = "Debian's Bullet is built without BT_THREADSAFE: serial only";
    caps.sleep = true;
    caps.continuous = true;
    caps.disableRotation = true;
    caps.disableFriction = true;
    caps.disableWarmStarting = true;
    caps.damping = true;
    caps.notes =
        "serial only (Debian's Bullet is built without BT_THREADSAFE); "
        "2D-constrained mode: linear factor (1,1,0), angular factor (0,0,1), "
        "btConvex2dConvex2dAlgorithm + GJK/EPA penetration solver for polygon pairs; "
        "circles are btSphereShape with z inertia m r^2/2 set explicitly; "
        "polygons are btConvex2dShape around a btConvexHullShape extruded to z = +-0.5 m, "
        "vertices moved inward by the 0.04 m hull margin so edges lie on the scene's edges "
        "(corners rounded by 0.04 m; smaller margin on polygons too small for it); "
        "mass and inertia from the scene's exact mass properties; "
        "compound bodies (and capsules off the body's x axis): btCompoundShape of the shapes "
        "about the scene's centre of mass, one friction and restitution per body; "
        "joints: btGeneric6DofSpring2Constraint (revolute, prismatic, weld, wheel; limits, "
        "motors, Box2D-style springs on the reduced mass or inertia, ERP 0.2), no distance joint; "
        "friction and restitution are multiplied (f1*f2, e1*e2); "
        "restitution threshold = scene's; iterations = scene's velocity iterations, "
        "no position iterations: Bullet's defaults (split impulse for penetration deeper than "
        "0.04 m, Baumgarte 0.2 folded into the velocities for shallower, which adds energy to "
        "elastic collisions); "
        "continuous: per-body swept-sphere CCD (sphere = inner radius, threshold = inner "
        "radius); sleep: Bullet's thresholds 0.8 m/s, 1 rad/s, 2 s; "
        "damping: per-body, Bullet's (1 - d)^dt law with d chosen so one step gives the "
        "scene's factor 1 / (1 + dt c); "
        "contacts = manifolds with a point at distance <= 0";
    return caps;
  }

  void DoLoad(const Scene& scene, int /*threads: 1*/) override {
    Refuse(scene.bodies, scene.joints);
    // Built aside and swapped in at the end, so a throwing Load keeps the previous world.
    auto next = std::make_unique<BulletWorld>();
    auto filtered = [](const BodyDesc& b) { return b.categoryBits != 1 || b.maskBits != 0xFFFFFFFFu; };
    next->filtered = std::any_of(scene.bodies.begin(), scene.bodies.end(), filtered);
    for (const BodyGroup& g : scene.groupSamples) {
      next->filtered = next->filtered || std::any_of(g.bodies.begin(), g.bodies.end(), filtered);
    }
    BuildWorld(scene, *next);
    for (size_t i = 0; i < scene.bodies.size(); ++i) AddBody(scene, scene.bodies[i], *next);
    for (const JointDesc& j : scene.joints) AddJoint(j, 0, *next);
    world_ = std::move(next);
    settings_ = scene;
    settings_.bodies.clear();
    settings_.joints.clear();
    settings_.groupSamples.clear();
    settings_.driver = nullptr;
    sceneBodies_ = scene.bodies.size();
    sceneJoints_ = scene.joints.size();
    groups_.clear();
  }

  void CheckGroup(const Scene& /*scene*/, const BodyGroup& group) const override {
    Refuse(group.bodies, group.joints);
    // At Load the world is made filtered for the scene's groupSamples too; a group added to a
    // world loaded without filters cannot bring its own.
    if (world_ && !world_->filtered && std::any_of(group.bodies.begin(), group.bodies.end(), [](const BodyDesc& b) {
          return b.categoryBits != 1 || b.maskBits != 0xFFFFFFFFu;
        })) {
      throw Unsupported("bullet: a group with collision filters added to a world loaded without any (list it in the scene's groupSamples)");
    }
  }

  // A group's bodies and joints go at the end of the body and constraint vectors, which stay in
  // the adapter's order; its shapes stay with the world until the next Load.
  void DoAddGroup(int group, const BodyGroup& desc) override {
    BulletWorld& w = *world_;
    const size_t firstBody = w.bodies.size();
    for (const BodyDesc& b : desc.bodies) AddBody(settings_, b, w);
    for (const JointDesc& j : desc.joints) AddJoint(j, firstBody, w);
    groups_.emplace(group, GroupSize{desc.bodies.size(), desc.joints.size()});
  }

  // The group's constraints leave the world before its bodies (a body must not outlive in the
  // world a constraint that refers to it, nor be freed while one does).
  void DoRemoveGroup(int group) override {
    size_t first = sceneBodies_, firstJoint = sceneJoints_;
    for (const auto& [id, size] : groups_) {
      if (id == group) break;
      first += size.bodies;
      firstJoint += size.joints;
    }
    const size_t count = groups_.at(group).bodies, joints = groups_.at(group).joints;
    BulletWorld& w = *world_;
    for (size_t i = firstJoint; i < firstJoint + joints; ++i) w.world->removeConstraint(w.constraints[i].get());
    w.constraints.erase(w.constraints.begin() + std::ptrdiff_t(firstJoint),
                        w.constraints.begin() + std::ptrdiff_t(firstJoint + joints));
    for (size_t i = first; i < first + count; ++i) w.world->removeRigidBody(w.bodies[i].get());
    w.bodies.erase(w.bodies.begin() + std::ptrdiff_t(first), w.bodies.begin() + std::ptrdiff_t(first + count));
    w.localCenters.erase(w.localCenters.begin() + std::ptrdiff_t(first), w.localCenters.begin() + std::ptrdiff_t(first + count));
    w.dynamic.erase(w.dynamic.begin() + std::ptrdiff_t(first), w.dynamic.begin() + std::ptrdiff_t(first + count));
    groups_.erase(group);
  }

 private:
  // What the adapter cannot run among these bodies and joints, as Unsupported.
  static void Refuse(const std::vector<BodyDesc>& bodies, const std::vector<JointDesc>& joints) {
    // Bullet moves a kinematic body by its motion state's transform, which the caller sets each
    // step, not by a velocity; the scene API drives kinematic bodies by velocity (SetVelocity).
    for (const BodyDesc& b : bodies) {
      if (b.kinematic) throw Unsupported("bullet: kinematic bodies move by transform in Bullet, not by velocity");
      // Bullet's 2D mode wraps convex shapes of some thickness (btConvex2dShape); a line has none,
      // and a thin box would be another shape, caught on its corners.
      if (b.shape == ShapeKind::kSegment || b.shape == ShapeKind::kChainSegment) {
        throw Unsupported("bullet: no segment or chain shape in Bullet's 2D mode (a thin box would be another shape)");
      }
      // Bullet's friction and restitution belong to the body, not to each child shape.
      for (const ShapeDesc& extra : b.extraShapes) {
        if (extra.shape == ShapeKind::kSegment || extra.shape == ShapeKind::kChainSegment) {
          throw Unsupported("bullet: no segment or chain shape in Bullet's 2D mode (a thin box would be another shape)");
        }
        if (extra.friction != b.friction || extra.restitution != b.restitution) {
          throw Unsupported("bullet: a compound body's shapes must share friction and restitution (Bullet's are per body)");
        }
      }
    }
    for (const JointDesc& j : joints) {
      // A rod keeps anchor B on a circle about anchor A; a 6-dof frame fixed in bodyA limits
      // translations along its own axes, not a radius, and btPoint2PointConstraint holds length 0.
      if (j.kind == JointKind::kDistance) {
        throw Unsupported("bullet: no distance joint (Bullet's constraints hold no length between two anchors)");
      }
    }
  }

 public:

  void DoStep() override { world_->world->stepSimulation(world_->timeStep, 0); }

  int BodyCount() const override {
    return world_ ? static_cast<int>(world_->bodies.size()) : 0;
  }

  void ReadBodies(std::vector<BodyState>& out) const override {
    if (!world_) {
      out.clear();
      return;
    }
    const size_t n = world_->bodies.size();
    out.resize(n);
    for (size_t i = 0; i < n; ++i) {
      const btRigidBody& body = *world_->bodies[i];
      const btTransform& xf = body.getCenterOfMassTransform();
      const btQuaternion q = xf.getRotation();
      const Vec2 lc = world_->localCenters[i];
      const btVector3 origin = xf.getOrigin() - xf.getBasis() * btVector3(lc.x, lc.y, 0);
      BodyState& s = out[i];
      s.position = {Real(origin.x()), Real(origin.y())};
      s.angle = NormalizeAngle(2.0 * std::atan2(double(q.z()), double(q.w())));
      s.velocity = {Real(body.getLinearVelocity().x()), Real(body.getLinearVelocity().y())};
      s.angularVelocity = Real(body.getAngularVelocity().z());
    }
  }

  int ContactCount() const override {
    if (!world_) return 0;
    // Bullet keeps points up to its contact breaking threshold apart; only count manifolds
    // whose shapes really touch (distance includes the margins).
    btCollisionDispatcher& dispatcher = *world_->dispatcher;
    int count = 0;
    for (int m = 0; m < dispatcher.getNumManifolds(); ++m) {
      const btPersistentManifold* manifold = dispatcher.getManifoldByIndexInternal(m);
      for (int p = 0; p < manifold->getNumContacts(); ++p) {
        if (manifold->getContactPoint(p).getDistance() <= 0) {
          ++count;
          break;
        }
      }
    }
    return count;
  }

  void DoSetVelocity(int body, Vec2 velocity, Real angularVelocity) override {
    // A static body never moves (as in the other engines), and with rotation off the angular
    // velocity stays 0: Bullet would otherwise integrate it despite the zero angular factor.
    if (!world_->dynamic[body]) return;
    btRigidBody& b = *world_->bodies[body];
    b.setLinearVelocity(btVector3(velocity.x, velocity.y, 0));
    b.setAngularVelocity(btVector3(0, 0, world_->rotation ? angularVelocity : Real(0)));
    b.activate(true);
  }

  /// A body's mass and z inertia about its centre of mass as Bullet holds them; for tests.
  std::pair<double, double> MassOf(int body) const {
    const btRigidBody& b = *world_->bodies.at(size_t(body));
    if (b.getInvMass() == 0) return {0.0, 0.0};
    return {1.0 / double(b.getInvMass()), 1.0 / double(b.getInvInertiaDiagLocal().z())};
  }

  /// Largest departure from the plane over all bodies (z position and velocity, x and y of
  /// the rotation and angular velocity); for tests.
  double OutOfPlane() const {
    double worst = 0;
    if (!world_) return worst;
    for (const auto& body : world_->bodies) {
      const btTransform& xf = body->getCenterOfMassTransform();
      const btQuaternion q = xf.getRotation();
      for (double v : {double(xf.getOrigin().z()), double(body->getLinearVelocity().z()),
                       double(q.x()), double(q.y()), double(body->getAngularVelocity().x()),
                       double(body->getAngularVelocity().y())}) {
        worst = std::max(worst, std::abs(v));
      }
    }
    return worst;
  }

 private:
  static void BuildWorld(const Scene& scene, BulletWorld& w) {
    const int n = static_cast<int>(scene.bodies.size());
    btDefaultCollisionConstructionInfo info;
    info.m_defaultMaxPersistentManifoldPoolSize = std::max(kMinPoolSize, 4 * n);
    info.m_defaultMaxCollisionAlgorithmPoolSize = std::max(kMinPoolSize, 4 * n);
    w.configuration = std::make_unique<btDefaultCollisionConfiguration>(info);
    // The pool's block size is set from the default algorithms; the dispatcher would write a
    // larger algorithm past the end of its block rather than fail.
    const int blockSize = w.configuration->getCollisionAlgorithmPool()->getElementSize();
    if (blockSize < int(sizeof(btConvex2dConvex2dAlgorithm)) ||
        blockSize < int(sizeof(btBox2dBox2dCollisionAlgorithm))) {
      throw std::logic_error("bullet: collision algorithm pool blocks too small for 2D pairs");
    }
    w.dispatcher = std::make_unique<btCollisionDispatcher>(w.configuration.get());
    w.convex2dCreate = std::make_unique<btConvex2dConvex2dAlgorithm::CreateFunc>(
        &w.simplexSolver, &w.penetrationSolver);
    w.box2dCreate = std::make_unique<btBox2dBox2dCollisionAlgorithm::CreateFunc>();
    w.dispatcher->registerCollisionCreateFunc(CONVEX_2D_SHAPE_PROXYTYPE,
                                              CONVEX_2D_SHAPE_PROXYTYPE, w.convex2dCreate.get());
    w.dispatcher->registerCollisionCreateFunc(BOX_2D_SHAPE_PROXYTYPE, BOX_2D_SHAPE_PROXYTYPE,
                                              w.box2dCreate.get());
    w.broadphase = std::make_unique<btDbvtBroadphase>();
    w.solver = std::make_unique<btSequentialImpulseConstraintSolver>();
    w.world = std::make_unique<btDiscreteDynamicsWorld>(w.dispatcher.get(), w.broadphase.get(),
                                                        w.solver.get(), w.configuration.get());
    // Before any body is added: addRigidBody copies the world's gravity into each body.
    const Effects& fx = scene.effects;
    w.world->setGravity(fx.gravity ? btVector3(scene.gravity.x, scene.gravity.y, 0)
                                   : btVector3(0, 0, 0));
    btContactSolverInfo& solverInfo = w.world->getSolverInfo();
    solverInfo.m_numIterations = scene.velocityIterations;
    solverInfo.m_restitutionVelocityThreshold = scene.restitutionThreshold;
    if (!fx.warmStarting) solverInfo.m_solverMode &= ~SOLVER_USE_WARMSTARTING;

    w.rotation = fx.rotation;
    w.timeStep = scene.timeStep;
    w.bodies.reserve(scene.bodies.size());
    w.localCenters.reserve(scene.bodies.size());
    w.dynamic.reserve(scene.bodies.size());
  }

  // One scene shape as a Bullet shape (owned by w.shapes) placed by `where` in the body's
  // centre-of-mass frame (`localCenter`: body origin to centre of mass). innerRadius: the
  // largest circle about the shape's own centre that it contains.
  static btCollisionShape* MakeShape(const ShapeDesc& desc, Vec2 localCenter, BulletWorld& w,
                                     btTransform& where, Real& innerRadius) {
    where.setIdentity();
    if (desc.shape == ShapeKind::kCircle) {
      innerRadius = desc.radius;
      where.setOrigin(btVector3(desc.center.x - localCenter.x, desc.center.y - localCenter.y, 0));
      w.shapes.push_back(std::make_unique<btSphereShape>(desc.radius));
      return w.shapes.back().get();
    }
    if (desc.shape == ShapeKind::kCapsule) {  // btCapsuleShapeX turned onto the centres' line
      innerRadius = desc.radius;
      const Vec2 c1 = desc.vertices[0], c2 = desc.vertices[1], mid = Real(0.5) * (c1 + c2);
      const Vec2 d = c2 - c1;
      where.setOrigin(btVector3(mid.x - localCenter.x, mid.y - localCenter.y, 0));
      where.setRotation(btQuaternion(btVector3(0, 0, 1), btScalar(std::atan2(d.y, d.x))));
      w.shapes.push_back(std::make_unique<btCapsuleShapeX>(desc.radius, Length(d)));
      return w.shapes.back().get();
    }
    std::vector<Vec2> centred(desc.vertices.size());
    for (size_t i = 0; i < centred.size(); ++i) centred[i] = desc.vertices[i] - localCenter;
    Vec2 mean{};
    for (Vec2 v : desc.vertices) mean = mean + v;
    mean = (Real(1) / Real(desc.vertices.size())) * mean;
    std::vector<Vec2> aroundMean(desc.vertices.size());
    for (size_t i = 0; i < centred.size(); ++i) aroundMean[i] = desc.vertices[i] - mean;
    innerRadius = InnerRadius(aroundMean);

    // Bullet adds the margin outside the hull: shrink the hull by it so the rounded result has
    // the scene's edges. Halve the margin for polygons too small to shrink by the full one.
    std::vector<Vec2> core;
    Real margin = kHullMargin;
    while (margin >= kMinHullMargin && !InsetPolygon(centred, margin, core)) margin *= Real(0.5);
    if (margin < kMinHullMargin) {
      margin = kMinHullMargin;
      core = centred;
    }
    auto hull = std::make_unique<btConvexHullShape>();
    hull->setMargin(margin);
    for (Vec2 v : core) {
      hull->addPoint(btVector3(v.x, v.y, -kHalfThickness), false);
      hull->addPoint(btVector3(v.x, v.y, kHalfThickness), false);
    }
    hull->recalcLocalAabb();
    auto flat = std::make_unique<btConvex2dShape>(hull.get());
    w.shapes.push_back(std::move(hull));
    w.shapes.push_back(std::move(flat));
    return w.shapes.back().get();
  }

  // The body's collision shape: its one shape, or a btCompoundShape of all of them (also for a
  // lone capsule off the body's x axis, which needs a child transform). innerRadius: the
  // smallest of the shapes' (the swept sphere of continuous collision).
  static btCollisionShape* MakeBodyShape(const BodyDesc& desc, Vec2 localCenter, BulletWorld& w,
                                         Real& innerRadius) {
    const std::vector<ShapeDesc> shapes = ShapesOf(desc);
    std::vector<std::pair<btCollisionShape*, btTransform>> parts;
    innerRadius = std::numeric_limits<Real>::max();
    for (const ShapeDesc& sd : shapes) {
      btTransform where;
      Real r = 0;
      btCollisionShape* shape = MakeShape(sd, localCenter, w, where, r);
      parts.emplace_back(shape, where);
      innerRadius = std::min(innerRadius, r);
    }
    const btTransform& only = parts[0].second;
    if (parts.size() == 1 && only.getBasis() == btMatrix3x3::getIdentity() &&
        only.getOrigin().fuzzyZero()) {
      return parts[0].first;
    }
    auto compound = std::make_unique<btCompoundShape>(/*enableDynamicAabbTree=*/parts.size() > 8,
                                                      int(parts.size()));
    for (const auto& [shape, where] : parts) compound->addChildShape(where, shape);
    w.shapes.push_back(std::move(compound));
    return w.shapes.back().get();
  }

  static void AddBody(const Scene& scene, const BodyDesc& desc, BulletWorld& w) {
    const Effects& fx = scene.effects;
    // Static bodies are built around their own origin: they never rotate, and their density may
    // be 0.
    MassProperties mp;
    if (desc.dynamic) mp = ComputeMassProperties(desc);
    const Vec2 lc = desc.dynamic ? mp.localCenter : Vec2{};
    Real innerRadius = 0;
    btCollisionShape* shape = MakeBodyShape(desc, lc, w, innerRadius);

    const btScalar mass = desc.dynamic ? btScalar(mp.mass) : btScalar(0);
    // Bullet's own inertia is 2/5 m r^2 for a sphere and a bounding-box guess for a hull; the
    // scene's is exact. Only z matters (the angular factor zeroes x and y), but x and y must be
    // positive for Bullet's inverse.
    const btScalar inertia = desc.dynamic ? btScalar(mp.inertia) : btScalar(0);
    btRigidBody::btRigidBodyConstructionInfo info(mass, nullptr, shape,
                                                  btVector3(inertia, inertia, inertia));
    const btQuaternion rotation(btVector3(0, 0, 1), desc.angle);
    const btTransform frame(rotation, btVector3(desc.position.x, desc.position.y, 0));
    const btVector3 centre = frame * btVector3(lc.x, lc.y, 0);
    info.m_startWorldTransform = btTransform(rotation, centre);
    info.m_friction = fx.friction ? desc.friction : Real(0);
    info.m_restitution = fx.restitution ? desc.restitution : Real(0);
    // Bullet multiplies velocities by (1 - d)^dt each step; d = 1 - (1 + dt c)^(-1/dt) makes
    // that the scene's 1 / (1 + dt c) at the scene's fixed step.
    const double h = scene.timeStep;
    auto bulletDamping = [&](Real c) { return btScalar(1 - std::pow(1 + h * double(c), -1 / h)); };
    info.m_linearDamping = fx.damping ? bulletDamping(desc.linearDamping) : btScalar(0);
    info.m_angularDamping = fx.damping ? bulletDamping(desc.angularDamping) : btScalar(0);

    auto body = std::make_unique<btRigidBody>(info);
    if (desc.dynamic) {
      body->setLinearFactor(btVector3(1, 1, 0));
      body->setAngularFactor(fx.rotation ? btVector3(0, 0, 1) : btVector3(0, 0, 0));
      // Scene and read-back velocities are the centre of mass's, as in Quadrant and Box2D.
      body->setLinearVelocity(btVector3(desc.velocity.x, desc.velocity.y, 0));
      body->setAngularVelocity(btVector3(0, 0, fx.rotation ? desc.angularVelocity : Real(0)));
      if (fx.continuous) {
        body->setCcdMotionThreshold(innerRadius);
        body->setCcdSweptSphereRadius(innerRadius);
      }
    }
    if (!fx.sleep) body->setActivationState(DISABLE_DEACTIVATION);
    if (!desc.awake) body->setActivationState(ISLAND_SLEEPING);  // woken by a collision with an awake body
    if (w.filtered) {
      // Bullet's broad-phase rule is Box2D's (each group in the other's mask); with any filter in
      // the scene every body takes its own bits, so default bodies keep colliding with filtered ones.
      w.world->addRigidBody(body.get(), int(desc.categoryBits), int(desc.maskBits));
    } else {
      w.world->addRigidBody(body.get());
    }
    w.bodies.push_back(std::move(body));
    w.localCenters.push_back(lc);
    w.dynamic.push_back(desc.dynamic);
  }

  // Box2D's soft-constraint stiffness and damping for a spring of `hertz` and `ratio` on the
  // pair's reduced mass (or inertia): k = m w^2, c = 2 m ratio w, as b2LinearStiffness.
  static void Spring(double reduced, Real hertz, Real ratio, btScalar& k, btScalar& c) {
    const double omega = 2 * std::numbers::pi * double(hertz);
    k = btScalar(reduced * omega * omega);
    c = btScalar(2 * reduced * double(ratio) * omega);
  }
  static double Reduced(double a, double b) {
    if (a > 0 && b > 0) return a * b / (a + b);
    return a > 0 ? a : b;
  }

  // One scene joint (body indices offset by `firstBody`) as a btGeneric6DofSpring2Constraint:
  // frame A on bodyA and frame B on bodyB at the anchor, both with x along the joint's axis (the
  // world x for revolute and weld) and frame B turned back by the reference angle, so that the
  // constraint's z angle is the scene's joint angle and its x translation the travel along the
  // axis. Locked: lower = upper = 0; free: lower > upper (Bullet's convention). Bullet's angle
  // and velocities are bodyA's relative to bodyB (its getAngle(2) is -0.3 for bodyB turned by
  // +0.3): angle limits and motor speeds go in negated and swapped.
  static void AddJoint(const JointDesc& d, size_t firstBody, BulletWorld& w) {
    btRigidBody& a = *w.bodies[firstBody + size_t(d.bodyA)];
    btRigidBody& b = *w.bodies[firstBody + size_t(d.bodyB)];
    const bool slides = d.kind == JointKind::kPrismatic || d.kind == JointKind::kWheel;
    const Vec2 axis = slides ? Normalize(d.axis) : Vec2{1, 0};
    const double phi = std::atan2(double(axis.y), double(axis.x));
    auto angleOf = [](const btRigidBody& body) {
      const btQuaternion q = body.getCenterOfMassTransform().getRotation();
      return 2.0 * std::atan2(double(q.z()), double(q.w()));
    };
    const double angleA = angleOf(a), angleB = angleOf(b);
    const btVector3 anchor(d.anchor.x, d.anchor.y, 0);
    btTransform frameA(btQuaternion(btVector3(0, 0, 1), btScalar(phi - angleA)),
                       a.getCenterOfMassTransform().inverse() * anchor);
    btTransform frameB(btQuaternion(btVector3(0, 0, 1), btScalar(phi - angleB - double(d.referenceAngle))),
                       b.getCenterOfMassTransform().inverse() * anchor);
    auto c = std::make_unique<btGeneric6DofSpring2Constraint>(a, b, frameA, frameB, RO_XYZ);
    btGeneric6DofSpring2Constraint& j = *c;
    for (int i = 0; i < 6; ++i) j.setLimit(i, 0, 0);  // all locked, then freed below
    const double massA = a.getInvMass() > 0 ? 1.0 / double(a.getInvMass()) : 0.0;
    const double massB = b.getInvMass() > 0 ? 1.0 / double(b.getInvMass()) : 0.0;
    const double inertiaA = a.getInvMass() > 0 ? 1.0 / double(a.getInvInertiaDiagLocal().z()) : 0.0;
    const double inertiaB = b.getInvMass() > 0 ? 1.0 / double(b.getInvInertiaDiagLocal().z()) : 0.0;
    btScalar k = 0, damping = 0;
    // Springs get the scene's stiffness and damping as given (limitIfNeeded = false): Bullet's
    // own cap would soften a 5 Hz ragdoll spring at 60 Hz.
    auto spring = [&](int dof, double reduced, Real hertz, Real ratio) {
      if (hertz <= 0) return;
      Spring(reduced, hertz, ratio, k, damping);
      j.enableSpring(dof, true);
      j.setStiffness(dof, k, false);
      j.setDamping(dof, damping, false);
      j.setEquilibriumPoint(dof, 0);
    };
    constexpr int kSlide = 0, kTurn = 5;
    switch (d.kind) {
      case JointKind::kRevolute:
        if (d.enableLimit) {
          j.setLimit(kTurn, -d.upperAngle, -d.lowerAngle);
        } else {
          j.setLimit(kTurn, 1, -1);
        }
        if (d.enableMotor) {
          j.enableMotor(kTurn, true);
          j.setTargetVelocity(kTurn, -d.motorSpeed);
          j.setMaxMotorForce(kTurn, d.maxMotorTorque);
        }
        if (d.enableSpring) spring(kTurn, Reduced(inertiaA, inertiaB), d.hertz, d.dampingRatio);
        break;
      case JointKind::kPrismatic:
      case JointKind::kWheel:
        if (d.enableLimit) {
          j.setLimit(kSlide, d.lowerTranslation, d.upperTranslation);
        } else {
          j.setLimit(kSlide, 1, -1);
        }
        if (d.kind == JointKind::kPrismatic) {
          if (d.enableMotor) {
            j.enableMotor(kSlide, true);
            j.setTargetVelocity(kSlide, -d.motorSpeed);
            j.setMaxMotorForce(kSlide, d.maxMotorForce);
          }
        } else {
          j.setLimit(kTurn, 1, -1);  // the wheel turns freely, or by its motor
          if (d.enableMotor) {
            j.enableMotor(kTurn, true);
            j.setTargetVelocity(kTurn, -d.motorSpeed);
            j.setMaxMotorForce(kTurn, d.maxMotorTorque);
          }
          if (d.enableSpring) spring(kSlide, Reduced(massA, massB), d.hertz, d.dampingRatio);
        }
        break;
      case JointKind::kWeld:
        if (d.hertz > 0) {
          for (int dof : {0, 1}) {
            j.setLimit(dof, 1, -1);
            spring(dof, Reduced(massA, massB), d.hertz, d.dampingRatio);
          }
        }
        if (d.angularHertz > 0) {
          j.setLimit(kTurn, 1, -1);
          spring(kTurn, Reduced(inertiaA, inertiaB), d.angularHertz, d.angularDampingRatio);
        }
        break;
      case JointKind::kDistance:  // refused by Refuse
        throw std::logic_error("bullet: distance joint reached AddJoint");
    }
    w.world->addConstraint(c.get(), /*disableCollisionsBetweenLinkedBodies=*/!d.collideConnected);
    w.constraints.push_back(std::move(c));
  }

  std::unique_ptr<BulletWorld> world_;
  Scene settings_;                 // the loaded scene's settings, for the groups' bodies
  size_t sceneBodies_ = 0;
  size_t sceneJoints_ = 0;
  struct GroupSize {
    size_t bodies = 0, joints = 0;
  };
  std::map<int, GroupSize> groups_;  // live groups by id: their body and joint counts
};

}  // namespace

std::unique_ptr<Adapter> MakeBulletAdapter() { return std::make_unique<BulletAdapter>(); }

/// Test hook (declared by the Bullet adapter tests, not in a header): how far the adapter's
/// bodies have left the z = 0 plane. Throws quadrant::Error for an adapter of another engine.
double BulletOutOfPlane(const Adapter& adapter) {
  const auto* bullet = dynamic_cast<const BulletAdapter*>(&adapter);
  if (!bullet) throw Error("BulletOutOfPlane: not a Bullet adapter");
  return bullet->OutOfPlane();
}

/// Test hook, as BulletOutOfPlane: body `body`'s mass (kg) and z inertia about its centre of
/// mass (kg m^2) as given to Bullet; (0, 0) for a static body.
std::pair<double, double> BulletMassOf(const Adapter& adapter, int body) {
  const auto* bullet = dynamic_cast<const BulletAdapter*>(&adapter);
  if (!bullet) throw Error("BulletMassOf: not a Bullet adapter");
  if (body < 0 || body >= bullet->BodyCount()) throw Error("BulletMassOf: body index out of range");
  return bullet->MassOf(body);
}

}  // namespace quadrant::scene
