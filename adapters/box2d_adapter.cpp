// The Box2D 2.4.1 adapter (Debian's libbox2d): the reference engine for validation.
//
// Everything is translated once in Load; Step is the driver plus one b2World::Step, so a timed
// loop measures Box2D and nothing of ours.
#include <box2d/box2d.h>

#include <cfloat>
#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "adapter.h"
#include "adapter_factories.h"
#include "quadrant/error.h"

namespace quadrant::scene {
namespace {

constexpr char kName[] = "box2d";

b2Vec2 ToB2(Vec2 v) { return {static_cast<float>(v.x), static_cast<float>(v.y)}; }
Vec2 FromB2(const b2Vec2& v) { return {Real(v.x), Real(v.y)}; }

// Box2D welds polygon vertices closer than half its linear slop and, if fewer than three are
// left, silently replaces the polygon by a 2 m box. Refuse such a polygon instead of
// simulating a different body.
void RequireWeldSafePolygon(const ShapeDesc& body, int index) {
  const float minDistance = 0.5f * b2_linearSlop;
  const size_t n = body.vertices.size();
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = i + 1; j < n; ++j) {
      b2Vec2 d = ToB2(body.vertices[j]) - ToB2(body.vertices[i]);
      if (d.LengthSquared() < minDistance * minDistance) {
        throw Unsupported("box2d: scene body " + std::to_string(index) +
                          " has polygon vertices closer than Box2D's weld distance (" +
                          std::to_string(minDistance) + " m)");
      }
    }
  }
}

class Box2dAdapter final : public Adapter {
 public:
  std::string Name() const override { return kName; }

  Capabilities Caps() const override {
    Capabilities caps;
    caps.maxThreads = 1;
    caps.threadLimit = "Box2D 2.4.1 is single-threaded";
    caps.sleep = true;
    caps.continuous = true;
    caps.disableRotation = true;
    caps.disableFriction = true;
    caps.disableWarmStarting = true;
    caps.damping = true;
    caps.notes =
        "Box2D 2.4.1 (Debian), single-threaded. Friction mixing sqrt(f1*f2), restitution "
        "mixing max(e1, e2); restitution threshold set per fixture from the scene (default "
        "1 m/s). Velocity/position iterations from the scene (defaults 8/3); scene pipeline repeats "
        "are ignored (one b2World::Step per step). Continuous physics (dynamic vs static TOI) "
        "follows the scene's continuous effect (Box2D's own default is on). Warm starting "
        "follows the scene. Polygons carry Box2D's 0.01 m skin (b2_polygonRadius), so they "
        "collide 0.01 m larger than the scene says; mass comes from density (exact, skin "
        "excluded). Sleep uses Box2D's defaults (0.5 s below 0.01 m/s and 2 deg/s). Rotation "
        "off = SetFixedRotation. Damping: the scene's per-body rates as b2BodyDef damping (the same law).";
    return caps;
  }

  void DoLoad(const Scene& scene, int /*threads: 1*/) override {
    // Refuse before touching the current world, so a refused Load leaves it usable.
    Refuse(scene.bodies, scene.joints, "scene");

    bodies_.clear();
    groups_.clear();
    all_.clear();
    world_.reset();

    fx_ = scene.effects;
    restitutionThreshold_ = static_cast<float>(scene.restitutionThreshold);
    const Effects& fx = fx_;
    world_ = std::make_unique<b2World>(fx.gravity ? ToB2(scene.gravity) : b2Vec2(0.0f, 0.0f));
    world_->SetAllowSleeping(fx.sleep);
    world_->SetWarmStarting(fx.warmStarting);
    world_->SetContinuousPhysics(fx.continuous);

    timeStep_ = static_cast<float>(scene.timeStep);
    velocityIterations_ = scene.velocityIterations;
    positionIterations_ = scene.positionIterations;
    rotation_ = fx.rotation;

    bodies_.reserve(scene.bodies.size());
    for (const BodyDesc& desc : scene.bodies) bodies_.push_back(MakeBody(desc));
    // Joints: each b2*JointDef::Initialize takes the world anchor (and axis) and the bodies'
    // angles at load as the reference, as the scene does. Springs in Box2D 2.4.1 are a stiffness
    // and a damping, from hertz and damping ratio on the pair's masses (b2LinearStiffness,
    // b2AngularStiffness).
    for (const JointDesc& d : scene.joints) MakeJoint(d, bodies_[size_t(d.bodyA)], bodies_[size_t(d.bodyB)]);
    all_ = bodies_;
  }

