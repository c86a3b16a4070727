// The Quadrant adapter: a scene becomes a World once, at load time. Which world (solver, broad
// phase, scheme, the soft_step budget) is quadrant_variant.cpp's policy; this file translates.
#include <algorithm>
#include <string>

#include "adapter_factories.h"
#include "quadrant_variant.h"
#include "quadrant/world.h"

namespace quadrant::scene {
namespace {

class QuadrantAdapter final : public Adapter {
 public:
  explicit QuadrantAdapter(std::string_view variant) : variant_(variant), v_(QuadrantVariant::Parse(variant)) {}

  std::string Name() const override { return variant_.empty() ? "quadrant" : "quadrant:" + variant_; }

  Capabilities Caps() const override {
    Capabilities c;
    c.maxThreads = kMaxThreads;
    c.threadLimit = "WorldDef.threadCount is at most 64";
    c.disableRotation = true;
    c.disableFriction = true;
    c.disableWarmStarting = true;
    c.continuous = true;
    c.sleep = v_.scheme == ParallelScheme::kDeterministic;
    c.notes = v_.Describe() +
              "; friction sqrt(f1*f2), restitution max(e1,e2) as Box2D; speculative contacts 0.02 m; "
              "no polygon skin; continuous collision = velocity-swept speculative contacts (scene flag); "
              "sleep: islands over contacts, 0.5 s below 0.01 m/s and 2 deg/s (Box2D 2.4's values), a "
              "sleeping body reads back velocity 0; scheme " + (v_.scheme == ParallelScheme::kQuadrants ? "quadrants" : "deterministic");
    return c;
  }

  void DoLoad(const Scene& scene, int threads) override {
    if (scene.effects.sleep && v_.scheme == ParallelScheme::kQuadrants) {
      throw Unsupported("quadrant's quadrants scheme has no sleeping (the deterministic scheme has)");
    }
    const WorldDef def = v_.MakeWorldDef(scene, threads);
    if (!scene.joints.empty() && (def.solver != SolverType::kSoftStep || def.scheme != ParallelScheme::kDeterministic)) {
      throw Unsupported("joints are solved by quadrant's soft_step solver with the deterministic scheme only");
    }
    if (def.scheme == ParallelScheme::kQuadrants) {
      for (const BodyDesc& b : scene.bodies) {
        if (b.categoryBits != 1 || b.maskBits != 0xFFFFFFFFu) {
          throw Unsupported("quadrant's quadrants scheme has no collision filters (the deterministic scheme has)");
        }
        if (b.shape == ShapeKind::kSegment || b.shape == ShapeKind::kChainSegment) {
          throw Unsupported("quadrant's quadrants scheme has no segments (the deterministic scheme has)");
        }
        if (!b.extraShapes.empty()) {
          throw Unsupported("quadrant's quadrants scheme has no compound bodies (the deterministic scheme has)");
        }
      }
    }
    auto world = std::make_unique<World>(def);
    std::vector<BodyId> ids;
    ids.reserve(scene.bodies.size());
    for (size_t i = 0; i < scene.bodies.size(); ++i) {
      BodyDef bd = ToBodyDef(scene.bodies[i]);
      bd.userData = i;  // the scene index, for Contacts()
      ids.push_back(world->CreateBody(bd));
    }
    for (const JointDesc& d : scene.joints) {
      const BodyId a = ids[size_t(d.bodyA)], b = ids[size_t(d.bodyB)];
      const Real reference = scene.bodies[size_t(d.bodyB)].angle - scene.bodies[size_t(d.bodyA)].angle;
      const Vec2 axisA = InvRotate(world->GetRotation(a), d.axis);  // the axis in bodyA's frame
      // The fields every definition has: the bodies, the anchor (one world point) and the filter.
      auto common = [&](auto& j) {
        j.bodyA = a;
        j.bodyB = b;
        j.localAnchorA = world->GetLocalPoint(a, d.anchor);
        j.localAnchorB = world->GetLocalPoint(b, d.anchor);
        j.collideConnected = d.collideConnected;
      };
      switch (d.kind) {
        case JointKind::kRevolute: {
          RevoluteJointDef j;
          common(j);
          j.referenceAngle = reference;
          j.enableLimit = d.enableLimit;
          j.lowerAngle = d.lowerAngle;
          j.upperAngle = d.upperAngle;
          j.enableMotor = d.enableMotor;
          j.motorSpeed = d.motorSpeed;
          j.maxMotorTorque = d.maxMotorTorque;
          j.enableSpring = d.enableSpring;
          j.hertz = d.hertz;
          j.dampingRatio = d.dampingRatio;
          world->CreateRevoluteJoint(j);
          break;
        }
        case JointKind::kPrismatic: {
          PrismaticJointDef j;
          common(j);
          j.localAxisA = axisA;
          j.referenceAngle = reference;
          j.enableLimit = d.enableLimit;
          j.lowerTranslation = d.lowerTranslation;
          j.upperTranslation = d.upperTranslation;
          j.enableMotor = d.enableMotor;
          j.motorSpeed = d.motorSpeed;
          j.maxMotorForce = d.maxMotorForce;
          j.enableSpring = d.enableSpring;
          j.hertz = d.hertz;
          j.dampingRatio = d.dampingRatio;
          world->CreatePrismaticJoint(j);
          break;
        }
        case JointKind::kDistance: {
          DistanceJointDef j;
          common(j);
          j.localAnchorB = world->GetLocalPoint(b, d.anchorB);
          j.length = d.length > 0 ? d.length : Length(d.anchorB - d.anchor);
          j.enableSpring = d.enableSpring;
          j.hertz = d.hertz;
          j.dampingRatio = d.dampingRatio;
          j.enableLimit = d.enableLimit;
          j.minLength = d.minLength;
          j.maxLength = d.maxLength;
          world->CreateDistanceJoint(j);
          break;
        }
        case JointKind::kWeld: {
          WeldJointDef j;
          common(j);
          j.referenceAngle = reference;
          j.linearHertz = d.hertz;
          j.linearDampingRatio = d.dampingRatio;
          j.angularHertz = d.angularHertz;
          j.angularDampingRatio = d.angularDampingRatio;
          world->CreateWeldJoint(j);
          break;
        }
        case JointKind::kWheel: {
          WheelJointDef j;
          common(j);
          j.localAxisA = axisA;
          j.enableSpring = d.enableSpring;
          j.hertz = d.hertz;
          j.dampingRatio = d.dampingRatio;
          j.enableLimit = d.enableLimit;
          j.lowerTranslation = d.lowerTranslation;
          j.upperTranslation = d.upperTranslation;
          j.enableMotor = d.enableMotor;
          j.motorSpeed = d.motorSpeed;
          j.maxMotorTorque = d.maxMotorTorque;
          world->CreateWheelJoint(j);
          break;
        }
      }
    }
    world_ = std::move(world);
    ids_ = std::move(ids);
    scene_ = &scene;
    dt_ = scene.timeStep;
    pipelineRepeats_ = scene.pipelineRepeats;
    totals_ = Profile{};
  }

