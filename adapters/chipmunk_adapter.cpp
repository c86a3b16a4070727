// The Chipmunk 7.0.3 adapter (Debian's libchipmunk): the fastest packaged peer on sparse scenes.
//
// Everything is translated once in Load; Step is the driver plus one space step. Chipmunk takes
// body mass, moment and centre of gravity as given, so it gets the scene's exact values.
#include <chipmunk/chipmunk.h>
// cpHastySpace.h lacks the C linkage block the other headers carry.
extern "C" {
#include <chipmunk/cpHastySpace.h>
}

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_set>
#include <vector>

#include "adapter.h"
#include "adapter_factories.h"
#include "quadrant/error.h"

namespace quadrant::scene {
namespace {

constexpr char kName[] = "chipmunk";
// Chipmunk's default slop (0.1) is meant for pixel units; 0.005 m is Box2D's linear slop.
constexpr cpFloat kCollisionSlop = 0.005;
// Box2D's sleep settings, so sleeping scenes compare like with like.
constexpr cpFloat kSleepTime = 0.5;
constexpr cpFloat kIdleSpeed = 0.01;
constexpr int kMaxThreads = 2;  // cpHastySpace runs at most two solver threads
constexpr int kWarmUpBodies = 64;
constexpr int kWarmUpSteps = 100;

cpVect ToCp(Vec2 v) { return cpv(cpFloat(v.x), cpFloat(v.y)); }
Vec2 FromCp(cpVect v) { return {Real(v.x), Real(v.y)}; }

// Debian's Chipmunk (built with assertions on) prints a banner on stdout when the first space
// of the process is made; tools that write results to stdout would get it mixed in. Send it to
// stderr, where it still tells the reader that this Chipmunk runs its assertion checks.
cpSpace* NewFirstSpaceBannerToStderr() {
  std::fflush(stdout);
  const int saved = dup(STDOUT_FILENO);
  const bool redirected = saved >= 0 && dup2(STDERR_FILENO, STDOUT_FILENO) >= 0;
  cpSpace* space = cpSpaceNew();
  std::fflush(stdout);
  if (redirected) dup2(saved, STDOUT_FILENO);
  if (saved >= 0) close(saved);
  return space;
}

// The first space stepped in a process runs 1.5-2x slower (allocator and cache warm-up), which
// would land on whichever scene a benchmark happens to load first. Pay it once, untimed.
void WarmUpOnce() {
  static std::once_flag once;
  std::call_once(once, [] {
    cpSpace* space = NewFirstSpaceBannerToStderr();
    cpSpaceSetGravity(space, cpv(0, -10));
    cpSpaceSetCollisionSlop(space, kCollisionSlop);
    std::vector<cpBody*> bodies;
    std::vector<cpShape*> shapes;
    cpShape* ground = cpSegmentShapeNew(cpSpaceGetStaticBody(space), cpv(-20, 0), cpv(20, 0), 0);
    cpSpaceAddShape(space, ground);
    shapes.push_back(ground);
    for (int i = 0; i < kWarmUpBodies; ++i) {
      const cpFloat radius = 0.5;
      const cpFloat mass = CP_PI * radius * radius;
      cpBody* body = cpSpaceAddBody(space, cpBodyNew(mass, cpMomentForCircle(mass, 0, radius,
                                                                             cpvzero)));
      cpBodySetPosition(body, cpv(-8.0 + (i % 16), 1.0 + (i / 16) * 1.1));
      bodies.push_back(body);
      shapes.push_back(cpSpaceAddShape(space, cpCircleShapeNew(body, radius, cpvzero)));
    }
    for (int i = 0; i < kWarmUpSteps; ++i) cpSpaceStep(space, 1.0 / 60.0);
    cpSpaceFree(space);
    for (cpShape* s : shapes) cpShapeFree(s);
    for (cpBody* b : bodies) cpBodyFree(b);
  });
}

class ChipmunkAdapter final : public Adapter {
 public:
  ~ChipmunkAdapter() override { Release(); }

  std::string Name() const override { return kName; }

