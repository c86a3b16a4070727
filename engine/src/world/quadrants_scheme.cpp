// The thesis's data-partitioned step; see quadrants_scheme.h for the scheme.
#include "world/quadrants_scheme.h"

#include <algorithm>

#include "quadrant/task_system.h"
#include "parallel/stage_clock.h"

namespace quadrant {
namespace {

using Clock = StageClock;

// Interleaves the bits of x and y (Morton order), so a block of consecutive cells is a compact
// region: for 4 threads at level 1 each thread gets one quadrant, for 2 threads a half.
int Morton(int x, int y) {
  int m = 0;
  for (int bit = 0; bit < 8; ++bit) m |= ((x >> bit) & 1) << (2 * bit) | ((y >> bit) & 1) << (2 * bit + 1);
  return m;
}

}  // namespace

struct QuadrantsScheme::Partition {
  int index = 0;                      // thread index, or threads_ for the master
  AABB region{};                      // the cells' bounding box (threads only)
  std::vector<int> own;               // owned bodies (global indices)
  std::vector<int> subset;            // detection subset: own + master bodies reaching in
  std::vector<AABB> subsetAabb;
  std::vector<uint8_t> subsetMovable;
  std::unique_ptr<BroadPhase> broadPhase;
  std::vector<CandidatePair> pairs;   // global indices
  std::vector<Contact> contacts;      // global indices
  // The private world: own bodies first, then ghosts of foreign bodies its contacts touch.
  Bodies local;
  std::vector<int> globalOf;
  std::vector<int> localOf;           // global -> local, -1 when absent (kept all -1 between uses)
  std::vector<Contact> localContacts;
  std::unique_ptr<Solver> solver;
  std::unique_ptr<TaskSystem> inlineTasks;
  std::unique_ptr<StageRunner> inlineRun;
  Profile profile;
};

QuadrantsScheme::QuadrantsScheme(const WorldDef& def, int threads) : threads_(threads) {
  level_ = threads <= 4 ? 1 : threads <= 16 ? 2 : 3;
  for (int p = 0; p <= threads; ++p) {
    auto part = std::make_unique<Partition>();
    part->index = p;
    part->broadPhase = MakeBroadPhase(def.broadPhase, def.quadTreeMaxDepth);
    part->solver = MakeSolver(def.solver);
    part->inlineTasks = MakeThreadPool(1);
    part->inlineRun = std::make_unique<StageRunner>(*part->inlineTasks, def.minParallelItems);
    parts_.push_back(std::move(part));
  }
}

QuadrantsScheme::~QuadrantsScheme() = default;

void QuadrantsScheme::AssignOwners(const Bodies& bodies) {
  const int n = bodies.Count();
  owner_.assign(n, 0);
  for (auto& part : parts_) part->own.clear();
  if (n == 0) return;
  AABB box = bodies.aabb[0];
  for (int i = 1; i < n; ++i) box = Union(box, bodies.aabb[i]);
  const Real side = std::max(box.upper.x - box.lower.x, box.upper.y - box.lower.y);
  region_ = {box.lower, box.lower + Vec2{side, side}};
  const int cellsPerSide = 1 << level_;
  const int cells = cellsPerSide * cellsPerSide;
  const double scale = double(cellsPerSide) / (double(side) * (1.0 + 1e-6) + 1e-12);
  auto cellOf = [&](Real v, Real origin) { return std::clamp(int((double(v) - origin) * scale), 0, cellsPerSide - 1); };
  auto threadOf = [&](int cx, int cy) {
    const int m = Morton(cx, cy);
    int t = 0;
    while (t + 1 < threads_ && BlockBegin(cells, threads_, t + 1) <= m) ++t;
    return t;
  };
  for (int t = 0; t < threads_; ++t) parts_[t]->region = {{Real(1e30), Real(1e30)}, {Real(-1e30), Real(-1e30)}};
  const Real cellSide = side / Real(cellsPerSide);
  for (int cy = 0; cy < cellsPerSide; ++cy) {
    for (int cx = 0; cx < cellsPerSide; ++cx) {
      const Vec2 lo = region_.lower + Vec2{cx * cellSide, cy * cellSide};
      AABB& r = parts_[threadOf(cx, cy)]->region;
      r = Union(r, AABB{lo, lo + Vec2{cellSide, cellSide}});
    }
  }
  for (int i = 0; i < n; ++i) {
    const AABB& b = bodies.aabb[i];
    const int x0 = cellOf(b.lower.x, region_.lower.x), x1 = cellOf(b.upper.x, region_.lower.x);
    const int y0 = cellOf(b.lower.y, region_.lower.y), y1 = cellOf(b.upper.y, region_.lower.y);
    // One thread has no master: the thesis's single-threaded engine merges World and SubWorld.
    const int owner = threads_ == 1 ? 0 : (x0 == x1 && y0 == y1) ? threadOf(x0, y0) : -1;
    owner_[i] = owner;
    parts_[owner < 0 ? threads_ : owner]->own.push_back(i);
  }
}

void QuadrantsScheme::Detect(Partition& part, const Bodies& bodies, const WorldDef& def, Real dt, bool master) {
  part.subset = part.own;
  if (!master) {
    for (int i : parts_[threads_]->own) {
      if (Overlaps(bodies.aabb[i], part.region)) part.subset.push_back(i);
    }
  }
  part.subsetAabb.clear();
  part.subsetMovable.clear();
  for (int i : part.subset) {
    part.subsetAabb.push_back(bodies.aabb[i]);
    part.subsetMovable.push_back(bodies.dynamic[i]);
  }
  std::vector<CandidatePair> local;
  part.broadPhase->FindPairs(part.subsetAabb, part.subsetMovable, local, *part.inlineRun);
  const int ownCount = static_cast<int>(part.own.size());
  part.pairs.clear();
  for (const CandidatePair& p : local) {
    // Two master bodies are the master's pair, not a thread's.
    if (!master && p.a >= ownCount && p.b >= ownCount) continue;
    const int a = part.subset[p.a], b = part.subset[p.b];
    part.pairs.push_back(a < b ? CandidatePair{a, b} : CandidatePair{b, a});
  }
  part.contacts.clear();
  CollidePairs(bodies, def, dt, part.pairs, part.contacts);
}

// Copies the bodies this partition needs into its private world and maps its contacts there.
void QuadrantsScheme::BuildLocal(Partition& part, const Bodies& bodies, ContactCache& cache, bool warm) {
  if (warm) cache.Restore(part.contacts);
  part.localOf.resize(bodies.Count(), -1);
  part.globalOf.clear();
  auto add = [&](int g) {
    if (part.localOf[g] >= 0) return part.localOf[g];
    part.localOf[g] = static_cast<int>(part.globalOf.size());
    part.globalOf.push_back(g);
    return part.localOf[g];
  };
  for (int g : part.own) add(g);
  part.localContacts = part.contacts;
  for (Contact& c : part.localContacts) {
    c.a = add(c.a);
    c.b = add(c.b);
  }
  Bodies& l = part.local;
  const int m = static_cast<int>(part.globalOf.size());
  auto copy = [&](auto& dst, const auto& src) {
    dst.resize(m);
    for (int k = 0; k < m; ++k) dst[k] = src[part.globalOf[k]];
  };
  copy(l.type, bodies.type);
  copy(l.xf, bodies.xf);
  copy(l.center, bodies.center);
  copy(l.localCenter, bodies.localCenter);
  copy(l.vel, bodies.vel);
  copy(l.inv, bodies.inv);
  copy(l.linearDamping, bodies.linearDamping);
  copy(l.angularDamping, bodies.angularDamping);
  for (int g : part.globalOf) part.localOf[g] = -1;  // leave the map clean for the next step
}

void QuadrantsScheme::Solve(Partition& part, const WorldDef& def, Real dt) {
  StepContext ctx;
  ctx.dt = dt;
  ctx.def = &def;
  ctx.bodies = &part.local;
  ctx.contacts = part.localContacts;
  part.profile = Profile{};
  ctx.profile = &part.profile;
  ctx.run = part.inlineRun.get();
  part.solver->Step(ctx);
  // Impulses back onto the partition's contacts (global indices) for warm starting.
  for (size_t c = 0; c < part.contacts.size(); ++c) part.contacts[c].manifold = part.localContacts[c].manifold;
}

void QuadrantsScheme::WriteBack(Partition& part, Bodies& bodies) const {
  // Own bodies come first in the private world; ghosts are dropped.
  for (size_t k = 0; k < part.own.size(); ++k) {
    const int g = part.globalOf[k];
    bodies.vel[g] = part.local.vel[k];
    bodies.center[g] = part.local.center[k];
    bodies.xf[g] = part.local.xf[k];
  }
}

void QuadrantsScheme::Step(Real dt, const WorldDef& def, Bodies& bodies, StageRunner& run, ContactCache& cache,
                           std::vector<Contact>& contacts, int& pairs, Profile& profile) {
  const bool warm = def.solver != SolverType::kThesis && def.effects.warmStarting;
  Partition& master = *parts_[threads_];
  auto t0 = Clock::now();
  run.Serial(Stage::kBroadPhase, [&] { AssignOwners(bodies); });
  // Each thread detects in its region; then the master among the root bodies.
  run.For(Stage::kBroadPhase, threads_, 1, [&](int begin, int end, int) {
    for (int t = begin; t < end; ++t) Detect(*parts_[t], bodies, def, dt, false);
  });
  run.Serial(Stage::kBroadPhase, [&] {
    Detect(master, bodies, def, dt, true);
    // The master also resolves its side of every thread's contact with a root body.
    for (int t = 0; t < threads_; ++t) {
      for (const Contact& c : parts_[t]->contacts) {
        if (owner_[c.a] < 0 || owner_[c.b] < 0) master.contacts.push_back(c);
      }
    }
  });
  auto t1 = Clock::now();
  run.For(Stage::kPersistence, threads_ + 1, 1, [&](int begin, int end, int) {
    for (int p = begin; p < end; ++p) BuildLocal(*parts_[p], bodies, cache, warm);
  });
  auto t2 = Clock::now();
  // Threads solve and integrate their own bodies; the master solves the root bodies from the
  // same pre-solve copies (built above), so both sides of a boundary contact start equal.
  run.For(Stage::kSolve, threads_, 1, [&](int begin, int end, int) {
    for (int t = begin; t < end; ++t) Solve(*parts_[t], def, dt);
  });
  run.Serial(Stage::kSolve, [&] { Solve(master, def, dt); });
  run.For(Stage::kIntegrate, threads_ + 1, 1, [&](int begin, int end, int) {
    for (int p = begin; p < end; ++p) WriteBack(*parts_[p], bodies);
  });
  auto t3 = Clock::now();
  run.Serial(Stage::kPersistence, [&] {
    contacts.clear();
    pairs = 0;
    for (auto& part : parts_) {
      contacts.insert(contacts.end(), part->contacts.begin(), part->contacts.end());
      pairs += static_cast<int>(part->pairs.size());
    }
    if (warm) cache.Store(contacts);
  });
  auto t4 = Clock::now();
  profile.broadPhase += Ms(t0, t1);
  profile.persistence += Ms(t1, t2) + Ms(t3, t4);
  profile.solve += Ms(t2, t3);
}

}  // namespace quadrant
