// Soft step: sub-stepping with soft contacts and relaxation (Box2D 3's family; Catto,
// "Solver2D", 2024). Per step the contacts are found once; then, for each of N sub-steps of
// h = dt/N: gravity, warm start, one soft solve (contacts act as stiff damped springs:
// penetration is pushed out at a bounded speed instead of by an impulse that adds velocity),
// position integration, and one relax solve (the same rows with no bias, removing the push-out
// velocity). Restitution comes first, as pairwise collisions before the sub-steps (shared with
// pgs: ApplyCollisions in contact_constraints.h); the early-bounce shifts follow the last sub-step.
// With RestitutionPolicy::kBox2d it is Box2D's velocity target instead, applied after the first
// sub-step (ApplyBox2dRestitution).
//
// Why: many small steps converge where many iterations of one big step do not (Macklin et al.
// 2019, "Small steps in physics simulation"), which is what stacks and large mass ratios need.
// The separation of each point is re-evaluated every sub-step from how far its bodies moved.
//
// Why restitution comes first: applied after the sub-steps from the pre-step approach speed
// (Box2D 3's way) it gained energy here (elastic polygon stress +63 % kinetic energy; the
// 3000-step soak ended with 56 bodies out of the box).
//
// Deep overlap: a contact point is soft only down to contactPushMaxDepth (0.01 m) of
// penetration. A deeper point is a rigid row (full mass: it holds whatever load it carries, as
// pgs's rows do) whose push-out bias is the one a soft point has at that depth; the rest of the
// overlap is moved out after the sub-steps by pgs's position pass (SolvePositions), which changes
// positions, not velocities. Pushed out entirely by velocity, a row of overlapping bodies added
// up the push speeds of its contacts, which the relax pass cannot take back (overlap_recovery
// 10.8 m/s, confined 15.6 m/s; 2 allowed; now 1.32 and 1.54). A soft deep point with only its
// bias capped would cap the load it holds too: at 4 sub-steps the 100 kg box of mass_ratio_100
// fell through the pyramid. docs/soft_step.md gives the figures of every variant measured.
//
// Heavy loads sag: a soft contact is a spring of stiffness m_eff (2 pi contactHertz)^2 and sags
// by load / stiffness whatever the sub-step (1000 N on a 1 kg box's corner at 30 Hz: 0.071 m).
// The Quadrant adapter turns a scene's larger solver budget into more sub-steps with the
// stiffness scaled along (quadrant_adapter.cpp says why).
//
// Data (issue #13, after Box2D 3's layout; the code is this project's): the sub-steps work on a
// 32-byte solver state per body (velocity, and the motion dp, dq since the step began), not on
// the body arrays, and on the contact rows in structure-of-arrays groups of eight per graph
// colour, solved eight at a time with AVX or four with SSE2 (soft_rows.h; the one-row path gives
// the same bits, WorldDef::softSimd, SoftSimdTest). A point's separation in a sub-step is its prepared one plus
// the normal part of how far its anchors moved; the anchors, fixed at preparation, are also the
// lever arms (Box2D 3 does the same). The bounce shifts and the position pass act on the states
// too, and the states go back to the bodies once, after the position pass. Base-100 pyramid,
// instructions per step (callgrind, 1 thread): 80.9M at c70fd1b, 38.9M now (solver 62.1M ->
// 22.7M); docs/soft_step.md has the steps.
//
// Shared with pgs as components this solver holds: the colouring (constraint_graph.h: graph_)
// and the prepared constraints with the collision passes and row kernels (contact_constraints.h:
// constraints_, kept only with restitution).
#include <atomic>
#include <cmath>
#include <cstring>
#include <numbers>

#include "dynamics/constraint_graph.h"
#include "dynamics/contact_constraints.h"
#include "dynamics/soft_rows.h"

namespace quadrant {
namespace {

using Clock = StageClock;

// Soft constraint coefficients for a spring of `hertz` and damping ratio `zeta` over step h:
// the bias velocity is biasRate * C, and massScale / impulseScale soften the impulse.
struct Softness {
  Real biasRate = 0;
  Real massScale = 1;
  Real impulseScale = 0;
};

// How a contact of two dynamic bodies meets WorldDef::softMassRatioLimit this step: not at all
// (plain), with the light body's masses scaled (limited), or over the ratio with the light body
// unsupported, so unscaled (cold). A cold contact is not warm-started: an impulse built with the
// scaled masses of an earlier step, applied to the light body's own, throws it (random extreme
// worlds went non-finite within 30 steps: 66 of 300, none without the warm start).
enum class LaneEnds : uint8_t { kPlain, kLimited, kCold };

Softness MakeSoftness(Real hertz, Real zeta, Real h) {
  if (hertz <= 0) return {};
  const Real omega = 2 * std::numbers::pi_v<Real> * hertz;
  const Real a1 = 2 * zeta + h * omega;
  const Real a2 = h * omega * a1;
  const Real a3 = Real(1) / (Real(1) + a2);
  return {omega / a1, a2 * a3, a3};
}

class SoftStepSolver final : public Solver {
 public:
  const char* Name() const override { return "soft_step"; }

  void Step(StepContext& ctx) override {
    DispatchEffects(ctx.def->effects,
                    [&](auto rotation, auto friction) { Run<decltype(rotation)::value, decltype(friction)::value>(ctx); });
  }

