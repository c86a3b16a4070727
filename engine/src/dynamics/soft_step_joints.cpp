// The soft step's joints (soft_step.h; the definitions in quadrant/joints.h). Per step the joints
// are coloured so that no two of one colour share a dynamic body (greedy, in joint order: the
// same colouring for any thread count) and prepared once: each anchor relative to its body's
// centre of mass, turned to world axes at the step's start, and the centres' offset. In each
// sub-step the joints are warm-started and solved before the contacts and relaxed before them,
// on the bodies' solver states: an anchor is its start offset turned by the body's rotation since
// the step began (dq), and a separation is the start offset plus the bodies' motion since then
// (dp), so no transform is rebuilt inside the sub-steps (Box2D 3's formulation; Catto, "Solver2D").
//
// Joint types: revolute (point; limit, motor, spring on the angle), distance (axis; rod, or spring
// between limits), weld (point and angle), prismatic (axial spring, motor, limits; across the axis
// and the angle as one 2x2 block), wheel (angular motor; axial spring and limits; across the axis),
// motor (point and angle driven towards their targets with bounded impulses) and mouse (bodyB's
// anchor pulled to a world target by a bounded spring; bodyA is not read).
//
// Rigid rows are soft springs of WorldDef::jointHertz and jointDampingRatio while the bias acts
// (the solve) and plain velocity rows in the relax pass; a limit that is still open is
// speculative (it lets the gap close within the sub-step, no further). Accumulated impulses are
// per sub-step and re-applied by each sub-step's warm start, as the contacts' are.
#include <algorithm>
#include <bit>
#include <cmath>
#include <numbers>

#include "dynamics/soft_step.h"

