// Tests for the broad phases (engine/src/collision/broad_phase.h): quad tree and uniform grid must both
// report exactly the brute-force set of overlapping pairs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "collision/broad_phase.h"
#include "quadrant/task_system.h"
#include "parallel/stage_runner.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

using PairSet = std::set<std::pair<int32_t, int32_t>>;

struct Input {
  std::vector<AABB> aabbs;
  std::vector<uint8_t> movable;
};

/// The reference: every pair a < b whose boxes overlap (touching counts) with at least one
/// movable body.
void FindPairsOnce(BroadPhase& bp, const Input& in, std::vector<CandidatePair>& out) {
  std::unique_ptr<TaskSystem> tasks = MakeThreadPool(1);
  StageRunner run(*tasks, 1);
  bp.FindPairs(in.aabbs, in.movable, out, run);
}

PairSet BruteForce(const Input& in) {
  PairSet out;
  const int n = int(in.aabbs.size());
  for (int a = 0; a < n; ++a) {
    for (int b = a + 1; b < n; ++b) {
      if (!in.movable[a] && !in.movable[b]) continue;
      if (Overlaps(in.aabbs[a], in.aabbs[b])) out.insert({a, b});
    }
  }
  return out;
}

/// Runs the broad phase on one thread (or `threads`, with every section split) and checks the
/// raw output's form: a < b, indices in range, no pair twice. Returns the pairs as a set.
PairSet FindAll(BroadPhase& bp, const Input& in, std::vector<CandidatePair>* raw = nullptr, int threads = 1) {
  std::unique_ptr<TaskSystem> tasks = MakeThreadPool(threads);
  StageRunner run(*tasks, 1);
  std::vector<CandidatePair> out = {{7, 3}};  // stale content: FindPairs must clear it
  bp.FindPairs(in.aabbs, in.movable, out, run);
  PairSet set;
  const int n = int(in.aabbs.size());
  for (const CandidatePair& p : out) {
    EXPECT_LT(p.a, p.b) << bp.Name();
    EXPECT_GE(p.a, 0) << bp.Name();
    EXPECT_LT(p.b, n) << bp.Name();
    bool inserted = set.insert({p.a, p.b}).second;
    EXPECT_TRUE(inserted) << bp.Name() << ": pair (" << p.a << ", " << p.b << ") reported twice";
  }
  if (raw) *raw = out;
  return set;
}

/// Reports the first few differences between the engine's and the reference's pair sets.
::testing::AssertionResult SameSet(const PairSet& got, const PairSet& want, const Input& in) {
  if (got == want) return ::testing::AssertionSuccess();
  auto fail = ::testing::AssertionFailure();
  fail << "got " << got.size() << " pairs, want " << want.size() << ".";
  int shown = 0;
  auto show = [&](const std::pair<int32_t, int32_t>& p, const char* what) {
    const AABB& a = in.aabbs[p.first];
    const AABB& b = in.aabbs[p.second];
    fail << "\n  " << what << " (" << p.first << ", " << p.second << "): [" << a.lower.x << ","
         << a.lower.y << " - " << a.upper.x << "," << a.upper.y << "] m=" << int(in.movable[p.first])
         << " vs [" << b.lower.x << "," << b.lower.y << " - " << b.upper.x << "," << b.upper.y
         << "] m=" << int(in.movable[p.second]);
  };
  for (const auto& p : want) {
    if (!got.count(p) && shown++ < 8) show(p, "missing");
  }
  for (const auto& p : got) {
    if (!want.count(p) && shown++ < 16) show(p, "extra");
  }
  return fail;
}