 private:
  template <bool kRotation, bool kFriction>
  void Run(StepContext& ctx) {
    const WorldDef& def = *ctx.def;
    Bodies& bodies = *ctx.bodies;
    StageRunner& run = *ctx.run;
    const int n = def.softSubSteps;
    const Real h = ctx.dt / Real(n);
    const Real invH = Real(1) / h;
    // Stiffer than the sub-step can resolve is unstable: at most a quarter of its rate.
    const Real hertz = std::min(def.contactHertz, Real(0.25) * invH);
    const Softness soft = MakeSoftness(hertz, def.contactDampingRatio, h);
    // Contacts with a static body hold twice as stiff: nothing on the other side gives way.
    const Softness staticSoft = MakeSoftness(2 * hertz, def.contactDampingRatio, h);
    // Each sub-step's friction row is bounded by mu times its normal impulse plus 1/n of the step's
    // collision impulse. The tangential impulse is a per-sub-step one (the warm start applies it
    // again every sub-step), so with the whole collision impulse in every sub-step's bound a
    // sliding bounce got up to n times the friction Coulomb allows over the impact: circle-circle
    // e = 0.5 differed from Box2D by 6.96 % at p90 with 4 sub-steps and 0.00 % with one; with the
    // share, 0.00 % at 4, and the whole campaign's p90 went from 9.47 % to 6.66 % (2000 hits, seed
    // 17).
    collisionShare_ = Real(1) / Real(n);

    double integrateMs = 0;
    auto t0 = Clock::now();
    // The sub-steps run on the compact solver state (velocity and motion since the step began,
    // 32 bytes a body) and on the rows in groups of eight (soft_rows.h), not on the body arrays
    // and the constraints. LoadFixedStates clears last step's flags and colour masks first; the
    // colouring's gather then marks the rows' bodies (MarkRow).
    auto ti = Clock::now();
    LoadFixedStates(run, bodies, def.effects.sleep);
    integrateMs += Ms(ti, Clock::now());
    const bool supported = def.softMassRatioLimit > 0;
    NextStamp(bodies.Count(), supported);
    if (supported) {
      graph_.Color(run, ctx, /*clearLater=*/true, [this](int a, int b) { MarkRow<true>(a, b); });
    } else {
      graph_.Color(run, ctx, /*clearLater=*/true, [this](int a, int b) { MarkRow<false>(a, b); });
    }
    const int m = graph_.Count();
    if (def.effects.restitution) constraints_.Resize(m);  // only restitution reads the list (lean, below)
    contacts_ = ctx.contacts;
    inv_ = bodies.inv.data();
    const bool simd = def.softSimd;
    vex_ = simd && def.softVex && CpuHasAvx();  // soft_rows.h: the rows eight at a time with AVX
    // Without restitution nothing but the rows reads a prepared constraint: each is prepared into
    // a local one as its row is built (BuildRows), and the list of constraints (144 bytes each,
    // written and read back once a step) is not kept. The restitution passes need the list.
    const bool lean = !def.effects.restitution;
    const bool box2dRestitution = def.effects.restitution && def.restitution == RestitutionPolicy::kBox2d;
    // The rows' part of the step: from preparing the constraints and the restitution passes to
    // storing the rows' bodies and impulses. The free bodies (MoveFreeBodies) do not depend on it:
    // no row reads or writes them (the restitution passes change the velocities of bodies with
    // an inverse mass in a contact only, which MarkRow has flagged as in rows, and LoadFixedStates
    // reads only those without one).
    auto rows = [&] {
      if (!lean) {
        run.For(Stage::kSolve, m, run.MinHeavyItems(),
                [&](int b, int e, int) { constraints_.Prepare<kRotation, true>(ctx, graph_, b, e); });
      }
      if (def.effects.restitution && !box2dRestitution) {
        const Vec2 stepGravity = def.effects.gravity ? ctx.dt * def.gravity : Vec2{};
        constraints_.ApplyCollisionPasses<kRotation>(run, graph_, bodies, def, Real(1) / ctx.dt, stepGravity);
      }
      lean ? BuildRows<kRotation, true>(ctx, soft, staticSoft, def.softMassRatioLimit)
           : BuildRows<kRotation, false>(ctx, soft, staticSoft, def.softMassRatioLimit);
      auto tr = Clock::now();
      LoadStates(run, bodies);
      integrateMs += Ms(tr, Clock::now());
      const SoftSolveParams prm{invH, def.contactPushMaxDepth, def.contactPushMaxVelocity};
      // Whether the position pass can move anything (CorrectStatePositions): the last sub-step's
      // first relax pass sees every point's separation at the step's final positions, and without
      // restitution nothing moves the bodies after it (the bounce shifts and Box2D's restitution
      // do). A point is counted deep below -contactPushMaxDepth + kDeepMargin: the position pass
      // computes the same separation in another order of operations, which differs by far less
      // (a few float ulps of the anchors and the motion, about 1e-6 m), so with no deep point it
      // moves nothing, and skipping it gives the same bits. Base-100 pyramid: its one pass over
      // the rows found nothing to move every step (0.98M instructions a step).
      std::atomic<bool>& deep = deep_.flag;
      deep.store(false, std::memory_order_relaxed);
      const bool maySkipPositions = !def.effects.restitution;
      constexpr Real kDeepMargin = Real(1e-4);
      SoftSolveParams lastPrm = prm;
      if (maySkipPositions) {
        lastPrm.deep = &deep;
        lastPrm.deepBelow = -def.contactPushMaxDepth + kDeepMargin;
      }
      // Each sub-step is one region of stages (TaskSystem::ParallelStages): gravity, the warm start
      // and the soft solve colour by colour, the positions, the relax passes colour by colour; the
      // threads go from stage to stage inside one job instead of one hand-over per pass (base-100
      // pyramid, default engine: 52 jobs a step before). Which thread runs which chunk never
      // changes the arithmetic. The sub-steps' integration is therefore timed as part of the solve.
      for (int sub = 0; sub < n; ++sub) {
        BeginRegion();
        IntegrateStateVelocities(run, bodies, def, h, sub == 0 ? ctx.dt : Real(0));
        if (def.effects.warmStarting) {
          ForEachGroup(run, simd, [&](auto lanes, SoftRowGroup& g, int lane) {
            WarmStartRows<decltype(lanes), kRotation>(states_.data(), g, lane);
          });
        }
        ForEachGroup(run, simd, [&](auto lanes, SoftRowGroup& g, int lane) {
          SolveRows<decltype(lanes), kRotation, kFriction, true>(states_.data(), g, lane, prm);
        });
        // The rotation guard is per world step: per sub-step it allowed n times the turn (188 rad/s
        // instead of 47 at 4 sub-steps), and spinning triangles of the soak left the box.
        IntegrateStatePositions(run, bodies, def, h, ctx.dt);
        // Friction only in the last relax pass: the earlier ones settle the normal impulses that
        // bound it. Base-100 pyramid: 44.7M -> 43.2M instructions a step, and the 16 hard cases hold
        // as with friction in both (tall_stack top 0.034 m; with friction in the first pass only
        // 0.051 m, which fails).
        //
        // With two or more relax passes the first stores each point's speculative bias and the later
        // ones load it (soft_rows.h, RelaxBias, says why).
        //
        // Lean (no restitution), the step's last relax pass also stores each row's impulses into
        // its contact as it solves the row (StoreLaneImpulses): nothing changes them after that
        // pass. A pass of their own read every group again after the position pass, at two
        // threads half of them from the other core's cache (a static split of all groups against
        // the passes' dynamic one per colour), and cost the base-100 pyramid 26-28 us a step at 1
        // thread and 28-32 at 2; the sub-step regions moved by -2 to +9 us a step, within the
        // runs' noise (2 alternated runs each, timed inside the runs with rdtsc). Same bits.
        const int relax = def.softRelaxIterations;
        const SoftSolveParams& firstPrm = sub == n - 1 ? lastPrm : prm;  // the first pass looks for deep points
        const bool storeLast = lean && sub == n - 1;
        for (int it = 0; it < relax; ++it) {
          if (relax == 1) {
            storeLast ? RelaxPass<kRotation, kFriction, RelaxBias::kCompute, true>(run, simd, firstPrm)
                      : RelaxPass<kRotation, kFriction, RelaxBias::kCompute>(run, simd, firstPrm);
          } else if (it == 0) {
            def.softFrictionEveryRelaxPass
                ? RelaxPass<kRotation, kFriction, RelaxBias::kComputeAndStore>(run, simd, firstPrm)
                : RelaxPass<kRotation, false, RelaxBias::kComputeAndStore>(run, simd, firstPrm);
          } else if (it == relax - 1 && storeLast) {
            RelaxPass<kRotation, kFriction, RelaxBias::kLoad, true>(run, simd, prm);
          } else if (it == relax - 1 || def.softFrictionEveryRelaxPass) {
            RelaxPass<kRotation, kFriction, RelaxBias::kLoad>(run, simd, prm);
          } else {
            RelaxPass<kRotation, false, RelaxBias::kLoad>(run, simd, prm);
          }
        }
        EndRegion(run);
        if (box2dRestitution && sub == 0 && m > 0) ApplyBox2dRestitution<kRotation, kFriction>(run, def, h);
      }
      if (def.effects.restitution && m > 0) {
        graph_.ForEachColor(run, [&](int b, int e) { ApplyStateBounceShifts(b, e); });
      }
      // Overlap deeper than the soft contacts push out (contactPushMaxDepth) is moved out here, by pgs's
      // position pass (on the solver states): positions change, velocities do not, so deep overlap
      // cannot fling bodies.
      if (m > 0 && (!maySkipPositions || deep.load(std::memory_order_relaxed))) {
        CorrectStatePositions<kRotation>(run, def, simd);
      }
      // Lean, the last relax pass stored the impulses (storeLast above; WorldDef validation keeps
      // softSubSteps and softRelaxIterations >= 1, so that pass always runs).
      if (!lean) {
        StoreRowImpulses(run);
        run.For(Stage::kSolve, m, run.MinHeavyItems(), [&](int b, int e, int) { constraints_.StoreImpulses(ctx.contacts, b, e); });
      }
    };
    // Few rows among many bodies (the sparse stress scenes): the rows' part runs on one thread
    // beside the free bodies' pass on the others (StageRunner::Beside), instead of its passes
    // splitting a few hundred rows across the threads with a barrier for every colour of every
    // pass, which gained nothing: circle stress N = 16000 (about 670 contacts a step) at 2 threads
    // had 53 stages in 11 regions a step, and its solve took 0.174 ms against 0.183 on 1 thread
    // (lead's measurement at ef96acf). kRowCost: a contact costs the rows' part about 30 times
    // what a free body costs MoveFreeBodies (callgrind, 20 steps of that scene, 1 thread: 1.24M
    // instructions a step for the rows' part, 0.92M for the free bodies' pass), so with up to
    // count / 16 contacts the rows' part is at most about twice the free bodies' work, and beside
    // it costs the step at most its own time, where split it cost about that and more. Measured
    // with this branch's other changes against main e65e950 (9 interleaved rounds, each after half
    // a second with the machine under 15 % busy, 60 + 10 steps, medians, 2 threads): solve +
    // integrate 0.275 -> 0.216 ms per step, the step 0.709 -> 0.584 (1 thread 0.906 / 0.905). The
    // rows' part is now the longer of the two sides.
    constexpr int kRowCost = 16;
    const int count = bodies.Count();
    if (int64_t(kRowCost) * m <= count) {
      run.Beside(Stage::kSolve, rows, count, run.MinItems(), [&](int b, int e) { MoveFreeBodies(bodies, def, ctx.dt, b, e); });
    } else {
      rows();
      ti = Clock::now();
      run.Dynamic(Stage::kIntegrate, count, run.MinItems(), kBodyGrain, [&](int b, int e) { MoveFreeBodies(bodies, def, ctx.dt, b, e); });
      integrateMs += Ms(ti, Clock::now());
    }
    // After the free bodies' pass, not in the rows' part: MoveFour reads the transforms of all
    // four bodies of a group (writing only the free ones), so the rows' bodies must not be
    // written while it runs.
    ti = Clock::now();
    StoreRowStates(run, bodies, def);
    integrateMs += Ms(ti, Clock::now());
    const double total = Ms(t0, Clock::now());
    ctx.profile->integrate += integrateMs;
    ctx.profile->solve += total - integrateMs;
  }

  // One relax pass over the rows (Run says which), queued in the sub-step's region.
  // kStore: then the rows' impulses into their contacts (lean only: Run says when).
  template <bool kRotation, bool kFriction, RelaxBias kRelax, bool kStore = false>
  void RelaxPass(StageRunner& run, bool simd, const SoftSolveParams& prm) {
    ForEachGroup(run, simd, [this, prm](auto lanes, SoftRowGroup& g, int lane) {
      RelaxBiasRows* cache = kRelax == RelaxBias::kCompute ? nullptr : &relaxBias_[&g - groups_.data()];
      SolveRows<decltype(lanes), kRotation, kFriction, false, kRelax>(states_.data(), g, lane, prm, cache);
      if constexpr (kStore) StoreLaneImpulses(g, lane, lane + kLaneWidth<decltype(lanes)>);
    });
  }

  // Lanes [begin, end) of group g: their accumulated impulses straight into their contacts'
  // manifolds (padding lanes have none), for the next step's warm start.
  void StoreLaneImpulses(const SoftRowGroup& g, int begin, int end) {
    for (int lane = begin; lane < end; ++lane) {
      if (g.constraint[lane] < 0) continue;
      Manifold& mf = contacts_[graph_.ContactOf(g.constraint[lane])].manifold;
      for (int pt = 0; pt < mf.pointCount; ++pt) {
        mf.points[pt].normalImpulse = g.p[pt].normalImpulse[lane];
        mf.points[pt].tangentImpulse = g.p[pt].tangentImpulse[lane];
      }
    }
  }

