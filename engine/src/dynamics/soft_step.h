// The soft step solver, declared for its parts: sub-stepping with soft contacts and relaxation
// (Box2D 3's family; Catto, "Solver2D", 2024). Contacts are found once a step; each of N sub-steps
// of h = dt/N applies gravity, warm starts, solves the rows softly (penetration pushed out at a
// bounded speed), integrates positions and relaxes (the same rows without the push-out bias).
// Many small steps converge where many iterations of one step do not (Macklin et al. 2019, "Small
// steps in physics simulation"), which stacks and large mass ratios need.
//
// The parts, one role each, all of them members of SoftStepSolver:
//   solver_soft_step.cpp       the step as a list of stages, and how the passes are scheduled;
//   soft_step_rows.cpp         the contact rows, eight to a group per colour (BuildRows);
//   soft_step_state.cpp        the solver state of the bodies: load, sub-step integration, store;
//   soft_step_restitution.cpp  Box2D-style restitution and the bounce shifts on the states;
//   soft_step_bundles.cpp      the rows of a sparse scene in bundles of contact islands.
// The scheduling templates every part uses (ForEachGroup, BodyPass) are here, inline.
//
// Promises: the same bits on any thread count and any row width (one row, four with SSE2, eight
// with AVX: WorldDef::softSimd, SoftSimdTest). Measured: base-100 pyramid, 1 thread, 38.9M
// instructions a step, from 80.9M before issue #13 moved the sub-steps onto 32-byte states and
// row groups (docs/soft_step.md, docs/notes/soft_step.md).
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <functional>
#include <numbers>
#include <span>
#include <utility>
#include <vector>

#include "dynamics/constraint_graph.h"
#include "dynamics/contact_constraints.h"
#include "dynamics/soft_rows.h"
#include "dynamics/solver.h"

namespace quadrant {

// How a contact of two dynamic bodies meets WorldDef::softMassRatioLimit this step: not at all
// (plain), with the light body's masses scaled (limited), or over the ratio with the light body
// unsupported, so unscaled (cold). A cold contact is not warm-started: an impulse built with the
// scaled masses of an earlier step, applied to the light body's own, throws it (random extreme
// worlds went non-finite within 30 steps: 66 of 300; none without that warm start).
enum class LaneEnds : uint8_t { kPlain, kLimited, kCold };

// Soft constraint coefficients for a spring of `hertz` and damping ratio `zeta` over step h:
// the bias velocity is biasRate * C, and massScale / impulseScale soften the impulse.
struct Softness {
  Real biasRate = 0;
  Real massScale = 1;
  Real impulseScale = 0;
};

inline Softness MakeSoftness(Real hertz, Real zeta, Real h) {
  if (hertz <= 0) return {};
  const Real omega = 2 * std::numbers::pi_v<Real> * hertz;
  const Real a1 = 2 * zeta + h * omega;
  const Real a2 = h * omega * a1;
  const Real a3 = Real(1) / (Real(1) + a2);
  return {omega / a1, a2 * a3, a3};
}

// One joint's data for this step, in colour order.
struct SoftJointRow {
  int joint;            // index into joints_
  int a, b;             // dense body indices
  bool dynA, dynB;      // whether the row writes that body's state
  JointType type;
  Vec2 frameA, frameB;  // anchors relative to the centres of mass, in world axes at the step's start
  Vec2 deltaCenter;     // centre of B minus centre of A at the step's start
  Real deltaAngle;      // the joint angle at the step's start (relative angle minus reference)
  Real mA, mB, iA, iB;
  Real axialMass;       // 1 / (iA + iB), the angular rows' mass (0 if neither turns)
  Vec2 axisA;           // prismatic, wheel: the axis in world axes at the step's start
  bool inChain;         // revolute: its point rows are solved with its chain's (SolveChain)
  // The joint's settings the sub-steps read, copied here so a pass reads its rows alone (the
  // Joint records are larger and in another order): see Joint.
  bool enableLimit, enableMotor, enableSpring;
  Real lower, upper, motorSpeed, maxMotorTorque, maxForce, correctionFactor, hertz, angularHertz, length;
  Softness spring, angularSpring;
  // Accumulated impulses (per sub-step), loaded from the joint and stored back after the step.
  Vec2 linearImpulse;
  Real angularImpulse, springImpulse, motorImpulse, lowerImpulse, upperImpulse, perpImpulse;
};

class SoftStepSolver final : public Solver {
 public:
  const char* Name() const override { return "soft_step"; }
  bool JointColoringKept() const override { return jointColoringKept_; }
  int RowBundles() const override { return bundles_; }
  void Step(StepContext& ctx) override;