  Capabilities Caps() const override {
    Capabilities caps;
    caps.maxThreads = kMaxThreads;
    caps.threadLimit = "1 thread is a cpSpace, 2 a cpHastySpace (it threads only the impulse solver)";
    caps.sleep = true;
    caps.continuous = false;
    caps.disableRotation = true;
    caps.disableFriction = true;
    caps.disableWarmStarting = false;
    caps.damping = true;
    caps.notes =
        "Chipmunk 7.0.3 (Debian, built with assertions on), doubles. Friction and elasticity "
        "mixing: multiplied (f1*f2, e1*e2); no restitution threshold (elasticity applies at "
        "every approach speed). Collision slop 0.005 m (metre units), default collision bias; "
        "cpSpaceSetIterations = scene velocity iterations; no position iterations or "
        "sub-steps. Mass, moment and centre of gravity set to the scene's exact values; "
        "polygons have radius 0. Rotation off = infinite moment. Sleep: 0.5 s below "
        "0.01 m/s (Box2D's values); a sleeping body reads back the velocity it fell asleep with "
        "(Box2D zeroes it). Threads: 1 = cpSpace, 2 = cpHastySpace with 2 threads "
        "(only the impulse solver threaded, nondeterministic). No continuous collision, "
        "warm starting cannot be switched off. Damping: one space-wide rate for linear and "
        "angular motion (cpSpaceSetDamping, converted so one step gives 1 / (1 + dt c)); "
        "scenes with per-body or unequal linear and angular rates are unsupported; Chipmunk "
        "damps before adding gravity, Box2D and Quadrant after.";
    return caps;
  }

  void DoLoad(const Scene& scene, int threads) override {
    // Refuse before touching the current space, so a refused Load leaves it usable.
    const Effects& fx = scene.effects;
    double damping = 0;
    bool dampingSet = false;
    Refuse(fx, scene.bodies, scene.joints, damping, dampingSet);

    WarmUpOnce();
    Release();

    hasty_ = threads == kMaxThreads;
    if (hasty_) {
      space_ = cpHastySpaceNew();
      cpHastySpaceSetThreads(space_, kMaxThreads);
    } else {
      space_ = cpSpaceNew();
    }
    cpSpaceSetGravity(space_, fx.gravity ? ToCp(scene.gravity) : cpvzero);
    cpSpaceSetIterations(space_, scene.velocityIterations);
    cpSpaceSetCollisionSlop(space_, kCollisionSlop);
    cpSpaceSetSleepTimeThreshold(space_, fx.sleep ? kSleepTime : INFINITY);
    cpSpaceSetIdleSpeedThreshold(space_, kIdleSpeed);
    // Chipmunk keeps damping^dt of the velocity per step: damping = (1 + dt c)^(-1/dt) gives the
    // scene's 1 / (1 + dt c).
    if (fx.damping) cpSpaceSetDamping(space_, std::pow(1 + scene.timeStep * damping, -1 / double(scene.timeStep)));

    timeStep_ = cpFloat(scene.timeStep);
    rotation_ = fx.rotation;

    bodies_.reserve(scene.bodies.size());
    fx_ = fx;
    damping_ = damping;
    dampingSet_ = dampingSet;
    bodies_.reserve(scene.bodies.size());
    shapes_.reserve(scene.bodies.size());
    for (const BodyDesc& desc : scene.bodies) MakeBody(desc, bodies_, shapes_);
    MakeJoints(scene.bodies, bodies_, scene.joints, constraints_);
    all_ = bodies_;
  }

  void CheckGroup(const Scene& scene, const BodyGroup& group) const override {
    // At Load the rate is the new scene's; during a run, the loaded one's.
    double rate = damping_;
    bool rateSet = dampingSet_;
    if (!scene.bodies.empty()) {
      rate = 0;
      rateSet = false;
      Refuse(scene.effects, scene.bodies, {}, rate, rateSet);
    }
    Refuse(scene.effects, group.bodies, group.joints, rate, rateSet);
  }

  void DoAddGroup(int group, const BodyGroup& desc) override {
    Owned& made = groups_[group];
    for (const BodyDesc& body : desc.bodies) MakeBody(body, made.bodies, made.shapes);
    MakeJoints(desc.bodies, made.bodies, desc.joints, made.constraints);
    all_.insert(all_.end(), made.bodies.begin(), made.bodies.end());  // the highest id so far: it goes last
  }