/// A random scene: `n` boxes of sizes 0.05..5 m in a +-range square, some snapped onto
/// power-of-two coordinates (0, +-1, +-2, +-4, ...), some static, one huge box covering
/// everything, and a few exact touching/identical pairs.
Input RandomInput(uint32_t seed, int n, Real range) {
  std::mt19937 rng(seed);
  auto uni = [&](double lo, double hi) {
    return lo + (hi - lo) * (double(rng()) / double(std::mt19937::max()));
  };
  const double pow2[] = {0, 1, -1, 2, -2, 4, -4, 8, -8, 16, -16, 0.5, -0.5};
  Input in;
  for (int i = 0; i < n; ++i) {
    // Sizes log-uniform between 0.05 and 5 m.
    double w = 0.05 * std::pow(100.0, uni(0, 1));
    double h = 0.05 * std::pow(100.0, uni(0, 1));
    double x = uni(-range, range - w);
    double y = uni(-range, range - h);
    int snap = int(rng() % 6);
    if (snap == 0) x = pow2[rng() % 13];           // lower edge on a boundary
    if (snap == 1) x = pow2[rng() % 13] - w;       // upper edge on a boundary
    if (snap == 2) y = pow2[rng() % 13];
    if (snap == 3) { x = pow2[rng() % 13]; y = pow2[rng() % 13] - h; }
    AABB box{{Real(x), Real(y)}, {Real(x + w), Real(y + h)}};
    in.aabbs.push_back(box);
    in.movable.push_back(rng() % 5 == 0 ? 0 : 1);  // ~20 % static
  }
  // Exact touching: a box whose lower x is another's upper x, and one sharing only a corner.
  if (n >= 2) {
    AABB a = in.aabbs[0];
    AABB t{{a.upper.x, a.lower.y}, {a.upper.x + Real(0.5), a.upper.y}};
    AABB c{{a.upper.x, a.upper.y}, {a.upper.x + Real(0.25), a.upper.y + Real(0.25)}};
    in.aabbs.push_back(t);
    in.movable.push_back(1);
    in.aabbs.push_back(c);
    in.movable.push_back(1);
    in.aabbs.push_back(in.aabbs[1]);  // an identical copy
    in.movable.push_back(1);
  }
  // One huge movable box over everything (mid list, so both a < huge and huge < b occur).
  AABB huge{{-range * 2, -range * 2}, {range * 2, range * 2}};
  in.aabbs.insert(in.aabbs.begin() + in.aabbs.size() / 2, huge);
  in.movable.insert(in.movable.begin() + in.movable.size() / 2, 1);
  return in;
}

struct Factory {
  const char* name;
  std::unique_ptr<BroadPhase> (*make)();
};

std::unique_ptr<BroadPhase> MakeQt() { return MakeQuadTree(8); }
std::unique_ptr<BroadPhase> MakeGrid() { return MakeUniformGrid(); }

class BroadPhaseTest : public ::testing::TestWithParam<Factory> {};

TEST_P(BroadPhaseTest, EmptyInputGivesNoPairs) {
  auto bp = GetParam().make();
  Input in;
  std::vector<CandidatePair> out = {{0, 1}};
  FindPairsOnce(*bp, in, out);
  EXPECT_TRUE(out.empty());
  // A single box has nobody to pair with.
  in.aabbs.push_back({{0, 0}, {1, 1}});
  in.movable.push_back(1);
  FindPairsOnce(*bp, in, out);
  EXPECT_TRUE(out.empty());
}

TEST_P(BroadPhaseTest, HandMadeTouchingAndStaticCases) {
  auto bp = GetParam().make();
  Input in;
  in.aabbs = {
      {{0, 0}, {1, 1}},                          // 0 movable
      {{1, 0}, {2, 1}},                          // 1 touches 0 along x = 1
      {{2, 1}, {3, 2}},                          // 2 touches 1 at the corner (2, 1)
      {{Real(3.001), 0}, {4, 1}},                // 3 just apart from 2
      {{-1, -1}, {Real(0.5), Real(0.5)}},        // 4 static, overlaps 0
      {{-1, -1}, {Real(0.5), Real(0.5)}},        // 5 static, identical to 4: static-static
      {{Real(0.25), Real(0.25)}, {Real(0.75), Real(0.75)}},  // 6 inside 0
  };
  in.movable = {1, 1, 1, 1, 0, 0, 1};
  PairSet want = BruteForce(in);
  PairSet expected = {{0, 1}, {1, 2}, {0, 4}, {0, 5}, {0, 6}, {4, 6}, {5, 6}};
  ASSERT_EQ(want, expected);  // the reference itself
  EXPECT_TRUE(SameSet(FindAll(*bp, in), want, in));
}

TEST_P(BroadPhaseTest, AllStaticGivesNoPairs) {
  auto bp = GetParam().make();
  Input in = RandomInput(7, 50, 10);
  std::fill(in.movable.begin(), in.movable.end(), uint8_t(0));
  EXPECT_TRUE(FindAll(*bp, in).empty());
}