  void CheckGroup(const Scene& /*scene*/, const BodyGroup& group) const override { Refuse(group.bodies, group.joints, "group"); }

  void DoAddGroup(int group, const BodyGroup& desc) override {
    std::vector<b2Body*> made;
    made.reserve(desc.bodies.size());
    for (const BodyDesc& body : desc.bodies) made.push_back(MakeBody(body));
    for (const JointDesc& d : desc.joints) MakeJoint(d, made[size_t(d.bodyA)], made[size_t(d.bodyB)]);
    all_.insert(all_.end(), made.begin(), made.end());  // the highest id so far: it goes last
    groups_.emplace(group, std::move(made));
  }

  void DoRemoveGroup(int group) override {
    auto it = groups_.find(group);
    for (b2Body* body : it->second) world_->DestroyBody(body);  // its joints go with it
    groups_.erase(it);
    all_ = bodies_;
    for (const auto& [id, made] : groups_) all_.insert(all_.end(), made.begin(), made.end());
  }

  void DoStep() override { world_->Step(timeStep_, velocityIterations_, positionIterations_); }

  int BodyCount() const override { return static_cast<int>(all_.size()); }

  void ReadBodies(std::vector<BodyState>& out) const override {
    out.resize(all_.size());
    for (size_t i = 0; i < all_.size(); ++i) {
      const b2Body* body = all_[i];
      out[i].position = FromB2(body->GetPosition());
      out[i].angle = Real(body->GetAngle());
      out[i].velocity = FromB2(body->GetLinearVelocity());
      out[i].angularVelocity = Real(body->GetAngularVelocity());
    }
  }

  int ContactCount() const override {
    if (!world_) return 0;
    int touching = 0;
    for (const b2Contact* c = world_->GetContactList(); c != nullptr; c = c->GetNext()) {
      if (c->IsTouching()) ++touching;
    }
    return touching;
  }

  std::vector<ContactReadback> Contacts() const override {
    std::vector<ContactReadback> out;
    if (!world_) return out;
    // Scene indices by body; built per call, since this read-back is for validation only.
    std::unordered_map<const b2Body*, int> index;
    for (size_t i = 0; i < all_.size(); ++i) index[all_[i]] = static_cast<int>(i);
    for (const b2Contact* c = world_->GetContactList(); c != nullptr; c = c->GetNext()) {
      if (!c->IsTouching()) continue;
      const b2Manifold* m = c->GetManifold();
      b2WorldManifold wm;
      c->GetWorldManifold(&wm);
      ContactReadback r;
      r.bodyA = index.at(c->GetFixtureA()->GetBody());
      r.bodyB = index.at(c->GetFixtureB()->GetBody());
      r.normal = FromB2(wm.normal);
      r.pointCount = m->pointCount;
      for (int k = 0; k < m->pointCount && k < 2; ++k) {
        r.points[k] = FromB2(wm.points[k]);
        r.separations[k] = Real(wm.separations[k]);
        r.normalImpulses[k] = Real(m->points[k].normalImpulse);
        r.tangentImpulses[k] = Real(m->points[k].tangentImpulse);
      }
      out.push_back(r);
    }
    return out;
  }