  // The rows in groups of eight, colour by colour (a colour's last group padded), from the
  // prepared constraints. Friction is solved in the relax pass only (as Box2D 3 does since it
  // split its push stage): during the soft solve the velocities still carry the push-out the
  // relax pass removes and the normal impulse its soft bias, so a friction row there resists a
  // sliding that is not real and is bounded by a load that is not real, and the warm start
  // carries its impulse into the next sub-step. With friction in both passes the 15-box stack's
  // top crept 0.014 m in 9 s and slowly toppled (worse at 8 and 16 sub-steps, with less
  // numerical damping: 0.14-0.17 m); with friction in the relax pass only it moves 0.0003 m.
  //
  // kLean: each constraint is prepared here into a local one (Run says when) instead of read from
  // the prepared list; the same arithmetic, so the same rows.
  template <bool kRotation, bool kLean>
  void BuildRows(StepContext& ctx, const Softness& soft, const Softness& staticSoft, Real massLimit) {
    StageRunner& run = *ctx.run;
    groupStart_.assign(ConstraintGraph::kColors + 2, 0);
    for (int k = 0; k <= ConstraintGraph::kColors; ++k) {
      const int count = graph_.ColorBegin(k + 1) - graph_.ColorBegin(k);
      groupStart_[k + 1] = groupStart_[k] + (count + kGroupRows - 1) / kGroupRows;
    }
    groups_.resize(groupStart_[ConstraintGraph::kColors + 1]);
    relaxBias_.resize(groups_.size());
    PlanPassStages();
    // One stage over every colour's groups: a group is built from its own constraints alone, so
    // no group waits for another colour's, and each chunk finds its groups' colours in
    // groupStart_. A stage per colour cost the base-100 pyramid five or six barriers a step, two
    // of them around colours of one chunk with the other thread idle. Traced at 2 threads (rdtsc
    // around the region, 5 alternated runs, medians over the steps): 77.9, 97.3, 77.1, 81.7, 164
    // -> 75.8, 75.6, 75.7, 106, 81.2 us; about 2 us where both runs of a pair were quiet.
    stagePlan_.assign(1, {groupStart_[ConstraintGraph::kColors + 1], ConstraintGraph::kColorGrain / kGroupRows});
    run.Stages(Stage::kSolve, stagePlan_, std::max(1, run.MinHeavyItems() / kGroupRows), [&](int, int gb, int ge) {
      int k = 0;  // the colour of group gb, then of each group in turn
      while (groupStart_[k + 1] <= gb) ++k;
      {
        for (int gi = gb; gi < ge; ++gi) {
          while (groupStart_[k + 1] <= gi) ++k;
          const int begin = groupStart_[k];
          SoftRowGroup& g = groups_[gi];
          if constexpr (kLean && kRotation) {
            const int first = graph_.ColorBegin(k) + (gi - begin) * kGroupRows;
            FillLeanGroup(ctx, g, first, graph_.ColorBegin(k + 1), soft, staticSoft, massLimit);
            continue;
          }
          for (int lane = 0; lane < kGroupRows; ++lane) {
            const int c = graph_.ColorBegin(k) + (gi - begin) * kGroupRows + lane;
            if (c >= graph_.ColorBegin(k + 1)) {
              PadLane(g, lane);
              continue;
            }
            if constexpr (kLean) {
              FillLeanLane<kRotation>(ctx, g, lane, c, soft, staticSoft, massLimit);
              continue;
            }
            const ContactConstraint& cc = constraints_[c];
            g.a[lane] = cc.a;
            g.b[lane] = cc.b;
            g.constraint[lane] = c;
            g.nx[lane] = cc.normal.x;
            g.ny[lane] = cc.normal.y;
            g.friction[lane] = cc.friction;
            g.invMassA[lane] = cc.invMassA;
            g.invIA[lane] = cc.invIA;
            g.invMassB[lane] = cc.invMassB;
            g.invIB[lane] = cc.invIB;
            // WorldDef::softMassRatioLimit: in a contact of two dynamic bodies whose masses differ
            // by more than the limit, the lighter one takes part as if it were only `limit` times
            // lighter (its inverse mass and inertia scaled down alike), so the heavy body's load
            // cannot drive it out of the way within the sub-step's single pass (docs/soft_step.md
            // gives the figures: a 1000 kg box on a 1 kg slab sinks 0.16 m and slides 0.86 m at
            // 4 sub-steps without it, 0.004 m and 0.0001 m with a limit of 10).
            //
            // Only where the lighter body also touches a static (or kinematic) body: its support
            // absorbs momentum there anyway, and between free bodies momentum stays exact (with the
            // limit on every contact the random campaign's 1:100 hits lost up to 1.99 of the mover's
            // momentum, and a 1:100 head-on hit came out wrong).
            bool limited = false, cold = false;
            if (massLimit > 0 && cc.invMassA > 0 && cc.invMassB > 0) {
              if (cc.invMassA > massLimit * cc.invMassB) {
                if (supported_[cc.a] == stamp_) {
                  const Real f = massLimit * cc.invMassB / cc.invMassA;
                  g.invMassA[lane] *= f;
                  g.invIA[lane] *= f;
                  limited = true;
                } else {
                  cold = true;
                }
              } else if (cc.invMassB > massLimit * cc.invMassA) {
                if (supported_[cc.b] == stamp_) {
                  const Real f = massLimit * cc.invMassA / cc.invMassB;
                  g.invMassB[lane] *= f;
                  g.invIB[lane] *= f;
                  limited = true;
                } else {
                  cold = true;
                }
              }
            }
            const Softness& s = (cc.invMassA == 0 || cc.invMassB == 0) ? staticSoft : soft;
            g.biasRate[lane] = s.biasRate;
            g.massScale[lane] = s.massScale;
            g.impulseScale[lane] = s.impulseScale;
            for (int pt = 0; pt < 2; ++pt) {
              SoftPointRows& p = g.p[pt];
              if (pt >= cc.pointCount) {
                PadPoint(p, lane);
                continue;
              }
              const PointConstraint& pc = cc.points[pt];
              p.rAx[lane] = pc.rA.x;
              p.rAy[lane] = pc.rA.y;
              p.rBx[lane] = pc.rB.x;
              p.rBy[lane] = pc.rB.y;
              p.separation[lane] = pc.separation;
              p.normalMass[lane] = pc.normalMass;
              p.tangentMass[lane] = pc.tangentMass;
              if (limited) {
                const Vec2 n = cc.normal, t = RightPerp(n);
                const Real rnA = Cross(pc.rA, n), rnB = Cross(pc.rB, n);
                const Real rtA = Cross(pc.rA, t), rtB = Cross(pc.rB, t);
                const Real mA = g.invMassA[lane], mB = g.invMassB[lane], iA = g.invIA[lane], iB = g.invIB[lane];
                const Real kn = mA + mB + iA * rnA * rnA + iB * rnB * rnB;
                const Real kt = mA + mB + iA * rtA * rtA + iB * rtB * rtB;
                p.normalMass[lane] = kn > 0 ? Real(1) / kn : Real(0);
                p.tangentMass[lane] = kt > 0 ? Real(1) / kt : Real(0);
              }
              p.normalImpulse[lane] = cold ? Real(0) : pc.normalImpulse;
              p.tangentImpulse[lane] = cold ? Real(0) : pc.tangentImpulse;
              p.collisionImpulse[lane] = pc.collisionImpulse * collisionShare_;
            }
          }
        }
      }
    });
  }

  // BuildRows' lane for constraint c straight from its contact (the lean path: Run says when),
  // with PrepareContact's arithmetic and then BuildRows' own, expression for expression, so the
  // same row bit for bit; without the constraint in between (base-100 pyramid: BuildRows 293 ->
  // 257 instructions a contact, the lane 237 of them).
  template <bool kRotation>
  void FillLeanLane(const StepContext& ctx, SoftRowGroup& g, int lane, int c, const Softness& soft,
                    const Softness& staticSoft, Real massLimit) {
    const Bodies& bodies = *ctx.bodies;
    const Contact& contact = contacts_[graph_.ContactOf(c)];
    const int a = contact.a, b = contact.b;
    const Vec2 n = contact.manifold.normal;
    const Real invMassA = inv_[a].invMass, invMassB = inv_[b].invMass;
    const Real invIA = kRotation ? inv_[a].invInertia : Real(0), invIB = kRotation ? inv_[b].invInertia : Real(0);
    const LaneEnds ends = FillLaneEnds<kRotation>(g, lane, c, contact, soft, staticSoft, massLimit);
    const bool limited = ends == LaneEnds::kLimited, cold = ends == LaneEnds::kCold;
    const Real mA = g.invMassA[lane], iA = g.invIA[lane], mB = g.invMassB[lane], iB = g.invIB[lane];
    const Real skin = ctx.def->polygonSkin > 0 ? PolygonSkin(*ctx.def, bodies.shape[a].type == ShapeType::kPolygon,
                                                             bodies.shape[b].type == ShapeType::kPolygon)
                                               : Real(0);
    const Vec2 t = RightPerp(n);
    const int count = contact.manifold.pointCount;
    for (int pt = 0; pt < 2; ++pt) {
      SoftPointRows& p = g.p[pt];
      if (pt >= count) {
        PadPoint(p, lane);
        continue;
      }
      const ManifoldPoint& mp = contact.manifold.points[pt];
      const Vec2 rA = mp.point - bodies.center[a];
      const Vec2 rB = mp.point - bodies.center[b];
      p.rAx[lane] = rA.x;
      p.rAy[lane] = rA.y;
      p.rBx[lane] = rB.x;
      p.rBy[lane] = rB.y;
      Real kn, kt;
      if (!limited) {  // PrepareContact's
        kn = invMassA + invMassB;
        kt = kn;
        if constexpr (kRotation) {
          const Real rnA = Cross(rA, n), rnB = Cross(rB, n);
          const Real rtA = Cross(rA, t), rtB = Cross(rB, t);
          kn += invIA * rnA * rnA + invIB * rnB * rnB;
          kt += invIA * rtA * rtA + invIB * rtB * rtB;
        }
      } else {  // BuildRows' for a limited contact
        const Real rnA = Cross(rA, n), rnB = Cross(rB, n);
        const Real rtA = Cross(rA, t), rtB = Cross(rB, t);
        kn = mA + mB + iA * rnA * rnA + iB * rnB * rnB;
        kt = mA + mB + iA * rtA * rtA + iB * rtB * rtB;
      }
      p.normalMass[lane] = kn > 0 ? Real(1) / kn : Real(0);
      p.tangentMass[lane] = kt > 0 ? Real(1) / kt : Real(0);
      p.separation[lane] = mp.separation - skin;
      p.normalImpulse[lane] = cold ? Real(0) : mp.normalImpulse;
      p.tangentImpulse[lane] = cold ? Real(0) : mp.tangentImpulse;
      p.collisionImpulse[lane] = Real(0) * collisionShare_;  // no collisions without restitution
    }
  }

  // The part of a lean row's lane that does not depend on its points: bodies, normal, friction,
  // inverse masses (with WorldDef::softMassRatioLimit, as BuildRows says) and softness. Returns
  // whether the limit scaled the lane's masses.
  template <bool kRotation>
  [[gnu::always_inline]] LaneEnds FillLaneEnds(SoftRowGroup& g, int lane, int c, const Contact& contact, const Softness& soft,
                                           const Softness& staticSoft, Real massLimit) {
    const int a = contact.a, b = contact.b;
    const Vec2 n = contact.manifold.normal;
    const Real invMassA = inv_[a].invMass, invMassB = inv_[b].invMass;
    const Real invIA = kRotation ? inv_[a].invInertia : Real(0), invIB = kRotation ? inv_[b].invInertia : Real(0);
    g.a[lane] = a;
    g.b[lane] = b;
    g.constraint[lane] = c;
    g.nx[lane] = n.x;
    g.ny[lane] = n.y;
    g.friction[lane] = contact.friction;
    Real mA = invMassA, iA = invIA, mB = invMassB, iB = invIB;
    LaneEnds ends = LaneEnds::kPlain;
    if (massLimit > 0 && invMassA > 0 && invMassB > 0) {
      if (invMassA > massLimit * invMassB) {
        if (supported_[a] == stamp_) {
          const Real f = massLimit * invMassB / invMassA;
          mA *= f;
          iA *= f;
          ends = LaneEnds::kLimited;
        } else {
          ends = LaneEnds::kCold;
        }
      } else if (invMassB > massLimit * invMassA) {
        if (supported_[b] == stamp_) {
          const Real f = massLimit * invMassA / invMassB;
          mB *= f;
          iB *= f;
          ends = LaneEnds::kLimited;
        } else {
          ends = LaneEnds::kCold;
        }
      }
    }
    g.invMassA[lane] = mA;
    g.invIA[lane] = iA;
    g.invMassB[lane] = mB;
    g.invIB[lane] = iB;
    const Softness& s = (invMassA == 0 || invMassB == 0) ? staticSoft : soft;
    g.biasRate[lane] = s.biasRate;
    g.massScale[lane] = s.massScale;
    g.impulseScale[lane] = s.impulseScale;
    return ends;
  }

