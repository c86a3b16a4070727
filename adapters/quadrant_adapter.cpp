// The Quadrant adapter: a scene becomes a World once, at load time. Which world (solver, broad
// phase, scheme, the soft_step budget) is quadrant_variant.cpp's policy; this file translates.
#include <algorithm>
#include <map>
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
    Refuse(def, scene.bodies, scene.joints);
    auto world = std::make_unique<World>(def);
    std::vector<BodyId> ids;
    // userData: the scene index, for Contacts()
    CreateBodiesAndJoints(*world, scene.bodies, scene.joints, 0, ids);
    world_ = std::move(world);
    ids_ = std::move(ids);
    groups_.clear();
    scene_ = &scene;
    dt_ = scene.timeStep;
    pipelineRepeats_ = scene.pipelineRepeats;
    totals_ = Profile{};
  }

  void CheckGroup(const Scene& scene, const BodyGroup& group) const override {
    if (scene.effects.sleep && v_.scheme == ParallelScheme::kQuadrants) {
      throw Unsupported("quadrant's quadrants scheme has no sleeping (the deterministic scheme has)");
    }
    Refuse(v_.MakeWorldDef(scene, 1), group.bodies, group.joints);
  }

  void DoAddGroup(int group, const BodyGroup& desc) override {
    // CreateBody and the joints' Create* validate before adding anything, and ValidateGroup ran
    // the engine's own rules: a throw here would be a bug, and the bodies made so far go again.
    std::vector<BodyId> ids;
    try {
      // userData: group + 1 and the index in it, for Contacts()
      CreateBodiesAndJoints(*world_, desc.bodies, desc.joints, (uint64_t(group) + 1) << 32, ids);
    } catch (...) {
      for (BodyId id : ids) world_->DestroyBody(id);
      throw;
    }
    groups_.emplace(group, std::move(ids));
  }

  void DoRemoveGroup(int group) override {
    auto it = groups_.find(group);
    for (BodyId id : it->second) world_->DestroyBody(id);  // their joints go with them
    groups_.erase(it);
  }

  void DoStep() override {
    world_->StepRepeated(dt_, pipelineRepeats_);
    totals_ += world_->GetProfile();
  }

  std::vector<std::pair<std::string, double>> StageTotals() const override {
    std::vector<std::pair<std::string, double>> out = {
        {"broad_phase", totals_.broadPhase}, {"narrow_phase", totals_.narrowPhase},
        {"persistence", totals_.persistence}, {"solve", totals_.solve},
        {"integrate", totals_.integrate},     {"total", totals_.total},
        // Steps on the one-thread path, and of those the ones too small to split (Profile).
        {"steps_alone", double(totals_.aloneSteps)}, {"steps_small", double(totals_.smallSteps)}};
    // Load balance: thread CPU work and critical path per stage (see StageRunner).
    for (size_t k = 0; k < kStageCount; ++k) {
      out.push_back({std::string("work_") + kStageNames[k], totals_.balance[k].workMs});
      out.push_back({std::string("critical_") + kStageNames[k], totals_.balance[k].criticalMs});
    }
    return out;
  }

  int BodyCount() const override { return world_ ? world_->GetBodyCount() : 0; }

  // Scene bodies, then each live group's (adapter.h's order).
  void ReadBodies(std::vector<BodyState>& out) const override {
    out.clear();
    out.reserve(size_t(BodyCount()));
    auto read = [&](BodyId id) {
      out.push_back({world_->GetPosition(id), world_->GetAngle(id), world_->GetLinearVelocity(id), world_->GetAngularVelocity(id)});
    };
    for (BodyId id : ids_) read(id);
    for (const auto& [group, ids] : groups_) {
      for (BodyId id : ids) read(id);
    }
  }

  int ContactCount() const override { return world_ ? world_->GetCounters().touchingContacts : 0; }

  // Every manifold the world keeps, speculative ones (separation > 0) included.
  std::vector<ContactReadback> Contacts() const override {
    std::vector<ContactReadback> out;
    if (!world_) return out;
    // Each body carries its scene index as user data (DoLoad), a group's body its group + 1 in
    // the upper half and its index in the group in the lower (DoAddGroup).
    std::map<uint64_t, int> groupOffset;
    int offset = int(ids_.size());
    for (const auto& [group, ids] : groups_) {
      groupOffset[uint64_t(group) + 1] = offset;
      offset += int(ids.size());
    }
    auto sceneIndex = [&](BodyId id) {
      const uint64_t data = world_->GetUserData(id);
      if ((data >> 32) == 0) return static_cast<int>(data);
      return groupOffset.at(data >> 32) + static_cast<int>(data & 0xFFFFFFFFu);
    };
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
    const BodyId id = BodyAt(body);
    world_->SetLinearVelocity(id, velocity);
    world_->SetAngularVelocity(id, angularVelocity);
  }

  uint64_t StateHash() const override { return world_ ? world_->StateHash() : 0; }

  World* GetWorld() { return world_.get(); }

 private:
  // The body at a valid index, in adapter.h's order.
  BodyId BodyAt(int index) const {
    if (size_t(index) < ids_.size()) return ids_[size_t(index)];
    size_t rest = size_t(index) - ids_.size();
    for (const auto& [group, ids] : groups_) {
      if (rest < ids.size()) return ids[rest];
      rest -= ids.size();
    }
    return {};  // not reached: Adapter::SetVelocity checked the index
  }

  // What a world of `def` cannot run among these bodies and joints, as Unsupported.
  static void Refuse(const WorldDef& def, const std::vector<BodyDesc>& bodies, const std::vector<JointDesc>& joints) {
    if (!joints.empty() && (def.solver != SolverType::kSoftStep || def.scheme != ParallelScheme::kDeterministic)) {
      throw Unsupported("joints are solved by quadrant's soft_step solver with the deterministic scheme only");
    }
    if (def.scheme == ParallelScheme::kQuadrants) {
      for (const BodyDesc& b : bodies) {
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
  }

  // The bodies (userData = userDataBase | index) into `ids`, in order, then the joints between them.
  static void CreateBodiesAndJoints(World& world, const std::vector<BodyDesc>& bodies, const std::vector<JointDesc>& joints,
                                    uint64_t userDataBase, std::vector<BodyId>& ids) {
    ids.reserve(bodies.size());
    for (size_t i = 0; i < bodies.size(); ++i) {
      BodyDef bd = ToBodyDef(bodies[i]);
      bd.userData = userDataBase | i;
      ids.push_back(world.CreateBody(bd));
    }
    CreateJoints(world, ids, bodies, joints);
  }

  // The joints among `bodies` (made as `ids`; joint indices index both).
  static void CreateJoints(World& world, const std::vector<BodyId>& ids, const std::vector<BodyDesc>& bodies,
                           const std::vector<JointDesc>& joints) {
    World* const w = &world;
    for (const JointDesc& d : joints) {
      const BodyId a = ids[size_t(d.bodyA)], b = ids[size_t(d.bodyB)];
      const Real reference = bodies[size_t(d.bodyB)].angle - bodies[size_t(d.bodyA)].angle + d.referenceAngle;
      const Vec2 axisA = InvRotate(w->GetRotation(a), d.axis);  // the axis in bodyA's frame
      // The fields every definition has: the bodies, the anchor (one world point) and the filter.
      auto common = [&](auto& j) {
        j.bodyA = a;
        j.bodyB = b;
        j.localAnchorA = w->GetLocalPoint(a, d.anchor);
        j.localAnchorB = w->GetLocalPoint(b, d.anchor);
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
          w->CreateRevoluteJoint(j);
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
          w->CreatePrismaticJoint(j);
          break;
        }
        case JointKind::kDistance: {
          DistanceJointDef j;
          common(j);
          j.localAnchorB = w->GetLocalPoint(b, d.anchorB);
          j.length = d.length > 0 ? d.length : Length(d.anchorB - d.anchor);
          j.enableSpring = d.enableSpring;
          j.hertz = d.hertz;
          j.dampingRatio = d.dampingRatio;
          j.enableLimit = d.enableLimit;
          j.minLength = d.minLength;
          j.maxLength = d.maxLength;
          w->CreateDistanceJoint(j);
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
          w->CreateWeldJoint(j);
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
          w->CreateWheelJoint(j);
          break;
        }
      }
    }
  }

  std::string variant_;
  QuadrantVariant v_;
  static constexpr int kMaxThreads = 64;

  std::unique_ptr<World> world_;
  std::vector<BodyId> ids_;                      ///< the scene's bodies
  std::map<int, std::vector<BodyId>> groups_;    ///< live groups by id (AddGroup)
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