  /// A call between passes, on the calling thread, with the bodies' solver states (by dense body
  /// index; a body holds one only where inRows is set): in every sub-step after the warm start
  /// and after the soft solve, after the last sub-step's relax passes, and before Box2D-style
  /// bounces. The distributed world (quadrant::mpi) replaces its shadows' states there with their
  /// owners'; nothing else sets it. `rowsMoved`: a pass since the last call (the bounces) moved
  /// bodies through their rows. Else only v and w can differ between a body's states on two
  /// ranks that held the same state at the last call: dp and dq change only by the per-body
  /// integration, which gives the same bits for the same velocity.
  using StateExchange = std::function<void(std::span<SolverBody> states, std::span<const uint8_t> inRows, bool rowsMoved)>;
  void SetStateExchange(StateExchange exchange) { exchange_ = std::move(exchange); }

 private:
  struct StepPlan;  // what one step's stages share (solver_soft_step.cpp)

  // The step (solver_soft_step.cpp).
  template <bool kRotation, bool kFriction>
  void Run(StepContext& ctx);
  template <bool kRotation, bool kFriction>
  void PrepareContacts(StepContext& ctx, const StepPlan& step, double& integrateMs);
  template <bool kRotation, bool kFriction>
  void SolveContacts(StepContext& ctx, const StepPlan& step);
  template <bool kRotation, bool kFriction>
  void SubStep(StepContext& ctx, const StepPlan& step, int sub, const SoftSolveParams& prm,
               const SoftSolveParams& lastPrm);
  template <bool kRotation, bool kFriction>
  void RelaxPasses(StageRunner& run, const WorldDef& def, bool simd, const SoftSolveParams& firstPrm,
                   const SoftSolveParams& prm, bool storeLast, bool foldWarm);
  template <bool kRotation, bool kFriction, RelaxBias kRelax, bool kStore = false>
  void RelaxPass(StageRunner& run, bool simd, const SoftSolveParams& prm, bool foldWarm = false);
  void StoreLaneImpulses(const SoftRowGroup& g, int begin, int end);
  // The contacts of colour-order rows [begin, end) (FillLeanGroup's reads, up to the manifold's
  // point count) toward the cache: rows in colour order visit the contact list out of its order,
  // a miss a row. Forced inline: GCC 12 deletes calls of a function that only prefetches.
  __attribute__((always_inline)) void PrefetchRowContacts(int begin, int end) const {
    for (int k = begin; k < end; ++k) PrefetchContact(graph_.ContactOf(k));
  }
  // Group g's lanes [begin, end) (StoreLaneImpulses' writes).
  __attribute__((always_inline)) void PrefetchLaneContacts(const SoftRowGroup& g, int begin, int end) const {
    for (int lane = begin; lane < end; ++lane) {
      if (g.constraint[lane] >= 0) PrefetchContact(graph_.ContactOf(g.constraint[lane]));
    }
  }
  __attribute__((always_inline)) void PrefetchContact(int c) const {
    const char* p = reinterpret_cast<const char*>(&contacts_[size_t(c)]);
    __builtin_prefetch(p);
    __builtin_prefetch(p + 64);
    __builtin_prefetch(reinterpret_cast<const char*>(&contacts_[size_t(c)].manifold.pointCount));
  }
  template <bool kRotation>
  void CorrectStatePositions(StageRunner& run, const WorldDef& def, bool simd);
  void StoreRowImpulses(StageRunner& run);

