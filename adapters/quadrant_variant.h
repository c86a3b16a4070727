// What "quadrant:<variant>" selects, and how a scene under a variant becomes a WorldDef: the
// policy the Quadrant adapter used to hold (issue 16). The adapter only translates.
#pragma once

#include <string>
#include <string_view>

#include "quadrant/world.h"
#include "scene.h"

namespace quadrant::scene {

struct QuadrantVariant {
  SolverType solver = WorldDef{}.solver;  ///< the engine's default unless a token names one
  BroadPhaseType broadPhase = BroadPhaseType::kUniformGrid;
  ParallelScheme scheme = ParallelScheme::kDeterministic;
  int softSubSteps = 0;        ///< sub<N>; 0: derived from the budget (soft_step) or the engine's
  int iterations = 0;          ///< it<N>; 0: the scene's velocity iterations
  int positionIterations = 0;  ///< pos<N>; 0: the scene's
  RestitutionPolicy restitution = RestitutionPolicy::kCollisions;  ///< b2rest: kBox2d (pgs and soft_step)
  Real polygonSkin = 0;        ///< b2skin: Box2D 2.4.1's 0.01 m polygon radius
  bool thesisCoupled = false;  ///< coupled: the thesis solver's coupled impulse
  bool frictionEveryRelax = false;  ///< relaxfriction: soft_step's WorldDef::softFrictionEveryRelaxPass
  bool thesisPoints = false;   ///< points: the thesis solver's impulse at each touching point
  int thesisPasses = 0;        ///< passes<N>: the thesis solver's WorldDef::thesisPasses; 0: the engine's
  bool thesisAccumulated = false;  ///< accum: the thesis solver's WorldDef::thesisAccumulatedImpulse
  bool box2dPositions = false;  ///< b2possolve: WorldDef::box2dPositionSolve
  bool thesisBlock = false;  ///< block: the thesis solver's WorldDef::thesisBlockImpulse
  bool thesisPositionPass = false;  ///< b2pos: the thesis solver's WorldDef::thesisPositionPass
  bool jointChainSolve = true;   // nochain: WorldDef::jointChainSolve off
  bool speculativeContacts = true;  ///< nospec: WorldDef::speculativeContacts off (touching points only, as Box2D 2.4.1)
  bool box2dClip = false;           ///< b2clip: WorldDef::box2dPolygonClip (Box2D 2.4.1's polygon manifold)
  bool contactRecycling = true;     ///< norecycle: WorldDef::contactRecycleDistance 0 (Box2D 2.4.1 recycles no manifold)
  int massRatioLimit = 0;      ///< ratio<N>: soft_step's WorldDef::softMassRatioLimit; 0: the engine's
  int relaxIterations = 0;     ///< relax<N>: soft_step's WorldDef::softRelaxIterations; 0: the engine's
  bool box2d3Soft = false;     ///< b3soft: soft_step with Box2D 3's settings (relax 1, no ratio limit, damping 10)

  /// Tokens joined by '+' ("" is the default): thesis, pgs, soft_step, quadtree, grid,
  /// deterministic, quadrants, sub<N>, it<N>, pos<N>, relax<N>, ratio<N>, passes<N> (N in [1,
  /// 1000]), b3soft, relaxfriction, b2rest, b2skin, coupled, points.
  /// Throws quadrant::Error naming an unknown token and the known ones.
  static QuadrantVariant Parse(std::string_view variant);

  /// The world for `scene` on `threads` threads: the scene's settings and effects, this variant's
  /// solver, broad phase and scheme, and the soft_step budget mapping (quadrant_variant.cpp).
  WorldDef MakeWorldDef(const Scene& scene, int threads) const;

  /// "solver pgs, broad phase uniform grid", for the adapter's notes.
  std::string Describe() const;
};

}  // namespace quadrant::scene
