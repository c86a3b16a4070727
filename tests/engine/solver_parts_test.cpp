// Unit tests for the step's parts that only had tests through whole worlds: the 2x2 block solve
// (SolveLcp2, contact_constraints.h), the contact cache (contact_cache.h), the islands
// (islands.h) and the contact sort (World::Impl::SortContacts, seen through GetContacts).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "collision/contact_cache.h"
#include "dynamics/constraint_graph.h"
#include "dynamics/contact_constraints.h"
#include "collision/contact_sort.h"
#include "dynamics/islands.h"
#include "quadrant/world.h"
#include "test_helpers.h"
#include "world/world_internal.h"

namespace quadrant {
namespace {

using namespace test;

// ---- The 2x2 block solve --------------------------------------------------------------------

// x >= 0, w = K x + b >= 0 and x_i w_i = 0 for both rows: the complementarity conditions.
void ExpectComplementary(Real k11, Real k12, Real k22, Real b0, Real b1, Real x0, Real x1) {
  const double w0 = double(k11) * x0 + double(k12) * x1 + b0;
  const double w1 = double(k12) * x0 + double(k22) * x1 + b1;
  const double tol = 1e-4 * (1 + std::abs(double(b0)) + std::abs(double(b1)));
  EXPECT_GE(x0, -tol);
  EXPECT_GE(x1, -tol);
  EXPECT_GE(w0, -tol);
  EXPECT_GE(w1, -tol);
  EXPECT_NEAR(x0 * w0, 0, tol);
  EXPECT_NEAR(x1 * w1, 0, tol);
}

TEST(BlockSolve, EachOfTheFourCases) {
  Real x0 = -1, x1 = -1;
  // Both approaching equally on a symmetric K: both points push, equally.
  ASSERT_TRUE(SolveLcp2(2, 1, 2, -3, -3, x0, x1));
  EXPECT_NEAR(x0, 1, 1e-6);
  EXPECT_NEAR(x1, 1, 1e-6);
  // The second point separating fast: only the first pushes, and the second stays separating.
  ASSERT_TRUE(SolveLcp2(2, 1, 2, -2, 5, x0, x1));
  EXPECT_NEAR(x0, 1, 1e-6);
  EXPECT_EQ(x1, 0);
  // Mirror: only the second.
  ASSERT_TRUE(SolveLcp2(2, 1, 2, 5, -2, x0, x1));
  EXPECT_EQ(x0, 0);
  EXPECT_NEAR(x1, 1, 1e-6);
  // Both separating: no impulse.
  ASSERT_TRUE(SolveLcp2(2, 1, 2, 1, 2, x0, x1));
  EXPECT_EQ(x0, 0);
  EXPECT_EQ(x1, 0);
}

TEST(BlockSolve, RandomProblemsSatisfyComplementarity) {
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 2000; ++trial) {
    // A symmetric positive definite K, as the effective mass of two contact rows is.
    const double a = 0.2 + std::abs(u(rng)), c = 0.2 + std::abs(u(rng));
    const double off = 0.9 * std::sqrt(a * c) * u(rng);
    const Real k11 = Real(a), k22 = Real(c), k12 = Real(off);
    const Real b0 = Real(3 * u(rng)), b1 = Real(3 * u(rng));
    Real x0 = 0, x1 = 0;
    ASSERT_TRUE(SolveLcp2(k11, k12, k22, b0, b1, x0, x1)) << "trial " << trial;
    ExpectComplementary(k11, k12, k22, b0, b1, x0, x1);
  }
}

// ---- The contact cache ------------------------------------------------------------------------

Contact MakeContact(int a, int b, int points, uint32_t id0, uint32_t id1, Real impulse) {
  Contact c;
  c.a = a;
  c.b = b;
  c.manifold.pointCount = points;
  c.manifold.points[0].id = id0;
  c.manifold.points[1].id = id1;
  for (int k = 0; k < points; ++k) {
    c.manifold.points[k].normalImpulse = impulse + Real(k);
    c.manifold.points[k].tangentImpulse = -impulse;
  }
  return c;
}

TEST(ContactCache, RestoresByPairAndFeatureId) {
  ContactCache cache;
  std::vector<Contact> last = {MakeContact(0, 1, 2, 7, 8, 1), MakeContact(0, 2, 1, 3, 0, 5),
                               MakeContact(1, 2, 1, 4, 0, 0),  // carries nothing: not stored
                               MakeContact(3, 9, 2, 1, 2, 2)};
  last[2].manifold.points[0].tangentImpulse = 0;
  cache.Store(last);
  // This step: the first pair kept one feature (8) and gained one (9); the second pair's feature
  // changed; a new pair; the last pair unchanged.
  std::vector<Contact> now = {MakeContact(0, 1, 2, 9, 8, 0), MakeContact(0, 2, 1, 4, 0, 0),
                              MakeContact(1, 2, 1, 4, 0, 0), MakeContact(2, 5, 1, 1, 0, 0),
                              MakeContact(3, 9, 2, 1, 2, 0)};
  EXPECT_EQ(cache.Restore(now), 3);
  EXPECT_EQ(now[0].manifold.points[0].normalImpulse, 0);  // feature 9 is new
  EXPECT_EQ(now[0].manifold.points[1].normalImpulse, 2);  // feature 8 was point 1: 1 + 1
  EXPECT_EQ(now[0].manifold.points[1].tangentImpulse, -1);
  EXPECT_EQ(now[1].manifold.points[0].normalImpulse, 0);  // feature 3 is gone
  EXPECT_EQ(now[2].manifold.points[0].normalImpulse, 0);  // nothing was stored for (1, 2)
  EXPECT_EQ(now[3].manifold.points[0].normalImpulse, 0);  // a new pair
  EXPECT_EQ(now[4].manifold.points[0].normalImpulse, 2);
  EXPECT_EQ(now[4].manifold.points[1].normalImpulse, 3);
  // Out of key order the lookup still finds every entry.
  std::vector<Contact> shuffled = {MakeContact(3, 9, 2, 1, 2, 0), MakeContact(0, 1, 2, 9, 8, 0)};
  EXPECT_EQ(cache.Restore(shuffled), 3);
  EXPECT_EQ(shuffled[1].manifold.points[1].normalImpulse, 2);
  cache.Clear();
  std::vector<Contact> again = {MakeContact(3, 9, 2, 1, 2, 0)};
  EXPECT_EQ(cache.Restore(again), 0);
}

TEST(ContactCache, ParallelStoreEqualsSerialStore) {
  std::vector<Contact> contacts;
  for (int i = 0; i < 3000; ++i) contacts.push_back(MakeContact(i, i + 1, 1 + i % 2, uint32_t(i), 5, Real(i % 3)));
  ContactCache serial, parallel;
  serial.Store(contacts);
  auto pool = MakeThreadPool(3);
  StageRunner run(*pool, 16);
  parallel.Store(contacts, run);
  EXPECT_GT(run.Balance()[size_t(Stage::kPersistence)].workMs, 0.0);
  std::vector<Contact> a = contacts, b = contacts;
  for (Contact& c : a) c.manifold.points[0].normalImpulse = c.manifold.points[1].normalImpulse = -7;
  for (Contact& c : b) c.manifold.points[0].normalImpulse = c.manifold.points[1].normalImpulse = -7;
  EXPECT_EQ(serial.Restore(a), parallel.Restore(b));
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].manifold.points[0].normalImpulse, b[i].manifold.points[0].normalImpulse) << i;
  }
}