namespace quadrant {
namespace {

constexpr Real kPi = std::numbers::pi_v<Real>;
constexpr int kLimitRounds = 4;

Real Wrap(Real angle) {
  if (angle > kPi) angle -= 2 * kPi;
  if (angle < -kPi) angle += 2 * kPi;
  return angle;
}

// The angle of rotation r (its sine and cosine) relative to q: the angle of q^T r.
Real RelativeAngle(Rot q, Rot r) { return std::atan2(q.c * r.s - q.s * r.c, q.c * r.c + q.s * r.s); }

Vec2 Solve22(Real k11, Real k12, Real k22, Vec2 b) {
  Real det = k11 * k22 - k12 * k12;
  if (det != 0) det = Real(1) / det;
  return {det * (k22 * b.x - k12 * b.y), det * (k11 * b.y - k12 * b.x)};
}

}  // namespace

// Colours and prepares the joints, and marks their dynamic bodies as in rows (LoadStates then
// gives them states). Serial: a joint's colour depends on every earlier one that shares a body;
// a few nanoseconds a joint.
void SoftStepSolver::PrepareJoints(const StepContext& ctx, Real h) {
  joints_ = ctx.joints;
  jointRows_.clear();
  if (joints_.empty()) {  // a world without joints pays these lines a step
    jointsVersion_ = ~uint64_t(0);
    chainStart_.assign(1, 0);  // no chains left from a step that had joints
    return;
  }
  const Bodies& bodies = *ctx.bodies;
  const WorldDef& def = *ctx.def;
  StageRunner& run = *ctx.run;
  const bool rotation = def.effects.rotation;
  const int n = static_cast<int>(joints_.size());
  // Each joint's ends that move (bit 0: A, bit 1: B; a mouse joint pulls bodyB only), in
  // parallel, marking them as in rows, and counting the joints whose ends differ from last
  // step's. The colouring and the chains are a function of these and of the joints (their
  // version): where neither changed, last step's are this step's, bit for bit, and the serial
  // colouring is skipped (joint_grid 9993: 0.65 ms of serial work a step).
  const bool sameJoints = ctx.jointsVersion == jointsVersion_ && jointEnds_.size() == joints_.size();
  jointsVersion_ = ctx.jointsVersion;
  jointEnds_.resize(joints_.size());
  jointEndsChanged_.assign(size_t(std::max(1, run.Workers())), 0);
  run.For(Stage::kSolve, n, run.MinHeavyItems(), [&](int begin, int end, int worker) {
    int changed = 0;
    for (int k = begin; k < end; ++k) {
      const Joint& j = joints_[size_t(k)];
      const bool dynA = j.type != JointType::kMouse && bodies.inv[j.a].invMass > 0, dynB = bodies.inv[j.b].invMass > 0;
      const uint8_t ends = uint8_t((dynA ? 1 : 0) | (dynB ? 2 : 0));
      changed += ends != jointEnds_[size_t(k)] ? 1 : 0;
      jointEnds_[size_t(k)] = ends;
      if (dynA) std::atomic_ref<uint8_t>(inRows_[j.a]).store(1, std::memory_order_relaxed);
      if (dynB) std::atomic_ref<uint8_t>(inRows_[j.b]).store(1, std::memory_order_relaxed);
    }
    jointEndsChanged_[size_t(worker)] += changed;
  });
  int changed = 0;
  for (int c : jointEndsChanged_) changed += c;
  const bool reuse = sameJoints && changed == 0;
  jointColoringKept_ = reuse;
  std::vector<int>& colorOf = jointColorOf_;
  std::vector<int>& slotOf = jointSlotOf_;
  if (!reuse) {
    jointColorStart_.assign(ConstraintGraph::kColors + 2, 0);
    jointBodyColors_.resize(size_t(bodies.Count()), 0);
    colorOf.assign(size_t(n), ConstraintGraph::kColors);
    for (int k = 0; k < n; ++k) {
      const Joint& j = joints_[size_t(k)];
      const bool dynA = (jointEnds_[size_t(k)] & 1) != 0, dynB = (jointEnds_[size_t(k)] & 2) != 0;
      if (!dynA && !dynB) {
        colorOf[size_t(k)] = -1;  // nothing to move: no row
        continue;
      }
      const uint64_t used = (dynA ? jointBodyColors_[j.a] : 0) | (dynB ? jointBodyColors_[j.b] : 0);
      const int color = used == ~uint64_t(0) ? ConstraintGraph::kColors : std::countr_one(used);
      colorOf[size_t(k)] = color;
      if (color < ConstraintGraph::kColors) {
        if (dynA) jointBodyColors_[j.a] |= uint64_t(1) << color;
        if (dynB) jointBodyColors_[j.b] |= uint64_t(1) << color;
      }
      ++jointColorStart_[size_t(color) + 1];
    }
    for (int c = 0; c <= ConstraintGraph::kColors; ++c) jointColorStart_[size_t(c) + 1] += jointColorStart_[size_t(c)];
    // Each joint's row position (the colours' fill order), the masks back to zero for the next
    // colouring.
    std::vector<int> fill(jointColorStart_.begin(), jointColorStart_.end() - 1);
    slotOf.assign(joints_.size(), -1);
    for (int k = 0; k < n; ++k) {
      const Joint& j = joints_[size_t(k)];
      if (colorOf[size_t(k)] < 0) continue;
      jointBodyColors_[j.a] = 0;
      jointBodyColors_[j.b] = 0;
      slotOf[size_t(k)] = fill[size_t(colorOf[size_t(k)])]++;
    }
  }
  jointRows_.resize(size_t(jointColorStart_[ConstraintGraph::kColors + 1]));
  const Real hertz = std::min(def.jointHertz, Real(0.25) / h);
  const Softness rigid = MakeSoftness(hertz, def.jointDampingRatio, h);
  jointSoft_ = rigid;
  // The rows, in parallel: each reads its joint and bodies and writes its own row.
  const bool warm = def.effects.warmStarting;
  ctx.run->For(Stage::kSolve, n, ctx.run->MinHeavyItems(), [&](int begin, int end, int) {
    for (int k = begin; k < end; ++k) {
      if (slotOf[size_t(k)] < 0) continue;
      const Joint& j = joints_[size_t(k)];
      SoftJointRow& r = jointRows_[size_t(slotOf[size_t(k)])];
      r.joint = k;
      r.a = j.a;
      r.b = j.b;
      r.type = j.type;
      const BodyInverseMass ia = bodies.inv[j.a], ib = bodies.inv[j.b];
      r.dynA = j.type != JointType::kMouse && ia.invMass > 0;
      r.dynB = ib.invMass > 0;
      r.mA = r.dynA ? ia.invMass : 0;
      r.mB = ib.invMass;
      r.iA = rotation && r.dynA ? ia.invInertia : 0;
      r.iB = rotation ? ib.invInertia : 0;
      const Rot qA = bodies.xf[j.a].q, qB = bodies.xf[j.b].q;
      r.frameA = Rotate(qA, j.localAnchorA - bodies.localCenter[j.a]);
      r.frameB = Rotate(qB, j.localAnchorB - bodies.localCenter[j.b]);
      r.deltaCenter = bodies.center[j.b] - (j.type == JointType::kMouse ? j.target : bodies.center[j.a]);
      r.axisA = Rotate(qA, j.localAxisA);
      // The angle only where a row reads it (an atan2: joint_grid's plain revolute joints need none).
      const bool angled = j.type == JointType::kWeld || j.type == JointType::kPrismatic || j.type == JointType::kMotor ||
                          (j.type == JointType::kRevolute && (j.enableLimit || j.enableSpring));
      r.deltaAngle = angled ? Wrap(RelativeAngle(qA, qB) - j.referenceAngle) : Real(0);
      const Real turning = r.iA + r.iB;
      r.axialMass = turning > 0 ? Real(1) / turning : Real(0);
      r.spring = j.enableSpring || j.type == JointType::kWeld || j.type == JointType::kMouse
                     ? MakeSoftness(j.hertz, j.dampingRatio, h)
                     : Softness{};
      r.angularSpring = j.type == JointType::kWeld ? MakeSoftness(j.angularHertz, j.angularDampingRatio, h) : Softness{};
      r.linearImpulse = warm ? j.linearImpulse : Vec2{};
      r.angularImpulse = warm ? j.angularImpulse : 0;
      r.springImpulse = warm ? j.springImpulse : 0;
      r.motorImpulse = warm ? j.motorImpulse : 0;
      r.lowerImpulse = warm ? j.lowerImpulse : 0;
      r.upperImpulse = warm ? j.upperImpulse : 0;
      r.perpImpulse = warm ? j.perpImpulse : 0;
      r.inChain = false;
      r.enableLimit = j.enableLimit;
      r.enableMotor = j.enableMotor;
      r.enableSpring = j.enableSpring;
      r.lower = j.lower;
      r.upper = j.upper;
      r.motorSpeed = j.motorSpeed;
      r.maxMotorTorque = j.maxMotorTorque;
      r.maxForce = j.maxForce;
      r.correctionFactor = j.correctionFactor;
      r.hertz = j.hertz;
      r.angularHertz = j.angularHertz;
      r.length = j.length;
    }
  });
  if (reuse) {
    for (int q : chainRows_) jointRows_[size_t(q)].inChain = true;  // last step's chains
  } else {
    chainStart_.assign(1, 0);
    chainRows_.clear();
    chainShared_.clear();
    if (def.jointChainSolve) FindChains(bodies.Count());
  }
  LoadChains(run);
}

// The chains among the revolute rows (and the rigid welds'): paths of rows of one kind linked by
// shared dynamic bodies, solved as one system each (SolveChain). At a body with two such rows the
// two continue each other; at a body with more (a net, a ragdoll's torso) rows are paired most
// opposite first (their other bodies more than 120 degrees apart), so that a net is cut into its
// rows and columns and each is solved exactly, line by line: a 30 x 30 net hung from its top
// stretches its top joints 0.0557 m joint by joint at the default budget (hanging_grid). A path
// never holds a dynamic body twice (a loop is cut open); paths that share a body get different
// colours, and each colour is one stage. Rows left alone stay with the row-by-row solve. Serial,
// in row order: the same chains, in the same order, for any thread count.
void SoftStepSolver::FindChains(int bodyCount) {
  const int n = static_cast<int>(jointRows_.size());
  auto chainRow = [&](int k) {
    const SoftJointRow& r = jointRows_[size_t(k)];
    return r.type == JointType::kRevolute || (r.type == JointType::kWeld && r.hertz == 0 && r.angularHertz == 0);
  };
  auto dyn = [&](int k, int body) {
    const SoftJointRow& r = jointRows_[size_t(k)];
    return (body == r.a && r.dynA) || (body == r.b && r.dynB);
  };
  auto other = [&](int k, int body) {
    const SoftJointRow& r = jointRows_[size_t(k)];
    return body == r.a ? r.b : r.a;
  };
  // Each dynamic body's chain rows (in row order), as compressed lists.
  std::vector<int>& start = chainAdjStart_;
  std::vector<int>& adj = chainAdj_;
  start.assign(size_t(bodyCount) + 1, 0);
  for (int k = 0; k < n; ++k) {
    if (!chainRow(k)) continue;
    const SoftJointRow& r = jointRows_[size_t(k)];
    if (r.dynA) ++start[size_t(r.a) + 1];
    if (r.dynB) ++start[size_t(r.b) + 1];
  }
  for (int b = 0; b < bodyCount; ++b) start[size_t(b) + 1] += start[size_t(b)];
  adj.resize(size_t(start[size_t(bodyCount)]));
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (int k = 0; k < n; ++k) {
      if (!chainRow(k)) continue;
      const SoftJointRow& r = jointRows_[size_t(k)];
      if (r.dynA) adj[size_t(fill[size_t(r.a)]++)] = k;
      if (r.dynB) adj[size_t(fill[size_t(r.b)]++)] = k;
    }
  }
  // partner[2k + side]: the row that continues row k across its end `side` (0: a, 1: b), or -1.
  std::vector<int>& partner = chainPartner_;
  partner.assign(size_t(2 * n), -1);
  auto side = [&](int k, int body) { return body == jointRows_[size_t(k)].a ? 0 : 1; };
  auto link = [&](int k1, int k2, int body) {
    partner[size_t(2 * k1 + side(k1, body))] = k2;
    partner[size_t(2 * k2 + side(k2, body))] = k1;
  };
  struct Pairing {
    Real dot;
    int i, j;
  };
  std::vector<Pairing> pairings;
  for (int body = 0; body < bodyCount; ++body) {
    const int b0 = start[size_t(body)], d = start[size_t(body) + 1] - b0;
    if (d < 2) continue;
    const int* rows = adj.data() + b0;
    if (d == 2) {
      if (jointRows_[size_t(rows[0])].type == jointRows_[size_t(rows[1])].type) link(rows[0], rows[1], body);
      continue;
    }
    // The direction from this body to each row's other body.
    auto dir = [&](int k) {
      const SoftJointRow& r = jointRows_[size_t(k)];
      const Vec2 v = body == r.a ? r.deltaCenter : -r.deltaCenter;
      const Real len = Length(v);
      return len > 0 ? (Real(1) / len) * v : Vec2{};
    };
    pairings.clear();
    for (int i = 0; i < d; ++i) {
      for (int j = i + 1; j < d; ++j) {
        if (jointRows_[size_t(rows[i])].type != jointRows_[size_t(rows[j])].type) continue;
        const Real dot = Dot(dir(rows[i]), dir(rows[j]));
        if (dot < Real(-0.5)) pairings.push_back({dot, i, j});
      }
    }
    std::sort(pairings.begin(), pairings.end(), [](const Pairing& x, const Pairing& y) {
      return x.dot != y.dot ? x.dot < y.dot : (x.i != y.i ? x.i < y.i : x.j < y.j);
    });
    for (const Pairing& p : pairings) {
      const int ki = rows[p.i], kj = rows[p.j];
      if (partner[size_t(2 * ki + side(ki, body))] < 0 && partner[size_t(2 * kj + side(kj, body))] < 0) link(ki, kj, body);
    }
  }
  auto across = [&](int k, int body) { return dyn(k, body) ? partner[size_t(2 * k + side(k, body))] : -1; };
  // The paths, found in row order; then coloured.
  std::vector<int>& mark = chainBodyMark_;  // per body: the last path that holds it
  mark.assign(size_t(bodyCount), -1);
  std::vector<uint8_t>& seen = chainSeen_;
  seen.assign(size_t(n), 0);
  std::vector<int>& rows = chainPathRows_;
  std::vector<int>& shared = chainPathShared_;
  std::vector<int>& pathStart = chainPathStart_;
  rows.clear();
  shared.clear();
  pathStart.assign(1, 0);
  for (int k0 = 0; k0 < n; ++k0) {
    while (chainRow(k0) && !seen[size_t(k0)]) {
      // Back to an end through bodyA's side (round a loop at most once).
      int cur = k0, via = jointRows_[size_t(k0)].a;
      for (int guard = 0; guard < n; ++guard) {
        const int prev = across(cur, via);
        if (prev < 0 || prev == k0 || seen[size_t(prev)]) break;
        via = other(prev, via);
        cur = prev;
      }
      // From there, forwards, while the next row brings no body the path already holds.
      const int id = static_cast<int>(pathStart.size()) - 1;
      const int first = static_cast<int>(rows.size());
      if (dyn(cur, via)) mark[size_t(via)] = id;
      int k = cur, inner = other(k, via);
      while (true) {
        seen[size_t(k)] = 1;
        rows.push_back(k);
        if (dyn(k, inner)) mark[size_t(inner)] = id;
        const int next = across(k, inner);
        if (next < 0 || seen[size_t(next)]) break;
        const int far = other(next, inner);
        if (dyn(next, far) && mark[size_t(far)] == id) break;
        shared.push_back(inner);
        inner = far;
        k = next;
      }
      shared.push_back(-1);
      if (static_cast<int>(rows.size()) - first < 2) {  // one row: the row-by-row solve's
        rows.resize(size_t(first));
        shared.resize(size_t(first));
      } else {
        pathStart.push_back(static_cast<int>(rows.size()));
      }
    }
  }
  // Colours: no two paths of one colour share a dynamic body (greedy, in path order). A path that
  // finds no free colour is left to the row-by-row solve.
  const int paths = static_cast<int>(pathStart.size()) - 1;
  std::vector<uint64_t>& used = chainBodyColors_;
  used.assign(size_t(bodyCount), 0);
  std::vector<int>& colorOf = chainPathColor_;
  colorOf.assign(size_t(paths), -1);
  auto eachBody = [&](int p, auto&& fn) {
    for (int q = pathStart[size_t(p)]; q < pathStart[size_t(p) + 1]; ++q) {
      const SoftJointRow& r = jointRows_[size_t(rows[size_t(q)])];
      if (r.dynA) fn(r.a);
      if (r.dynB) fn(r.b);
    }
  };
  chainColorStart_.assign(kChainColors + 1, 0);
  for (int p = 0; p < paths; ++p) {
    uint64_t taken = 0;
    eachBody(p, [&](int body) { taken |= used[size_t(body)]; });
    if (taken == ~uint64_t(0)) continue;
    const int color = std::countr_one(taken);
    colorOf[size_t(p)] = color;
    eachBody(p, [&](int body) { used[size_t(body)] |= uint64_t(1) << color; });
    ++chainColorStart_[size_t(color) + 1];
  }
  for (int c = 0; c < kChainColors; ++c) chainColorStart_[size_t(c) + 1] += chainColorStart_[size_t(c)];
  // The kept paths, colour by colour, as the chains.
  chainStart_.assign(1, 0);
  chainRows_.clear();
  chainShared_.clear();
  for (int c = 0; c < kChainColors; ++c) {
    if (chainColorStart_[size_t(c) + 1] == chainColorStart_[size_t(c)]) continue;
    for (int p = 0; p < paths; ++p) {
      if (colorOf[size_t(p)] != c) continue;
      for (int q = pathStart[size_t(p)]; q < pathStart[size_t(p) + 1]; ++q) {
        chainRows_.push_back(rows[size_t(q)]);
        chainShared_.push_back(shared[size_t(q)]);
        jointRows_[size_t(rows[size_t(q)])].inChain = true;
      }
      chainStart_.push_back(static_cast<int>(chainRows_.size()));
    }
  }
  chainSlots_.resize(chainRows_.size());
}