  // FillLeanLane for a whole group with rotation (the default): the per-lane part (bodies,
  // masses, softness, the points' separations and impulses) lane by lane, then the points' lever
  // arms and effective masses for all eight lanes at once (two halves of four with SSE2), with the
  // same operations per lane in the same order, so the same row bit for bit (rows with a padded
  // lane or point are padded afterwards, as FillLeanLane pads them). Base-100 pyramid: the lane
  // fill was 237 instructions a contact, its four divisions a point pair a chain of scalar
  // dependencies.
  void FillLeanGroup(const StepContext& ctx, SoftRowGroup& g, int first, int colorEnd, const Softness& soft,
                     const Softness& staticSoft, Real massLimit) {
    const Bodies& bodies = *ctx.bodies;
    const bool skinOn = ctx.def->polygonSkin > 0;
    // The points and the bodies' centres of each lane; 1 in `limited` for a lane whose masses
    // softMassRatioLimit scaled (its effective masses are computed from the scaled ones, as
    // BuildRows does), and the lanes and points to pad afterwards.
    alignas(32) Real px[2][kGroupRows] = {}, py[2][kGroupRows] = {};
    alignas(32) Real cax[kGroupRows] = {}, cay[kGroupRows] = {}, cbx[kGroupRows] = {}, cby[kGroupRows] = {};
    alignas(32) Real limitedLane[kGroupRows] = {};
    unsigned padLane = 0, padPoint[2] = {0, 0};
    for (int lane = 0; lane < kGroupRows; ++lane) {
      const int c = first + lane;
      if (c >= colorEnd) {
        padLane |= 1u << lane;
        continue;
      }
      const Contact& contact = contacts_[graph_.ContactOf(c)];
      const int a = contact.a, b = contact.b;
      const LaneEnds ends = FillLaneEnds<true>(g, lane, c, contact, soft, staticSoft, massLimit);
      if (ends == LaneEnds::kLimited) limitedLane[lane] = 1;
      const bool cold = ends == LaneEnds::kCold;
      const Real skin = skinOn ? PolygonSkin(*ctx.def, bodies.shape[a].type == ShapeType::kPolygon,
                                             bodies.shape[b].type == ShapeType::kPolygon)
                               : Real(0);
      const Vec2 ca = bodies.center[a], cb = bodies.center[b];
      cax[lane] = ca.x;
      cay[lane] = ca.y;
      cbx[lane] = cb.x;
      cby[lane] = cb.y;
      const int count = contact.manifold.pointCount;
      for (int pt = 0; pt < 2; ++pt) {
        SoftPointRows& p = g.p[pt];
        if (pt >= count) {
          padPoint[pt] |= 1u << lane;
          continue;
        }
        const ManifoldPoint& mp = contact.manifold.points[pt];
        px[pt][lane] = mp.point.x;
        py[pt][lane] = mp.point.y;
        p.separation[lane] = mp.separation - skin;
        p.normalImpulse[lane] = cold ? Real(0) : mp.normalImpulse;
        p.tangentImpulse[lane] = cold ? Real(0) : mp.tangentImpulse;
        p.collisionImpulse[lane] = Real(0) * collisionShare_;  // no collisions without restitution
      }
    }
    for (int pt = 0; pt < 2; ++pt) {
#if QUADRANT_SOFT_SIMD
      for (int lane = 0; lane < kGroupRows; lane += 4) LeanPointMath<F4>(g, pt, lane, px[pt], py[pt], cax, cay, cbx, cby, limitedLane);
#else
      for (int lane = 0; lane < kGroupRows; ++lane) LeanPointMath<Real>(g, pt, lane, px[pt], py[pt], cax, cay, cbx, cby, limitedLane);
#endif
    }
    for (int lane = 0; lane < kGroupRows; ++lane) {
      if (padLane >> lane & 1u) {
        PadLane(g, lane);
        continue;
      }
      for (int pt = 0; pt < 2; ++pt) {
        if (padPoint[pt] >> lane & 1u) PadPoint(g.p[pt], lane);
      }
    }
  }

  // FillLeanGroup's vector part for point `pt` of lanes [lane, lane + width of V): FillLeanLane's
  // expressions for rA, rB and the two effective masses, with both of its formulas computed and
  // the lane's one selected (an unlimited lane: (mA + mB) + (iA rnA rnA + iB rnB rnB), as
  // PrepareContact sums it; a limited one: ((mA + mB) + iA rnA rnA) + iB rnB rnB, as BuildRows does).
  template <class V>
  [[gnu::always_inline]] static void LeanPointMath(SoftRowGroup& g, int pt, int lane, const Real* px, const Real* py,
                                                   const Real* cax, const Real* cay, const Real* cbx, const Real* cby,
                                                   const Real* limitedLane) {
    const V z = Splat(Real(0), V{});
    SoftPointRows& p = g.p[pt];
    const V x = Load(px, lane, z), y = Load(py, lane, z);
    const V rAx = x - Load(cax, lane, z), rAy = y - Load(cay, lane, z);
    const V rBx = x - Load(cbx, lane, z), rBy = y - Load(cby, lane, z);
    Store(p.rAx, lane, rAx);
    Store(p.rAy, lane, rAy);
    Store(p.rBx, lane, rBx);
    Store(p.rBy, lane, rBy);
    const V nx = Load(g.nx, lane, z), ny = Load(g.ny, lane, z);
    const V tx = ny, ty = Neg(nx);  // RightPerp(n)
    const V rnA = rAx * ny - rAy * nx, rnB = rBx * ny - rBy * nx;
    const V rtA = rAx * ty - rAy * tx, rtB = rBx * ty - rBy * tx;
    const V mA = Load(g.invMassA, lane, z), mB = Load(g.invMassB, lane, z);
    const V iA = Load(g.invIA, lane, z), iB = Load(g.invIB, lane, z);
    const V m = mA + mB;
    const V knFree = m + (iA * rnA * rnA + iB * rnB * rnB);
    const V ktFree = m + (iA * rtA * rtA + iB * rtB * rtB);
    const V knLimited = m + iA * rnA * rnA + iB * rnB * rnB;
    const V ktLimited = m + iA * rtA * rtA + iB * rtB * rtB;
    const auto limited = Greater(Load(limitedLane, lane, z), z);
    const V kn = Select(limited, knLimited, knFree), kt = Select(limited, ktLimited, ktFree);
    const V one = Splat(Real(1), z);
    Store(p.normalMass, lane, Masked(Greater(kn, z), Div(one, kn)));
    Store(p.tangentMass, lane, Masked(Greater(kt, z), Div(one, kt)));
  }


  // The flags of the rows' ends, set from the colouring's gather (ConstraintGraph::Color) for a
  // contact with dynamic ends a and b (-1 for an end that is not dynamic): inRows_[i] = 1 for
  // every dynamic body in a row (LoadStates says what for; LoadFixedStates has cleared the flags
  // and set the kinematic ones), and, with kSupported, supported_[i] = stamp_ for every dynamic
  // body with a contact against a static, kinematic or sleeping one (WorldDef::softMassRatioLimit
  // acts only on those). Workers may write one flag at once, always the same value: relaxed
  // atomic stores (plain stores on x86), so that is no data race. The stamp changes every step,
  // so supported_ needs no clearing pass. This was a pass of its own, colour by colour (a stage
  // and a barrier per colour at 2 threads; base-100 pyramid: 0.32M instructions a step).
  template <bool kSupported>
  void MarkRow(int a, int b) {
    if (a >= 0) std::atomic_ref<uint8_t>(inRows_[a]).store(1, std::memory_order_relaxed);
    if (b >= 0) std::atomic_ref<uint8_t>(inRows_[b]).store(1, std::memory_order_relaxed);
    if constexpr (kSupported) {
      if (a >= 0 && b < 0) std::atomic_ref<uint32_t>(supported_[a]).store(stamp_, std::memory_order_relaxed);
      if (b >= 0 && a < 0) std::atomic_ref<uint32_t>(supported_[b]).store(stamp_, std::memory_order_relaxed);
    }
  }

  // This step's stamp for supported_ (MarkRow).
  void NextStamp(int bodyCount, bool supported) {
    if (!supported) return;
    supported_.resize(bodyCount, 0);
    if (++stamp_ == 0) {  // wrapped (after 2^32 steps): no flag may hold the new stamp
      std::fill(supported_.begin(), supported_.end(), 0u);
      stamp_ = 1;
    }
  }

  static void PadPoint(SoftPointRows& p, int lane) {
    p.rAx[lane] = p.rAy[lane] = p.rBx[lane] = p.rBy[lane] = 0;
    p.separation[lane] = kPadSeparation;
    p.normalMass[lane] = p.tangentMass[lane] = 0;
    p.normalImpulse[lane] = p.tangentImpulse[lane] = 0;
    p.collisionImpulse[lane] = 0;
  }

  // A row that touches nothing: inverse masses 0, so it writes no body. It reads the bodies of
  // the group's first row (always a real one), which only this thread writes in this colour:
  // any other body could be written by another thread meanwhile (a race, though its values
  // would be discarded).
  static void PadLane(SoftRowGroup& g, int lane) {
    g.a[lane] = g.a[0];
    g.b[lane] = g.b[0];
    g.constraint[lane] = -1;
    g.nx[lane] = 0;
    g.ny[lane] = 1;
    g.friction[lane] = 0;
    g.invMassA[lane] = g.invIA[lane] = g.invMassB[lane] = g.invIB[lane] = 0;
    g.biasRate[lane] = 0;
    g.massScale[lane] = 1;
    g.impulseScale[lane] = 0;
    PadPoint(g.p[0], lane);
    PadPoint(g.p[1], lane);
  }