  void DoSetVelocity(int body, Vec2 velocity, Real angularVelocity) override {
    // Box2D ignores velocities of static bodies; so does every adapter.
    b2Body* b = all_[static_cast<size_t>(body)];
    b->SetLinearVelocity(ToB2(velocity));
    // With rotation off every engine keeps angular velocity at zero (Quadrant's definition);
    // Box2D's fixed rotation would otherwise integrate a set angular velocity forever.
    b->SetAngularVelocity(rotation_ ? static_cast<float>(angularVelocity) : 0.0f);
  }

 private:
  // What Box2D 2.4.1 cannot run among these bodies and joints, as Unsupported ("scene body 3 ...").
  static void Refuse(const std::vector<BodyDesc>& bodies, const std::vector<JointDesc>& joints, const char* what) {
    for (int i = 0; i < static_cast<int>(bodies.size()); ++i) {
      for (const ShapeDesc& shape : ShapesOf(bodies[i])) {
        if (shape.shape == ShapeKind::kPolygon) RequireWeldSafePolygon(shape, i);
      }
      // With every category in 16 bits, a mask's upper bits never match one: Box2D's 16-bit
      // masks give the same pairs.
      if (bodies[i].categoryBits > 0xFFFFu) {
        throw Unsupported("Box2D 2.4.1's collision categories hold 16 bits; " + std::string(what) + " body " + std::to_string(i) + " uses more");
      }
    }
    for (const JointDesc& d : joints) {
      if (d.kind == JointKind::kRevolute && d.enableSpring) throw Unsupported("Box2D 2.4.1's revolute joint has no spring");
      if (d.kind == JointKind::kPrismatic && d.enableSpring) throw Unsupported("Box2D 2.4.1's prismatic joint has no spring");
      if (d.kind == JointKind::kWeld && d.hertz > 0) {
        throw Unsupported("Box2D 2.4.1's weld joint is soft only in its angle (linear hertz must be 0)");
      }
    }
  }