namespace {

// Small dense blocks, row-major: N x N (N = 2 or 3).
template <int N>
void Invert(const Real m[N * N], Real out[N * N]) {
  if constexpr (N == 2) {
    Real det = m[0] * m[3] - m[1] * m[2];
    if (det != 0) det = Real(1) / det;
    out[0] = det * m[3], out[1] = -det * m[1], out[2] = -det * m[2], out[3] = det * m[0];
  } else {
    const Real c0 = m[4] * m[8] - m[5] * m[7], c1 = m[5] * m[6] - m[3] * m[8], c2 = m[3] * m[7] - m[4] * m[6];
    Real det = m[0] * c0 + m[1] * c1 + m[2] * c2;
    if (det != 0) det = Real(1) / det;
    out[0] = det * c0, out[1] = det * (m[2] * m[7] - m[1] * m[8]), out[2] = det * (m[1] * m[5] - m[2] * m[4]);
    out[3] = det * c1, out[4] = det * (m[0] * m[8] - m[2] * m[6]), out[5] = det * (m[2] * m[3] - m[0] * m[5]);
    out[6] = det * c2, out[7] = det * (m[1] * m[6] - m[0] * m[7]), out[8] = det * (m[0] * m[4] - m[1] * m[3]);
  }
}
template <int N>
void MulVec(const Real m[N * N], const Real v[N], Real out[N]) {
  for (int i = 0; i < N; ++i) {
    Real sum = 0;
    for (int k = 0; k < N; ++k) sum += m[i * N + k] * v[k];
    out[i] = sum;
  }
}
// J_1 W J_2^T for two rows' Jacobians on one body (arms r1, r2; inverse mass m and inertia i): a
// point row is [1 0 -r.y; 0 1 r.x], a weld's angle row [0 0 1].
template <int N>
void Coupling(Vec2 r1, Vec2 r2, Real m, Real i, Real out[N * N]) {
  out[0] = m + i * r1.y * r2.y, out[1] = -i * r1.y * r2.x;
  out[N] = -i * r1.x * r2.y, out[N + 1] = m + i * r1.x * r2.x;
  if constexpr (N == 3) {
    out[2] = -i * r1.y, out[5] = i * r1.x;
    out[6] = -i * r2.y, out[7] = i * r2.x, out[8] = i;
  }
}

}  // namespace