  void DoRemoveGroup(int group) override {
    auto it = groups_.find(group);
    Owned& made = it->second;
    // Constraints, then shapes, then bodies (Chipmunk wakes a sleeping body it removes).
    for (cpConstraint* c : made.constraints) {
      cpSpaceRemoveConstraint(space_, c);
      cpConstraintFree(c);
    }
    for (cpShape* s : made.shapes) {
      cpSpaceRemoveShape(space_, s);
      cpShapeFree(s);
    }
    for (cpBody* b : made.bodies) {
      cpSpaceRemoveBody(space_, b);
      cpBodyFree(b);
    }
    groups_.erase(it);
    all_ = bodies_;
    for (const auto& [id, g] : groups_) all_.insert(all_.end(), g.bodies.begin(), g.bodies.end());
  }

  void DoStep() override {
    if (hasty_) {
      cpHastySpaceStep(space_, timeStep_);
    } else {
      cpSpaceStep(space_, timeStep_);
    }
  }

  int BodyCount() const override { return static_cast<int>(all_.size()); }

  void ReadBodies(std::vector<BodyState>& out) const override {
    out.resize(all_.size());
    for (size_t i = 0; i < all_.size(); ++i) {
      const cpBody* body = all_[i];
      out[i].position = FromCp(cpBodyGetPosition(body));  // the origin, not the centre
      out[i].angle = Real(cpBodyGetAngle(body));
      out[i].velocity = FromCp(cpBodyGetVelocity(body));  // of the centre of gravity
      out[i].angularVelocity = Real(cpBodyGetAngularVelocity(body));
    }
  }

  int ContactCount() const override {
    // Every touching arbiter has a dynamic body (static pairs never collide), and sleeping
    // bodies keep their arbiters threaded, so walking the dynamic bodies finds them all; a
    // pair of dynamic bodies lists its arbiter twice, hence the set.
    std::unordered_set<const cpArbiter*> touching;
    for (cpBody* body : all_) {
      if (cpBodyGetType(body) != CP_BODY_TYPE_DYNAMIC) continue;
      cpBodyEachArbiter(
          body,
          [](cpBody*, cpArbiter* arbiter, void* data) {
            if (cpArbiterGetCount(arbiter) > 0) {
              static_cast<std::unordered_set<const cpArbiter*>*>(data)->insert(arbiter);
            }
          },
          &touching);
    }
    return static_cast<int>(touching.size());
  }

  void DoSetVelocity(int body, Vec2 velocity, Real angularVelocity) override {
    cpBody* b = all_[static_cast<size_t>(body)];
    // A static body with a velocity would act as a moving surface in Chipmunk's solver; Box2D
    // ignores velocities of static bodies, and so does every adapter.
    if (cpBodyGetType(b) == CP_BODY_TYPE_STATIC) return;
    cpBodySetVelocity(b, ToCp(velocity));  // also wakes a sleeping body
    // With rotation off the moment is infinite: a set spin would never stop, while every
    // engine keeps angular velocity at zero then (Quadrant's definition).
    cpBodySetAngularVelocity(b, rotation_ ? cpFloat(angularVelocity) : 0.0);
  }

 private:
  // What Chipmunk cannot run among these bodies and joints in a space of `fx`, as Unsupported;
  // with damping, the one space-wide rate they share (`rate`, `rateSet` carry it across calls).
  static void Refuse(const Effects& fx, const std::vector<BodyDesc>& bodies, const std::vector<JointDesc>& joints,
                     double& rate, bool& rateSet) {
    if (fx.continuous) throw Unsupported("chipmunk: no continuous collision detection");
    if (!fx.warmStarting) throw Unsupported("chipmunk: warm starting cannot be switched off");
    for (const JointDesc& d : joints) {
      if (d.kind == JointKind::kWheel) throw Unsupported("chipmunk: no wheel joint (a groove with a spring is not mapped)");
      if (d.kind == JointKind::kPrismatic && (d.enableMotor || d.enableSpring)) {
        throw Unsupported("chipmunk: a groove joint has no motor or spring along its axis");
      }
      if (d.kind == JointKind::kWeld && d.hertz > 0) throw Unsupported("chipmunk: a pivot cannot be soft (weld linear hertz)");
    }
    if (fx.damping) {
      for (const BodyDesc& b : bodies) {
        if (!b.dynamic) continue;
        const bool same = b.linearDamping == b.angularDamping && (!rateSet || double(b.linearDamping) == rate);
        if (!same) {
          throw Unsupported("chipmunk: damping is one space-wide rate for linear and angular motion; this scene's "
                            "bodies have different or unequal rates");
        }
        rate = double(b.linearDamping);
        rateSet = true;
      }
    }
  }

