// The Quadrant adapter: a scene becomes a World once, at load time.
//
// Variants ("quadrant:<tokens>", tokens joined by '+'): solver "thesis" or "pgs", broad phase
// "quadtree" or "grid", parallel scheme "deterministic" or "quadrants", "b2rest" for Box2D 2.4.1's
// restitution (RestitutionPolicy::kBox2d, pgs only), "b2skin" for its 0.01 m polygon skin
// (WorldDef::polygonSkin), "coupled" for the thesis solver's coupled impulse
// (WorldDef::thesisCoupledImpulse). The default is pgs with
// the uniform grid and the deterministic scheme, the combination the suite measured fastest
// on the stress scenes (see README).
//
// Solver budget for soft_step: a scene states the budget a case needs as pgs velocity
// iterations (Box2D 2.4's default 8; 16 or 32 in the hard cases that need more). Box2D 3 spends
// its default on 4 sub-steps, so soft_step gets velocityIterations / 2 sub-steps (4 at the
// default) and its contact stiffness scales with them (30 Hz at 4 sub-steps, 60 Hz at 8): each
// sub-step then holds its contacts exactly as soft as a default sub-step (the soft
// coefficients depend on hertz x sub-step, which stays 30 Hz / 240 Hz), so a larger budget is the
// default solver on a finer sub-step, not a different spring. Why both: more sub-steps alone do not
// stop a soft contact's sag, load / (m_eff (2 pi hertz)^2), which does not depend on the
// sub-step (mass_ratio_400 at 16 sub-steps and 30 Hz: 0.085 m, limit 0.02); and at 8 sub-steps
// and 30 Hz the 15-box stack's top slid 0.16 m (at 60 Hz: 0.0003 m). sub<N> sets the sub-steps
// explicitly and leaves the stiffness at the engine's default.
#include <algorithm>
#include <string>

#include "adapter_factories.h"
#include "quadrant/world.h"

namespace quadrant::scene {
namespace {

class QuadrantAdapter final : public Adapter {
 public:
  explicit QuadrantAdapter(std::string_view variant) : variant_(variant) {
    size_t start = 0;
    while (start <= variant.size() && !variant.empty()) {
      size_t end = variant.find('+', start);
      std::string_view token = variant.substr(start, end == std::string_view::npos ? std::string_view::npos : end - start);
      if (token == "thesis") {
        solver_ = SolverType::kThesis;
      } else if (token == "pgs") {
        solver_ = SolverType::kPgs;
      } else if (token == "soft_step") {
        solver_ = SolverType::kSoftStep;
      } else if (token.size() > 3 && token.starts_with("sub") && ParseCount(token.substr(3), &softSubSteps_)) {
      } else if (token.size() > 2 && token.starts_with("it") && ParseCount(token.substr(2), &iterations_)) {
      } else if (token.size() > 3 && token.starts_with("pos") && ParseCount(token.substr(3), &positionIterations_)) {
      } else if (token.size() > 5 && token.starts_with("relax") && ParseCount(token.substr(5), &relaxIterations_)) {
        // soft_step's WorldDef::softRelaxIterations.
      } else if (token.size() > 5 && token.starts_with("ratio") && ParseCount(token.substr(5), &massRatioLimit_)) {
        // soft_step's WorldDef::softMassRatioLimit (issue #13 item 3: a heavy body on a light one).
      } else if (token == "b2rest") {
        restitution_ = RestitutionPolicy::kBox2d;
      } else if (token == "coupled") {
        thesisCoupled_ = true;
      } else if (token == "b2skin") {
        polygonSkin_ = Real(0.01);  // Box2D 2.4.1's b2_polygonRadius
      } else if (token == "quadtree") {
        broadPhase_ = BroadPhaseType::kQuadTree;
      } else if (token == "grid") {
        broadPhase_ = BroadPhaseType::kUniformGrid;
      } else if (token == "deterministic") {
        scheme_ = ParallelScheme::kDeterministic;
      } else if (token == "quadrants") {
        scheme_ = ParallelScheme::kQuadrants;
      } else {
        throw Error("unknown quadrant variant '" + std::string(token) + "' (known: thesis, pgs, soft_step, quadtree, grid, deterministic, quadrants, sub<N>, it<N>, pos<N>, relax<N>, ratio<N>, b2rest, b2skin, coupled)");
      }
      if (end == std::string_view::npos) break;
      start = end + 1;
    }
  }