  // fn(lanes, group, lane): lanes is a Real (one row: the given lane), an F4 (the four rows from
  // `lane`) or an F8Avx (the group's eight rows; kLaneWidth says how many). The overflow colour's
  // rows may share bodies: one at a time, in order, on one thread.
  template <class Fn>
  void ForEachGroup(StageRunner& run, bool simd, Fn&& fn) {
    if (collecting_) {
      QueueGroups(simd, std::forward<Fn>(fn));
      return;
    }
    // One region per pass, a stage per colour (ForEachColor says why); the overflow colour's
    // groups are one chunk, run row by row.
    stagePlan_.clear();
    stageFirst_.clear();
    for (const StagePart& part : passStages_) {
      stagePlan_.push_back({part.count, part.grain});
      stageFirst_.push_back(part.first);
    }
    const int overflow = groupStart_[ConstraintGraph::kColors];
    run.Stages(Stage::kSolve, stagePlan_, std::max(1, run.MinHeavyItems() / kGroupRows), [&](int s, int b, int e) {
      RunGroups(simd && stageFirst_[s] < overflow, fn, stageFirst_[s] + b, stageFirst_[s] + e);
    });
  }

  // Groups [gb, ge) eight rows at a time with AVX where vex_, else four (fourWide: two calls a
  // group), or row by row (the scalar path, and the overflow colour, whose rows may share bodies).
  template <class Fn>
  void RunGroups(bool fourWide, Fn& fn, int gb, int ge) {
#if QUADRANT_SOFT_SIMD
    if (fourWide) {
      if (vex_) {
        for (int gi = gb; gi < ge; ++gi) fn(F8Avx{}, groups_[gi], 0);
      } else {
        for (int gi = gb; gi < ge; ++gi) {
          fn(F4{}, groups_[gi], 0);
          fn(F4{}, groups_[gi], kLanes);
        }
      }
      return;
    }
#else
    (void)fourWide;
#endif
    for (int gi = gb; gi < ge; ++gi) {
      for (int lane = 0; lane < kGroupRows; ++lane) fn(Real{}, groups_[gi], lane);
    }
  }

  // RestitutionPolicy::kBox2d (restitution_policy.h): Box2D's restitution as a velocity target
  // rather than a collision before the sub-steps. Each point whose approach speed before the step
  // gave it a bias (touching, above the threshold) gets rigid rows after the first sub-step's relax
  // pass: restitutionIterations passes of, per contact, friction then normal rows, the normal row
  // keeping vn >= -e vn0 with an impulse of its own (it can only push apart), friction bounded by
  // mu times the sub-step's normal impulse plus that one, as Box2D 2.4.1's iterations bound it by
  // the whole biased impulse. The later sub-steps' warm start repeats this sub-step's friction and
  // their relax pass clamps it back to their own bound, so the step's friction stays within mu
  // times its normal impulses (RestitutionPolicyTest.SlidingBounceGetsCoulombFrictionOverTheWholeImpact).
  //
  // Why after the first sub-step, not after the last as Box2D 3 applies it: the bodies then move
  // apart within the step, as in Box2D 2.4.1. One row at a time (no four-wide path), colour by
  // colour as the rows are solved: it runs once per step, on bouncing points, under this setting.
  template <bool kRotation, bool kFriction>
  void ApplyBox2dRestitution(StageRunner& run, const WorldDef& def, Real h) {
    SolverBody* states = states_.data();
    auto row = [&](SoftRowGroup& g, int lane) {
      const int c = g.constraint[lane];
      if (c < 0) return;
      const ContactConstraint& cc = constraints_[c];
      if (cc.points[0].restitutionBias <= 0 && (cc.pointCount < 2 || cc.points[1].restitutionBias <= 0)) return;
      const Vec2 n = cc.normal, t = RightPerp(n);
      SolverBody& A = states[cc.a];
      SolverBody& B = states[cc.b];
      SolverBody a = A, b = B;
      auto relative = [&](const PointConstraint& pc) { return RelativeVelocity<kRotation>(a, b, pc); };
      auto apply = [&](const PointConstraint& pc, Vec2 P) { ApplyPointImpulse<kRotation>(cc, pc, P, a, b); };
      Real bounce[2] = {0, 0};  // the normal rows' bounce impulses
      for (int it = 0; it < def.restitutionIterations; ++it) {
        if constexpr (kFriction) {
          for (int k = 0; k < cc.pointCount; ++k) {
            SoftPointRows& p = g.p[k];
            p.tangentImpulse[lane] = SolveFrictionRow<kRotation>(cc, cc.points[k], t, p.tangentImpulse[lane],
                                                                 p.normalImpulse[lane] + bounce[k], a, b);
          }
        }
        const PointConstraint& p0 = cc.points[0];
        const PointConstraint& p1 = cc.points[1];
        if (cc.pointCount == 2 && cc.block && p0.restitutionBias > 0 && p1.restitutionBias > 0) {
          // Both points of a face together (the 2x2 problem, as pgs's block solver): one after the
          // other, four passes left a box landing flat spinning at 0.006 rad/s.
          const Real k11 = Real(1) / p0.normalMass, k22 = Real(1) / p1.normalMass;
          const Real b0 = Dot(relative(p0), n) - p0.restitutionBias - (k11 * bounce[0] + cc.k12 * bounce[1]);
          const Real b1 = Dot(relative(p1), n) - p1.restitutionBias - (cc.k12 * bounce[0] + k22 * bounce[1]);
          Real x0, x1;
          if (SolveLcp2(k11, cc.k12, k22, b0, b1, x0, x1)) {
            apply(p0, (x0 - bounce[0]) * n);
            apply(p1, (x1 - bounce[1]) * n);
            bounce[0] = x0;
            bounce[1] = x1;
          }
          continue;
        }
        for (int k = 0; k < cc.pointCount; ++k) {
          const PointConstraint& pc = cc.points[k];
          if (pc.restitutionBias <= 0) continue;
          const Real vn = Dot(relative(pc), n);
          const Real newImpulse = std::max(bounce[k] - pc.normalMass * (vn - pc.restitutionBias), Real(0));
          apply(pc, (newImpulse - bounce[k]) * n);
          bounce[k] = newImpulse;
        }
      }
      // The first sub-step's motion as if the bounce had acted from its start, as Box2D 2.4.1's
      // bias does within the step it is captured in.
      auto move = [&](SolverBody& to, const SolverBody& from) {
        to.dp += h * (from.v - to.v);
        if constexpr (kRotation) {
          if (from.w != to.w) to.dq = IntegrateRot(to.dq, h * (from.w - to.w));
        }
        to.v = from.v;
        to.w = from.w;
      };
      if (cc.invMassA > 0) move(A, a);
      if (cc.invMassB > 0) move(B, b);
    };
    ForEachGroup(run, false, [&](auto lanes, SoftRowGroup& g, int lane) {
      if constexpr (std::is_same_v<decltype(lanes), Real>) {
        row(g, lane);
      } else {
        for (int l = lane; l < lane + kLaneWidth<decltype(lanes)>; ++l) row(g, l);
      }
    });
  }

  // ApplyBounceShifts (contact_constraints.h) on the solver states.
  void ApplyStateBounceShifts(int begin, int end) {
    for (int c = begin; c < end; ++c) {
      const ContactConstraint& cc = constraints_[c];
      Vec2 d;
      if (!ContactConstraints::BounceShift(cc, d)) continue;
      if (cc.invMassA > 0) states_[cc.a].dp += cc.invMassA * d;
      if (cc.invMassB > 0) states_[cc.b].dp -= cc.invMassB * d;
    }
  }