  // Bundles (soft_step_bundles.cpp): where this step's rows fall into many small contact
  // islands, they are dealt into bundles that share no dynamic body, and each region of passes
  // runs bundle by bundle (EndRegion) instead of colour by colour with a barrier per colour.
  // MayBundle: whether this step may (before the colouring); FindIslands beside the colouring's
  // greedy pass (ConstraintGraph::Color's `beside`); ApplyBundles after it (bundles_ > 0 if so).
  bool MayBundle(const StageRunner& run, const StepContext& ctx, bool box2dRestitution) const;
  void FindIslands(const StepContext& ctx, int workers);
  void ApplyBundles(StageRunner& run);
  void LayOutBundleGroups();
  void RunRegionByBundle(StageRunner& run);

  // The rows (soft_step_rows.cpp).
  template <bool kRotation, bool kLean>
  void BuildRows(StepContext& ctx, const Softness& soft, const Softness& staticSoft, Real massLimit);
  void FillLeanGroup(const StepContext& ctx, SoftRowGroup& g, int first, int colorEnd, const Softness& soft,
                     const Softness& staticSoft, Real massLimit);
  template <bool kRotation>
  void FillLeanLane(const StepContext& ctx, SoftRowGroup& g, int lane, int c, const Softness& soft,
                    const Softness& staticSoft, Real massLimit);
  template <bool kRotation>
  LaneEnds FillLaneEnds(SoftRowGroup& g, int lane, int c, const Contact& contact, const Softness& soft,
                    const Softness& staticSoft, Real massLimit);
  void NextStamp(int bodyCount, bool supported);
  // Extends supported_ through the pile (WorldDef::softMassRatioLimit): a dynamic body that
  // touches a supported one whose mass is within the limit of its own is supported too, so a
  // heavy body on a pile that stands on the ground is held as on a body that touches it. Run
  // only after a step that had a contact over the limit (overLimit_): nothing else reads it.
  void PropagateSupport(StageRunner& run, const StepContext& ctx, Real massLimit);
  void MarkOverLimit() { std::atomic_ref<uint8_t>(overLimit_).store(1, std::memory_order_relaxed); }

  // The colouring's gather calls this for a contact with dynamic ends a and b (-1 for an end that
  // is not dynamic): inRows_ = 1 for every dynamic body in a row (LoadStates), and with kSupported
  // supported_ = stamp_ for a dynamic body touching a static, kinematic or sleeping one
  // (WorldDef::softMassRatioLimit acts only on those). Threads may set one flag at once, always to
  // the same value: relaxed atomic stores, no data race. The stamp changes every step, so
  // supported_ needs no clearing. Inline: the colouring calls it for every contact.
  template <bool kSupported>
  void MarkRow(int a, int b) {
    if (a >= 0) std::atomic_ref<uint8_t>(inRows_[a]).store(1, std::memory_order_relaxed);
    if (b >= 0) std::atomic_ref<uint8_t>(inRows_[b]).store(1, std::memory_order_relaxed);
    if constexpr (kSupported) {
      if (a >= 0 && b < 0) std::atomic_ref<uint32_t>(supported_[a]).store(stamp_, std::memory_order_relaxed);
      if (b >= 0 && a < 0) std::atomic_ref<uint32_t>(supported_[b]).store(stamp_, std::memory_order_relaxed);
    }
  }

  // The joints (soft_step_joints.cpp): coloured and prepared per step, solved in each sub-step
  // before the contacts (warm start, solve with bias, relax), their impulses stored after it.
  void PrepareJoints(const StepContext& ctx, Real h);
  void WarmStartJoints(int begin, int end);
  void SolveJoints(int begin, int end, bool useBias);
  void StoreJoints(StageRunner& run);
  void FindChains(int bodyCount);
  void SolveChain(int chain);
  // fn(begin, end) over the joint rows, a stage per joint colour, queued in the sub-step's region.
  static constexpr int kJointGrain = 32;
  template <class Fn>
  void JointPass(Fn fn) {
    if (jointRows_.empty()) return;
    const int pass = static_cast<int>(regionFns_.size());
    regionFns_.emplace_back(fn);
    for (int c = 0; c <= ConstraintGraph::kColors; ++c) {
      const int first = jointColorStart_[size_t(c)], count = jointColorStart_[size_t(c) + 1] - first;
      if (count == 0) continue;
      // The overflow colour's joints may share bodies: one chunk, in order.
      regionPlan_.push_back({count, c == ConstraintGraph::kColors ? count : kJointGrain});
      regionFirst_.push_back(first);
      regionPass_.push_back(pass);
      regionOnBodies_.push_back(0);
    }
  }

