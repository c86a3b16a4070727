// The soft step (soft_step.h): the step as a list of stages, and how their passes are scheduled.
// Per step: (1) the states of the bodies rows read but never write; (2) the colouring, which
// flags the rows' bodies; (3) the rows' part beside the pass that moves the free bodies: the
// restitution collisions, the rows (BuildRows), N sub-steps, the bounce shifts, the position pass
// and the impulses kept for the warm start; (4) the rows' bodies back from their states. A
// sub-step is one region of stages (gravity, warm start, soft solve, positions, relax), so the
// threads go from stage to stage inside one job.
//
// Restitution comes first, as pairwise collisions (contact_constraints.h, shared with pgs), or
// with RestitutionPolicy::kBox2d after the first sub-step (soft_step_restitution.cpp). Overlap
// deeper than contactPushMaxDepth is not pushed out by velocity: the position pass moves it out
// after the sub-steps, changing positions only.
//
// Promises: the same bits on any thread count (which thread runs a chunk never changes its
// arithmetic). Measured: pushed out by velocity, a row of overlapping bodies added up its
// contacts' push speeds (overlap_recovery 10.8 m/s, 2 allowed; now 1.32); split across the
// threads, circle stress N = 16000's few hundred rows took 0.174 ms a step at 2 threads against
// 0.183 ms at 1, hence the rows' part beside the free bodies. docs/soft_step.md has the figures.
#include <atomic>
#include <cmath>
#include <functional>
#include <optional>

#include "dynamics/soft_step.h"

