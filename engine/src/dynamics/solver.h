// Solvers: one interface, several accuracy/cost trade-offs (the mission: show what accuracy
// costs in time). A solver owns the part of the step from velocities to positions: applying
// gravity, resolving contacts, integrating, correcting positions. It records its own time in
// Profile::solve and Profile::integrate.
#pragma once

#include <memory>

#include "world/world_internal.h"

namespace quadrant {

class Solver {
 public:
  virtual ~Solver() = default;
  /// Advances velocities and positions by ctx.dt, resolving ctx.contacts, and leaves the
  /// accumulated impulses in the contacts' manifold points (for warm starting next step).
  virtual void Step(StepContext& ctx) = 0;
  virtual const char* Name() const = 0;
  /// Whether the last Step kept the joint colouring of the step before (Counters::jointColoringKept).
  virtual bool JointColoringKept() const { return false; }
  virtual int RowBundles() const { return 0; }  // Counters::rowBundles
};

std::unique_ptr<Solver> MakeThesisSolver();
std::unique_ptr<Solver> MakePgsSolver();
std::unique_ptr<Solver> MakeSoftStepSolver();
std::unique_ptr<Solver> MakeJacobiSolver();
std::unique_ptr<Solver> MakeSolver(SolverType type);

}  // namespace quadrant