  std::string Name() const override { return variant_.empty() ? "quadrant" : "quadrant:" + variant_; }

  Capabilities Caps() const override {
    Capabilities c;
    c.maxThreads = kMaxThreads;
    c.disableRotation = true;
    c.disableFriction = true;
    c.disableWarmStarting = true;
    c.continuous = true;
    c.sleep = scheme_ == ParallelScheme::kDeterministic;
    c.notes = std::string("solver ") +
              (solver_ == SolverType::kThesis ? "thesis" : solver_ == SolverType::kPgs ? "pgs" : "soft_step") +
              ", broad phase " + (broadPhase_ == BroadPhaseType::kQuadTree ? "quad-tree" : "uniform grid") +
              "; friction sqrt(f1*f2), restitution max(e1,e2) as Box2D; speculative contacts 0.02 m; "
              "no polygon skin; continuous collision = velocity-swept speculative contacts (scene flag); "
              "sleep: islands over contacts, 0.5 s below 0.01 m/s and 2 deg/s (Box2D 2.4's values), a "
              "sleeping body reads back velocity 0; scheme " + (scheme_ == ParallelScheme::kQuadrants ? "quadrants" : "deterministic");
    return c;
  }

  void Load(const Scene& scene, int threads) override {
    ValidateScene(scene);
    if (threads < 1 || threads > kMaxThreads) throw Error("quadrant: threads must be in [1, 64]");
    if (scene.effects.sleep && scheme_ == ParallelScheme::kQuadrants) {
      throw Unsupported("quadrant's quadrants scheme has no sleeping (the deterministic scheme has)");
    }
    WorldDef def;
    def.gravity = scene.gravity;
    def.solver = solver_;
    def.broadPhase = broadPhase_;
    def.velocityIterations = iterations_ > 0 ? iterations_ : scene.velocityIterations;
    if (softSubSteps_ > 0) {
      def.softSubSteps = softSubSteps_;
    } else if (solver_ == SolverType::kSoftStep) {
      def.softSubSteps = std::max(1, def.velocityIterations / 2);
      def.contactHertz = WorldDef{}.contactHertz * Real(def.softSubSteps) / Real(WorldDef{}.softSubSteps);
    }
    def.positionIterations = positionIterations_ > 0 ? positionIterations_ : scene.positionIterations;
    def.softMassRatioLimit = Real(massRatioLimit_);
    if (relaxIterations_ > 0) def.softRelaxIterations = relaxIterations_;
    def.restitutionThreshold = scene.restitutionThreshold;
    def.restitution = restitution_;
    def.polygonSkin = polygonSkin_;
    def.thesisCoupledImpulse = thesisCoupled_;
    def.threadCount = threads;
    def.scheme = scheme_;
    def.effects.gravity = scene.effects.gravity;
    def.effects.friction = scene.effects.friction;
    def.effects.restitution = scene.effects.restitution;
    def.effects.rotation = scene.effects.rotation;
    def.effects.warmStarting = scene.effects.warmStarting;
    def.effects.continuous = scene.effects.continuous;
    def.effects.damping = scene.effects.damping;
    def.effects.sleep = scene.effects.sleep;  // Box2D 2.4's tolerances: the WorldDef defaults
    auto world = std::make_unique<World>(def);
    std::vector<BodyId> ids;
    ids.reserve(scene.bodies.size());
    for (const BodyDesc& b : scene.bodies) {
      BodyDef bd;
      bd.type = b.dynamic ? BodyType::kDynamic : b.kinematic ? BodyType::kKinematic : BodyType::kStatic;
      bd.position = b.position;
      bd.angle = b.angle;
      bd.linearVelocity = b.velocity;
      bd.angularVelocity = b.angularVelocity;
      bd.linearDamping = b.linearDamping;  // the engine applies them only with effects.damping
      bd.angularDamping = b.angularDamping;
      bd.shape = b.shape == ShapeKind::kCircle ? ShapeDef::MakeCircle(b.radius) : ShapeDef::FromPolygon(MakePolygon(b.vertices));
      bd.shape.density = b.density;
      bd.shape.friction = b.friction;
      bd.shape.restitution = b.restitution;
      ids.push_back(world->CreateBody(bd));
    }
    world_ = std::move(world);
    ids_ = std::move(ids);
    scene_ = &scene;
    dt_ = scene.timeStep;
    subSteps_ = scene.subSteps;
    driver_ = scene.driver;
    step_ = 0;
    totals_ = Profile{};
  }