namespace quadrant {

using Clock = StageClock;

// What one step's stages share.
struct SoftStepSolver::StepPlan {
  int n;  // sub-steps
  Real h, invH;
  Softness soft, staticSoft;  // contacts between dynamic bodies; with a static body (twice as stiff)
  int m;                      // rows (coloured contacts)
  bool simd;
  bool lean;                  // no restitution: no constraint list, the rows straight from the contacts
  bool box2dRestitution;      // RestitutionPolicy::kBox2d
};

void SoftStepSolver::Step(StepContext& ctx) {
  jointColoringKept_ = false;  // set by the joints' preparation, when there are joints
  DispatchEffects(ctx.def->effects,
                  [&](auto rotation, auto friction) { Run<decltype(rotation)::value, decltype(friction)::value>(ctx); });
}

template <bool kRotation, bool kFriction>
void SoftStepSolver::Run(StepContext& ctx) {
  const WorldDef& def = *ctx.def;
  Bodies& bodies = *ctx.bodies;
  StageRunner& run = *ctx.run;
  StepPlan step;
  rowsMoved_ = false;  // LoadStates starts every state's motion at zero
  step.n = def.softSubSteps;
  step.h = ctx.dt / Real(step.n);
  step.invH = Real(1) / step.h;
  // Stiffer than the sub-step can resolve is unstable: at most a quarter of its rate. Contacts
  // with a static body hold twice as stiff: nothing on the other side gives way.
  const Real hertz = std::min(def.contactHertz, Real(0.25) * step.invH);
  step.soft = MakeSoftness(hertz, def.contactDampingRatio, step.h);
  step.staticSoft = MakeSoftness(2 * hertz, def.contactDampingRatio, step.h);
  // Each sub-step's friction bound takes 1/n of the step's collision impulse: the warm start
  // repeats the tangential impulse every sub-step, so with the whole collision impulse in each
  // bound a sliding bounce got up to n times the friction Coulomb allows over the impact.
  collisionShare_ = Real(1) / Real(step.n);

  double integrateMs = 0;
  auto t0 = Clock::now();
  // 1. The states of the bodies rows read but never write; the flags cleared for the colouring.
  auto ti = Clock::now();
  LoadFixedStates(run, bodies, def.effects.sleep);
  integrateMs += Ms(ti, Clock::now());
  // 2. The colouring; its gather flags the rows' bodies (MarkRow). Beside its greedy pass, a
  // sparse scene's contact islands (soft_step_bundles.cpp).
  step.box2dRestitution = def.effects.restitution && def.restitution == RestitutionPolicy::kBox2d;
  const bool mayBundle = MayBundle(run, ctx, step.box2dRestitution);
  // Built only where the step may bundle: its three references exceed std::function's inline
  // buffer, so it allocates.
  std::optional<std::function<void()>> islands;
  if (mayBundle) {
    islands.emplace([&] { FindIslands(ctx, run.Workers()); });
  } else {
    islandsFor_ = 0;  // the next step that may bundle finds them anew
  }
  const std::function<void()>* beside = islands ? &*islands : nullptr;
  const bool supported = def.softMassRatioLimit > 0;
  NextStamp(bodies.Count(), supported);
  if (supported) {
    graph_.Color(run, ctx, /*clearLater=*/true, [this](int a, int b) { MarkRow<true>(a, b); }, beside);
    // Only where last step had a contact over the limit (issue #26: Solver2D's heavy boxes on
    // pyramids, whose top boxes touch no static body, toppled them unheld).
    if (overLimit_) PropagateSupport(run, ctx, def.softMassRatioLimit);
    overLimit_ = 0;
  } else {
    graph_.Color(run, ctx, /*clearLater=*/true, [this](int a, int b) { MarkRow<false>(a, b); }, beside);
  }
  step.m = graph_.Count();
  // The joints' colouring; it marks their dynamic bodies as in rows, for LoadStates.
  PrepareJoints(ctx, step.h);
  jointInvH_ = step.invH;
  // The bundles applied before anything reads the colour order (SetBundles reorders each colour).
  constexpr int kRowCost = 16;
  const int count = bodies.Count();
  const bool sparse = int64_t(kRowCost) * (step.m + int64_t(jointRows_.size())) <= count;
  if (mayBundle) {
    ApplyBundles(run);
  } else {
    bundles_ = 0;
    bundlesApplied_ = bundlesKept_ = false;
    graph_.ClearBundles();
  }
  // Only restitution and Box2D's position pass read the list.
  if (def.effects.restitution || def.box2dPositionSolve) constraints_.Resize(step.m);
  contacts_ = ctx.contacts;
  gravityScaled_ = ctx.gravityScaled;
  inv_ = bodies.inv.data();
  step.simd = def.softSimd;
  vex_ = step.simd && def.softVex && CpuHasAvx();  // soft_rows.h: the rows eight at a time with AVX
  step.lean = !def.effects.restitution && !def.box2dPositionSolve;
  // The warm start of sub-steps 2..n added up by the relax pass before (SubStep), except where
  // something between the two changes a row's impulses (Box2D's bounces), and without gravity
  // (off, or zero: the same bits either way): there the gravity pass does not run, and one to add
  // the sums cost more than the warm start's stages save (64000 circles at 2 threads, 2-core VM:
  // 1.15x the time, nine interleaved pairs; their rows run beside the free bodies, where no stage
  // waits). The distributed world's exchange after the warm start still gives the shadows their
  // owners' states.
  const bool gravity = def.effects.gravity && (def.gravity.x != 0 || def.gravity.y != 0);
  foldWarm_ = def.effects.warmStarting && gravity && !step.box2dRestitution && step.n > 1;

  // 3. The rows' part and the free bodies' pass, which are independent: no row reads or writes
  // a free body. With few rows among many bodies the rows' part runs on one thread beside the
  // free bodies' pass on the others, instead of splitting a few hundred rows across the threads
  // with a barrier for every colour of every pass. kRowCost: a contact costs the rows' part about
  // 30 times what a free body costs its pass, so with at most count / 16 contacts the rows' part
  // is at most about twice the free bodies' work, and beside them costs the step at most its own.
  // (On 64000 circles a contact costs more: 1274 of them took 1.05 ms alone, 3x the free bodies.)
  //
  // The rows' preparation (constraints, restitution's collisions, the rows, their bodies' states)
  // runs first on all the threads; only the sub-steps and what follows them are the lone part.
  // 64000 circles, 1274 contacts: the whole rows' part alone was 1.05 ms beside 0.34 ms of free
  // bodies; the scaling model's 8 / 16 threads went from 3.23x / 3.98x to 3.78x / 4.75x, the 2
  // threads measured here within the noise (0.96, eleven interleaved pairs), the same bits.
  // From 4 threads on, a sparse scene's rows run in bundles of contact islands instead
  // (soft_step_bundles.cpp), with the free bodies' blocks taken after the bundles.
  auto rows = [&] { SolveContacts<kRotation, kFriction>(ctx, step); };
  PrepareContacts<kRotation, kFriction>(ctx, step, integrateMs);
  // The state exchange calls MPI between passes: on the calling thread, so not beside. (Box2D's
  // position pass snapshots every body in PrepareContacts and runs after StoreRowStates: neither
  // is in the lone part.) Bundled, the rows' passes split across the threads themselves.
  auto moveFree = [&](int b, int e) { MoveFreeBodies(bodies, def, ctx.dt, b, e); };
  if (bundles_ > 0) {  // the free bodies beside the first region's bundles
    freePass_ = {&bodies, &def, ctx.dt};
    freeCount_ = count;
    rows();
    if (freeCount_ > 0) run.Dynamic(Stage::kIntegrate, count, run.MinItems(), kBodyGrain, moveFree);
    freeCount_ = 0;
  } else if (!exchange_ && sparse) {
    run.Beside(Stage::kSolve, rows, count, run.MinItems(), moveFree);
  } else {
    rows();
    ti = Clock::now();
    run.Dynamic(Stage::kIntegrate, count, run.MinItems(), kBodyGrain, moveFree);
    integrateMs += Ms(ti, Clock::now());
  }
  // 4. The rows' bodies back from their states; after the free bodies' pass, which reads the
  // transforms of four bodies at a time (writing only the free ones).
  ti = Clock::now();
  StoreRowStates(run, bodies, def);
  // WorldDef::box2dPositionSolve: Box2D 2.4.1's position pass on the bodies, in place of the soft
  // push and the state position pass (SolveContacts), serially in colour order.
  if (def.box2dPositionSolve && step.m > 0) {
    run.Serial(Stage::kSolve, [&] { constraints_.CorrectPositionsBox2d<kRotation>(bodies, def, def.positionIterations); });
  }
  integrateMs += Ms(ti, Clock::now());
  const double total = Ms(t0, Clock::now());
  ctx.profile->integrate += integrateMs;
  ctx.profile->solve += total - integrateMs;
}

// The rows' part of the step, first half: the constraints and restitution's collisions, the
// rows and their bodies' states. No free body is read or written.
template <bool kRotation, bool kFriction>
void SoftStepSolver::PrepareContacts(StepContext& ctx, const StepPlan& step, double& integrateMs) {
  const WorldDef& def = *ctx.def;
  Bodies& bodies = *ctx.bodies;
  StageRunner& run = *ctx.run;
  const int m = step.m;
  // Lean, each constraint is prepared into a local one as its row is built (BuildRows); the
  // list (144 bytes a constraint) is kept only for the restitution passes, which read it.
  if (!step.lean) {
    run.For(Stage::kSolve, m, run.MinHeavyItems(),
            [&](int b, int e, int) { constraints_.Prepare<kRotation, true>(ctx, graph_, b, e); });
  }
  if (def.box2dPositionSolve && m > 0) {
    // Box2D's geometry of each point where the narrow phase saw the bodies (its position pass
    // runs after the rows' bodies are stored: Step).
    constraints_.SnapshotPositions(run, bodies);
    run.Serial(Stage::kSolve, [&] { constraints_.SnapshotBox2dGeometry(ctx); });
  }
  if (def.effects.restitution && !step.box2dRestitution) {
    const Vec2 stepGravity = def.effects.gravity ? ctx.dt * def.gravity : Vec2{};
    constraints_.ApplyCollisionPasses<kRotation>(run, graph_, bodies, def, Real(1) / ctx.dt, stepGravity);
  }
  step.lean ? BuildRows<kRotation, true>(ctx, step.soft, step.staticSoft, def.softMassRatioLimit)
            : BuildRows<kRotation, false>(ctx, step.soft, step.staticSoft, def.softMassRatioLimit);
  auto tr = Clock::now();
  LoadStates(run, bodies);
  integrateMs += Ms(tr, Clock::now());
}

// Second half: the sub-steps, then the bounce shifts, the position pass and the impulses for the
// warm start.
template <bool kRotation, bool kFriction>
void SoftStepSolver::SolveContacts(StepContext& ctx, const StepPlan& step) {
  const WorldDef& def = *ctx.def;
  StageRunner& run = *ctx.run;
  const int m = step.m;
  // With Box2D's position pass the rows push nothing out (Box2D 2.4.1's velocity rows carry no
  // position bias): overlap is the pass's alone.
  const SoftSolveParams prm{step.invH, def.contactPushMaxDepth, def.box2dPositionSolve ? Real(0) : def.contactPushMaxVelocity};
  // Whether the position pass can move anything: the last sub-step's first relax pass sees every
  // point's separation at the step's final positions, and without restitution nothing moves the
  // bodies after it. A point counts as deep below -contactPushMaxDepth + kDeepMargin: the position
  // pass computes the same separation in another order of operations, which differs by a few
  // float ulps (about 1e-6 m), so with no deep point it would move nothing: skipping it gives
  // the same bits.
  std::atomic<bool>& deep = deep_.flag;
  deep.store(false, std::memory_order_relaxed);
  const bool maySkipPositions = !def.effects.restitution;
  constexpr Real kDeepMargin = Real(1e-4);
  SoftSolveParams lastPrm = prm;
  if (maySkipPositions) {
    lastPrm.deep = &deep;
    lastPrm.deepBelow = -def.contactPushMaxDepth + kDeepMargin;
  }
  // Bundled, the sub-steps' regions are queued and run as one: a thread takes a bundle through
  // every sub-step, so its rows and states stay in one core's cache (a region per sub-step moved
  // half the bundles between the cores each time: 64000 circles at 2 threads, the solve stage
  // 0.80 -> 1.04 ms a step so, five interleaved pairs).
  deferRegions_ = bundles_ > 0;
  ClearRegion();
  for (int sub = 0; sub < step.n; ++sub) SubStep<kRotation, kFriction>(ctx, step, sub, prm, lastPrm);
  if (deferRegions_) {
    deferRegions_ = false;
    RunRegionByBundle(run);
  }
  if (def.effects.restitution && m > 0) {
    graph_.ForEachColor(run, [&](int b, int e) { ApplyStateBounceShifts(b, e); });
  }
  // Overlap deeper than the soft contacts push out is moved out here, on the states: positions
  // change, velocities do not, so deep overlap cannot fling bodies.
  if (m > 0 && !def.box2dPositionSolve && (!maySkipPositions || deep.load(std::memory_order_relaxed))) {
    CorrectStatePositions<kRotation>(run, def, step.simd);
  }
  // Lean, the last relax pass stored the impulses (RelaxPasses; WorldDef validation keeps
  // softSubSteps and softRelaxIterations >= 1, so that pass always runs).
  if (!jointRows_.empty()) StoreJoints(run);
  if (!step.lean) {
    StoreRowImpulses(run);
    run.For(Stage::kSolve, m, run.MinHeavyItems(), [&](int b, int e, int) { constraints_.StoreImpulses(ctx.contacts, b, e); });
  }
}

// One sub-step, as one region of stages: gravity, the warm start and the soft solve colour by
// colour, the positions, the relax passes colour by colour. The threads go from stage to stage
// inside one job; which thread runs which chunk never changes the arithmetic.
template <bool kRotation, bool kFriction>
void SoftStepSolver::SubStep(StepContext& ctx, const StepPlan& step, int sub, const SoftSolveParams& prm,
                             const SoftSolveParams& lastPrm) {
  const WorldDef& def = *ctx.def;
  StageRunner& run = *ctx.run;
  const bool simd = step.simd;
  // The order of a row's two points alternates: the soft solve takes point (sub & 1) first, the
  // relax passes the other. Gauss-Seidel gives the point solved first a little more of the load,
  // the same one every time in a fixed order: on a stack that is a torque of one sign on every
  // box, and the 50-box stack leaned until its top had moved 0.28 m (0.0004 m so; both with the
  // load-aware deep rule, LoadCompression in soft_rows_kernels.inc). Alternated every sub-step
  // alike in both passes, the last relax pass, whose impulses warm-start the next step, always
  // took the same order: mass_ratio_100's heavy box drifted 0.064 m (0.05 allowed; 0.020 m so).
  SoftSolveParams solvePrm = prm, relaxFirstPrm = sub == step.n - 1 ? lastPrm : prm, relaxPrm = prm;
  solvePrm.firstPoint = sub & 1;
  relaxFirstPrm.firstPoint = relaxPrm.firstPoint = 1 - (sub & 1);
  // The warm start of every sub-step after the first is folded into the relax pass before it:
  // that pass's last solve of a row leaves the row's impulses as the warm start applies them, so
  // it adds the row's warm start to its bodies' sums (warmNext_; a colour holds a body once, so
  // no two threads add to one sum), and the gravity pass adds each sum to its body. The arithmetic
  // is the warm start's, summed in another order (the same bits on any thread count); it saves a
  // stage per colour: on the base-100 pyramid 22 stages a sub-step -> 17 (each a barrier).
  const bool last = sub == step.n - 1;
  const bool warmFolded = foldWarm_ && sub > 0;
  BeginRegion();
  IntegrateStateVelocities(run, *ctx.bodies, def, step.h, sub == 0 ? ctx.dt : Real(0), warmFolded);
  // Joints before contacts in each pass, as Box2D 3: a joint's correction is then seen by the
  // contacts it pushes into. Every joint's row reads and writes only its own bodies' states.
  if (def.effects.warmStarting) JointPass([this](int b, int e) { WarmStartJoints(b, e); });
  if (def.effects.warmStarting && !warmFolded) {
    ForEachGroup(run, simd, [this](auto lanes, SoftRowGroup& g, int lane) {
      WarmStartRows<decltype(lanes), kRotation>(states_.data(), g, lane);
    });
  }
  // With a state exchange (the distributed world): the shadows' states before each solve pass
  // and before the positions move are their owners'. A shadow's warm start holds only this
  // rank's rows: solved from it, a base-20 pyramid across four ranks drifted 0.14-0.56 m in 59 s
  // (0.001-0.003 m so).
  if (exchange_) {
    EndRegion(run);
    Exchange();
    BeginRegion();
  }
  JointPass([this](int b, int e) { SolveJoints(b, e, true); });
  ChainPass();
  ForEachGroup(run, simd, [this, solvePrm](auto lanes, SoftRowGroup& g, int lane) {
    SolveRows<decltype(lanes), kRotation, kFriction, true>(states_.data(), g, lane, solvePrm);
  });
  if (exchange_) {
    EndRegion(run);
    Exchange();
    BeginRegion();
  }
  // The rotation guard is per world step (ctx.dt): per sub-step it allowed n times the turn.
  IntegrateStatePositions(run, *ctx.bodies, def, step.h, ctx.dt);
  JointPass([this](int b, int e) { SolveJoints(b, e, false); });
  RelaxPasses<kRotation, kFriction>(run, def, simd, relaxFirstPrm, relaxPrm, step.lean && last, foldWarm_ && !last);
  EndRegion(run);
  // After the relax passes the next exchange is the next sub-step's first (gravity and the warm
  // start change an owned body's state without reading a shadow's), except before the bounces
  // and at the end (the bounce shifts and the position pass read the shadows). On every rank
  // alike: the rounds must match.
  const bool bounce = step.box2dRestitution && sub == 0;
  if (exchange_ && (last || bounce)) Exchange();
  if (bounce && step.m > 0) {
    ApplyBox2dRestitution<kRotation, kFriction>(run, def, step.h);
    rowsMoved_ = true;  // the bounce moves the first sub-step's positions (dp, dq)
  }
  if (exchange_ && bounce && last) Exchange();
}

// The sub-step's softRelaxIterations relax passes. The first one gets firstPrm (in the last
// sub-step it looks for deep points). Friction only in the last pass (unless
// softFrictionEveryRelaxPass): the earlier ones settle the normal impulses that bound it; with
// friction in the first pass only, the tall stack's top moved 0.051 m (0.034 m allowed). With two
// or more passes the first stores each point's speculative bias and the later ones load it
// (soft_rows.h, RelaxBias). storeLast (lean, last sub-step): the last pass also stores each
// row's impulses into its contact as it solves the row (nothing changes them after it), instead
// of a pass of its own that read every group again.
template <bool kRotation, bool kFriction>
void SoftStepSolver::RelaxPasses(StageRunner& run, const WorldDef& def, bool simd, const SoftSolveParams& firstPrm,
                                 const SoftSolveParams& prm, bool storeLast, bool foldWarm) {
  const int relax = def.softRelaxIterations;
  for (int it = 0; it < relax; ++it) {
    if (relax == 1) {
      storeLast ? RelaxPass<kRotation, kFriction, RelaxBias::kCompute, true>(run, simd, firstPrm)
                : RelaxPass<kRotation, kFriction, RelaxBias::kCompute>(run, simd, firstPrm, foldWarm);
    } else if (it == 0) {
      def.softFrictionEveryRelaxPass
          ? RelaxPass<kRotation, kFriction, RelaxBias::kComputeAndStore>(run, simd, firstPrm)
          : RelaxPass<kRotation, false, RelaxBias::kComputeAndStore>(run, simd, firstPrm);
    } else if (it == relax - 1 && storeLast) {
      RelaxPass<kRotation, kFriction, RelaxBias::kLoad, true>(run, simd, prm);
    } else if (it == relax - 1 || def.softFrictionEveryRelaxPass) {
      RelaxPass<kRotation, kFriction, RelaxBias::kLoad>(run, simd, prm, foldWarm && it == relax - 1);
    } else {
      RelaxPass<kRotation, false, RelaxBias::kLoad>(run, simd, prm);
    }
  }
}

// One relax pass over the rows, queued in the sub-step's region; kStore: then the rows' impulses
// into their contacts.
template <bool kRotation, bool kFriction, RelaxBias kRelax, bool kStore>
void SoftStepSolver::RelaxPass(StageRunner& run, bool simd, const SoftSolveParams& prm, bool foldWarm) {
  ForEachGroup(run, simd, [this, prm, foldWarm](auto lanes, SoftRowGroup& g, int lane) {
    RelaxBiasRows* cache = kRelax == RelaxBias::kCompute ? nullptr : &relaxBias_[&g - groups_.data()];
    // The contacts StoreLaneImpulses writes, a group ahead (a group's solve is too short to
    // hide a miss): the next group in the list, which the same chunk most often takes next.
    if constexpr (kStore) {
      if (&g + 1 < groups_.data() + groups_.size()) PrefetchLaneContacts((&g)[1], lane, lane + kLaneWidth<decltype(lanes)>);
    }
    SolveRows<decltype(lanes), kRotation, kFriction, false, kRelax>(states_.data(), g, lane, prm, cache);
    if constexpr (kStore) StoreLaneImpulses(g, lane, lane + kLaneWidth<decltype(lanes)>);
    if (foldWarm) WarmStartRows<decltype(lanes), kRotation>(warmNext_.data(), g, lane);
  });
}

// Lanes [begin, end) of group g: their accumulated impulses straight into their contacts'
// manifolds (padding lanes have none), for the next step's warm start.
void SoftStepSolver::StoreLaneImpulses(const SoftRowGroup& g, int begin, int end) {
  for (int lane = begin; lane < end; ++lane) {
    if (g.constraint[lane] < 0) continue;
    Manifold& mf = contacts_[graph_.ContactOf(g.constraint[lane])].manifold;
    for (int pt = 0; pt < mf.pointCount; ++pt) {
      mf.points[pt].normalImpulse = g.p[pt].normalImpulse[lane];
      mf.points[pt].tangentImpulse = g.p[pt].tangentImpulse[lane];
    }
  }
}

// Up to positionIterations passes of SolvePositionRows (soft_rows.h), colour by colour; a pass
// that moves nothing leaves every later one nothing to do, so the loop stops there.
template <bool kRotation>
void SoftStepSolver::CorrectStatePositions(StageRunner& run, const WorldDef& def, bool simd) {
  const SoftPositionParams prm{def.contactPushMaxDepth, def.baumgarte, def.maxLinearCorrection};
  SolverBody* states = states_.data();
  std::atomic<bool>& anyMoved = moved_.flag;
  for (int it = 0; it < def.positionIterations; ++it) {
    anyMoved.store(false, std::memory_order_relaxed);
    ForEachGroup(run, simd, [&](auto lanes, SoftRowGroup& g, int lane) {
      bool moved = false;
      if constexpr (std::is_same_v<decltype(lanes), Real>) {
        SolvePositionRows<Real, kRotation>(states, g, lane, prm, moved);
      } else if (!SolvePositionRows<decltype(lanes), kRotation>(states, g, lane, prm, moved)) {
        for (int l = lane; l < lane + kLaneWidth<decltype(lanes)>; ++l) {
          SolvePositionRows<Real, kRotation>(states, g, l, prm, moved);
        }
      }
      if (moved && !anyMoved.load(std::memory_order_relaxed)) anyMoved.store(true, std::memory_order_relaxed);
    });
    if (!anyMoved.load(std::memory_order_relaxed)) break;  // read after the last colour's join
  }
}

// The accumulated impulses back into the constraints (StoreImpulses keeps them for the next
// step's warm start). With restitution only: lean, the last relax pass stores them.
void SoftStepSolver::StoreRowImpulses(StageRunner& run) {
  const int count = static_cast<int>(groups_.size());
  run.For(Stage::kSolve, count, std::max(1, run.MinHeavyItems() / kGroupRows), [&](int gb, int ge, int) {
    for (int gi = gb; gi < ge; ++gi) {
      const SoftRowGroup& g = groups_[gi];
      for (int lane = 0; lane < kGroupRows; ++lane) {
        if (g.constraint[lane] < 0) continue;
        ContactConstraint& cc = constraints_[g.constraint[lane]];
        for (int pt = 0; pt < cc.pointCount; ++pt) {
          cc.points[pt].normalImpulse = g.p[pt].normalImpulse[lane];
          cc.points[pt].tangentImpulse = g.p[pt].tangentImpulse[lane];
        }
      }
    }
  });
}

// Scheduling.

void SoftStepSolver::BeginRegion() {
  collecting_ = true;
  if (!deferRegions_) ClearRegion();  // deferred: appended to the queued regions
}

void SoftStepSolver::ClearRegion() {
  regionPlan_.clear();
  regionFirst_.clear();
  regionPass_.clear();
  regionOnBodies_.clear();
  regionFns_.clear();
}

// A region splits across the threads only where its splitting stages hold, on average, half of
// MinHeavyItems / kGroupRows items (16 groups of eight rows by default) per stage: every stage
// costs a barrier, and 64 rows (kColorGrain) are about a microsecond of rows, what a barrier and
// the rows' states moving to the other core cost.
void SoftStepSolver::EndRegion(StageRunner& run) {
  collecting_ = false;
  if (deferRegions_) return;  // SolveContacts runs the queue
  if (bundles_ > 0) {
    RunRegionByBundle(run);
    return;
  }
  const int stages = static_cast<int>(regionPlan_.size());
  const int minItems = std::max(run.MinHeavyItems() / kGroupRows, run.MinHeavyItems() / (2 * kGroupRows) * stages);
  run.Stages(Stage::kSolve, regionPlan_, std::max(1, minItems), [&](int s, int b, int e) {
    regionFns_[regionPass_[s]](regionFirst_[s] + b, regionFirst_[s] + e);
  });
}

// The stages of a pass over the rows: one per colour, except that consecutive colours of at most
// kSmallRows rows each share one stage of one chunk, run on one thread in colour order (the same
// order of row solves, so the same bits, without a barrier between them). The greedy colouring
// leaves a few such small colours at the end (the base-100 pyramid: four colours of about 2500
// rows, then 20-160 and 10-45, as it settles). kSmallRows: 256 rows are about 1.5 us of one
// thread's work (the pyramid's colour of 2500 rows: 14 us), a quarter of a barrier's fitted cost
// (6 us, tools/scaling.py), so two such colours in one chunk beat two stages at any thread count.
// The overflow colour is one chunk of its own, row by row.
void SoftStepSolver::PlanPassStages() {
  passStages_.clear();
  constexpr int kGrain = ConstraintGraph::kColorGrain / kGroupRows;
  constexpr int kSmallRows = 256, kSmall = kSmallRows / kGroupRows;
  bool lastSmall = false;
  for (int color = 0; color <= ConstraintGraph::kColors; ++color) {
    const int begin = groupStart_[color], count = groupStart_[color + 1] - begin;
    if (count == 0) continue;
    if (color == ConstraintGraph::kColors) {
      passStages_.push_back({begin, count, count});
      lastSmall = false;
      continue;
    }
    const bool small = count <= kSmall;
    if (small && lastSmall) {
      StagePart& last = passStages_.back();
      last.count += count;
      last.grain = last.count;
      continue;
    }
    passStages_.push_back({begin, count, small ? count : kGrain});
    lastSmall = small;
  }
}

std::unique_ptr<Solver> MakeSoftStepSolver() { return std::make_unique<SoftStepSolver>(); }

}  // namespace quadrant