  // A scene body as a Box2D body, with the loaded scene's effects (fx_).
  b2Body* MakeBody(const BodyDesc& desc) {
    const Effects& fx = fx_;
    b2BodyDef def;
    def.type = desc.dynamic ? b2_dynamicBody : desc.kinematic ? b2_kinematicBody : b2_staticBody;
    def.position = ToB2(desc.position);
    def.angle = static_cast<float>(desc.angle);
    def.allowSleep = fx.sleep;
    def.awake = desc.awake;
    def.fixedRotation = !fx.rotation;
    // Box2D 2.4's damping law is the scene's own: 1 / (1 + dt c) per step.
    def.linearDamping = fx.damping ? static_cast<float>(desc.linearDamping) : 0.0f;
    def.angularDamping = fx.damping ? static_cast<float>(desc.angularDamping) : 0.0f;
    b2Body* body = world_->CreateBody(&def);

    // One fixture per scene shape (several for a compound body); a capsule is Box2D 2.4's
    // way: a box along its segment and a circle on each end, on one body, with the body's exact
    // mass set after (the three fixtures' own overlap).
    bool capsule = false;
    for (const ShapeDesc& shape : ShapesOf(desc)) {
      b2CircleShape circle;
      b2PolygonShape polygon;
      b2FixtureDef fixture;
      b2PolygonShape capsuleBox;
      b2CircleShape capsuleEnds[2];
      // Segments are b2EdgeShape: two-sided, or one-sided with its ghost vertices (v0, v3) for a
      // chain segment. Box2D 2.4.1's one-sided edge collides on the right of v1 -> v2, the
      // scene's convention, so the vertices pass in their order.
      b2EdgeShape edge;
      if (shape.shape == ShapeKind::kCircle) {
        circle.m_radius = static_cast<float>(shape.radius);
        circle.m_p = ToB2(shape.center);
        fixture.shape = &circle;
      } else if (shape.shape == ShapeKind::kSegment) {
        edge.SetTwoSided(ToB2(shape.vertices[0]), ToB2(shape.vertices[1]));
        fixture.shape = &edge;
      } else if (shape.shape == ShapeKind::kChainSegment) {
        edge.SetOneSided(ToB2(shape.vertices[0]), ToB2(shape.vertices[1]), ToB2(shape.vertices[2]), ToB2(shape.vertices[3]));
        fixture.shape = &edge;
      } else if (shape.shape == ShapeKind::kCapsule) {
        capsule = true;
        const Vec2 c1 = shape.vertices[0], c2 = shape.vertices[1];
        const Vec2 axis = c2 - c1;
        capsuleBox.SetAsBox(0.5f * static_cast<float>(Length(axis)), static_cast<float>(shape.radius),
                            ToB2(Real(0.5) * (c1 + c2)), std::atan2(static_cast<float>(axis.y), static_cast<float>(axis.x)));
        fixture.shape = &capsuleBox;
        for (int e = 0; e < 2; ++e) {
          capsuleEnds[e].m_radius = static_cast<float>(shape.radius);
          capsuleEnds[e].m_p = ToB2(shape.vertices[e]);
        }
      } else {
        std::vector<b2Vec2> points;
        points.reserve(shape.vertices.size());
        for (Vec2 v : shape.vertices) points.push_back(ToB2(v));
        polygon.Set(points.data(), static_cast<int32>(points.size()));
        fixture.shape = &polygon;
      }
      fixture.density = desc.dynamic ? static_cast<float>(shape.density) : 0.0f;
      fixture.friction = fx.friction ? static_cast<float>(shape.friction) : 0.0f;
      fixture.restitution = fx.restitution ? static_cast<float>(shape.restitution) : 0.0f;
      fixture.restitutionThreshold = static_cast<float>(restitutionThreshold_);
      fixture.filter.categoryBits = static_cast<uint16>(desc.categoryBits);
      fixture.filter.maskBits = static_cast<uint16>(desc.maskBits & 0xFFFFu);
      body->CreateFixture(&fixture);
      if (shape.shape == ShapeKind::kCapsule) {
        for (b2CircleShape& end : capsuleEnds) {
          fixture.shape = &end;
          body->CreateFixture(&fixture);
        }
      }
    }
    if (capsule && desc.dynamic) {
      const MassProperties mp = ComputeMassProperties(desc);
      b2MassData md;
      md.mass = static_cast<float>(mp.mass);
      md.center = ToB2(mp.localCenter);
      // Box2D's I is about the body origin.
      md.I = static_cast<float>(mp.inertia + mp.mass * Dot(mp.localCenter, mp.localCenter));
      body->SetMassData(&md);
    }

    // Set after the fixture: b2BodyDef's velocity would be taken as the origin's and shifted
    // when the centre of mass moves, while the scene gives the centre of mass's.
    if (desc.dynamic || desc.kinematic) {
      body->SetLinearVelocity(ToB2(desc.velocity));
      body->SetAngularVelocity(fx.rotation ? static_cast<float>(desc.angularVelocity) : 0.0f);
    }
    return body;
  }