  // Up to positionIterations passes of SolvePositionRows (soft_rows.h), colour by colour; a pass
  // that moves nothing leaves every later one nothing to do, so the loop stops there.
  template <bool kRotation>
  void CorrectStatePositions(StageRunner& run, const WorldDef& def, bool simd) {
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
  // step's warm start). With restitution only: lean, the last relax pass stores them into the
  // contacts (StoreLaneImpulses).
  void StoreRowImpulses(StageRunner& run) {
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

  // The solver state of every body a row may read: its velocity (after the restitution passes), no motion yet.
  // And which bodies the sub-steps integrate (inRows_): every moving body at an end of a contact
  // row, and every kinematic body (rows read its motion, and a colour may share it, so it is not
  // marked from the rows). The rest are free: nothing acts on them but gravity within the step,
  // and StoreStates moves them over the whole step at once.
  // First the bodies that rows read but never write (inverse mass 0: static, kinematic, sleeping),
  // with the flags cleared (kinematic ones set); the colouring then flags the dynamic bodies in
  // rows (MarkRow). The same pass clears the colour masks Color left last step (before this step's
  // colouring, which needs them zero): one pass over the bodies instead of three (this, the masks' clearing and SnapshotPositions, whose snapshot LoadStates now takes
  // of the rows' bodies only), each a hand-over and a join at 2 threads (circle stress N = 16000:
  // 3 of the step's 5 solver passes over all 16004 bodies).
  void LoadFixedStates(StageRunner& run, const Bodies& bodies, bool sleep) {
    const int count = bodies.Count();
    states_.resize(count);
    inRows_.resize(count + kFlagPad);  // padded: the scans below read several flags at a time
    run.Dynamic(Stage::kIntegrate, count, run.MinItems(), kBodyGrain, [&](int b, int e) {
      graph_.ClearColors(b, e);
      // Raw pointers: with the vectors' own, every store reloaded their data pointers.
      const BodyInverseMass* inv = bodies.inv.data();
      const BodyVelocity* vel = bodies.vel.data();
      const BodyType* type = bodies.type.data();
      const uint8_t* awake = bodies.awake.data();
      SolverBody* states = states_.data();
      uint8_t* inRows = inRows_.data();
      for (int i = b; i < e; ++i) {
        // Static, kinematic and sleeping bodies (inverse mass 0) here: rows read them. The
        // dynamic ones in rows after the list below; free ones need no state (StoreStates moves
        // them from their velocity). Circle stress N = 4000: this pass was 1.92M of 20 steps'
        // instructions filling every body's state.
        uint8_t kinematicMoving = 0;
        if (inv[i].invMass == 0) {
          states[i] = SolverBody{vel[i].v, vel[i].w, 0, Vec2{}, Rot{}};
          // Moves(): a kinematic body is never static, so without sleep it moves.
          kinematicMoving = type[i] == BodyType::kKinematic && (!sleep || awake[i] != 0);
        }
        inRows[i] = kinematicMoving;
      }
    });
    for (int k = 0; k < kFlagPad; ++k) inRows_[count + k] = 0;
  }

  // After the colouring (MarkRow): the list of the bodies in rows and their states.
  void LoadStates(StageRunner& run, const Bodies& bodies) {
    const int count = bodies.Count();
    // The bodies the sub-steps integrate, in index order (so in the same order on any thread
    // count; each body's operations are its own, so the order changes no bit anyway). The sub-step
    // passes and StoreStates walk this list instead of every body: on the sparse stress scenes
    // about 95 % of the bodies are free. Eight flags at a time: most words are all zero there.
    // With MoveFour and the states loaded only where rows read them (callgrind on quadrant_icount,
    // 1 thread, same state hashes; before = d776c64): circle stress N = 4000, 20 steps, 56.37M ->
    // 49.94M instructions (pgs 46.30M); polygon stress 101.25M -> 93.62M (pgs 88.48M); base-100
    // pyramid, 10 steps, 430.35M -> 431.53M. What is left over pgs is mostly MoveFour's own arithmetic (about 66 instructions a
    // free body a step, kept operation for operation so the bits stay).
    // Written through a pointer into a list sized for every body (push_back was 23 instructions a
    // body in the base-100 pyramid), then cut to length.
    active_.resize(count);
    int* out = active_.data();
    int listed = 0;
    for (int i = 0; i < count; i += 8) {
      uint64_t eight;
      std::memcpy(&eight, &inRows_[i], sizeof eight);
      if (eight == 0) continue;
      for (int k = i; k < i + 8 && k < count; ++k) {
        out[listed] = k;
        listed += inRows_[k] != 0;
      }
    }
    active_.resize(listed);
    // Where the rows' bodies start (StoreRowStates adds their motion to it); the free bodies
    // need no snapshot (MoveFree).
    center0_.resize(count);
    rot0_.resize(count);
    run.Dynamic(Stage::kIntegrate, ActiveCount(), run.MinItems(), kBodyGrain, [&](int b, int e) {
      for (int k = b; k < e; ++k) {
        const int i = active_[k];
        if (bodies.inv[i].invMass != 0) states_[i] = SolverBody{bodies.vel[i].v, bodies.vel[i].w, 0, Vec2{}, Rot{}};
        center0_[i] = bodies.center[i];
        rot0_[i] = bodies.xf[i].q;
      }
    });
  }

  // Gravity over a sub-step, as IntegrateVelocities does on the bodies: for bodies with an inverse
  // mass (dynamic and awake; a sleeping body has inverse mass 0). Damping acts once per world step
  // (dampDt, 0 in the later sub-steps) with the step's factor 1 / (1 + dt c), the law every solver
  // and the scene description share (per sub-step the factor over a step was 1 / (1 + h c)^n:
  // 0.3 % more speed left after 60 steps at c = 0.7).
  void IntegrateStateVelocities(StageRunner& run, const Bodies& bodies, const WorldDef& def, Real h, Real dampDt) {
    const Effects& fx = def.effects;
    const bool damp = fx.damping && dampDt > 0;
    if (!fx.gravity && !damp) return;
    const Vec2 dv = fx.gravity ? h * def.gravity : Vec2{};
#if QUADRANT_SOFT_SIMD
    // Gravity alone: one four-wide add per body of (dv.x, dv.y, -0, -0), which leaves w and the
    // pad word exactly as they are (x + -0 is x for every x, signed zeros included).
    if (!damp && def.softSimd) {
      const __m128 add = _mm_set_ps(-0.0f, -0.0f, dv.y, dv.x);
      BodyPass(run, [this, &bodies, add](int b, int e, int) {
        for (int k = b; k < e; ++k) {
          const int i = active_[k];
          if (bodies.inv[i].invMass == 0) continue;
          float* v = &states_[i].v.x;
          _mm_storeu_ps(v, _mm_add_ps(_mm_loadu_ps(v), add));
        }
      });
      return;
    }
#endif
    BodyPass(run, [this, &bodies, dv, damp, dampDt](int b, int e, int) {
      for (int k = b; k < e; ++k) {
        const int i = active_[k];
        if (bodies.inv[i].invMass == 0) continue;
        SolverBody& st = states_[i];
        st.v += dv;
        if (damp) {
          st.v = (Real(1) / (Real(1) + dampDt * bodies.linearDamping[i])) * st.v;
          st.w *= Real(1) / (Real(1) + dampDt * bodies.angularDamping[i]);
        }
      }
    });
  }

  // Motion over a sub-step, with integrate.cpp's guards (speed limit; the turn limit per world
  // step stepDt). Every moving body (dynamic awake or kinematic) moves; static ones stay.
  void IntegrateStatePositions(StageRunner& run, const Bodies& bodies, const WorldDef& def, Real h, Real stepDt) {
    const Real maxSpeed2 = def.maxLinearSpeed * def.maxLinearSpeed;
    const Real maxAngularSpeed = def.maxRotation / stepDt;
    const bool rotation = def.effects.rotation, sleep = def.effects.sleep;
    // Only the bodies in rows (active_): StoreStates moves the free ones over the whole step.
    const bool simd = def.softSimd;
    const Real maxLinearSpeed = def.maxLinearSpeed;
    BodyPass(run, [this, &bodies, simd, sleep, rotation, h, maxSpeed2, maxLinearSpeed, maxAngularSpeed](int b, int e, int) {
      int k = b;
#if QUADRANT_SOFT_SIMD
      // Four bodies at a time: the same operations per body as the loop below (IntegrateRot's
      // small-angle branch is TurnBy), so the same bits. Circle stress (N = 4000, soft_step):
      // this pass was a third of the step's instructions, most of them IntegrateRot calls.
      if (simd) {
        for (; k + kLanes <= e; k += kLanes) {
          const int* idx = &active_[k];
          const bool done = vex_ ? IntegrateFourVex(bodies, idx, sleep, rotation, h, maxSpeed2, maxLinearSpeed, maxAngularSpeed)
                                 : IntegrateFour(bodies, idx, sleep, rotation, h, maxSpeed2, maxLinearSpeed, maxAngularSpeed);
          if (!done) {
            for (int l = 0; l < kLanes; ++l) {
              IntegrateOne(bodies, idx[l], sleep, rotation, h, maxSpeed2, maxLinearSpeed, maxAngularSpeed);
            }
          }
        }
      }
#else
      (void)simd;
#endif
      for (; k < e; ++k) {
        IntegrateOne(bodies, active_[k], sleep, rotation, h, maxSpeed2, maxLinearSpeed, maxAngularSpeed);
      }
    });
  }

  static bool Moves(const Bodies& bodies, int i, bool sleep) {
    return sleep ? bodies.awake[i] != 0 : bodies.type[i] != BodyType::kStatic;
  }

  void IntegrateOne(const Bodies& bodies, int i, bool sleep, bool rotation, Real h, Real maxSpeed2, Real maxSpeed,
                    Real maxAngularSpeed) {
    if (!inRows_[i] || !Moves(bodies, i, sleep)) return;
    SolverBody& st = states_[i];
    const Real speed2 = LengthSquared(st.v);
    if (speed2 > maxSpeed2) st.v = (maxSpeed / std::sqrt(speed2)) * st.v;
    st.w = std::clamp(st.w, -maxAngularSpeed, maxAngularSpeed);
    st.dp += h * st.v;
    if (rotation && st.w != 0) st.dq = IntegrateRot(st.dq, h * st.w);
  }

#if QUADRANT_SOFT_SIMD
  // Bodies idx[0..3] (distinct); returns false, having written nothing, if one of them turns by 0.5 rad or
  // more in the sub-step (IntegrateRot takes sin and cos there).
  // The same in AVX's encoding (soft_rows.h says why; the same operations, the same bits).
#if QUADRANT_SOFT_VEX
  [[gnu::target("avx"), gnu::noinline]] bool IntegrateFourVex(const Bodies& bodies, const int* idx, bool sleep,
                                                               bool rotation, Real h, Real maxSpeed2, Real maxSpeed,
                                                               Real maxAngularSpeed) {
    return IntegrateFour(bodies, idx, sleep, rotation, h, maxSpeed2, maxSpeed, maxAngularSpeed);
  }
#else
  bool IntegrateFourVex(const Bodies& bodies, const int* idx, bool sleep, bool rotation, Real h, Real maxSpeed2,
                        Real maxSpeed, Real maxAngularSpeed) {
    return IntegrateFour(bodies, idx, sleep, rotation, h, maxSpeed2, maxSpeed, maxAngularSpeed);
  }
#endif

  [[gnu::always_inline]] bool IntegrateFour(const Bodies& bodies, const int* idx, bool sleep, bool rotation, Real h, Real maxSpeed2,
                     Real maxSpeed, Real maxAngularSpeed) {
    float* s[kLanes] = {&states_[idx[0]].v.x, &states_[idx[1]].v.x, &states_[idx[2]].v.x, &states_[idx[3]].v.x};
    __m128 a0 = _mm_loadu_ps(s[0]), a1 = _mm_loadu_ps(s[1]), a2 = _mm_loadu_ps(s[2]), a3 = _mm_loadu_ps(s[3]);
    __m128 b0 = _mm_loadu_ps(s[0] + 4), b1 = _mm_loadu_ps(s[1] + 4), b2 = _mm_loadu_ps(s[2] + 4), b3 = _mm_loadu_ps(s[3] + 4);
    _MM_TRANSPOSE4_PS(a0, a1, a2, a3);
    _MM_TRANSPOSE4_PS(b0, b1, b2, b3);
    F4 vx{a0}, vy{a1}, w{a2}, dpx{b0}, dpy{b1}, qc{b2}, qs{b3};
    const F4 speed2 = vx * vx + vy * vy;
    const M4 fast = Greater(speed2, Splat(maxSpeed2, F4{}));
    if (Any(fast)) {
      const F4 scale = Div(Splat(maxSpeed, F4{}), Sqrt(speed2));
      vx = Select(fast, scale * vx, vx);
      vy = Select(fast, scale * vy, vy);
    }
    const F4 maxW = Splat(maxAngularSpeed, F4{});
    w = Min(Max(w, Neg(maxW)), maxW);
    const F4 hv = Splat(h, F4{});
    dpx = dpx + hv * vx;
    dpy = dpy + hv * vy;
    if (rotation) {
      const F4 turn = hv * w;
      const M4 turns = {_mm_cmpneq_ps(w.v, _mm_setzero_ps())};
      if (Any(turns)) {
        if (Any(GreaterEqual(Max(turn, Neg(turn)), Splat(Real(0.5), F4{})))) return false;
        F4 c = qc, sn = qs;
        TurnBy(c, sn, turn);
        qc = Select(turns, c, qc);
        qs = Select(turns, sn, qs);
      }
    }
    a0 = vx.v, a1 = vy.v, a2 = w.v, a3 = _mm_setzero_ps();
    b0 = dpx.v, b1 = dpy.v, b2 = qc.v, b3 = qs.v;
    _MM_TRANSPOSE4_PS(a0, a1, a2, a3);
    _MM_TRANSPOSE4_PS(b0, b1, b2, b3);
    const __m128 as[4] = {a0, a1, a2, a3}, bs[4] = {b0, b1, b2, b3};
    for (int k = 0; k < kLanes; ++k) {
      if (!Moves(bodies, idx[k], sleep)) continue;
      _mm_storeu_ps(s[k], as[k]);
      _mm_storeu_ps(s[k] + 4, bs[k]);
    }
    return true;
  }
#endif

  // Back to the bodies: velocity, centre (where the step began plus the motion) and rotation.
  // The free bodies (MoveFreeBodies) and those in rows (StoreRowStates) are separate passes: the
  // first does not depend on the sub-steps (Run runs it beside them where the rows are few).
  void StoreStates(StageRunner& run, Bodies& bodies, const WorldDef& def, Real dt) {
    run.For(Stage::kIntegrate, bodies.Count(), run.MinItems(),
            [&](int b, int e, int) { MoveFreeBodies(bodies, def, dt, b, e); });
    StoreRowStates(run, bodies, def);
  }

  // The free bodies among [b, e): moved over the whole step at once (MoveFree).
  void MoveFreeBodies(Bodies& bodies, const WorldDef& def, Real dt, int b, int e) {
    const bool sleep = def.effects.sleep;
    const FreeMotion fm = MakeFreeMotion(def, dt);
    int i = b;
#if QUADRANT_SOFT_SIMD
    // Four consecutive bodies at a time (MoveFour), writing the free ones among them.
    if (def.softSimd && fm.maxAngularSpeed > 0) {
      const uint8_t* awake = bodies.awake.data();
      const BodyType* type = bodies.type.data();
      const uint8_t* inRows = inRows_.data();
      for (; i + kLanes <= e; i += kLanes) {
        int mask = 0;  // bit k: body i + k is free (Moves() and not in rows)
        for (int k = 0; k < kLanes; ++k) {
          const bool moves = sleep ? awake[i + k] != 0 : type[i + k] != BodyType::kStatic;
          mask |= int(moves & (inRows[i + k] == 0)) << k;
        }
        if (mask == 0 || (vex_ ? MoveFourVex(bodies, fm, i, mask) : MoveFour(bodies, fm, i, mask))) continue;
        for (int k = 0; k < kLanes; ++k) {
          if (mask >> k & 1) MoveFree(bodies, fm, i + k);
        }
      }
    }
#endif
    for (; i < e; ++i) {
      if (Moves(bodies, i, sleep) && !inRows_[i]) MoveFree(bodies, fm, i);
    }
  }

  // The bodies in rows (active_): their solver states back to the bodies.
  void StoreRowStates(StageRunner& run, Bodies& bodies, const WorldDef& def) {
    const bool sleep = def.effects.sleep;
    // Split from MinHeavyItems bodies on: the rows' bodies are scattered over the arrays, so each
    // costs cache misses more than arithmetic (circle stress N = 16000, 1 thread: 1.5 % of the
    // step's cycles for about 1000 bodies, perf).
    run.Dynamic(Stage::kIntegrate, ActiveCount(), run.MinHeavyItems(), kBodyGrain / 4, [&](int b, int e) {
      for (int k = b; k < e; ++k) {
        const int i = active_[k];
        if (!Moves(bodies, i, sleep)) continue;
        const SolverBody& st = states_[i];
        bodies.vel[i] = BodyVelocity{st.v, st.w};
        bodies.center[i] = center0_[i] + st.dp;
        if (st.dq.s != 0 || st.dq.c != 1) {
          const Rot q = Mul(rot0_[i], st.dq);
          const Real inv = Real(1) / std::sqrt(q.c * q.c + q.s * q.s);
          bodies.xf[i].q = {q.c * inv, q.s * inv};
        }
        SyncTransform(bodies, i);
      }
    });
  }

  // A free body (no contact row, not kinematic: dynamic and awake) over the whole step, as the
  // sub-steps would move it but in closed form: with u its velocity after the first sub-step
  // (gravity h g, then the step's damping), it ends at u + (n - 1) h g having moved
  // n h u + n (n - 1) / 2 h^2 g, and turns by dt w at once. A body that the speed limit would
  // touch takes the sub-steps one by one (IntegrateOne's guards). Why: on the sparse stress scenes
  // about 95 % of the bodies touch nothing, and integrating each of them n times per step was the
  // largest stage (circle stress N = 4000, default engine: 21 % of the instructions).
  struct FreeMotion {
    Vec2 hg;        // a sub-step's gravity
    Vec2 dpGravity; // n (n - 1) / 2 h^2 g
    Real nh;        // n h
    Real nMinus1;
    Real maxSpeed2, maxSpeed, maxAngularSpeed;
    Real h, dt;
    int n;
    bool damping, rotation;
  };

  static FreeMotion MakeFreeMotion(const WorldDef& def, Real dt) {
    const int n = def.softSubSteps;
    const Real h = dt / Real(n);
    const Vec2 g = def.effects.gravity ? def.gravity : Vec2{};
    return {h * g,
            (Real(n * (n - 1) / 2) * h) * (h * g),
            Real(n) * h,
            Real(n - 1),
            def.maxLinearSpeed * def.maxLinearSpeed,
            def.maxLinearSpeed,
            def.maxRotation / dt,
            h,
            dt,
            n,
            def.effects.damping,
            def.effects.rotation};
  }

  void MoveFree(Bodies& bodies, const FreeMotion& fm, int i) {
    Vec2 u = bodies.vel[i].v + fm.hg;  // a free body has no solver state (LoadStates)
    Real w = bodies.vel[i].w;
    Vec2 vOut;
    if (fm.damping) {
      u = (Real(1) / (Real(1) + fm.dt * bodies.linearDamping[i])) * u;
      w *= Real(1) / (Real(1) + fm.dt * bodies.angularDamping[i]);
    }
    const Vec2 vEnd = u + fm.nMinus1 * fm.hg;
    w = std::clamp(w, -fm.maxAngularSpeed, fm.maxAngularSpeed);
    Vec2 dp;
    if (LengthSquared(u) > fm.maxSpeed2 || LengthSquared(vEnd) > fm.maxSpeed2) {
      Vec2 v = u;
      for (int k = 0; k < fm.n; ++k) {
        if (k > 0) v += fm.hg;
        const Real speed2 = LengthSquared(v);
        if (speed2 > fm.maxSpeed2) v = (fm.maxSpeed / std::sqrt(speed2)) * v;
        dp += fm.h * v;
      }
      vOut = v;
    } else {
      dp = fm.nh * u + fm.dpGravity;
      vOut = vEnd;
    }
    bodies.vel[i] = BodyVelocity{vOut, w};
    // Nothing has moved a free body yet in this step: its centre and rotation are where the step
    // began (no snapshot needed: LoadStates takes one of the rows' bodies only).
    bodies.center[i] = bodies.center[i] + dp;
    if (fm.rotation && w != 0) bodies.xf[i].q = IntegrateRot(bodies.xf[i].q, fm.dt * w);
    SyncTransform(bodies, i);
  }

#if QUADRANT_SOFT_SIMD
  // MoveFree for the free ones among bodies i..i+3 (mask) at once, with the same operations per body in the same
  // order (so the same bits): the velocity read from the bodies (a free body's state is its
  // velocity unchanged), std::clamp as max then min (the same for a nonzero limit, which the caller
  // checks), IntegrateRot's small-angle branch as TurnBy. Returns false, having written nothing,
  // when a body needs the speed limit or turns by 0.5 rad or more in the step: the caller then
  // moves the four one by one. Why: MoveFree was the largest of the per-body passes on the sparse
  // stress scenes (circle stress N = 4000: 7.9M of the 57.3M instructions of 20 steps).
#if QUADRANT_SOFT_VEX
  [[gnu::target("avx"), gnu::noinline]] bool MoveFourVex(Bodies& bodies, const FreeMotion& fm, int i, int mask) {
    return MoveFour(bodies, fm, i, mask);  // in AVX's encoding: the same operations, the same bits
  }
#else
  bool MoveFourVex(Bodies& bodies, const FreeMotion& fm, int i, int mask) { return MoveFour(bodies, fm, i, mask); }
#endif

  [[gnu::always_inline]] bool MoveFour(Bodies& bodies, const FreeMotion& fm, int i, int mask) {
    // Only the free lanes' velocities are read: the others belong to bodies in rows, whose
    // velocities the restitution passes may be writing meanwhile (Run's Beside); their lanes are
    // computed from zeros and dropped.
    const BodyVelocity* vel = bodies.vel.data() + i;
    BodyVelocity masked[kLanes];
    if (mask != 0xF) {
      for (int k = 0; k < kLanes; ++k) masked[k] = (mask >> k & 1) ? vel[k] : BodyVelocity{};
      vel = masked;
    }
    F4 ux{_mm_setr_ps(vel[0].v.x, vel[1].v.x, vel[2].v.x, vel[3].v.x)};
    F4 uy{_mm_setr_ps(vel[0].v.y, vel[1].v.y, vel[2].v.y, vel[3].v.y)};
    F4 w{_mm_setr_ps(vel[0].w, vel[1].w, vel[2].w, vel[3].w)};
    ux = ux + Splat(fm.hg.x, F4{});
    uy = uy + Splat(fm.hg.y, F4{});
    if (fm.damping) {
      const F4 one = Splat(Real(1), F4{}), dt = Splat(fm.dt, F4{});
      const F4 fl = Div(one, one + dt * F4{_mm_loadu_ps(bodies.linearDamping.data() + i)});
      ux = fl * ux;
      uy = fl * uy;
      w = w * Div(one, one + dt * F4{_mm_loadu_ps(bodies.angularDamping.data() + i)});
    }
    const Vec2 rest = fm.nMinus1 * fm.hg;
    const F4 ex = ux + Splat(rest.x, F4{}), ey = uy + Splat(rest.y, F4{});
    const F4 maxW = Splat(fm.maxAngularSpeed, F4{});
    w = Min(Max(w, Neg(maxW)), maxW);
    const F4 max2 = Splat(fm.maxSpeed2, F4{});
    if (Any(Greater(ux * ux + uy * uy, max2)) || Any(Greater(ex * ex + ey * ey, max2))) return false;
    // The transforms (p, q: 16 bytes each), four of them transposed into px, py, qc, qs.
    float* xf = &bodies.xf[i].p.x;
    static_assert(sizeof(Transform) == 4 * sizeof(Real));
    __m128 t0 = _mm_loadu_ps(xf), t1 = _mm_loadu_ps(xf + 4), t2 = _mm_loadu_ps(xf + 8), t3 = _mm_loadu_ps(xf + 12);
    _MM_TRANSPOSE4_PS(t0, t1, t2, t3);
    F4 qc{t2}, qs{t3};
    if (fm.rotation) {
      const M4 turns = {_mm_cmpneq_ps(w.v, _mm_setzero_ps())};
      if (Any(turns)) {
        const F4 turn = Splat(fm.dt, F4{}) * w;
        if (Any(GreaterEqual(Max(turn, Neg(turn)), Splat(Real(0.5), F4{})))) return false;
        F4 c = qc, sn = qs;  // a free body's rotation is still the step's first (MoveFree)
        TurnBy(c, sn, turn);
        qc = Select(turns, c, qc);
        qs = Select(turns, sn, qs);
      }
    }
    // Centres (8 bytes each): x0 y0 x1 y1 and x2 y2 x3 y3, split into xs and ys.
    const float* c0 = &bodies.center[i].x;
    const __m128 ca = _mm_loadu_ps(c0), cb = _mm_loadu_ps(c0 + 4);
    const F4 nh = Splat(fm.nh, F4{});
    const F4 cx = F4{_mm_shuffle_ps(ca, cb, _MM_SHUFFLE(2, 0, 2, 0))} + (nh * ux + Splat(fm.dpGravity.x, F4{}));
    const F4 cy = F4{_mm_shuffle_ps(ca, cb, _MM_SHUFFLE(3, 1, 3, 1))} + (nh * uy + Splat(fm.dpGravity.y, F4{}));
    // SyncTransform: p = centre - Rotate(q, localCenter).
    const float* lc = &bodies.localCenter[i].x;
    const __m128 la = _mm_loadu_ps(lc), lb = _mm_loadu_ps(lc + 4);
    const F4 lx{_mm_shuffle_ps(la, lb, _MM_SHUFFLE(2, 0, 2, 0))}, ly{_mm_shuffle_ps(la, lb, _MM_SHUFFLE(3, 1, 3, 1))};
    const F4 px = cx - (qc * lx - qs * ly), py = cy - (qs * lx + qc * ly);
    t0 = px.v, t1 = py.v, t2 = qc.v, t3 = qs.v;
    _MM_TRANSPOSE4_PS(t0, t1, t2, t3);
    // Only the free lanes are written (mask bit k: body i + k); the others were computed from
    // whatever they hold and are dropped.
    float* center = &bodies.center[i].x;
    const __m128 clo = _mm_unpacklo_ps(cx.v, cy.v), chi = _mm_unpackhi_ps(cx.v, cy.v);
    alignas(16) Real vxs[kLanes], vys[kLanes], ws[kLanes];
    _mm_store_ps(vxs, ex.v);
    _mm_store_ps(vys, ey.v);
    _mm_store_ps(ws, w.v);
    BodyVelocity* out = bodies.vel.data() + i;
    if (mask == 0xF) {
      _mm_storeu_ps(xf, t0);
      _mm_storeu_ps(xf + 4, t1);
      _mm_storeu_ps(xf + 8, t2);
      _mm_storeu_ps(xf + 12, t3);
      _mm_storeu_ps(center, clo);
      _mm_storeu_ps(center + 4, chi);
      for (int k = 0; k < kLanes; ++k) out[k] = BodyVelocity{{vxs[k], vys[k]}, ws[k]};
      return true;
    }
    const __m128 ts[kLanes] = {t0, t1, t2, t3};
    for (int k = 0; k < kLanes; ++k) {
      if (!(mask >> k & 1)) continue;
      _mm_storeu_ps(xf + 4 * k, ts[k]);
      out[k] = BodyVelocity{{vxs[k], vys[k]}, ws[k]};
    }
    if (mask & 1) _mm_storel_pi(reinterpret_cast<__m64*>(center), clo);
    if (mask & 2) _mm_storeh_pi(reinterpret_cast<__m64*>(center + 2), clo);
    if (mask & 4) _mm_storel_pi(reinterpret_cast<__m64*>(center + 4), chi);
    if (mask & 8) _mm_storeh_pi(reinterpret_cast<__m64*>(center + 6), chi);
    return true;
  }
#endif

  // A sub-step's passes as one region (Run says why): between BeginRegion and EndRegion the
  // passes are queued as stages, in order, and EndRegion runs them as one job.
  void BeginRegion() {
    collecting_ = true;
    regionPlan_.clear();
    regionFirst_.clear();
    regionPass_.clear();
    regionFns_.clear();
  }

  // A region splits only where its stages that split hold half of MinHeavyItems / kGroupRows items
  // (16 groups of eight rows by default) per stage of the region on average (StageRunner::Stages
  // counts them; the thresholds were measured with groups of four rows and MinHeavyItems / 4, the
  // same number of rows): every stage costs a barrier, and 64 rows (kColorGrain) are about a
  // microsecond of rows, what a barrier and the rows' states moving to the other core cost. Polygon stress N = 1000 at
  // 2 threads: 3 regions a step split, of 10 stages and about 290 items each.
  void EndRegion(StageRunner& run) {
    collecting_ = false;
    const int stages = static_cast<int>(regionPlan_.size());
    const int minItems = std::max(run.MinHeavyItems() / kGroupRows, run.MinHeavyItems() / (2 * kGroupRows) * stages);
    run.Stages(Stage::kSolve, regionPlan_, std::max(1, minItems), [&](int s, int b, int e) {
      regionFns_[regionPass_[s]](regionFirst_[s] + b, regionFirst_[s] + e);
    });
  }

  // A pass over the bodies in rows (active_): run now, or queued as one stage of the region.
  // A chunk of kBodyGrain bodies is a few microseconds of integration.
  static constexpr int kBodyGrain = 256;
  template <class Fn>
  void BodyPass(StageRunner& run, Fn fn) {
    const int count = ActiveCount();
    if (count <= 0) return;
    if (!collecting_) {
      run.For(Stage::kIntegrate, count, run.MinItems(), fn);
      return;
    }
    regionPass_.push_back(static_cast<int>(regionFns_.size()));
    regionFns_.emplace_back([fn](int b, int e) { fn(b, e, 0); });
    regionPlan_.push_back({count, kBodyGrain});
    regionFirst_.push_back(0);
  }

  // ForEachGroup's pass queued in the region: a stage per colour over absolute group indices
  // (the overflow colour one chunk, row by row). fn is kept by value; what it refers to lives
  // in Run until EndRegion.
  template <class Fn>
  void QueueGroups(bool simd, Fn fn) {
    const int overflow = groupStart_[ConstraintGraph::kColors];
    const int pass = static_cast<int>(regionFns_.size());
    regionFns_.emplace_back(
        [this, simd, fn, overflow](int gb, int ge) mutable { RunGroups(simd && gb < overflow, fn, gb, ge); });
    for (const StagePart& part : passStages_) {
      regionPlan_.push_back({part.count, part.grain});
      regionFirst_.push_back(part.first);
      regionPass_.push_back(pass);
    }
  }

  // The stages of a pass over the rows (ForEachGroup, QueueGroups): one per colour, except that
  // consecutive colours of at most one chunk each (kColorGrain rows) share one stage of one chunk,
  // run on one thread in colour order: the same order of row solves as a stage each, so the same
  // bits, without a barrier between them. The greedy colouring leaves a few such colours at the
  // end: the base-100 pyramid's contacts take four colours of about 2500 rows and two of 45 and
  // 12, which cost two stages (and barriers, the other thread idle) in every pass.
  struct StagePart {
    int first, count, grain;
  };
  void PlanPassStages() {
    passStages_.clear();
    constexpr int kGrain = ConstraintGraph::kColorGrain / kGroupRows;
    bool lastSmall = false;
    for (int color = 0; color <= ConstraintGraph::kColors; ++color) {
      const int begin = groupStart_[color], count = groupStart_[color + 1] - begin;
      if (count == 0) continue;
      if (color == ConstraintGraph::kColors) {  // the overflow colour: its own chunk, row by row
        passStages_.push_back({begin, count, count});
        lastSmall = false;
        continue;
      }
      const bool small = count <= kGrain;
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

  int ActiveCount() const { return static_cast<int>(active_.size()); }

  // Flags that any thread may set during a pass (the relax pass's deep points, the position
  // pass's moved rows), each alone in its cache line and stored only while still false. They were
  // locals of the caller's frame, stored by every group that set them: each such store took the
  // line (which also held the caller's other locals) from the other core. Base-100 pyramid, 2
  // threads, 3 alternated runs on a quiet machine, the position pass's regions (about 3 a step):
  // 173, 195, 176 -> 150, 153, 153 us a step (timed inside the runs with rdtsc, the pool already
  // claiming runs of chunks); same bits.
  struct alignas(64) SharedFlag {
    std::atomic<bool> flag{false};
  };
  SharedFlag deep_, moved_;

  static constexpr int kFlagPad = 8;
  std::vector<uint8_t> inRows_;  // per body (+ kFlagPad of padding): integrated by the sub-steps
  bool collecting_ = false;  // between BeginRegion and EndRegion
  std::vector<TaskSystem::StagePlan> regionPlan_;
  std::vector<int> regionFirst_, regionPass_;
  std::vector<std::function<void(int, int)>> regionFns_;
  std::vector<int> active_;      // the bodies with inRows_ set, ascending
  std::vector<uint32_t> supported_;  // MarkRow: stamp_ for a supported body this step
  uint32_t stamp_ = 0;
  Real collisionShare_ = 1;  // a sub-step's share of the step's collision impulses (Run says why)
  std::vector<SolverBody> states_;
  std::vector<SoftRowGroup> groups_;
  bool vex_ = false;  // the rows eight-wide with AVX, the integration four-wide in AVX's encoding (Run)
  std::span<Contact> contacts_;           // this step's (Run)
  const BodyInverseMass* inv_ = nullptr;  // this step's bodies' (Run)
  std::vector<RelaxBiasRows> relaxBias_;  // per group: the relax passes' speculative bias (RelaxBias)
  std::vector<int> groupStart_;
  std::vector<StagePart> passStages_;  // PlanPassStages
  std::vector<TaskSystem::StagePlan> stagePlan_;  // BuildRows' and ForEachGroup's region: a stage per colour
  std::vector<int> stageFirst_;                   // the first item (or colour) of each stage
  std::vector<Vec2> center0_;                     // LoadStates: where the rows' bodies start
  std::vector<Rot> rot0_;
  ConstraintGraph graph_;
  ContactConstraints constraints_;  // kept only with restitution (Run: lean)
};

}  // namespace

std::unique_ptr<Solver> MakeSoftStepSolver() { return std::make_unique<SoftStepSolver>(); }

}  // namespace quadrant