  // A scene body as a Chipmunk body and shape added to the space, owned by `bodies` and `shapes`.
  void MakeBody(const BodyDesc& desc, std::vector<cpBody*>& bodies_, std::vector<cpShape*>& shapes_) {
    const Effects& fx = fx_;
    cpBody* body;
    if (desc.dynamic) {
      const MassProperties mp = ComputeMassProperties(desc);
      body = cpBodyNew(cpFloat(mp.mass), fx.rotation ? cpFloat(mp.inertia) : INFINITY);
      // Chipmunk keeps the centre of gravity's world position fixed when the angle or the
      // centre changes, so the centre goes first, then the angle, then the origin position.
      cpBodySetCenterOfGravity(body, ToCp(mp.localCenter));
    } else if (desc.kinematic) {
      body = cpBodyNewKinematic();  // rotates about its origin: kinematic scene bodies are centred
    } else {
      body = cpBodyNewStatic();
    }
    bodies_.push_back(body);  // owned from here on, even if a later call throws
    cpBodySetAngle(body, cpFloat(desc.angle));
    cpBodySetPosition(body, ToCp(desc.position));
    if (desc.dynamic || desc.kinematic) {
      cpBodySetVelocity(body, ToCp(desc.velocity));
      cpBodySetAngularVelocity(body, fx.rotation ? cpFloat(desc.angularVelocity) : 0.0);
    }
    // Static bodies are placed before their shapes are added, which caches the shapes'
    // bounds once at the right transform; Chipmunk never reindexes static shapes itself.
    cpSpaceAddBody(space_, body);

    // One Chipmunk shape per scene shape (several for a compound body; the body's mass, centre
    // and inertia were set above from all of them).
    for (const ShapeDesc& sd : ShapesOf(desc)) {
      cpShape* shape;
      if (sd.shape == ShapeKind::kCircle) {
        shape = cpCircleShapeNew(body, cpFloat(sd.radius), ToCp(sd.center));
      } else if (sd.shape == ShapeKind::kCapsule) {
        // Chipmunk's segment with a radius is a capsule.
        shape = cpSegmentShapeNew(body, ToCp(sd.vertices[0]), ToCp(sd.vertices[1]), cpFloat(sd.radius));
      } else if (sd.shape == ShapeKind::kSegment) {
        shape = cpSegmentShapeNew(body, ToCp(sd.vertices[0]), ToCp(sd.vertices[1]), 0.0);
      } else if (sd.shape == ShapeKind::kChainSegment) {
        // Chipmunk's neighbours keep a body from catching on the joins, as the ghost vertices do,
        // but its segment stays two-sided: a body behind the chain collides with it there.
        shape = cpSegmentShapeNew(body, ToCp(sd.vertices[1]), ToCp(sd.vertices[2]), 0.0);
        cpSegmentShapeSetNeighbors(shape, ToCp(sd.vertices[0]), ToCp(sd.vertices[3]));
      } else {
        std::vector<cpVect> verts;
        verts.reserve(sd.vertices.size());
        for (Vec2 v : sd.vertices) verts.push_back(ToCp(v));
        shape = cpPolyShapeNew(body, static_cast<int>(verts.size()), verts.data(), cpTransformIdentity, 0.0);
      }
      shapes_.push_back(shape);
      cpShapeSetFriction(shape, fx.friction ? cpFloat(sd.friction) : 0.0);
      cpShapeSetElasticity(shape, fx.restitution ? cpFloat(sd.restitution) : 0.0);
      // Chipmunk's filter rule is Box2D's (each category in the other's mask), without a group.
      cpShapeSetFilter(shape, cpShapeFilterNew(CP_NO_GROUP, cpBitmask(desc.categoryBits), cpBitmask(desc.maskBits)));
      cpSpaceAddShape(space_, shape);
    }
    if (!desc.awake) cpBodySleep(body);  // after its shape: a sleeping body keeps its shapes' bounds
  }

