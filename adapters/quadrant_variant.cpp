// Quadrant's variants and the scene -> WorldDef mapping.
//
// Variants ("quadrant:<tokens>", tokens joined by '+'): solver "thesis", "pgs", "soft_step" or
// "jacobi" (the distributed world's solver, here in one process),
// broad phase "quadtree" or "grid", parallel scheme "deterministic" or "quadrants", "b2rest" for
// Box2D 2.4.1's restitution (RestitutionPolicy::kBox2d, pgs and soft_step), "b2skin" for its 0.01 m polygon
// skin (WorldDef::polygonSkin), "coupled" for the thesis solver's coupled impulse
// (WorldDef::thesisCoupledImpulse), "points" for its impulse at each touching point
// (WorldDef::thesisPointImpulses), "passes<N>" for its passes (WorldDef::thesisPasses), "accum"
// for its impulses accumulated and clamped over the passes (WorldDef::thesisAccumulatedImpulse),
// "block" for its two-point contacts' normal impulses solved together (WorldDef::thesisBlockImpulse),
// "b2pos" for Box2D 2.4.1's position pass instead of its push (WorldDef::thesisPositionPass),
// "relaxfriction" for soft_step's friction in every relax pass, "b3soft"
// for soft_step with Box2D 3's settings (one relax pass, no mass-ratio limit, damping ratio 10),
// "nochain" for revolute chains solved joint by joint (WorldDef::jointChainSolve off), "nospec"
// for touching contact points only (WorldDef::speculativeContacts off, as Box2D 2.4.1), "b2clip"
// for Box2D 2.4.1's polygon manifolds (WorldDef::box2dPolygonClip), "b2possolve" for its position
// pass's geometry (WorldDef::box2dPositionSolve, pgs, soft_step and thesis), "norecycle"
// for manifolds computed every step (WorldDef::contactRecycleDistance 0, as Box2D 2.4.1).
// The default is the engine's own (WorldDef: soft_step with two relax passes and a mass-ratio
// limit of 10) with the uniform grid and the deterministic scheme.
// relax<N> and ratio<N> override the engine's defaults; "pgs" alone is Box2D 2.4's solver.
//
// MakeWorldDef turns a scene's iteration budget into soft_step sub-steps and contact stiffness
// (4 sub-steps at 30 Hz for the default 8 iterations); the comment there says why.
#include "quadrant_variant.h"

#include <algorithm>

#include "quadrant/error.h"