// The store takes one entry per contact for contacts in strictly increasing key order (the
// world's), an entry of no points for one that carries nothing; any other order takes the
// filtered store. Both must restore exactly what the filtered store alone did: a contact that
// carried nothing is as absent, and among repeated keys the first carrying one is found.
TEST(ContactCache, StrictlyIncreasingAndOtherInputRestoreTheSame) {
  // Strictly increasing, (0, 2) and (1, 2) carrying nothing.
  std::vector<Contact> increasing = {MakeContact(0, 1, 2, 7, 8, 1), MakeContact(0, 2, 1, 3, 0, 0),
                                     MakeContact(1, 2, 1, 4, 0, 0), MakeContact(3, 9, 2, 1, 2, 2)};
  increasing[1].manifold.points[0].tangentImpulse = 0;
  increasing[2].manifold.points[0].tangentImpulse = Real(-0.0);  // -0 carries nothing either
  // The same contacts plus a repeated key: (1, 2) again, carrying this time, and a first (3, 9)
  // that carries nothing before the one that does.
  std::vector<Contact> repeated = increasing;
  repeated.insert(repeated.begin() + 3, MakeContact(1, 2, 1, 4, 0, 6));
  repeated.insert(repeated.begin() + 4, MakeContact(3, 9, 2, 1, 2, 0));
  repeated[4].manifold.points[1].normalImpulse = 0;
  repeated[4].manifold.points[0].tangentImpulse = repeated[4].manifold.points[1].tangentImpulse = 0;
  auto now = [] {
    std::vector<Contact> c = {MakeContact(0, 1, 2, 8, 7, 0), MakeContact(0, 2, 1, 3, 0, 0),
                              MakeContact(1, 2, 1, 4, 0, 0), MakeContact(3, 9, 2, 1, 2, 0)};
    for (Contact& x : c) {
      for (ManifoldPoint& p : x.manifold.points) p.normalImpulse = p.tangentImpulse = -7;  // untouched if absent
    }
    return c;
  };
  for (bool parallel : {false, true}) {
    ContactCache a, b;
    auto pool = MakeThreadPool(3);
    StageRunner run(*pool, 8);
    if (parallel) {
      a.Store(increasing, run);
      b.Store(repeated, run);
    } else {
      a.Store(increasing);
      b.Store(repeated);
    }
    std::vector<Contact> fromA = now(), fromB = now();
    EXPECT_EQ(a.Restore(fromA), 4) << parallel;  // (0, 1) and (3, 9), two features each
    EXPECT_EQ(fromA[0].manifold.points[0].normalImpulse, 2) << parallel;  // feature 8 was point 1
    EXPECT_EQ(fromA[0].manifold.points[1].normalImpulse, 1) << parallel;
    EXPECT_EQ(fromA[1].manifold.points[0].normalImpulse, -7) << parallel;  // carried nothing: absent
    EXPECT_EQ(fromA[2].manifold.points[0].normalImpulse, -7) << parallel;
    EXPECT_EQ(fromA[3].manifold.points[0].normalImpulse, 2) << parallel;
    EXPECT_EQ(b.Restore(fromB), 5) << parallel;
    EXPECT_EQ(fromB[2].manifold.points[0].normalImpulse, 6) << parallel;  // the carrying (1, 2)
    EXPECT_EQ(fromB[3].manifold.points[0].normalImpulse, 2) << parallel;  // the carrying (3, 9)
  }
}