  // A scene joint between two Box2D bodies.
  void MakeJoint(const JointDesc& d, b2Body* a, b2Body* b) {
    switch (d.kind) {
      case JointKind::kRevolute: {
        b2RevoluteJointDef jd;
        jd.Initialize(a, b, ToB2(d.anchor));
        jd.referenceAngle += static_cast<float>(d.referenceAngle);
        jd.collideConnected = d.collideConnected;
        jd.enableLimit = d.enableLimit;
        jd.lowerAngle = static_cast<float>(d.lowerAngle);
        jd.upperAngle = static_cast<float>(d.upperAngle);
        jd.enableMotor = d.enableMotor;
        jd.motorSpeed = static_cast<float>(d.motorSpeed);
        jd.maxMotorTorque = static_cast<float>(d.maxMotorTorque);
        world_->CreateJoint(&jd);
        break;
      }
      case JointKind::kPrismatic: {
        b2PrismaticJointDef jd;
        jd.Initialize(a, b, ToB2(d.anchor), ToB2(Normalize(d.axis)));
        jd.referenceAngle += static_cast<float>(d.referenceAngle);
        jd.collideConnected = d.collideConnected;
        jd.enableLimit = d.enableLimit;
        jd.lowerTranslation = static_cast<float>(d.lowerTranslation);
        jd.upperTranslation = static_cast<float>(d.upperTranslation);
        jd.enableMotor = d.enableMotor;
        jd.motorSpeed = static_cast<float>(d.motorSpeed);
        jd.maxMotorForce = static_cast<float>(d.maxMotorForce);
        world_->CreateJoint(&jd);
        break;
      }
      case JointKind::kDistance: {
        b2DistanceJointDef jd;
        jd.Initialize(a, b, ToB2(d.anchor), ToB2(d.anchorB));
        if (d.length > 0) jd.length = static_cast<float>(d.length);
        jd.collideConnected = d.collideConnected;
        if (d.enableSpring) {
          // Box2D 2.4.1 solves the spring (stiffness 0: none) between minLength and maxLength.
          jd.minLength = d.enableLimit ? static_cast<float>(d.minLength) : 0.0f;
          jd.maxLength = d.enableLimit ? static_cast<float>(d.maxLength) : FLT_MAX;
          jd.stiffness = jd.damping = 0.0f;
          if (d.hertz > 0) {
            b2LinearStiffness(jd.stiffness, jd.damping, static_cast<float>(d.hertz), static_cast<float>(d.dampingRatio), a, b);
          }
        } else {
          jd.minLength = jd.maxLength = jd.length;  // a rod: Box2D's rigid case
        }
        world_->CreateJoint(&jd);
        break;
      }
      case JointKind::kWeld: {
        b2WeldJointDef jd;
        jd.Initialize(a, b, ToB2(d.anchor));
        jd.referenceAngle += static_cast<float>(d.referenceAngle);
        jd.collideConnected = d.collideConnected;
        if (d.angularHertz > 0) {
          b2AngularStiffness(jd.stiffness, jd.damping, static_cast<float>(d.angularHertz),
                             static_cast<float>(d.angularDampingRatio), a, b);
        }
        world_->CreateJoint(&jd);
        break;
      }
      case JointKind::kWheel: {
        b2WheelJointDef jd;
        jd.Initialize(a, b, ToB2(d.anchor), ToB2(Normalize(d.axis)));
        jd.collideConnected = d.collideConnected;
        if (d.enableSpring) {
          b2LinearStiffness(jd.stiffness, jd.damping, static_cast<float>(d.hertz), static_cast<float>(d.dampingRatio), a, b);
        } else {
          jd.stiffness = jd.damping = 0.0f;
        }
        jd.enableLimit = d.enableLimit;
        jd.lowerTranslation = static_cast<float>(d.lowerTranslation);
        jd.upperTranslation = static_cast<float>(d.upperTranslation);
        jd.enableMotor = d.enableMotor;
        jd.motorSpeed = static_cast<float>(d.motorSpeed);
        jd.maxMotorTorque = static_cast<float>(d.maxMotorTorque);
        world_->CreateJoint(&jd);
        break;
      }
    }
  }

  std::unique_ptr<b2World> world_;  // owns every body and fixture
  std::vector<b2Body*> bodies_;     // scene body index -> Box2D body
  std::map<int, std::vector<b2Body*>> groups_;  // live groups by id (AddGroup)
  std::vector<b2Body*> all_;        // the adapter's body order: scene bodies, then the groups'
  Effects fx_;
  float restitutionThreshold_ = 1.0f;
  float timeStep_ = 1.0f / 60.0f;
  int velocityIterations_ = 8;
  int positionIterations_ = 3;
  bool rotation_ = true;
};

}  // namespace

std::unique_ptr<Adapter> MakeBox2dAdapter() { return std::make_unique<Box2dAdapter>(); }

}  // namespace quadrant::scene