namespace quadrant::scene {
namespace {

/// N of sub<N>, it<N>, pos<N>: digits only, in [1, 1000].
bool ParseCount(std::string_view digits, int* out) {
  int value = 0;
  for (char ch : digits) {
    if (ch < '0' || ch > '9' || value > 1000) return false;
    value = value * 10 + (ch - '0');
  }
  if (value < 1) return false;
  *out = value;
  return true;
}

}  // namespace

QuadrantVariant QuadrantVariant::Parse(std::string_view variant) {
  QuadrantVariant v;
  size_t start = 0;
  while (start <= variant.size() && !variant.empty()) {
    const size_t end = variant.find('+', start);
    const std::string_view token =
        variant.substr(start, end == std::string_view::npos ? std::string_view::npos : end - start);
    if (token == "thesis") {
      v.solver = SolverType::kThesis;
    } else if (token == "pgs") {
      v.solver = SolverType::kPgs;
    } else if (token == "soft_step") {
      v.solver = SolverType::kSoftStep;
    } else if (token == "jacobi") {
      v.solver = SolverType::kJacobi;
    } else if (token.size() > 3 && token.starts_with("sub") && ParseCount(token.substr(3), &v.softSubSteps)) {
    } else if (token.size() > 2 && token.starts_with("it") && ParseCount(token.substr(2), &v.iterations)) {
    } else if (token.size() > 3 && token.starts_with("pos") && ParseCount(token.substr(3), &v.positionIterations)) {
    } else if (token.size() > 5 && token.starts_with("relax") && ParseCount(token.substr(5), &v.relaxIterations)) {
      // soft_step's WorldDef::softRelaxIterations.
    } else if (token.size() > 5 && token.starts_with("ratio") && ParseCount(token.substr(5), &v.massRatioLimit)) {
      // soft_step's WorldDef::softMassRatioLimit (issue #13 item 3: a heavy body on a light one).
    } else if (token.size() > 6 && token.starts_with("passes") && ParseCount(token.substr(6), &v.thesisPasses)) {
      // the thesis solver's WorldDef::thesisPasses.
    } else if (token == "b3soft") {
      // soft_step as Box2D 3 sets it (one relax pass, no mass-ratio limit, damping ratio 10): the
      // engine's soft_step before issue #13 changed its defaults.
      v.box2d3Soft = true;
    } else if (token == "relaxfriction") {
      v.frictionEveryRelax = true;
    } else if (token == "b2rest") {
      v.restitution = RestitutionPolicy::kBox2d;
    } else if (token == "coupled") {
      v.thesisCoupled = true;
    } else if (token == "points") {
      v.thesisPoints = true;
    } else if (token == "accum") {
      v.thesisAccumulated = true;
    } else if (token == "b2possolve") {
      v.box2dPositions = true;
    } else if (token == "block") {
      v.thesisBlock = true;
    } else if (token == "b2pos") {
      v.thesisPositionPass = true;
    } else if (token == "nochain") {
      v.jointChainSolve = false;  // WorldDef::jointChainSolve: revolute chains joint by joint
    } else if (token == "nospec") {
      v.speculativeContacts = false;
    } else if (token == "b2clip") {
      v.box2dClip = true;
    } else if (token == "norecycle") {
      v.contactRecycling = false;
    } else if (token == "b2skin") {
      v.polygonSkin = Real(0.01);  // Box2D 2.4.1's b2_polygonRadius
    } else if (token == "quadtree") {
      v.broadPhase = BroadPhaseType::kQuadTree;
    } else if (token == "grid") {
      v.broadPhase = BroadPhaseType::kUniformGrid;
    } else if (token == "deterministic") {
      v.scheme = ParallelScheme::kDeterministic;
    } else if (token == "quadrants") {
      v.scheme = ParallelScheme::kQuadrants;
    } else {
      throw Error("unknown quadrant variant '" + std::string(token) +
                  "' (known: thesis, pgs, soft_step, jacobi, quadtree, grid, deterministic, quadrants, sub<N>, it<N>, "
                  "pos<N>, relax<N>, ratio<N>, passes<N>, b3soft, relaxfriction, b2rest, b2skin, coupled, points, accum, block, b2pos, "
                  "nochain, nospec, b2clip, b2possolve, norecycle)");
    }
    if (end == std::string_view::npos) break;
    start = end + 1;
  }
  return v;
}

// The solver budget for soft_step: a scene states the budget a case needs as pgs velocity
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
WorldDef QuadrantVariant::MakeWorldDef(const Scene& scene, int threads) const {
  WorldDef def;
  def.gravity = scene.gravity;
  def.solver = solver;
  def.broadPhase = broadPhase;
  def.velocityIterations = iterations > 0 ? iterations : scene.velocityIterations;
  if (softSubSteps > 0) {
    def.softSubSteps = softSubSteps;
  } else if (solver == SolverType::kSoftStep) {
    def.softSubSteps = std::max(1, def.velocityIterations / 2);
    def.contactHertz = WorldDef{}.contactHertz * Real(def.softSubSteps) / Real(WorldDef{}.softSubSteps);
  }
  def.positionIterations = positionIterations > 0 ? positionIterations : scene.positionIterations;
  def.restitutionThreshold = scene.restitutionThreshold;
  def.restitution = restitution;
  def.polygonSkin = polygonSkin;
  def.thesisCoupledImpulse = thesisCoupled;
  def.thesisPointImpulses = thesisPoints;
  if (thesisPasses > 0) def.thesisPasses = thesisPasses;
  def.thesisAccumulatedImpulse = thesisAccumulated;
  def.thesisBlockImpulse = thesisBlock;
  def.box2dPositionSolve = box2dPositions;
  def.thesisPositionPass = thesisPositionPass;
  def.jointChainSolve = jointChainSolve;
  def.speculativeContacts = speculativeContacts;
  def.box2dPolygonClip = box2dClip;
  if (!contactRecycling) def.contactRecycleDistance = 0;
  if (box2d3Soft) {
    def.softRelaxIterations = 1;
    def.softMassRatioLimit = 0;
    def.contactDampingRatio = 10;
  }
  if (massRatioLimit > 0) def.softMassRatioLimit = Real(massRatioLimit);
  if (relaxIterations > 0) def.softRelaxIterations = relaxIterations;
  def.softFrictionEveryRelaxPass = frictionEveryRelax;
  def.threadCount = threads;
  def.scheme = scheme;
  def.effects = scene.effects;  // one type (scene.h); sleep with Box2D 2.4's tolerances, WorldDef's defaults
  return def;
}

std::string QuadrantVariant::Describe() const {
  return std::string("solver ") +
         (solver == SolverType::kThesis  ? "thesis"
          : solver == SolverType::kPgs   ? "pgs"
          : solver == SolverType::kJacobi ? "jacobi"
                                          : "soft_step") +
         ", broad phase " + (broadPhase == BroadPhaseType::kQuadTree ? "quad-tree" : "uniform grid");
}

}  // namespace quadrant::scene