// Keep takes last step's contacts themselves (strictly increasing keys, as the sorter checked)
// instead of storing a copy: it restores exactly what Store does, including contacts that
// carried nothing (absent) and a -0 impulse; without the order's check it stores a copy.
TEST(ContactCache, KeepRestoresWhatStoreRestores) {
  std::mt19937 rng(7);
  std::vector<Contact> last;
  for (int a = 0; a < 300; ++a) {
    for (int b = a + 1; b < a + 4; ++b) {
      if (rng() % 3 == 0) continue;
      last.push_back(MakeContact(a, b, 1 + int(rng() % 2), rng() % 4, rng() % 4, Real(rng() % 3)));
      if (rng() % 5 == 0) last.back().manifold.points[0].tangentImpulse = Real(-0.0);
    }
  }
  std::vector<Contact> now;
  for (int a = 0; a < 300; ++a) {
    for (int b = a + 1; b < a + 4; ++b) {
      if (rng() % 4 != 0) now.push_back(MakeContact(a, b, 1 + int(rng() % 2), rng() % 4, rng() % 4, -7));
    }
  }
  ContactCache stored;
  stored.Store(last);
  std::vector<Contact> expected = now;
  const int matched = stored.Restore(expected);
  EXPECT_GT(matched, 100);
  for (bool checked : {true, false}) {
    ContactCache kept;
    std::vector<Contact> taken = last;
    kept.Keep(taken, checked);
    if (!checked) {
      EXPECT_EQ(taken.size(), last.size());  // stored: the caller's list is left as it was
    }
    std::vector<Contact> got = now;
    EXPECT_EQ(kept.Restore(got), matched) << checked;
    for (size_t i = 0; i < now.size(); ++i) {
      for (int k = 0; k < 2; ++k) {
        ASSERT_EQ(got[i].manifold.points[k].normalImpulse, expected[i].manifold.points[k].normalImpulse) << i;
        ASSERT_EQ(got[i].manifold.points[k].tangentImpulse, expected[i].manifold.points[k].tangentImpulse) << i;
      }
    }
    // A Store after Keep replaces what was kept; Clear forgets both.
    kept.Store(std::vector<Contact>{MakeContact(0, 1, 1, 99, 0, 4)});
    std::vector<Contact> one = {MakeContact(0, 1, 1, 99, 0, -7), MakeContact(0, 2, 1, 0, 0, -7)};
    EXPECT_EQ(kept.Restore(one), 1);
    EXPECT_EQ(one[0].manifold.points[0].normalImpulse, 4);
    kept.Clear();
    EXPECT_EQ(kept.Restore(one), 0);
  }
}