  // The joints among `descs` (made as `bodies_`; joint indices index both), owned by `constraints_`.
  // Joints. Revolute: a pivot, and for the limit, motor and spring Chipmunk's rotary limit (on
  // the absolute angle difference, so offset by the one at load), simple motor (its rate drives
  // wA - wB: the scene's speed negated) and damped rotary spring (stiffness and damping from
  // hertz and damping ratio on the pair's reduced inertia). Prismatic: a groove on bodyA
  // between the limits (a long one without) and a rotary limit of zero width. Distance: a pin
  // joint (rod), a slide joint (rope), a damped spring. Weld: a pivot and a zero-width rotary
  void MakeJoints(const std::vector<BodyDesc>& descs, const std::vector<cpBody*>& bodies_, const std::vector<JointDesc>& joints,
                  std::vector<cpConstraint*>& constraints_) {
    for (const JointDesc& d : joints) {
      // A joint of two bodies that never move does nothing in any engine; Chipmunk aborts on its
      // infinite mass ("Unsolvable constraint"), so it is not made.
      if (!descs[size_t(d.bodyA)].dynamic && !descs[size_t(d.bodyB)].dynamic) continue;
      cpBody* a = bodies_[size_t(d.bodyA)];
      cpBody* b = bodies_[size_t(d.bodyB)];
      auto add = [&](cpConstraint* c) {
        constraints_.push_back(c);
        cpConstraintSetCollideBodies(c, d.collideConnected ? cpTrue : cpFalse);
        cpSpaceAddConstraint(space_, c);
        return c;
      };
      auto inertia = [&](int i) {
        const BodyDesc& bd = descs[size_t(i)];
        return bd.dynamic ? cpFloat(ComputeMassProperties(bd).inertia) : INFINITY;
      };
      auto mass = [&](int i) {
        const BodyDesc& bd = descs[size_t(i)];
        return bd.dynamic ? cpFloat(ComputeMassProperties(bd).mass) : INFINITY;
      };
      auto reduced = [](cpFloat x, cpFloat y) { return std::isinf(x) ? y : std::isinf(y) ? x : x * y / (x + y); };
      const cpFloat twoPi = 2 * 3.14159265358979323846;
      const cpFloat reference = cpFloat(descs[size_t(d.bodyB)].angle - descs[size_t(d.bodyA)].angle + d.referenceAngle);
      auto rotarySpring = [&](Real hertz, Real ratio) {
        const cpFloat i = reduced(inertia(d.bodyA), inertia(d.bodyB)), omega = twoPi * cpFloat(hertz);
        add(cpDampedRotarySpringNew(a, b, reference, i * omega * omega, 2 * cpFloat(ratio) * i * omega));
      };
      switch (d.kind) {
        case JointKind::kRevolute:
          add(cpPivotJointNew(a, b, ToCp(d.anchor)));
          if (d.enableLimit) add(cpRotaryLimitJointNew(a, b, reference + d.lowerAngle, reference + d.upperAngle));
          if (d.enableMotor) cpConstraintSetMaxForce(add(cpSimpleMotorNew(a, b, -cpFloat(d.motorSpeed))), cpFloat(d.maxMotorTorque));
          if (d.enableSpring && d.hertz > 0) rotarySpring(d.hertz, d.dampingRatio);
          break;
        case JointKind::kPrismatic: {
          const Vec2 axis = Normalize(d.axis);
          const Real lo = d.enableLimit ? d.lowerTranslation : Real(-1e4), hi = d.enableLimit ? d.upperTranslation : Real(1e4);
          const cpVect g1 = cpBodyWorldToLocal(a, ToCp(d.anchor + lo * axis));
          const cpVect g2 = cpBodyWorldToLocal(a, ToCp(d.anchor + hi * axis));
          add(cpGrooveJointNew(a, b, g1, g2, cpBodyWorldToLocal(b, ToCp(d.anchor))));
          add(cpRotaryLimitJointNew(a, b, reference, reference));
          break;
        }
        case JointKind::kDistance: {
          const cpVect pa = cpBodyWorldToLocal(a, ToCp(d.anchor)), pb = cpBodyWorldToLocal(b, ToCp(d.anchorB));
          const cpFloat rest = d.length > 0 ? cpFloat(d.length) : cpFloat(Length(d.anchorB - d.anchor));
          if (!d.enableSpring) {
            cpConstraint* pin = add(cpPinJointNew(a, b, pa, pb));
            cpPinJointSetDist(pin, rest);
            break;
          }
          if (d.hertz > 0) {
            const cpFloat m = reduced(mass(d.bodyA), mass(d.bodyB)), omega = twoPi * cpFloat(d.hertz);
            add(cpDampedSpringNew(a, b, pa, pb, rest, m * omega * omega, 2 * cpFloat(d.dampingRatio) * m * omega));
          }
          if (d.enableLimit) add(cpSlideJointNew(a, b, pa, pb, cpFloat(d.minLength), cpFloat(d.maxLength)));
          break;
        }
        case JointKind::kWeld:
          add(cpPivotJointNew(a, b, ToCp(d.anchor)));
          if (d.angularHertz > 0) {
            rotarySpring(d.angularHertz, d.angularDampingRatio);
          } else {
            add(cpRotaryLimitJointNew(a, b, reference, reference));
          }
          break;
        case JointKind::kWheel: break;  // refused before the world was touched
      }
    }
  }