// The chains' rows' data, once a step, into their slots (a pass then reads the slots alone).
void SoftStepSolver::LoadChains(StageRunner& run) {
  if (ChainCount() <= 0) return;
  run.For(Stage::kSolve, ChainCount(), std::max(1, run.MinHeavyItems() / 64), [&](int begin, int end, int) {
    for (int q = chainStart_[size_t(begin)]; q < chainStart_[size_t(end)]; ++q) {
      const SoftJointRow& r = jointRows_[size_t(chainRows_[size_t(q)])];
      ChainSlot& slot = chainSlots_[size_t(q)];
      slot.row = chainRows_[size_t(q)];
      slot.a = r.a, slot.b = r.b;
      slot.dynA = r.dynA, slot.dynB = r.dynB;
      slot.mA = r.dynA ? r.mA : 0, slot.iA = r.dynA ? r.iA : 0;
      slot.mB = r.dynB ? r.mB : 0, slot.iB = r.dynB ? r.iB : 0;
      slot.frameA = r.frameA, slot.frameB = r.frameB;
      slot.deltaCenter = r.deltaCenter;
      slot.deltaAngle = r.deltaAngle;
    }
  });
}

// One chain's rows solved together: the block-tridiagonal system J W J^T x = -(J v + bias) of its
// rows (N x N blocks: a revolute joint's point, 2; a weld's point and angle, 3; row k and k + 1
// coupled through the body they share), at the bodies' present anchors and velocities, by block
// elimination along the chain (the Thomas algorithm), O(rows): one forward sweep builds each
// row's block and right-hand side and eliminates the row before; the backward sweep finds each
// row's impulse, softened as the row-by-row solve softens it, and applies it. The matrix is built
// afresh in every pass: with last pass's (or the step's) anchors a 1000:1 chain blows up. The
// solve pass only (with its bias): the relax passes take chain rows one by one (SolveJoints).
void SoftStepSolver::SolveChain(int chain) {
  if (jointRows_[size_t(chainSlots_[size_t(chainStart_[size_t(chain)])].row)].type == JointType::kWeld) {
    SolveChainOf<3>(chain);
  } else {
    SolveChainOf<2>(chain);
  }
}