// Restoring a list chunk by chunk with one cursor (as the contact sort does) gives what one
// call gives, also when a chunk goes back in key order.
TEST(ContactCache, ChunkedRestoreWithACursorEqualsOneCall) {
  std::mt19937 rng(11);
  std::vector<Contact> last;
  for (int a = 0; a < 400; ++a) {
    for (int b = a + 1; b < a + 4; ++b) {
      if (rng() % 3 != 0) last.push_back(MakeContact(a, b, 1 + int(rng() % 2), rng() % 4, rng() % 4, Real(rng() % 3)));
    }
  }
  ContactCache cache;
  cache.Store(last);
  std::vector<Contact> now;
  for (int a = 0; a < 400; ++a) {
    for (int b = a + 1; b < a + 4; ++b) {
      if (rng() % 4 != 0) now.push_back(MakeContact(a, b, 1 + int(rng() % 2), rng() % 4, rng() % 4, -7));
    }
  }
  std::swap(now[100], now[500]);  // out of order twice
  std::vector<Contact> whole = now, chunked = now;
  const int matched = cache.Restore(whole);
  EXPECT_GT(matched, 200);
  ContactCache::Cursor cursor;
  int chunkedMatched = 0;
  for (size_t begin = 0; begin < chunked.size(); begin += 37) {
    const size_t n = std::min<size_t>(37, chunked.size() - begin);
    chunkedMatched += cache.Restore(std::span<Contact>(chunked).subspan(begin, n), cursor);
  }
  EXPECT_EQ(chunkedMatched, matched);
  for (size_t i = 0; i < now.size(); ++i) {
    for (int k = 0; k < 2; ++k) {
      ASSERT_EQ(whole[i].manifold.points[k].normalImpulse, chunked[i].manifold.points[k].normalImpulse) << i;
      ASSERT_EQ(whole[i].manifold.points[k].tangentImpulse, chunked[i].manifold.points[k].tangentImpulse) << i;
    }
  }
}

// ---- Islands ------------------------------------------------------------------------------

