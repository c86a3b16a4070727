// Sleeping: islands, sleep timers and waking.
//
// Why: a settled pile costs as much per step as a falling one, although nothing in it moves.
// Sleeping stops simulating groups of bodies that have been at rest for a while (Box2D 2.4's
// rule: every body of the island slow for timeToSleep), and resumes them when they are touched.
//
// How a sleeping body leaves the pipeline: its velocity and inverse mass are set to 0 and its
// `dynamic` flag cleared, so the broad phase pairs it only with awake dynamic bodies (never
// with another sleeper or a static body), the solvers treat it as static and integration skips
// it. Nothing else in the step needs a sleep test. Islands are rebuilt every step from the
// sorted contacts, serially (Update), so every sleep decision is the same at any thread count.
//
// Waking: a contact between an awake dynamic body and a sleeping one wakes the sleeper's whole
// island in the same step (World::Impl::RunPipeline then finds the woken bodies' pairs and
// manifolds again before the solve), so a body thrown at a sleeping pile hits a pile that moves,
// not a static wall. The island a body fell asleep with is remembered as an id (the slot of the
// island's root); waking scans the bodies once for the marked ids.
#include "dynamics/islands.h"

#include <algorithm>

namespace quadrant {

void Islands::Sleep(Bodies& bodies, int i, uint32_t island) {
  bodies.vel[i] = BodyVelocity{};
  bodies.inv[i] = BodyInverseMass{};
  bodies.dynamic[i] = 0;
  bodies.awake[i] = 0;
  bodies.islandOf[i] = island;
}

void Islands::Wake(Bodies& bodies, int i) {
  bodies.inv[i] = AwakeInverseMass(bodies, i);
  bodies.dynamic[i] = 1;
  bodies.awake[i] = 1;
  bodies.sleepTime[i] = 0;
}

// The same expressions as World::CreateBody, so a woken body has its inverse mass bit for bit.
BodyInverseMass Islands::AwakeInverseMass(const Bodies& bodies, int i) {
  if (bodies.type[i] != BodyType::kDynamic) return bodies.inv[i];
  return BodyInverseMass{Real(1) / bodies.mass[i], bodies.inertia[i] > 0 ? Real(1) / bodies.inertia[i] : Real(0)};
}

int Islands::Find(int i) {
  while (parent_[i] != i) {
    parent_[i] = parent_[parent_[i]];  // path halving
    i = parent_[i];
  }
  return i;
}

// Islands are rebuilt every step from this step's contacts (no persistent island graph): a
// union-find over the contacts in their sorted order, serial, so the islands and every sleep
// decision are the same for any thread count. An island is connected by every contact in the
// list, speculative ones included (not only points at separation <= 0): the waking rule (head
// comment) fires on any contact, so an island built from fewer contacts could fall asleep next to an
// awake neighbour within speculative reach and be woken again at once, every step.
// Static and kinematic bodies do not join islands (a pile on the ground is not one island with
// every other pile on the ground); a moving kinematic body keeps the bodies it touches awake.
void Islands::Update(Bodies& bodies, std::span<const Contact> contacts, std::span<const Joint> joints,
                     const WorldDef& def, Real dt) {
  changed_.clear();
  const int n = bodies.Count();
  parent_.resize(n);
  const Real lin2 = def.linearSleepTolerance * def.linearSleepTolerance;
  const Real ang2 = def.angularSleepTolerance * def.angularSleepTolerance;
  for (int i = 0; i < n; ++i) {
    // Only awake dynamic bodies join islands (-1: not in any).
    if (bodies.type[i] != BodyType::kDynamic || bodies.awake[i] == 0) {
      parent_[i] = -1;
      continue;
    }
    parent_[i] = i;
    const BodyVelocity& v = bodies.vel[i];
    if (LengthSquared(v.v) > lin2 || v.w * v.w > ang2) {
      bodies.sleepTime[i] = 0;
    } else {
      bodies.sleepTime[i] += dt;
    }
  }
  auto movingKinematic = [&](int i) {
    return bodies.type[i] == BodyType::kKinematic && (bodies.vel[i].v.x != 0 || bodies.vel[i].v.y != 0 || bodies.vel[i].w != 0);
  };
  auto link = [&](int a, int b) {
    const bool inA = parent_[a] >= 0, inB = parent_[b] >= 0;
    if (inA && inB) {
      // Union by index: the smaller root stays the root, whatever order the unions come in.
      const int ra = Find(a), rb = Find(b);
      if (ra != rb) parent_[std::max(ra, rb)] = std::min(ra, rb);
    } else if (inA && movingKinematic(b)) {
      bodies.sleepTime[a] = 0;
    } else if (inB && movingKinematic(a)) {
      bodies.sleepTime[b] = 0;
    }
  };
  for (const Contact& c : contacts) link(c.a, c.b);
  for (const Joint& j : joints) link(j.a, j.b);
  // The island's time is its least rested body's.
  islandTime_.resize(n);
  for (int i = 0; i < n; ++i) {
    if (parent_[i] >= 0) islandTime_[i] = bodies.sleepTime[i];
  }
  for (int i = 0; i < n; ++i) {
    if (parent_[i] < 0) continue;
    const int r = Find(i);
    islandTime_[r] = std::min(islandTime_[r], bodies.sleepTime[i]);
  }
  for (int i = 0; i < n; ++i) {
    if (parent_[i] < 0) continue;
    const int r = Find(i);
    if (islandTime_[r] >= def.timeToSleep) {
      Sleep(bodies, i, bodies.slot[r]);
      changed_.push_back(i);
    }
  }
}

void Islands::Mark(uint32_t island) {
  if (island >= marked_.size()) marked_.resize(size_t(island) + 1, 0);
  if (marked_[island]) return;
  marked_[island] = 1;
  markedIds_.push_back(island);
}

int Islands::WakeMarked(Bodies& bodies) {
  if (markedIds_.empty()) return 0;
  int woken = 0;
  for (int i = 0; i < bodies.Count(); ++i) {
    if (IsSleeping(bodies, i) && bodies.islandOf[i] < marked_.size() && marked_[bodies.islandOf[i]]) {
      Wake(bodies, i);
      changed_.push_back(i);
      ++woken;
    }
  }
  for (uint32_t id : markedIds_) marked_[id] = 0;
  markedIds_.clear();
  return woken;
}

int Islands::WakeTouched(Bodies& bodies, std::span<const Contact> contacts) {
  changed_.clear();
  // Sleeping bodies are paired only with awake dynamic ones (their `dynamic` flag is 0), so
  // any contact with a sleeper is a touch by a simulated body.
  for (const Contact& c : contacts) {
    if (IsSleeping(bodies, c.a)) Mark(bodies.islandOf[c.a]);
    if (IsSleeping(bodies, c.b)) Mark(bodies.islandOf[c.b]);
  }
  return WakeMarked(bodies);
}

int Islands::WakeOverlapping(Bodies& bodies, const AABB& box) {
  changed_.clear();
  for (int i = 0; i < bodies.Count(); ++i) {
    if (IsSleeping(bodies, i) && Overlaps(bodies.aabb[i], box)) Mark(bodies.islandOf[i]);
  }
  return WakeMarked(bodies);
}

void Islands::WakeIslandOf(Bodies& bodies, int i) {
  changed_.clear();
  if (!IsSleeping(bodies, i)) return;
  Mark(bodies.islandOf[i]);
  WakeMarked(bodies);
}

}  // namespace quadrant