  // The space does not own bodies or shapes; it must go first because freeing it wakes
  // every sleeping body, which touches them.
  void Release() {
    if (space_ != nullptr) {
      // Chipmunk 7.0.3's space teardown wakes sleeping components from inside its own body
      // iteration, which misses some of them and leaks the contacts they saved (found with
      // LeakSanitizer, two sleeping piles). Waking them here, outside any iteration, frees them.
      for (cpBody* b : all_) {
        if (cpBodyGetType(b) == CP_BODY_TYPE_DYNAMIC) cpBodyActivate(b);
      }
      if (hasty_) {
        cpHastySpaceFree(space_);
      } else {
        cpSpaceFree(space_);
      }
      space_ = nullptr;
    }
    for (cpConstraint* c : constraints_) cpConstraintFree(c);
    constraints_.clear();
    for (cpShape* s : shapes_) cpShapeFree(s);
    for (cpBody* b : bodies_) cpBodyFree(b);
    shapes_.clear();
    bodies_.clear();
    for (auto& [id, g] : groups_) {
      for (cpConstraint* c : g.constraints) cpConstraintFree(c);
      for (cpShape* s : g.shapes) cpShapeFree(s);
      for (cpBody* b : g.bodies) cpBodyFree(b);
    }
    groups_.clear();
    all_.clear();
  }

  cpSpace* space_ = nullptr;
  bool hasty_ = false;
  std::vector<cpBody*> bodies_;  // scene body index -> Chipmunk body (owned)
  std::vector<cpShape*> shapes_;  // owned
  std::vector<cpConstraint*> constraints_;  // owned
  struct Owned {
    std::vector<cpBody*> bodies;
    std::vector<cpShape*> shapes;
    std::vector<cpConstraint*> constraints;
  };
  std::map<int, Owned> groups_;  // live groups by id (AddGroup), owned
  std::vector<cpBody*> all_;     // the adapter's body order: scene bodies, then the groups'
  Effects fx_;
  double damping_ = 0;           // the space's one damping rate (1/s) and whether a body set it
  bool dampingSet_ = false;
  cpFloat timeStep_ = 1.0 / 60.0;
  bool rotation_ = true;
};

}  // namespace

std::unique_ptr<Adapter> MakeChipmunkAdapter() { return std::make_unique<ChipmunkAdapter>(); }

}  // namespace quadrant::scene