// Bodies as the world keeps them, for `types`, all awake and at rest.
Bodies MakeBodies(const std::vector<BodyType>& types) {
  Bodies b;
  for (size_t i = 0; i < types.size(); ++i) {
    const bool dyn = types[i] == BodyType::kDynamic;
    b.type.push_back(types[i]);
    b.vel.push_back({});
    b.mass.push_back(dyn ? 1 : 0);
    b.inertia.push_back(dyn ? Real(0.5) : 0);
    b.inv.push_back(dyn ? BodyInverseMass{1, 2} : BodyInverseMass{});
    b.dynamic.push_back(dyn ? 1 : 0);
    b.awake.push_back(types[i] == BodyType::kStatic ? 0 : 1);
    b.sleepTime.push_back(0);
    b.islandOf.push_back(0);
    b.slot.push_back(uint32_t(i));
    b.aabb.push_back({{Real(i), 0}, {Real(i) + Real(0.5), 1}});
  }
  return b;
}

Contact Pair(int a, int b) {
  Contact c;
  c.a = a;
  c.b = b;
  return c;
}

TEST(Islands, ConnectedBodiesSleepTogetherAndWakeTogether) {
  using T = BodyType;
  // 0 ground; island {1, 2, 3} on it; island {4, 5}; 6 alone; 7 a kinematic body touching 6.
  Bodies bodies = MakeBodies({T::kStatic, T::kDynamic, T::kDynamic, T::kDynamic, T::kDynamic, T::kDynamic,
                              T::kDynamic, T::kKinematic});
  const std::vector<Contact> contacts = {Pair(0, 1), Pair(1, 2), Pair(0, 3), Pair(2, 3), Pair(4, 5), Pair(6, 7)};
  WorldDef def;
  Islands islands;
  bodies.vel[7].v = {1, 0};  // a moving kinematic body keeps what it touches awake
  bodies.vel[5].v = {1, 0};  // 5 moves: its island {4, 5} stays awake
  const Real dt = Real(0.1);
  for (int step = 0; step < 6; ++step) islands.Update(bodies, contacts, {}, def, dt);  // 0.6 s > 0.5 s
  for (int i : {1, 2, 3}) EXPECT_TRUE(Islands::IsSleeping(bodies, i)) << i;
  for (int i : {4, 5, 6}) EXPECT_FALSE(Islands::IsSleeping(bodies, i)) << i;
  EXPECT_EQ(bodies.islandOf[1], bodies.islandOf[2]);
  EXPECT_EQ(bodies.islandOf[1], bodies.islandOf[3]);
  EXPECT_EQ(bodies.inv[2].invMass, 0);  // a sleeper is static to every stage
  EXPECT_EQ(bodies.dynamic[2], 0);
  // An awake body touching one sleeper wakes its whole island, with its mass back bit for bit.
  EXPECT_EQ(islands.WakeTouched(bodies, std::vector<Contact>{Pair(3, 4)}), 3);
  for (int i : {1, 2, 3}) {
    EXPECT_FALSE(Islands::IsSleeping(bodies, i)) << i;
    EXPECT_EQ(bodies.inv[i].invMass, 1);
    EXPECT_EQ(bodies.inv[i].invInertia, 2);
    EXPECT_EQ(bodies.sleepTime[i], 0);
  }
  EXPECT_EQ(islands.Changed().size(), 3u);
}

TEST(Islands, WakeOverlappingAndWakeIslandOf) {
  using T = BodyType;
  Bodies bodies = MakeBodies({T::kDynamic, T::kDynamic, T::kDynamic});
  Islands::Sleep(bodies, 0, 10);
  Islands::Sleep(bodies, 1, 10);
  Islands::Sleep(bodies, 2, 11);
  Islands islands;
  // Body 2's box is [2, 2.5] x [0, 1]: a box over it wakes island 11 only.
  EXPECT_EQ(islands.WakeOverlapping(bodies, {{Real(2.2), 0}, {3, 1}}), 1);
  EXPECT_TRUE(Islands::IsSleeping(bodies, 0));
  EXPECT_FALSE(Islands::IsSleeping(bodies, 2));
  islands.WakeIslandOf(bodies, 1);
  EXPECT_FALSE(Islands::IsSleeping(bodies, 0));
  EXPECT_FALSE(Islands::IsSleeping(bodies, 1));
}