template <int N>
void SoftStepSolver::SolveChainOf(int chain) {
  SolverBody* s = states_.data();
  const Softness rigid = jointSoft_;
  const int begin = chainStart_[size_t(chain)], end = chainStart_[size_t(chain) + 1];
  // Row q's arm on `body`, its sign (+1 if it is the row's bodyB), the body's inverse mass and
  // inertia.
  auto onBody = [](const ChainSlot& slot, int body, Vec2& arm, Real& sign, Real& m, Real& i) {
    if (body == slot.b) {
      arm = slot.rB, sign = 1, m = slot.mB, i = slot.iB;
    } else {
      arm = slot.rA, sign = -1, m = slot.mA, i = slot.iA;
    }
  };
  Real t[N], diag[N * N], blockB[N * N], l[N * N];
  for (int q = begin; q < end; ++q) {
    ChainSlot& slot = chainSlots_[size_t(q)];
    const SolverBody& A = s[slot.a];
    const SolverBody& B = s[slot.b];
    slot.rA = Rotate(A.dq, slot.frameA);
    slot.rB = Rotate(B.dq, slot.frameB);
    const Vec2 rA = slot.rA, rB = slot.rB;
    const Vec2 cdot = (B.v + Cross(B.w, rB)) - (A.v + Cross(A.w, rA));
    const Vec2 bias = rigid.biasRate * ((B.dp - A.dp) + (rB - rA) + slot.deltaCenter);
    slot.rhs[0] = -(cdot.x + bias.x);
    slot.rhs[1] = -(cdot.y + bias.y);
    if constexpr (N == 3) {
      const Real angleBias = rigid.biasRate * Wrap(slot.deltaAngle + RelativeAngle(A.dq, B.dq));
      slot.rhs[2] = -((B.w - A.w) + angleBias);
    }
    Coupling<N>(rA, rA, slot.mA, slot.iA, diag);
    Coupling<N>(rB, rB, slot.mB, slot.iB, blockB);
    for (int k = 0; k < N * N; ++k) diag[k] += blockB[k];
    if (q > begin) {
      // C: row q - 1's coupling with row q through their shared body; D_q = K_q - L C and
      // y_q = rhs_q - L y_{q-1}, with L = C^T D_{q-1}^-1.
      ChainSlot& prev = chainSlots_[size_t(q) - 1];
      const int body = chainShared_[size_t(q) - 1];
      Vec2 r1, r2;
      Real s1, s2, m, i;
      onBody(prev, body, r1, s1, m, i);
      onBody(slot, body, r2, s2, m, i);
      Real* c = prev.c;
      Coupling<N>(r1, r2, m, i, c);
      for (int k = 0; k < N * N; ++k) c[k] *= s1 * s2;
      for (int i2 = 0; i2 < N; ++i2) {
        for (int j = 0; j < N; ++j) {
          Real sum = 0;
          for (int k = 0; k < N; ++k) sum += c[k * N + i2] * prev.inv[k * N + j];
          l[i2 * N + j] = sum;
        }
      }
      for (int i2 = 0; i2 < N; ++i2) {
        for (int j = 0; j < N; ++j) {
          Real sum = 0;
          for (int k = 0; k < N; ++k) sum += l[i2 * N + k] * c[k * N + j];
          diag[i2 * N + j] -= sum;
        }
      }
      MulVec<N>(l, prev.rhs, t);
      for (int k = 0; k < N; ++k) slot.rhs[k] -= t[k];
    }
    Invert<N>(diag, slot.inv);
  }
  // Back substitution: x_q = D_q^-1 (y_q - C_q x_{q+1}); each impulse applied as it is found (the
  // right-hand sides were all taken above).
  for (int q = end - 1; q >= begin; --q) {
    ChainSlot& slot = chainSlots_[size_t(q)];
    Real y[N];
    for (int i = 0; i < N; ++i) y[i] = slot.rhs[i];
    if (q < end - 1) {
      MulVec<N>(slot.c, chainSlots_[size_t(q) + 1].x, t);
      for (int i = 0; i < N; ++i) y[i] -= t[i];
    }
    MulVec<N>(slot.inv, y, slot.x);
    SoftJointRow& r = jointRows_[size_t(slot.row)];
    const Vec2 x{slot.x[0], slot.x[1]};
    const Vec2 P = rigid.massScale * x - rigid.impulseScale * r.linearImpulse;
    r.linearImpulse = r.linearImpulse + P;
    Real L = 0;
    if constexpr (N == 3) {
      L = rigid.massScale * slot.x[2] - rigid.impulseScale * r.angularImpulse;
      r.angularImpulse += L;
    }
    SolverBody& A = s[slot.a];
    SolverBody& B = s[slot.b];
    if (slot.dynA) {
      A.v = A.v - slot.mA * P;
      A.w -= slot.iA * (Cross(slot.rA, P) + L);
    }
    if (slot.dynB) {
      B.v = B.v + slot.mB * P;
      B.w += slot.iB * (Cross(slot.rB, P) + L);
    }
  }
}