  // The bodies' solver states (soft_step_state.cpp).
  void LoadFixedStates(StageRunner& run, const Bodies& bodies, bool sleep);
  void LoadStates(StageRunner& run, const Bodies& bodies);
  void IntegrateStateVelocities(StageRunner& run, const Bodies& bodies, const WorldDef& def, Real h, Real dampDt,
                                bool addWarm);
  void IntegrateStatePositions(StageRunner& run, const Bodies& bodies, const WorldDef& def, Real h, Real stepDt);
  void MoveFreeBodies(Bodies& bodies, const WorldDef& def, Real dt, int b, int e);
  void StoreRowStates(StageRunner& run, Bodies& bodies, const WorldDef& def);

  // Restitution (soft_step_restitution.cpp).
  template <bool kRotation, bool kFriction>
  void ApplyBox2dRestitution(StageRunner& run, const WorldDef& def, Real h);
  void ApplyStateBounceShifts(int begin, int end);

  // Scheduling (solver_soft_step.cpp; the templates here). A sub-step's passes are one region:
  // between BeginRegion and EndRegion ForEachGroup and BodyPass queue their passes as stages,
  // and EndRegion runs them as one job; outside a region they run at once.
  void BeginRegion();
  void EndRegion(StageRunner& run);
  void ClearRegion();
  void PlanPassStages();

  // fn(lanes, group, lane): lanes is a Real (one row: the given lane), an F4 (the four rows from
  // `lane`) or an F8Avx (the group's eight rows; kLaneWidth says how many). One stage per colour
  // (PlanPassStages); the overflow colour's rows may share bodies: one at a time, in order, on
  // one thread.
  template <class Fn>
  void ForEachGroup(StageRunner& run, bool simd, Fn&& fn) {
    if (collecting_) {
      QueueGroups(simd, std::forward<Fn>(fn));
      return;
    }
    if (bundles_ > 0) {  // a region of its own, run bundle by bundle
      BeginRegion();
      QueueGroups(simd, std::forward<Fn>(fn));
      EndRegion(run);
      return;
    }
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
  // group), or row by row (the scalar path, and the overflow colour).
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

  // ForEachGroup's pass queued in the region: a stage per colour over absolute group indices.
  // fn is kept by value; what it refers to must live until EndRegion.
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
      regionOnBodies_.push_back(0);
    }
  }