// ---- The contact sort ----------------------------------------------------------------------

// The world's contacts come out of the narrow phase per worker and are put in key order (a
// radix sort per worker, then a merge). Read back, they are in (bodyA, bodyB) order, each pair
// once, and the same list for any thread count.
TEST(ContactSort, ContactsAreInKeyOrderForAnyThreadCount) {
  auto contactsWith = [](int threads) {
    WorldDef def;
    def.threadCount = threads;
    def.minParallelItems = 8;  // split the narrow phase and the sort across the workers
    World world(def);
    AddGround(world, 30, Real(0.5), {0, -0.5});
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-0.05, 0.05);
    // Created top row first, so body index order is not the contacts' spatial order.
    for (int row = 11; row >= 0; --row) {
      for (int col = 0; col < 40; ++col) {
        AddCircle(world, {Real(-20 + col * 1.0 + u(rng)), Real(0.5 + row * 1.0)}, Real(0.5));
      }
    }
    StepN(world, 30);
    if (threads > 1) {
      EXPECT_TRUE(ParallelSectionRan(world.GetProfile()));
    }
    return world.GetContacts();
  };
  const std::vector<ContactInfo> one = contactsWith(1);
  ASSERT_GT(one.size(), 400u);
  for (size_t i = 1; i < one.size(); ++i) {
    const auto key = [](const ContactInfo& c) { return (uint64_t(c.bodyA.index) << 32) | c.bodyB.index; };
    ASSERT_LT(key(one[i - 1]), key(one[i])) << "contact " << i;
  }
  for (int threads : {2, 3, 4}) {
    const std::vector<ContactInfo> many = contactsWith(threads);
    ASSERT_EQ(many.size(), one.size()) << threads;
    for (size_t i = 0; i < one.size(); ++i) {
      ASSERT_EQ(many[i].bodyA, one[i].bodyA) << threads << " threads, contact " << i;
      ASSERT_EQ(many[i].bodyB, one[i].bodyB) << threads << " threads, contact " << i;
      ASSERT_EQ(many[i].normalImpulses[0], one[i].normalImpulses[0]) << threads << " threads, contact " << i;
    }
  }
}