TEST_P(BroadPhaseTest, RandomSetsMatchBruteForce) {
  auto bp = GetParam().make();
  for (uint32_t seed = 1; seed <= 20; ++seed) {
    Input in = RandomInput(seed, 20 + int(seed) * 10, Real(4 + seed));
    EXPECT_TRUE(SameSet(FindAll(*bp, in), BruteForce(in), in)) << GetParam().name << " seed " << seed;
  }
}

TEST_P(BroadPhaseTest, ThreeThreadsGiveTheSameSequenceAsOne) {
  // Parallel sections write per-worker buffers merged in worker order: the same pairs in the
  // same order as one thread, which the deterministic scheme relies on.
  auto bp = GetParam().make();
  for (uint32_t seed = 1; seed <= 5; ++seed) {
    Input in = RandomInput(seed, 400, Real(20));
    std::vector<CandidatePair> one, three;
    FindAll(*bp, in, &one, 1);
    FindAll(*bp, in, &three, 3);
    ASSERT_EQ(one.size(), three.size()) << GetParam().name;
    for (size_t k = 0; k < one.size(); ++k) {
      EXPECT_TRUE(one[k].a == three[k].a && one[k].b == three[k].b) << GetParam().name << " pair " << k;
    }
    EXPECT_TRUE(SameSet(FindAll(*bp, in, nullptr, 3), BruteForce(in), in)) << GetParam().name;
  }
}

TEST_P(BroadPhaseTest, ReusedInstanceAcrossDifferentInputs) {
  // Implementations keep buffers between calls; a big input followed by a small one (and
  // back) must not leak state.
  auto bp = GetParam().make();
  Input big = RandomInput(100, 300, 20);
  Input small = RandomInput(101, 10, 2);
  EXPECT_TRUE(SameSet(FindAll(*bp, big), BruteForce(big), big));
  EXPECT_TRUE(SameSet(FindAll(*bp, small), BruteForce(small), small));
  EXPECT_TRUE(SameSet(FindAll(*bp, big), BruteForce(big), big));
}

TEST_P(BroadPhaseTest, DeterministicOutput) {
  Input in = RandomInput(42, 400, 25);
  auto bp = GetParam().make();
  std::vector<CandidatePair> first, second, fresh;
  FindAll(*bp, in, &first);
  FindAll(*bp, in, &second);
  auto other = GetParam().make();
  FindAll(*other, in, &fresh);
  ASSERT_EQ(first.size(), second.size());
  ASSERT_EQ(first.size(), fresh.size());
  for (size_t i = 0; i < first.size(); ++i) {
    EXPECT_TRUE(first[i].a == second[i].a && first[i].b == second[i].b) << "index " << i;
    EXPECT_TRUE(first[i].a == fresh[i].a && first[i].b == fresh[i].b) << "index " << i;
  }
}

TEST_P(BroadPhaseTest, ThousandsOfRandomAabbs) {
  auto bp = GetParam().make();
  Input in = RandomInput(2024, 1500, 60);
  PairSet want = BruteForce(in);
  ASSERT_GT(want.size(), 1500u);  // the huge box alone pairs with everyone
  EXPECT_TRUE(SameSet(FindAll(*bp, in), want, in));
}

TEST_P(BroadPhaseTest, FarAwayAndNegativeCoordinates) {
  auto bp = GetParam().make();
  Input in;
  std::mt19937 rng(5);
  for (int i = 0; i < 200; ++i) {
    Real x = Real(int(rng() % 2000) - 1000) * Real(0.5);  // multiples of 0.5 in +-500
    Real y = Real(int(rng() % 40) - 20) * Real(0.5);
    Real w = Real(1 + rng() % 4) * Real(0.25);
    in.aabbs.push_back({{x, y}, {x + w, y + w}});  // many exact touches on the 0.25 lattice
    in.movable.push_back(rng() % 3 ? 1 : 0);
  }
  EXPECT_TRUE(SameSet(FindAll(*bp, in), BruteForce(in), in));
}

