// Tests for the pair cache (engine/src/collision/pair_cache.h): while it serves pairs from its fat boxes it
// must give exactly the broad phase's set, whatever the boxes, flags, body count and thread count
// do between calls; it must actually serve a resting scene and stand aside for a moving one; and a
// world stepped with it gives the same state, bit for bit, as one stepped without it.
#include <gtest/gtest.h>

#include <memory>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "collision/broad_phase.h"
#include "collision/pair_cache.h"
#include "quadrant/task_system.h"
#include "quadrant/world.h"
#include "parallel/stage_runner.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

using namespace test;
using PairSet = std::set<std::pair<int32_t, int32_t>>;

PairSet BruteForce(const std::vector<AABB>& boxes, const std::vector<uint8_t>& movable) {
  PairSet out;
  const int n = static_cast<int>(boxes.size());
  for (int a = 0; a < n; ++a) {
    for (int b = a + 1; b < n; ++b) {
      if ((movable[a] || movable[b]) && Overlaps(boxes[a], boxes[b])) out.insert({a, b});
    }
  }
  return out;
}

// A frame of the sequence: the boxes the caller's update writes, and the movable flags.
struct Frame {
  std::vector<AABB> boxes;
  std::vector<uint8_t> movable;
};

// Unit boxes on a loose grid (neighbours within a few centimetres), a few static.
Frame Pile(int n, uint32_t seed) {
  std::mt19937 rng(seed);
  Frame f;
  for (int i = 0; i < n; ++i) {
    const Real x = Real(i % 20) * Real(1.02), y = Real(i / 20) * Real(1.01);
    f.boxes.push_back({{x, y}, {x + 1, y + 1}});
    f.movable.push_back(rng() % 7 == 0 ? 0 : 1);
  }
  return f;
}

// Every box moved by up to `jitter` (m) in x and y, as a settling pile's bodies do.
Frame Jitter(const Frame& from, Real jitter, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> d(-1, 1);
  Frame f = from;
  for (AABB& b : f.boxes) {
    const Vec2 s{Real(d(rng)) * jitter, Real(d(rng)) * jitter};
    b = {b.lower + s, b.upper + s};
  }
  return f;
}

// Runs the cache over `frames` and checks every frame's pairs against brute force; returns the
// raw pair sequences.
std::vector<std::vector<CandidatePair>> RunFrames(BroadPhase& bp, PairCache& cache, const std::vector<Frame>& frames,
                                                  int threads) {
  std::unique_ptr<TaskSystem> tasks = MakeThreadPool(threads);
  StageRunner run(*tasks, 1);  // every section split
  std::vector<std::vector<CandidatePair>> all;
  for (size_t k = 0; k < frames.size(); ++k) {
    const Frame& target = frames[k];
    const int n = static_cast<int>(target.boxes.size());
    std::vector<AABB> boxes(static_cast<size_t>(n), AABB{{-1e3, -1e3}, {1e3, 1e3}});  // stale until updated
    std::vector<int> calls(static_cast<size_t>(n), 0);
    struct Ctx {
      const Frame* target;
      std::vector<AABB>* boxes;
      std::vector<int>* calls;
    };
    const Ctx ctx{&target, &boxes, &calls};
    const BroadPhase::BoxUpdate update{[](const void* c, int begin, int end) {
                                         const Ctx& x = *static_cast<const Ctx*>(c);
                                         for (int i = begin; i < end; ++i) {
                                           (*x.boxes)[i] = x.target->boxes[i];
                                           ++(*x.calls)[i];
                                         }
                                       },
                                       &ctx};
    std::vector<CandidatePair> got = {{7, 3}};  // stale content: must be replaced
    cache.UpdateAndFindPairs(bp, boxes, target.movable, got, run, update);
    for (int i = 0; i < n; ++i) EXPECT_EQ(calls[i], 1) << "frame " << k << " body " << i;
    PairSet set;
    for (const CandidatePair& p : got) {
      EXPECT_LT(p.a, p.b);
      EXPECT_TRUE(set.insert({p.a, p.b}).second) << "frame " << k << ": pair (" << p.a << ", " << p.b << ") twice";
    }
    EXPECT_EQ(set, BruteForce(target.boxes, target.movable)) << "frame " << k << ", " << threads << " threads";
    all.push_back(got);
  }
  return all;
}