// ContactSorter's paths against std::sort and a separate Restore: the counting sort on body a
// (buckets put in b-order by an insertion pass; with 3000 bodies body 0 touches all the others
// in shuffled order, which exceeds the insertion's budget of moves, so std::sort finishes),
// the radix sort above 16384 bodies, one or several parts, parts holding low and high keys
// (the narrow phase's blocks are runs of a spatial order), parts left empty, and the merge
// ranges on one or three workers.
TEST(ContactSort, EveryPathGivesKeyOrderWithImpulsesRestored) {
  for (int bodyCount : {700, 3000, 20000}) {
    std::mt19937 rng{uint32_t(bodyCount)};
    std::vector<Contact> all;
    const int groundContacts = bodyCount == 3000 ? bodyCount - 1 : 59;
    for (int b = 1; b <= groundContacts; ++b) all.push_back(MakeContact(0, b, 2, 1, 2, 0));
    for (int a = 1; a < bodyCount - 1; a += 1 + int(rng() % 40)) {
      for (int b = a + 1; b < std::min(bodyCount, a + 6); ++b) {
        if (rng() % 2 == 0) all.push_back(MakeContact(a, b, 1 + int(rng() % 2), rng() % 3, rng() % 3, 0));
      }
    }
    // Last step's impulses for about half of the pairs.
    std::vector<Contact> last;
    for (const Contact& c : all) {
      if (rng() % 2 == 0) last.push_back(MakeContact(c.a, c.b, 2, rng() % 3, rng() % 3, Real(1 + rng() % 5)));
    }
    ContactCache cache;
    cache.Store(last);
    std::vector<Contact> expected = all;
    std::sort(expected.begin(), expected.end(), [](const Contact& x, const Contact& y) { return x.Key() < y.Key(); });
    cache.Restore(expected);
    for (int parts : {1, 2, 4}) {
      for (bool bySpace : {false, true}) {
        WorkerLists<Contact> workerContacts;
        workerContacts.Reset(parts);
        std::vector<Contact> shuffled = all;
        std::shuffle(shuffled.begin(), shuffled.end(), rng);
        if (bySpace) {  // part p gets the p-th run of keys (the last part nothing when there are 4)
          std::sort(shuffled.begin(), shuffled.end(), [](const Contact& x, const Contact& y) { return x.Key() < y.Key(); });
          const int used = parts == 4 ? 3 : parts;
          for (size_t i = 0; i < shuffled.size(); ++i) workerContacts[int(i * size_t(used) / shuffled.size())].push_back(shuffled[i]);
          for (int p = 0; p < parts; ++p) std::shuffle(workerContacts[p].begin(), workerContacts[p].end(), rng);
        } else {
          for (size_t i = 0; i < shuffled.size(); ++i) workerContacts[int(i % size_t(parts))].push_back(shuffled[i]);
        }
        for (int threads : {1, 3}) {
          auto pool = MakeThreadPool(threads);
          StageRunner run(*pool, 8);
          for (bool restore : {false, true}) {
            ContactSorter sorter;
            std::vector<Contact> contacts;
            sorter.Sort(run, bodyCount, workerContacts, contacts, restore ? &cache : nullptr);
            EXPECT_TRUE(sorter.StrictlyIncreasing());
            ASSERT_EQ(contacts.size(), expected.size());
            for (size_t i = 0; i < contacts.size(); ++i) {
              ASSERT_EQ(contacts[i].Key(), expected[i].Key()) << bodyCount << " bodies, " << parts << " parts, " << i;
              if (!restore) continue;
              for (int k = 0; k < 2; ++k) {
                ASSERT_EQ(contacts[i].manifold.points[k].normalImpulse, expected[i].manifold.points[k].normalImpulse) << i;
                ASSERT_EQ(contacts[i].manifold.points[k].tangentImpulse, expected[i].manifold.points[k].tangentImpulse) << i;
              }
            }
          }
        }
      }
    }
  }
}

// ---- The constraint graph's colouring ------------------------------------------------------------

// The colouring as a list of (colour, contact) in colour order.
std::vector<std::pair<int, int>> Coloring(const ConstraintGraph& g) {
  std::vector<std::pair<int, int>> out;
  for (int k = 0; k <= ConstraintGraph::kColors; ++k) {
    for (int i = g.ColorBegin(k); i < g.ColorBegin(k + 1); ++i) out.push_back({k, g.ContactOf(i)});
  }
  return out;
}