  // A pass fn(begin, end, block) over the bodies in rows (active_): run now, or queued as one
  // stage of the region. A chunk of kBodyGrain bodies is a few microseconds of integration.
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
    regionOnBodies_.push_back(1);
  }

  int ActiveCount() const { return static_cast<int>(active_.size()); }

  // A stage of a pass over the rows (PlanPassStages): groups [first, first + count) in chunks of
  // `grain`.
  struct StagePart {
    int first, count, grain;
  };

  // A flag any thread may set during a pass (the relax pass's deep points, the position pass's
  // moved rows, PropagateSupport's marks), alone in its cache line and stored only while still
  // false: as a local of the caller's frame, each store took that line, with the caller's other
  // locals, from the other core.
  struct alignas(64) SharedFlag {
    std::atomic<bool> flag{false};
  };
  SharedFlag deep_, moved_, support_;

  static constexpr int kFlagPad = 8;
  StateExchange exchange_;
  bool rowsMoved_ = false;  // a pass moved bodies through their rows since the last exchange_
  void Exchange() {
    exchange_(states_, inRows_, rowsMoved_);
    rowsMoved_ = false;
  }
  std::vector<uint8_t> inRows_;  // per body (+ kFlagPad of padding): integrated by the sub-steps
  bool collecting_ = false;      // between BeginRegion and EndRegion
  std::vector<TaskSystem::StagePlan> regionPlan_;
  std::vector<int> regionFirst_, regionPass_;
  std::vector<uint8_t> regionOnBodies_;  // per region stage: over active_ (1) or over groups (0)
  std::vector<std::function<void(int, int)>> regionFns_;
  std::vector<int> active_;          // the bodies with inRows_ set, ascending
  // LoadStates' scan: per block of the flags its bodies in rows (bundled, with their bundles),
  // where it began, the blocks that ran in index order; bundled, per block and bundle its count,
  // then its place in active_.
  std::vector<std::vector<int>> activeParts_, activePartBundles_;
  std::vector<int> activePartBegin_, partOrder_, partBundleStart_;
  std::vector<uint32_t> supported_;  // MarkRow: stamp_ for a supported body this step
  uint32_t stamp_ = 0;
  // Set by BuildRows (relaxed atomic stores, all of 1) when a row joins two dynamic bodies whose
  // masses differ by more than softMassRatioLimit: the next step runs PropagateSupport.
  uint8_t overLimit_ = 0;
  Real collisionShare_ = 1;  // a sub-step's share of the step's collision impulses (Run says why)
  std::vector<SolverBody> states_;
  // The next sub-step's warm start, added up per body by this sub-step's last relax pass (v and w
  // only; zero between sub-steps and steps): SubStep says why. foldWarm_: this step does so.
  std::vector<SolverBody> warmNext_;
  bool foldWarm_ = false;
  std::vector<SoftRowGroup> groups_;
  bool gravityScaled_ = false;  // StepContext::gravityScaled: gravity per body, times its scale
  bool vex_ = false;  // the rows eight-wide with AVX, the integration four-wide in AVX's encoding
  std::span<Contact> contacts_;           // this step's
  const BodyInverseMass* inv_ = nullptr;  // this step's bodies'
  std::vector<RelaxBiasRows> relaxBias_;  // per group: the relax passes' speculative bias (RelaxBias)
  std::vector<int> groupStart_;           // per colour: its first group (and one past the last colour)
  // Bundles (ApplyBundles): their count (0: this step does not bundle); per colour and bundle the
  // first group (bundleGroupStart_, like ConstraintGraph::BundleBegin); per group its rows
  // [groupRowBegin_, groupRowEnd_) in colour order; per bundle its first body in active_.
  int bundles_ = 0;
  int islandBundles_ = 0;  // FindIslands' bundles, applied after the colouring
  int islandsFor_ = 0;     // the threads FindIslands last found them for (0: not found last step)
  bool islandsKept_ = false;     // FindIslands kept last step's islands
  bool bundlesApplied_ = false;  // ApplyBundles applied bundles (last step, until it runs)
  bool bundlesKept_ = false;     // this step's bundles and their rows' layout are last step's
  std::vector<int> bundleGroupStart_, groupRowBegin_, groupRowEnd_, bundleBodyStart_;
  // Per body, FindIslands' union-find (parent, and island at a root; -1 between steps) and the
  // bundle of a body in rows: one record, so each end a contact names is one cache line.
  struct BundleNode {
    int parent = -1, island = -1, bundle = 0;
  };
  std::vector<BundleNode> bundleNodes_;
  std::vector<int> islandRows_, bundleOfIsland_, bundleOfContact_;
  // Bundled, the free bodies' pass over [0, freeCount_) runs beside the first region's bundles,
  // in blocks the threads take after them (RunRegionByBundle), as StageRunner::Beside would.
  // MoveFreeBodies' arguments, held as plain pointers: no allocation a step.
  struct FreePass {
    Bodies* bodies = nullptr;
    const WorldDef* def = nullptr;
    Real dt = 0;
  } freePass_;
  int freeCount_ = 0;
  // Bundled, the sub-steps' regions are queued (EndRegion runs nothing) and run as one after the
  // last (SolveContacts): every stage of every sub-step for a bundle, by one thread. The queued
  // passes hold their parameters by value.
  bool deferRegions_ = false;
  SharedFlag kinematicInRows_;  // LoadFixedStates: a moving kinematic body is in active_ this step
  std::vector<StagePart> passStages_;     // PlanPassStages
  std::vector<TaskSystem::StagePlan> stagePlan_;  // BuildRows' and ForEachGroup's stages
  std::vector<int> stageFirst_;                   // the first group of each of those stages
  std::vector<Vec2> center0_;                     // LoadStates: where the rows' bodies start
  std::vector<Rot> rot0_;
  ConstraintGraph graph_;
  ContactConstraints constraints_;
  std::span<Joint> joints_;                 // this step's
  std::vector<SoftJointRow> jointRows_;         // in colour order
  std::vector<int> jointColorStart_;        // per colour: its first row (and one past the last)
  std::vector<uint64_t> jointBodyColors_;   // per body: the joint colours it holds (zero between steps)
  std::vector<int> jointColorOf_, jointSlotOf_;
  std::vector<uint8_t> jointEnds_;   // per joint: which ends move (PrepareJoints), last step's until refreshed
  std::vector<int> jointEndsChanged_;  // per worker
  uint64_t jointsVersion_ = ~uint64_t(0);  // StepContext::jointsVersion of the colouring kept

  bool jointColoringKept_ = false;  // the last step's colouring was the one before (Counters)
  Softness jointSoft_;                      // the rigid rows' softness this step
  // Chains (WorldDef::jointChainSolve): chain c's rows, in order, are chainRows_[chainStart_[c]
  // .. chainStart_[c + 1]); chainShared_[k] is the body the k-th row shares with the next.
  struct ChainSlot {
    int row, a, b;           // the joint row and its bodies
    bool dynA, dynB;         // whether the row moves that body
    Real mA, iA, mB, iB;     // 0 for an end that does not move
    Vec2 frameA, frameB;     // the anchors at the step's start (SoftJointRow)
    Vec2 deltaCenter;
    Real deltaAngle;
    Vec2 rA, rB;             // the anchors in this pass
    Real rhs[3], x[3];       // two entries for a revolute chain, three for a weld chain
    Real inv[9];             // the eliminated diagonal block's inverse
    Real c[9];               // the coupling block with the next row
  };
  void LoadChains(StageRunner& run);
  template <int N>
  void SolveChainOf(int chain);
  std::vector<int> chainRows_, chainStart_, chainShared_;
  std::vector<ChainSlot> chainSlots_;
  // Per chain colour (chains of one colour share no dynamic body): its first chain, and one past
  // the last colour's last.
  static constexpr int kChainColors = 64;
  std::vector<int> chainColorStart_;
  // FindChains' scratch: each body's chain rows, the rows that continue each other, the paths.
  std::vector<int> chainAdjStart_, chainAdj_, chainPartner_, chainBodyMark_;
  std::vector<int> chainPathRows_, chainPathShared_, chainPathStart_, chainPathColor_;
  std::vector<uint64_t> chainBodyColors_;
  std::vector<uint8_t> chainSeen_;
  int ChainCount() const { return static_cast<int>(chainStart_.size()) - 1; }
  // SolveChain over every chain, a stage per chain colour, queued in the region.
  void ChainPass() {
    if (ChainCount() <= 0) return;
    const int pass = static_cast<int>(regionFns_.size());
    regionFns_.emplace_back([this](int b, int e) {
      for (int c = b; c < e; ++c) SolveChain(c);
    });
    for (int c = 0; c < kChainColors; ++c) {
      const int first = chainColorStart_[size_t(c)], count = chainColorStart_[size_t(c) + 1] - first;
      if (count == 0) continue;
      regionPlan_.push_back({count, 1});
      regionFirst_.push_back(first);
      regionPass_.push_back(pass);
      regionOnBodies_.push_back(0);
    }
  }
  Real jointInvH_ = 0;  // kept only with restitution (Run: lean)
};

}  // namespace quadrant
