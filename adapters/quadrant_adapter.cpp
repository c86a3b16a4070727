// The Quadrant adapter: a scene becomes a World once, at load time.
//
// Variants ("quadrant:<tokens>", tokens joined by '+'): solver "thesis" or "pgs", broad phase
// "quadtree" or "grid". The default is pgs with the uniform grid, the combination the suite
// measured fastest on the stress scenes (see README).
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
      } else if (token == "quadtree") {
        broadPhase_ = BroadPhaseType::kQuadTree;
      } else if (token == "grid") {
        broadPhase_ = BroadPhaseType::kUniformGrid;
      } else {
        throw Error("unknown quadrant variant '" + std::string(token) + "' (known: thesis, pgs, quadtree, grid)");
      }
      if (end == std::string_view::npos) break;
      start = end + 1;
    }
  }

  std::string Name() const override { return variant_.empty() ? "quadrant" : "quadrant:" + variant_; }

  Capabilities Caps() const override {
    Capabilities c;
    c.maxThreads = 1;
    c.disableRotation = true;
    c.disableFriction = true;
    c.disableWarmStarting = true;
    c.notes = std::string("solver ") + (solver_ == SolverType::kThesis ? "thesis" : "pgs") +
              ", broad phase " + (broadPhase_ == BroadPhaseType::kQuadTree ? "quad-tree" : "uniform grid") +
              "; friction sqrt(f1*f2), restitution max(e1,e2) as Box2D; speculative contacts 0.02 m; "
              "no polygon skin; single-threaded until the parallel schemes land";
    return c;
  }

  void Load(const Scene& scene, int threads) override {
    ValidateScene(scene);
    if (threads != 1) throw Unsupported("quadrant runs 1 thread until the parallel schemes land");
    if (scene.effects.sleep) throw Unsupported("quadrant has no sleeping yet");
    if (scene.effects.continuous) throw Unsupported("quadrant has no continuous collision yet");
    if (scene.effects.damping) throw Unsupported("scene bodies carry no damping values yet");
    WorldDef def;
    def.gravity = scene.gravity;
    def.solver = solver_;
    def.broadPhase = broadPhase_;
    def.velocityIterations = scene.velocityIterations;
    def.positionIterations = scene.positionIterations;
    def.restitutionThreshold = scene.restitutionThreshold;
    def.threadCount = threads;
    def.effects.gravity = scene.effects.gravity;
    def.effects.friction = scene.effects.friction;
    def.effects.restitution = scene.effects.restitution;
    def.effects.rotation = scene.effects.rotation;
    def.effects.warmStarting = scene.effects.warmStarting;
    auto world = std::make_unique<World>(def);
    std::vector<BodyId> ids;
    ids.reserve(scene.bodies.size());
    for (const BodyDesc& b : scene.bodies) {
      BodyDef bd;
      bd.type = b.dynamic ? BodyType::kDynamic : BodyType::kStatic;
      bd.position = b.position;
      bd.angle = b.angle;
      bd.linearVelocity = b.velocity;
      bd.angularVelocity = b.angularVelocity;
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
    if (driver_) driver_(step_, *this);
    world_->Step(dt_, subSteps_);
    const Profile& p = world_->GetProfile();
    totals_.broadPhase += p.broadPhase;
    totals_.narrowPhase += p.narrowPhase;
    totals_.persistence += p.persistence;
    totals_.solve += p.solve;
    totals_.integrate += p.integrate;
    totals_.total += p.total;
    ++step_;
  }

  std::vector<std::pair<std::string, double>> StageTotals() const override {
    return {{"broad_phase", totals_.broadPhase}, {"narrow_phase", totals_.narrowPhase},
            {"persistence", totals_.persistence}, {"solve", totals_.solve},
            {"integrate", totals_.integrate},     {"total", totals_.total}};
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

  void SetVelocity(int body, Vec2 velocity, Real angularVelocity) override {
    if (body < 0 || body >= static_cast<int>(ids_.size())) throw Error("SetVelocity: body index out of range");
    world_->SetLinearVelocity(ids_[body], velocity);
    world_->SetAngularVelocity(ids_[body], angularVelocity);
  }

  uint64_t StateHash() const override { return world_ ? world_->StateHash() : 0; }

  World* GetWorld() { return world_.get(); }

 private:
  std::string variant_;
  SolverType solver_ = SolverType::kPgs;
  BroadPhaseType broadPhase_ = BroadPhaseType::kUniformGrid;
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