  void DoStep() override {
    world_->StepRepeated(dt_, pipelineRepeats_);
    totals_ += world_->GetProfile();
  }

  std::vector<std::pair<std::string, double>> StageTotals() const override {
    std::vector<std::pair<std::string, double>> out = {
        {"broad_phase", totals_.broadPhase}, {"narrow_phase", totals_.narrowPhase},
        {"persistence", totals_.persistence}, {"solve", totals_.solve},
        {"integrate", totals_.integrate},     {"total", totals_.total}};
    // Load balance: thread CPU work and critical path per stage (see StageRunner).
    for (size_t k = 0; k < kStageCount; ++k) {
      out.push_back({std::string("work_") + kStageNames[k], totals_.balance[k].workMs});
      out.push_back({std::string("critical_") + kStageNames[k], totals_.balance[k].criticalMs});
    }
    return out;
  }

  int BodyCount() const override { return world_ ? world_->GetBodyCount() : 0; }

  void ReadBodies(std::vector<BodyState>& out) const override {
    out.resize(ids_.size());
    for (size_t i = 0; i < ids_.size(); ++i) {
      out[i] = {world_->GetPosition(ids_[i]), world_->GetAngle(ids_[i]), world_->GetLinearVelocity(ids_[i]),
                world_->GetAngularVelocity(ids_[i])};
    }
  }

  int ContactCount() const override { return world_ ? world_->GetCounters().touchingContacts : 0; }

  // Every manifold the world keeps, speculative ones (separation > 0) included.
  std::vector<ContactReadback> Contacts() const override {
    std::vector<ContactReadback> out;
    if (!world_) return out;
    // Each body carries its scene index as user data (DoLoad).
    auto sceneIndex = [&](BodyId id) { return static_cast<int>(world_->GetUserData(id)); };
    for (const ContactInfo& c : world_->GetContacts()) {
      ContactReadback r;
      r.bodyA = sceneIndex(c.bodyA);
      r.bodyB = sceneIndex(c.bodyB);
      r.normal = c.normal;
      r.pointCount = c.pointCount;
      for (int k = 0; k < c.pointCount && k < 2; ++k) {
        r.points[k] = c.points[k];
        r.separations[k] = c.separations[k];
        r.normalImpulses[k] = c.normalImpulses[k];
        r.tangentImpulses[k] = c.tangentImpulses[k];
      }
      out.push_back(r);
    }
    return out;
  }

  void DoSetVelocity(int body, Vec2 velocity, Real angularVelocity) override {
    world_->SetLinearVelocity(ids_[body], velocity);
    world_->SetAngularVelocity(ids_[body], angularVelocity);
  }

  uint64_t StateHash() const override { return world_ ? world_->StateHash() : 0; }

  World* GetWorld() { return world_.get(); }

 private:
  std::string variant_;
  QuadrantVariant v_;
  static constexpr int kMaxThreads = 64;

  std::unique_ptr<World> world_;
  std::vector<BodyId> ids_;
  const Scene* scene_ = nullptr;
  Real dt_ = Real(1.0 / 60.0);
  int pipelineRepeats_ = 1;
  Profile totals_;
};

}  // namespace

std::unique_ptr<Adapter> MakeQuadrantAdapter(std::string_view variant) {
  return std::make_unique<QuadrantAdapter>(variant);
}

}  // namespace quadrant::scene