// The joints' impulses back into them, for the next step's warm start and the read-back.
void SoftStepSolver::StoreJoints(StageRunner& run) {
  run.For(Stage::kSolve, static_cast<int>(jointRows_.size()), run.MinHeavyItems(), [&](int begin, int end, int) {
    for (int k = begin; k < end; ++k) {
      const SoftJointRow& r = jointRows_[size_t(k)];
      Joint& j = joints_[size_t(r.joint)];
      j.linearImpulse = r.linearImpulse;
      j.angularImpulse = r.angularImpulse;
      j.springImpulse = r.springImpulse;
      j.motorImpulse = r.motorImpulse;
      j.lowerImpulse = r.lowerImpulse;
      j.upperImpulse = r.upperImpulse;
      j.perpImpulse = r.perpImpulse;
    }
  });
}

namespace {

struct Ends {
  Vec2 vA, vB;
  Real wA, wB;
};

// A row along `axis` (unit) or an angular row: applies impulse P at the anchors.
inline void ApplyLinear(Ends& e, Vec2 rA, Vec2 rB, Vec2 P, Real mA, Real mB, Real iA, Real iB) {
  e.vA = e.vA - mA * P;
  e.wA -= iA * Cross(rA, P);
  e.vB = e.vB + mB * P;
  e.wB += iB * Cross(rB, P);
}

// A one-sided angular or axial limit row: C >= 0 holds. Speculative while open (the gap may close
// within the sub-step), a soft spring while violated and the bias acts, plain in the relax pass.
inline Real LimitImpulse(Real C, Real Cdot, Real mass, Real& accumulated, bool useBias, const Softness& rigid,
                         Real invH) {
  Real bias = 0, massScale = 1, impulseScale = 0;
  if (C > 0) {
    bias = C * invH;
  } else if (useBias) {
    bias = rigid.biasRate * C;
    massScale = rigid.massScale;
    impulseScale = rigid.impulseScale;
  }
  Real impulse = -mass * massScale * (Cdot + bias) - impulseScale * accumulated;
  const Real next = std::max(accumulated + impulse, Real(0));
  impulse = next - accumulated;
  accumulated = next;
  return impulse;
}

}  // namespace

void SoftStepSolver::WarmStartJoints(int begin, int end) {
  SolverBody* s = states_.data();
  for (int k = begin; k < end; ++k) {
    const SoftJointRow& r = jointRows_[size_t(k)];
    SolverBody& A = s[r.a];
    SolverBody& B = s[r.b];
    const Vec2 rA = Rotate(A.dq, r.frameA), rB = Rotate(B.dq, r.frameB);
    // The impulse P at the anchors and the angular impulses LA, LB about the centres.
    Vec2 P = r.linearImpulse;
    Real LA = Cross(rA, P), LB = Cross(rB, P);
    switch (r.type) {
      case JointType::kRevolute: {
        const Real axial = r.springImpulse + r.motorImpulse + r.lowerImpulse - r.upperImpulse;
        LA += axial;
        LB += axial;
        break;
      }
      case JointType::kWeld:
      case JointType::kMotor:
        LA += r.angularImpulse;
        LB += r.angularImpulse;
        break;
      case JointType::kMouse: break;
      case JointType::kDistance: {
        const Vec2 d = (B.dp - A.dp) + r.deltaCenter + (rB - rA);
        P = (r.angularImpulse + r.springImpulse + r.lowerImpulse - r.upperImpulse) * Normalize(d);
        LA = Cross(rA, P);
        LB = Cross(rB, P);
        break;
      }
      case JointType::kPrismatic:
      case JointType::kWheel: {
        const Vec2 axis = Rotate(A.dq, r.axisA), perp{-axis.y, axis.x};
        const Vec2 d = (B.dp - A.dp) + r.deltaCenter + (rB - rA);
        const bool prismatic = r.type == JointType::kPrismatic;
        const Real axial = r.springImpulse + r.lowerImpulse - r.upperImpulse + (prismatic ? r.motorImpulse : 0);
        const Real turn = prismatic ? r.angularImpulse : r.motorImpulse;
        P = axial * axis + r.perpImpulse * perp;
        LA = axial * Cross(d + rA, axis) + r.perpImpulse * Cross(d + rA, perp) + turn;
        LB = axial * Cross(rB, axis) + r.perpImpulse * Cross(rB, perp) + turn;
        break;
      }
    }
    if (r.dynA) {
      A.v = A.v - r.mA * P;
      A.w -= r.iA * LA;
    }
    if (r.dynB) {
      B.v = B.v + r.mB * P;
      B.w += r.iB * LB;
    }
  }
}