// A pile that jitters by a few millimetres, with a body teleported, a flag flipped, bodies added
// and removed, and then the jitter again.
std::vector<Frame> RestingSequence() {
  std::vector<Frame> frames;
  const Frame pile = Pile(300, 5);
  for (int k = 0; k < 12; ++k) frames.push_back(Jitter(pile, Real(0.004), 100 + k));
  Frame jump = Jitter(pile, Real(0.004), 200);
  jump.boxes[17] = {{Real(3.5), Real(2.5)}, {Real(4.5), Real(3.5)}};  // onto its neighbours: new pairs
  frames.push_back(jump);
  frames.push_back(jump);
  Frame flip = jump;
  flip.movable[40] ^= 1;  // the only change: a flag (pairs of two statics drop out)
  flip.movable[41] = 0;
  frames.push_back(flip);
  Frame more = flip;
  more.boxes.push_back({{Real(0.5), Real(0.5)}, {Real(1.5), Real(1.5)}});  // one body more
  more.movable.push_back(1);
  frames.push_back(more);
  Frame fewer = more;
  fewer.boxes.resize(250);  // bodies removed
  fewer.movable.resize(250);
  frames.push_back(fewer);
  for (int k = 0; k < 8; ++k) frames.push_back(Jitter(fewer, Real(0.004), 300 + k));
  return frames;
}

class PairCacheTest : public ::testing::TestWithParam<BroadPhaseType> {};

TEST_P(PairCacheTest, RestingSceneIsServedWithTheBroadPhasesPairs) {
  std::vector<std::vector<CandidatePair>> one;
  for (const int threads : {1, 3}) {
    auto bp = MakeBroadPhase(GetParam(), 8);
    PairCache cache;
    const auto seq = RunFrames(*bp, cache, RestingSequence(), threads);
    // Jitter of 4 mm keeps every box in its fat box (0.1 m): most frames are served.
    EXPECT_GE(cache.Reused(), 15) << threads << " threads";
    EXPECT_LE(cache.Rebuilt(), 6) << threads << " threads";
    if (threads == 1) {
      one = seq;
    } else {  // the same pairs in the same order on any thread count
      ASSERT_EQ(seq.size(), one.size());
      for (size_t k = 0; k < seq.size(); ++k) {
        ASSERT_EQ(seq[k].size(), one[k].size()) << "frame " << k;
        for (size_t i = 0; i < seq[k].size(); ++i) {
          ASSERT_TRUE(seq[k][i].a == one[k][i].a && seq[k][i].b == one[k][i].b) << "frame " << k << " pair " << i;
        }
      }
    }
  }
}

TEST_P(PairCacheTest, MovingSceneMakesItStandAside) {
  // Every box moves 0.3 m a frame (out of its fat box every time): after the first tries the
  // plain broad phase runs, and the pairs stay right throughout.
  std::vector<Frame> frames;
  Frame f = Pile(200, 9);
  for (int k = 0; k < 100; ++k) {
    for (AABB& b : f.boxes) {
      const Vec2 s{Real(0.3), Real(k % 2 ? -0.3 : 0.3)};
      b = {b.lower + s, b.upper + s};
    }
    frames.push_back(f);
  }
  auto bp = MakeBroadPhase(GetParam(), 8);
  PairCache cache;
  RunFrames(*bp, cache, frames, 2);
  EXPECT_EQ(cache.Reused(), 0);
  EXPECT_LE(cache.Rebuilt(), 3);  // frames 0, 65 (a jump to 64 frames aside), ...
}

INSTANTIATE_TEST_SUITE_P(Both, PairCacheTest, ::testing::Values(BroadPhaseType::kUniformGrid, BroadPhaseType::kQuadTree));

// A world with the cache and one without step to the same state, bit for bit, on one thread and
// on three with every section split: a pile settling, which the cache serves, and the same pile
// with circles thrown at it, which keeps the cache aside (it is all or nothing: one body out of
// its fat box rebuilds every pair, so a few moving bodies among many resting ones cost it most
// of its use).
TEST(PairCacheWorldTest, SameStateWithAndWithoutTheCache) {
  for (const bool thrown : {false, true}) {
    for (const int threads : {1, 3}) {
      SCOPED_TRACE(std::string(thrown ? "pile and thrown circles, " : "pile, ") + std::to_string(threads) + " threads");
      uint64_t hashes[2] = {0, 0};
      int served[2] = {0, 0};
      for (const bool reuse : {false, true}) {
        WorldDef def;
        def.reusePairs = reuse;
        def.threadCount = threads;
        def.minParallelItems = 8;
        World world(def);
        AddGround(world);
        for (int row = 0; row < 12; ++row) {
          for (int i = 0; i < 12 - row; ++i) AddBox(world, {Real(i) + Real(0.5) * Real(row) - 6, Real(1.0) * row + Real(1)});
        }
        if (thrown) {
          for (int i = 0; i < 10; ++i) AddCircle(world, {Real(i) - 5, 20}, Real(0.3), {Real(i % 3) - 1, -5});
        }
        for (int step = 0; step < 150; ++step) {
          world.Step(kDt);
          served[reuse] += world.GetCounters().pairsReused ? 1 : 0;
        }
        hashes[reuse] = world.StateHash();
      }
      EXPECT_EQ(hashes[0], hashes[1]);
      EXPECT_EQ(served[0], 0) << "reusePairs off: the broad phase runs every step";
      if (!thrown) {
        EXPECT_GE(served[1], 100) << "the settling pile must be served from the cache";
      }
    }
  }
}

}  // namespace
}  // namespace quadrant