// A step whose contacts have last step's dynamic ends, in the same order, reuses last step's
// colouring; any change (another body, a body turned static, one contact more) colours afresh,
// and either way the colouring is the one a new graph computes, for 1 and 3 threads.
TEST(ConstraintGraph, ReusesTheColoringOnlyWhenTheEndsAreUnchanged) {
  WorldDef def;
  Bodies bodies;
  BodyDef ground;
  ground.shape = ShapeDef::Box(50, Real(0.5));
  AppendBody(bodies, ground, def, 0);
  for (int i = 0; i < 60; ++i) {
    BodyDef box;
    box.type = BodyType::kDynamic;
    box.position = {Real(i % 10), Real(1 + i / 10)};
    box.shape = ShapeDef::Box(Real(0.5), Real(0.5));
    AppendBody(bodies, box, def, uint32_t(i + 1));
  }
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> pick(0, 60);
  std::vector<Contact> contacts;
  for (int c = 0; c < 400; ++c) {
    Contact k;
    k.a = pick(rng);
    k.b = pick(rng);
    if (k.a == k.b) continue;
    if (k.a > k.b) std::swap(k.a, k.b);
    contacts.push_back(k);
  }
  for (int threads : {1, 3}) {
    def.threadCount = threads;
    auto tasks = MakeThreadPool(threads);
    StageRunner run(*tasks, 8);
    StepContext ctx;
    ctx.def = &def;
    ctx.bodies = &bodies;
    auto fresh = [&](std::vector<Contact>& list) {
      ConstraintGraph g;
      ctx.contacts = list;
      g.Color(run, ctx);
      return Coloring(g);
    };
    ConstraintGraph graph;
    auto colour = [&](std::vector<Contact>& list) {
      ctx.contacts = list;
      graph.Color(run, ctx);
      return Coloring(graph);
    };
    std::vector<Contact> list = contacts;
    EXPECT_EQ(colour(list), fresh(list));
    EXPECT_EQ(graph.reused_, 0);
    EXPECT_EQ(colour(list), fresh(list));  // the same ends: reused
    EXPECT_EQ(graph.reused_, 1);
    list[200].b = list[200].b == 60 ? 59 : 60;  // one end changed
    if (list[200].a == list[200].b) list[200].a = 0;
    EXPECT_EQ(colour(list), fresh(list));
    EXPECT_EQ(graph.reused_, 1);
    const Real mass = bodies.inv[list[10].a].invMass;
    if (mass > 0) {  // a body becomes fixed: its end is no longer dynamic
      bodies.inv[list[10].a].invMass = 0;
      EXPECT_EQ(colour(list), fresh(list));
      EXPECT_EQ(graph.reused_, 1);
      bodies.inv[list[10].a].invMass = mass;
    }
    list.push_back(list[5]);  // one contact more
    list.back().b = list.back().a == 1 ? 2 : 1;
    EXPECT_EQ(colour(list), fresh(list));
    list.pop_back();
    EXPECT_EQ(colour(list), fresh(list));  // one fewer
    const int64_t reused = graph.reused_;
    EXPECT_EQ(colour(list), fresh(list));
    EXPECT_EQ(graph.reused_, reused + 1);
    // No two constraints of one colour share a dynamic body.
    const auto all = Coloring(graph);
    for (size_t i = 0; i < all.size(); ++i) {
      for (size_t j = i + 1; j < all.size() && all[j].first == all[i].first; ++j) {
        if (all[i].first == ConstraintGraph::kColors) break;
        const Contact& x = list[all[i].second];
        const Contact& y = list[all[j].second];
        for (int u : {x.a, x.b}) {
          for (int v : {y.a, y.b}) {
            if (u == v) {
              EXPECT_EQ(bodies.inv[u].invMass, 0) << "colour " << all[i].first;
            }
          }
        }
      }
    }
  }
}

// A pair reported twice (never by the broad phase) is still sorted, and the sorter says the
// keys do not strictly increase, so the world stores a copy instead of keeping the list.
TEST(ContactSort, ARepeatedPairIsReported) {
  for (int bodyCount : {50, 20000}) {
    for (int parts : {1, 2}) {
      WorkerLists<Contact> workerContacts;
      workerContacts.Reset(parts);
      for (int a = 0; a < 40; ++a) workerContacts[a % parts].push_back(MakeContact(a, a + 1, 1, 0, 0, 0));
      workerContacts[parts - 1].push_back(MakeContact(7, 8, 1, 0, 0, 0));  // (7, 8) again
      auto pool = MakeThreadPool(parts);
      StageRunner run(*pool, 4);
      ContactSorter sorter;
      std::vector<Contact> contacts;
      sorter.Sort(run, bodyCount, workerContacts, contacts);
      EXPECT_FALSE(sorter.StrictlyIncreasing()) << bodyCount << " bodies, " << parts << " parts";
      ASSERT_EQ(contacts.size(), 41u);
      for (size_t i = 1; i < contacts.size(); ++i) EXPECT_LE(contacts[i - 1].Key(), contacts[i].Key()) << i;
      workerContacts[parts - 1].pop_back();
      sorter.Sort(run, bodyCount, workerContacts, contacts);
      EXPECT_TRUE(sorter.StrictlyIncreasing()) << bodyCount << " bodies, " << parts << " parts";
    }
  }
}

}  // namespace
}  // namespace quadrant