  void Step() override {
    if (!world_) throw Error("quadrant: Step before Load");
    if (driver_) driver_(step_, *this);
    world_->Step(dt_, subSteps_);
    const Profile& p = world_->GetProfile();
    totals_.broadPhase += p.broadPhase;
    totals_.narrowPhase += p.narrowPhase;
    totals_.persistence += p.persistence;
    totals_.solve += p.solve;
    totals_.integrate += p.integrate;
    totals_.total += p.total;
    for (size_t k = 0; k < kStageCount; ++k) {
      totals_.balance[k].workMs += p.balance[k].workMs;
      totals_.balance[k].criticalMs += p.balance[k].criticalMs;
    }
    ++step_;
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
    auto sceneIndex = [this](BodyId id) {
      for (size_t i = 0; i < ids_.size(); ++i) {
        if (ids_[i] == id) return static_cast<int>(i);
      }
      return -1;
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

  void SetVelocity(int body, Vec2 velocity, Real angularVelocity) override {
    if (body < 0 || body >= static_cast<int>(ids_.size())) throw Error("SetVelocity: body index out of range");
    // Both checked before either is set, so a refused call changes nothing.
    if (!IsFinite(velocity) || !IsFinite(angularVelocity)) throw Error("SetVelocity: velocity is not finite");
    world_->SetLinearVelocity(ids_[body], velocity);
    world_->SetAngularVelocity(ids_[body], angularVelocity);
  }

  uint64_t StateHash() const override { return world_ ? world_->StateHash() : 0; }

  World* GetWorld() { return world_.get(); }

 private:
  std::string variant_;
  SolverType solver_ = SolverType::kPgs;
  RestitutionPolicy restitution_ = RestitutionPolicy::kCollisions;
  Real polygonSkin_ = 0;
  bool thesisCoupled_ = false;
  BroadPhaseType broadPhase_ = BroadPhaseType::kUniformGrid;
  ParallelScheme scheme_ = ParallelScheme::kDeterministic;
  int softSubSteps_ = 0;  // 0: the engine's default
  int massRatioLimit_ = 0;  // 0: off (WorldDef::softMassRatioLimit)
  int relaxIterations_ = 0;  // 0: the engine's default (WorldDef::softRelaxIterations)
  int iterations_ = 0;    // 0: the scene's
  int positionIterations_ = 0;  // 0: the scene's
  static constexpr int kMaxThreads = 64;

  static bool ParseCount(std::string_view digits, int* out) {
    int value = 0;
    for (char ch : digits) {
      if (ch < '0' || ch > '9' || value > 1000) return false;
      value = value * 10 + (ch - '0');
    }
    if (value < 1) return false;
    *out = value;
    return true;
  }
  std::unique_ptr<World> world_;
  std::vector<BodyId> ids_;
  const Scene* scene_ = nullptr;
  Driver driver_;
  Real dt_ = Real(1.0 / 60.0);
  int subSteps_ = 1;
  int step_ = 0;
  Profile totals_;
};

}  // namespace

std::unique_ptr<Adapter> MakeQuadrantAdapter(std::string_view variant) {
  return std::make_unique<QuadrantAdapter>(variant);
}

}  // namespace quadrant::scene