TEST_P(BroadPhaseTest, CrowdedCellsMatchBruteForceOnAnyThreadCount) {
  // Equal boxes whose lower corners crowd a few cells (the grid's cell is one box wide), so a
  // body meets runs of many bodies in its own, right and upper cells: longer than the grid
  // scan's windows of four. Also bodies on the region's left and right edges.
  auto bp = GetParam().make();
  std::mt19937 rng(7);
  Input in;
  for (int i = 0; i < 600; ++i) {
    const Real x = Real(int(rng() % 40)) * Real(0.1), y = Real(int(rng() % 30)) * Real(0.1);
    in.aabbs.push_back({{x, y}, {x + 1, y + 1}});
    in.movable.push_back(rng() % 7 ? 1 : 0);
  }
  const PairSet want = BruteForce(in);
  std::vector<CandidatePair> one, three;
  EXPECT_TRUE(SameSet(FindAll(*bp, in, &one, 1), want, in)) << GetParam().name;
  EXPECT_TRUE(SameSet(FindAll(*bp, in, &three, 3), want, in)) << GetParam().name;
  ASSERT_EQ(one.size(), three.size());
  for (size_t k = 0; k < one.size(); ++k) {
    ASSERT_TRUE(one[k].a == three[k].a && one[k].b == three[k].b) << GetParam().name << " pair " << k;
  }
}

TEST_P(BroadPhaseTest, UpdateAndFindPairsUpdatesEveryBoxOnceBeforeReadingIt) {
  // The caller's box update runs inside the broad phase (the grid: in its first stage, chunk by
  // chunk, on any thread): every box is updated exactly once, and the pairs are those of the
  // updated boxes, in FindPairs' order, on one thread and on three. Also for 1 and 0 bodies.
  for (const int count : {0, 1, 700}) {
    const Input target = RandomInput(11, count, Real(25));  // (it may add a huge box)
    const int n = static_cast<int>(target.aabbs.size());
    for (const int threads : {1, 3}) {
      std::vector<CandidatePair> want;
      FindAll(*GetParam().make(), target, &want, threads);
      Input in = target;
      for (AABB& b : in.aabbs) b = {{Real(-1e3), Real(-1e3)}, {Real(1e3), Real(1e3)}};  // stale: meets everything
      struct Ctx {
        const Input* target;
        Input* in;
        std::vector<int>* calls;
      };
      std::vector<int> calls(size_t(n), 0);
      const Ctx ctx{&target, &in, &calls};
      const BroadPhase::BoxUpdate update{[](const void* c, int begin, int end) {
                                           const Ctx& x = *static_cast<const Ctx*>(c);
                                           for (int i = begin; i < end; ++i) {
                                             x.in->aabbs[i] = x.target->aabbs[i];
                                             ++(*x.calls)[i];  // each index in one chunk only
                                           }
                                         },
                                         &ctx};
      std::unique_ptr<TaskSystem> tasks = MakeThreadPool(threads);
      StageRunner run(*tasks, 1);
      std::vector<CandidatePair> got = {{7, 3}};
      auto bp = GetParam().make();
      bp->UpdateAndFindPairs(in.aabbs, in.movable, got, run, update);
      for (int i = 0; i < n; ++i) ASSERT_EQ(calls[i], 1) << GetParam().name << " body " << i << " of " << n;
      ASSERT_EQ(got.size(), want.size()) << GetParam().name << " n " << n << " threads " << threads;
      for (size_t k = 0; k < got.size(); ++k) {
        ASSERT_TRUE(got[k].a == want[k].a && got[k].b == want[k].b) << GetParam().name << " pair " << k;
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Both, BroadPhaseTest,
                         ::testing::Values(Factory{"QuadTree", &MakeQt}, Factory{"UniformGrid", &MakeGrid}),
                         [](const ::testing::TestParamInfo<Factory>& info) { return std::string(info.param.name); });

TEST(BroadPhaseFactoryTest, MakeBroadPhaseGivesBothKinds) {
  auto qt = MakeBroadPhase(BroadPhaseType::kQuadTree, 8);
  auto grid = MakeBroadPhase(BroadPhaseType::kUniformGrid, 8);
  ASSERT_NE(qt, nullptr);
  ASSERT_NE(grid, nullptr);
  EXPECT_STRNE(qt->Name(), grid->Name());
  Input in = RandomInput(9, 200, 10);
  EXPECT_EQ(FindAll(*qt, in), FindAll(*grid, in));
}

TEST(BroadPhaseFactoryTest, ShallowQuadTreeStillExact) {
  // Depth 1 puts almost everything in the root; depth 12 is the documented maximum.
  for (int depth : {1, 12}) {
    auto qt = MakeQuadTree(depth);
    Input in = RandomInput(77, 300, 30);
    EXPECT_TRUE(SameSet(FindAll(*qt, in), BruteForce(in), in)) << "depth " << depth;
  }
}

}  // namespace
}  // namespace quadrant