void SoftStepSolver::SolveJoints(int begin, int end, bool useBias) {
  SolverBody* s = states_.data();
  const Real invH = jointInvH_;
  const Softness rigid = jointSoft_;
  for (int k = begin; k < end; ++k) {
    SoftJointRow& r = jointRows_[size_t(k)];
    const SoftJointRow& j = r;  // the joint's settings, as copied into its row
    SolverBody& A = s[r.a];
    SolverBody& B = s[r.b];
    Ends e{A.v, B.v, A.w, B.w};
    const Real mA = r.mA, mB = r.mB, iA = r.iA, iB = r.iB;
    const Vec2 rA = Rotate(A.dq, r.frameA), rB = Rotate(B.dq, r.frameB);
    const Vec2 dcA = A.dp, dcB = B.dp;
    auto angle = [&] { return Wrap(r.deltaAngle + RelativeAngle(A.dq, B.dq)); };
    // The point rows (revolute and weld): the anchors' relative velocity to zero, the separation
    // pushed out softly while the bias acts (or always, for a weld's linear spring).
    auto point = [&](const Softness& soft, bool bias) {
      const Vec2 cdot = (e.vB + Cross(e.wB, rB)) - (e.vA + Cross(e.wA, rA));
      Vec2 b{};
      Real massScale = 1, impulseScale = 0;
      if (bias) {
        const Vec2 sep = (dcB - dcA) + (rB - rA) + r.deltaCenter;
        b = soft.biasRate * sep;
        massScale = soft.massScale;
        impulseScale = soft.impulseScale;
      }
      const Real k11 = mA + mB + rA.y * rA.y * iA + rB.y * rB.y * iB;
      const Real k12 = -rA.y * rA.x * iA - rB.y * rB.x * iB;
      const Real k22 = mA + mB + rA.x * rA.x * iA + rB.x * rB.x * iB;
      const Vec2 x = Solve22(k11, k12, k22, cdot + b);
      const Vec2 P = -massScale * x - impulseScale * r.linearImpulse;
      r.linearImpulse = r.linearImpulse + P;
      ApplyLinear(e, rA, rB, P, mA, mB, iA, iB);
    };
    auto turn = [&](Real impulse) {
      e.wA -= iA * impulse;
      e.wB += iB * impulse;
    };
    switch (r.type) {
      case JointType::kRevolute: {
        if (!r.inChain || !useBias) point(rigid, useBias);
        if (j.enableSpring && j.hertz > 0 && r.axialMass > 0) {
          const Real C = angle();
          const Real impulse = -r.spring.massScale * r.axialMass * (e.wB - e.wA + r.spring.biasRate * C) -
                               r.spring.impulseScale * r.springImpulse;
          r.springImpulse += impulse;
          turn(impulse);
        }
        if (j.enableMotor && r.axialMass > 0) {
          const Real most = j.maxMotorTorque / invH;
          const Real old = r.motorImpulse;
          r.motorImpulse = std::clamp(old - r.axialMass * (e.wB - e.wA - j.motorSpeed), -most, most);
          turn(r.motorImpulse - old);
        }
        // With a limit the point and the limit rows are coupled (stopping the turn moves the
        // anchor), so they take a few Gauss-Seidel rounds together: a bar pinned at its end and
        // stopped by its limit kept 12 % of its speed as a bounce after one round, 0.4 % after four.
        if (j.enableLimit && r.axialMass > 0) {
          const Real a = angle();
          for (int round = 0; round < kLimitRounds; ++round) {
            if (round > 0) point(rigid, useBias);  // the same soft row: rounds converge to its solution
            turn(LimitImpulse(a - j.lower, e.wB - e.wA, r.axialMass, r.lowerImpulse, useBias, rigid, invH));
            turn(-LimitImpulse(j.upper - a, e.wA - e.wB, r.axialMass, r.upperImpulse, useBias, rigid, invH));
          }
        }
        break;
      }
      case JointType::kWeld: {
        if (r.inChain && useBias) break;  // its chain's solve has its point and angle
        if (r.axialMass > 0) {
          const bool spring = j.angularHertz > 0;
          const Softness& soft = spring ? r.angularSpring : rigid;
          Real bias = 0, massScale = 1, impulseScale = 0;
          if (spring || useBias) {
            bias = soft.biasRate * angle();
            massScale = soft.massScale;
            impulseScale = soft.impulseScale;
          }
          const Real impulse = -r.axialMass * massScale * (e.wB - e.wA + bias) - impulseScale * r.angularImpulse;
          r.angularImpulse += impulse;
          turn(impulse);
        }
        const bool spring = j.hertz > 0;
        point(spring ? r.spring : rigid, spring || useBias);
        break;
      }
      case JointType::kPrismatic:
      case JointType::kWheel: {
        const bool prismatic = r.type == JointType::kPrismatic;
        const Vec2 axis = Rotate(A.dq, r.axisA), perp{-axis.y, axis.x};
        const Vec2 d = (dcB - dcA) + r.deltaCenter + (rB - rA);
        const Real translation = Dot(axis, d);
        const Real a1 = Cross(d + rA, axis), a2 = Cross(rB, axis);
        const Real kAxial = mA + mB + iA * a1 * a1 + iB * a2 * a2;
        const Real mass = kAxial > 0 ? Real(1) / kAxial : Real(0);
        auto cdot = [&] { return Dot(axis, e.vB - e.vA) + a2 * e.wB - a1 * e.wA; };
        auto push = [&](Real impulse) {
          const Vec2 P = impulse * axis;
          e.vA = e.vA - mA * P;
          e.wA -= iA * impulse * a1;
          e.vB = e.vB + mB * P;
          e.wB += iB * impulse * a2;
        };
        if (!prismatic && j.enableMotor && r.axialMass > 0) {
          const Real most = j.maxMotorTorque / invH;
          const Real old = r.motorImpulse;
          r.motorImpulse = std::clamp(old - r.axialMass * (e.wB - e.wA - j.motorSpeed), -most, most);
          turn(r.motorImpulse - old);
        }
        if (j.enableSpring && j.hertz > 0) {
          const Real impulse = -r.spring.massScale * mass * (cdot() + r.spring.biasRate * translation) -
                               r.spring.impulseScale * r.springImpulse;
          r.springImpulse += impulse;
          push(impulse);
        }
        if (prismatic && j.enableMotor) {
          const Real most = j.maxForce / invH;
          const Real old = r.motorImpulse;
          r.motorImpulse = std::clamp(old + mass * (j.motorSpeed - cdot()), -most, most);
          push(r.motorImpulse - old);
        }
        if (j.enableLimit) {
          push(LimitImpulse(translation - j.lower, cdot(), mass, r.lowerImpulse, useBias, rigid, invH));
          push(-LimitImpulse(j.upper - translation, -cdot(), mass, r.upperImpulse, useBias, rigid, invH));
        }
        const Real s1 = Cross(d + rA, perp), s2 = Cross(rB, perp);
        Real massScale = 1, impulseScale = 0;
        if (useBias) {
          massScale = rigid.massScale;
          impulseScale = rigid.impulseScale;
        }
        if (prismatic) {
          // Across the axis and the relative turn, solved together (they share the lever s1, s2).
          const Vec2 cd{Dot(perp, e.vB - e.vA) + s2 * e.wB - s1 * e.wA, e.wB - e.wA};
          const Vec2 bias = useBias ? rigid.biasRate * Vec2{Dot(perp, d), angle()} : Vec2{};
          const Real k11 = mA + mB + iA * s1 * s1 + iB * s2 * s2, k12 = iA * s1 + iB * s2;
          const Real k22 = iA + iB > 0 ? iA + iB : Real(1);
          const Vec2 x = Solve22(k11, k12, k22, cd + bias);
          const Vec2 impulse = -massScale * x - impulseScale * Vec2{r.perpImpulse, r.angularImpulse};
          r.perpImpulse += impulse.x;
          r.angularImpulse += impulse.y;
          const Vec2 P = impulse.x * perp;
          e.vA = e.vA - mA * P;
          e.wA -= iA * (impulse.x * s1 + impulse.y);
          e.vB = e.vB + mB * P;
          e.wB += iB * (impulse.x * s2 + impulse.y);
        } else {
          const Real cd = Dot(perp, e.vB - e.vA) + s2 * e.wB - s1 * e.wA;
          const Real bias = useBias ? rigid.biasRate * Dot(perp, d) : Real(0);
          const Real k = mA + mB + iA * s1 * s1 + iB * s2 * s2;
          const Real impulse = -massScale * (k > 0 ? Real(1) / k : Real(0)) * (cd + bias) - impulseScale * r.perpImpulse;
          r.perpImpulse += impulse;
          const Vec2 P = impulse * perp;
          e.vA = e.vA - mA * P;
          e.wA -= iA * impulse * s1;
          e.vB = e.vB + mB * P;
          e.wB += iB * impulse * s2;
        }
        break;
      }
      case JointType::kMotor: {
        // Always correcting (no relax): a controller, not a constraint.
        const Real c = j.correctionFactor * invH;
        if (r.axialMass > 0) {
          const Real most = j.maxMotorTorque / invH;
          const Real old = r.angularImpulse;
          r.angularImpulse = std::clamp(old - r.axialMass * (e.wB - e.wA + c * angle()), -most, most);
          turn(r.angularImpulse - old);
        }
        const Vec2 sep = (dcB - dcA) + (rB - rA) + r.deltaCenter;
        const Vec2 cd = (e.vB + Cross(e.wB, rB)) - (e.vA + Cross(e.wA, rA)) + c * sep;
        const Real k11 = mA + mB + rA.y * rA.y * iA + rB.y * rB.y * iB;
        const Real k12 = -rA.y * rA.x * iA - rB.y * rB.x * iB;
        const Real k22 = mA + mB + rA.x * rA.x * iA + rB.x * rB.x * iB;
        const Vec2 old = r.linearImpulse;
        r.linearImpulse = r.linearImpulse - Solve22(k11, k12, k22, cd);
        const Real most = j.maxForce / invH, size = Length(r.linearImpulse);
        if (size > most) r.linearImpulse = (most / size) * r.linearImpulse;
        ApplyLinear(e, rA, rB, r.linearImpulse - old, mA, mB, iA, iB);
        break;
      }
      case JointType::kMouse: {
        const Vec2 C = dcB + rB + r.deltaCenter;  // the anchor's offset from the target
        const Vec2 cd = e.vB + Cross(e.wB, rB);
        const Real k11 = mB + rB.y * rB.y * iB, k12 = -rB.y * rB.x * iB, k22 = mB + rB.x * rB.x * iB;
        const Vec2 x = Solve22(k11, k12, k22, cd + r.spring.biasRate * C);
        const Vec2 old = r.linearImpulse;
        r.linearImpulse = r.linearImpulse - r.spring.massScale * x - r.spring.impulseScale * r.linearImpulse;
        const Real most = j.maxForce / invH, size = Length(r.linearImpulse);
        if (size > most) r.linearImpulse = (most / size) * r.linearImpulse;
        const Vec2 P = r.linearImpulse - old;
        e.vB = e.vB + mB * P;
        e.wB += iB * Cross(rB, P);
        break;
      }
      case JointType::kDistance: {
        const Vec2 d = (dcB - dcA) + r.deltaCenter + (rB - rA);
        const Real length = Length(d);
        const Vec2 axis = length > 0 ? (Real(1) / length) * d : Vec2{1, 0};
        const Real crA = Cross(rA, axis), crB = Cross(rB, axis);
        const Real kAxial = mA + mB + iA * crA * crA + iB * crB * crB;
        const Real mass = kAxial > 0 ? Real(1) / kAxial : Real(0);
        auto cdot = [&] { return Dot(axis, (e.vB + Cross(e.wB, rB)) - (e.vA + Cross(e.wA, rA))); };
        auto push = [&](Real impulse) { ApplyLinear(e, rA, rB, impulse * axis, mA, mB, iA, iB); };
        if (j.enableSpring) {
          if (j.hertz > 0) {
            const Real C = length - j.length;
            const Real impulse = -r.spring.massScale * mass * (cdot() + r.spring.biasRate * C) -
                                 r.spring.impulseScale * r.springImpulse;
            r.springImpulse += impulse;
            push(impulse);
          }
          if (j.enableLimit) {
            push(LimitImpulse(length - j.lower, cdot(), mass, r.lowerImpulse, useBias, rigid, invH));
            push(-LimitImpulse(j.upper - length, -cdot(), mass, r.upperImpulse, useBias, rigid, invH));
          }
        } else {
          Real bias = 0, massScale = 1, impulseScale = 0;
          if (useBias) {
            bias = rigid.biasRate * (length - j.length);
            massScale = rigid.massScale;
            impulseScale = rigid.impulseScale;
          }
          const Real impulse = -massScale * mass * (cdot() + bias) - impulseScale * r.angularImpulse;
          r.angularImpulse += impulse;
          push(impulse);
        }
        break;
      }
    }
    if (r.dynA) {
      A.v = e.vA;
      A.w = e.wA;
    }
    if (r.dynB) {
      B.v = e.vB;
      B.w = e.wB;
    }
  }
}

}  // namespace quadrant
