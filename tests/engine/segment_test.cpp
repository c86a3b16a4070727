// Tests for segments and chains (ShapeDef::MakeSegment, MakeChainSegment, MakeChainBodies,
// World::CreateChain, collision/segment_collide.cpp, the segment cases of queries.cpp): a
// segment's manifolds are a radius-0 capsule's, bodies rest on static and kinematic segments,
// a chain is one-sided, a box slides across a chain's joins without catching where plain
// segments make it catch, the queries, the drawing and the refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <span>
#include <vector>

#include "collision/narrow_phase.h"
#include "quadrant/debug_draw.h"
#include "quadrant/world.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

using namespace test;

const Transform kIdentity{{0, 0}, MakeRot(0)};

ChainDef def4() {
  ChainDef def;
  def.points = {{3, 0}, {2, 0}, {1, 0}, {0, 0}};
  return def;
}

BodyId AddSegment(World& world, Vec2 p1, Vec2 p2, BodyType type = BodyType::kStatic, Vec2 position = {}) {
  BodyDef def;
  def.type = type;
  def.position = position;
  def.shape = ShapeDef::MakeSegment(p1, p2);
  return world.CreateBody(def);
}

bool SameManifold(const Manifold& a, const Manifold& b) {
  if (a.pointCount != b.pointCount) return false;
  if (a.pointCount == 0) return true;
  if (a.normal.x != b.normal.x || a.normal.y != b.normal.y) return false;
  for (int j = 0; j < a.pointCount; ++j) {
    if (a.points[j].point.x != b.points[j].point.x || a.points[j].point.y != b.points[j].point.y ||
        a.points[j].separation != b.points[j].separation) {
      return false;
    }
  }
  return true;
}

TEST(SegmentTest, ManifoldsAreThoseOfACapsuleOfRadiusZero) {
  const Vec2 p1{-1, 0}, p2{1, Real(0.2)};
  const ShapeDef seg = ShapeDef::MakeSegment(p1, p2);
  const Capsule core{p1, p2, 0};
  const Transform xfSeg{{Real(0.1), Real(-0.05)}, MakeRot(Real(0.1))};
  const ShapeDef box = ShapeDef::Box(Real(0.3), Real(0.2));
  const ShapeDef circle = ShapeDef::MakeCircle(Real(0.25));
  const ShapeDef capsule = ShapeDef::MakeCapsule({Real(-0.3), 0}, {Real(0.3), 0}, Real(0.1));
  int touching = 0;
  for (int k = 0; k < 12; ++k) {
    const Transform xf{{Real(-1.4 + 0.25 * k), Real(0.19 + 0.01 * (k % 3))}, MakeRot(Real(0.2 * k))};
    SCOPED_TRACE(k);
    const Real spec = Real(0.1);
    Manifold want = CollidePolygonAndCapsule(box.polygon, xf, core, xfSeg, spec);
    want.normal = -want.normal;
    EXPECT_TRUE(SameManifold(Collide(seg, xfSeg, box, xf, spec), want));
    EXPECT_TRUE(SameManifold(Collide(seg, xfSeg, circle, xf, spec), CollideCapsuleAndCircle(core, xfSeg, circle.circle, xf, spec)));
    EXPECT_TRUE(SameManifold(Collide(seg, xfSeg, capsule, xf, spec), CollideCapsules(core, xfSeg, capsule.capsule, xf, spec)));
    // The other way round the normal flips.
    const Manifold back = Collide(box, xf, seg, xfSeg, spec);
    EXPECT_EQ(back.pointCount, want.pointCount);
    if (back.pointCount > 0) {
      EXPECT_EQ(back.normal.y, -want.normal.y);
    }
    touching += want.pointCount > 0;
  }
  EXPECT_GT(touching, 6);
  // Segments of either kind never collide with each other, even crossing.
  const ShapeDef cross = ShapeDef::MakeSegment({0, -1}, {0, 1});
  const ShapeDef chain = ShapeDef::MakeChainSegment({2, 1}, {1, 0}, {-1, 0}, {-2, 1});
  EXPECT_EQ(Collide(seg, kIdentity, cross, kIdentity, 1).pointCount, 0);
  EXPECT_EQ(Collide(chain, kIdentity, cross, kIdentity, 1).pointCount, 0);
  EXPECT_EQ(Collide(cross, kIdentity, chain, kIdentity, 1).pointCount, 0);
}

TEST(SegmentTest, MassIsZeroAndTheBoxIsTheSegments) {
  const MassData md = ComputeMass(Segment{{0, 0}, {2, 1}});
  EXPECT_EQ(md.mass, 0);
  EXPECT_EQ(md.rotationalInertia, 0);
  EXPECT_TRUE(VecNear(md.center, {1, Real(0.5)}, 1e-6));
  World world;
  const BodyId id = AddSegment(world, {-1, 0}, {1, 0}, BodyType::kStatic, {3, 1});
  const AABB box = world.GetAABB(id);
  EXPECT_TRUE(VecNear(box.lower, {2, 1}, 1e-6));
  EXPECT_TRUE(VecNear(box.upper, {4, 1}, 1e-6));
}

TEST(SegmentTest, BodiesRestOnStaticAndKinematicSegments) {
  for (SolverType solver : {SolverType::kSoftStep, SolverType::kPgs}) {
    SCOPED_TRACE(static_cast<int>(solver));
    WorldDef def;
    def.solver = solver;
    World world(def);
    AddSegment(world, {-5, 0}, {5, 0});
    // A kinematic segment carrying a box sideways at 1 m/s, and a circle resting on the ground.
    BodyDef lift;
    lift.type = BodyType::kKinematic;
    lift.position = {0, 3};
    lift.linearVelocity = {1, 0};
    lift.shape = ShapeDef::MakeSegment({-2, 0}, {2, 0});
    world.CreateBody(lift);
    const BodyId box = AddBox(world, {-2, 1}, Real(0.5), Real(0.5), 1, Real(0.3));
    const BodyId rider = AddBox(world, {0, Real(3.3)}, Real(0.25), Real(0.25));
    const BodyId ball = AddCircle(world, {-4, Real(0.5)}, Real(0.25));
    const BodyId capsule = [&] {
      BodyDef c;
      c.type = BodyType::kDynamic;
      c.position = {2, 1};
      c.angle = Real(0.5);
      c.shape = ShapeDef::MakeCapsule({Real(-0.4), 0}, {Real(0.4), 0}, Real(0.2));
      return world.CreateBody(c);
    }();
    StepN(world, 90);
    EXPECT_NEAR(world.GetPosition(box).y, 0.5, 0.02);
    EXPECT_NEAR(std::sin(world.GetAngle(box)), 0, 0.02);
    EXPECT_NEAR(world.GetPosition(capsule).y, 0.2, 0.02);
    EXPECT_NEAR(world.GetPosition(ball).y, 0.25, 0.02);
    EXPECT_NEAR(world.GetPosition(rider).y, 3.25, 0.02);  // rides the kinematic segment
    EXPECT_GT(world.GetPosition(rider).x, 1.3);
  }
}

// A flat chain to slide along, left to right at y = 0, as static segments: chain segments with
// their ghosts, or plain two-sided segments meeting at the same points.
struct Slide {
  Real minSpeed = 1e9, maxSpeed = 0, maxUp = 0, endX = 0;
};

Slide SlideBox(bool chain, Real friction, Real seconds, SolverType solver = SolverType::kSoftStep) {
  WorldDef def;
  def.solver = solver;
  World world(def);
  // Ground to stand on runs right to left (its collision side, the right of p1 -> p2, is up).
  ChainDef ground;
  for (int x = 40; x >= -3; --x) ground.points.push_back({Real(x), 0});
  ground.friction = friction;
  if (chain) {
    world.CreateChain(ground);
  } else {
    for (size_t k = 1; k + 2 < ground.points.size(); ++k) {
      BodyDef seg;
      seg.shape = ShapeDef::MakeSegment(ground.points[k], ground.points[k + 1]);
      seg.shape.friction = friction;
      world.CreateBody(seg);
    }
  }
  BodyDef box;
  box.type = BodyType::kDynamic;
  box.position = {Real(0.3), Real(0.25)};
  box.linearVelocity = {5, 0};
  box.shape = ShapeDef::Box(Real(0.25), Real(0.25));
  box.shape.friction = friction;
  const BodyId id = world.CreateBody(box);
  Slide s;
  const int steps = int(seconds * 60);
  for (int i = 0; i < steps; ++i) {
    world.Step(kDt);
    const Vec2 v = world.GetLinearVelocity(id);
    s.minSpeed = std::min(s.minSpeed, v.x);
    s.maxSpeed = std::max(s.maxSpeed, v.x);
    s.maxUp = std::max(s.maxUp, v.y);
  }
  s.endX = world.GetPosition(id).x;
  return s;
}

TEST(ChainTest, ABoxSlidesAcrossTwentyJoinsWithoutCatchingWherePlainSegmentsCatch) {
  for (SolverType solver : {SolverType::kSoftStep, SolverType::kPgs}) {
    SCOPED_TRACE(static_cast<int>(solver));
    // Frictionless, 4.2 s at 5 m/s: 21 m, 21 joins.
    const Slide smooth = SlideBox(true, 0, Real(4.2), solver);
    EXPECT_GT(smooth.endX, 21);
    EXPECT_GT(smooth.minSpeed, 5 * 0.99);
    EXPECT_LT(smooth.maxSpeed, 5 * 1.01);
    EXPECT_LT(smooth.maxUp, 0.05);
    // The same ground as plain segments: the box catches on the joins (it slows) or bumps (it
    // jumps).
    const Slide rough = SlideBox(false, 0, Real(4.2), solver);
    // (Measured: it stops dead within 2 m, jumping up at 1.7-1.9 m/s, on both solvers.)
    EXPECT_TRUE(rough.minSpeed < 5 * 0.99 || rough.maxUp > 0.05)
        << "min speed " << rough.minSpeed << ", max upward " << rough.maxUp;
  }
}

TEST(ChainTest, FrictionSlowsTheSlidingBoxAsCoulombsLawSays) {
  // mu = 0.2 on both: the box decelerates at mu g = 2 m/s^2: 5 -> 3 m/s in 1 s, 4 m covered.
  const Slide s = SlideBox(true, Real(0.2), 1);
  EXPECT_NEAR(s.minSpeed, 3, 0.03);
  EXPECT_NEAR(s.endX, 0.3 + 4, 0.05);
  EXPECT_LT(s.maxUp, 0.05);
}

TEST(ChainTest, AChainIsOneSidedAndSmoothOverConvexAndConcaveJoins) {
  // A valley and a hill, ground running right to left: bodies collide from above only.
  World world;
  ChainDef def;
  def.points = {{12, 4}, {10, 2}, {8, 1}, {6, Real(0.5)}, {4, 1}, {2, Real(1.5)}, {0, 1}, {-2, 0}, {-4, 0}, {-6, 0}};
  const std::vector<BodyId> ids = world.CreateChain(def);
  ASSERT_EQ(ids.size(), def.points.size() - 3);
  // A circle dropped onto the hill's slope rolls to and fro in the valley (x = 6), above the
  // chain; a box dropped alone into the valley rests on both slopes (bottom corners at y = 0.575).
  const BodyId ball = AddCircle(world, {Real(3.5), 3}, Real(0.3));
  // A box below rises through the ground (gravity up for it) without touching it.
  BodyDef below;
  below.type = BodyType::kDynamic;
  below.position = {-3, -2};
  below.gravityScale = -1;
  below.shape = ShapeDef::Box(Real(0.3), Real(0.3));
  const BodyId riser = world.CreateBody(below);
  Real lowestBall = 10, westmost = 10, eastmost = -10;
  for (int i = 0; i < 600; ++i) {
    world.Step(kDt);
    const Vec2 p = world.GetPosition(ball);
    // The ground under the ball between x = 4 and 8 is 0.5 + |x - 6| / 4.
    if (std::abs(p.x - 6) < 2) lowestBall = std::min(lowestBall, p.y - (Real(0.5) + std::abs(p.x - 6) / 4));
    if (i > 120) westmost = std::min(westmost, p.x), eastmost = std::max(eastmost, p.x);
  }
  EXPECT_GT(lowestBall, 0.28);  // its radius above the ground, less the slop
  EXPECT_GT(westmost, 2);       // kept in the valley between the hill and the rise
  EXPECT_LT(eastmost, 10);
  EXPECT_GT(world.GetPosition(riser).y, 5);  // passed through from behind
  // Alone in the valley, the box settles there.
  World quiet;
  quiet.CreateChain(def);
  const BodyId box = AddBox(quiet, {6, 2}, Real(0.3), Real(0.3));
  StepN(quiet, 300);
  EXPECT_NEAR(quiet.GetPosition(box).x, 6, 0.02);
  EXPECT_NEAR(quiet.GetPosition(box).y, 0.875, 0.02);
  EXPECT_LT(Length(quiet.GetLinearVelocity(box)), 0.02);
}

TEST(ChainTest, MakeChainBodiesBuildsOpenChainsAndLoopsWithTheirGhosts) {
  ChainDef open;
  open.points = {{3, 0}, {2, 0}, {1, 0}, {0, 0}, {-1, 0}};
  open.friction = Real(0.3);
  const std::vector<BodyDef> bodies = MakeChainBodies(open);
  ASSERT_EQ(bodies.size(), 2u);  // the first and last segments are ghosts only
  EXPECT_EQ(bodies[0].type, BodyType::kStatic);
  EXPECT_EQ(bodies[0].shape.type, ShapeType::kChainSegment);
  EXPECT_EQ(bodies[0].shape.friction, Real(0.3));
  const ChainSegment& c0 = bodies[0].shape.chainSegment;
  EXPECT_TRUE(VecNear(c0.ghost1, {3, 0}, 0) && VecNear(c0.segment.point1, {2, 0}, 0) &&
              VecNear(c0.segment.point2, {1, 0}, 0) && VecNear(c0.ghost2, {0, 0}, 0));
  ChainDef loop;
  loop.isLoop = true;
  loop.points = {{0, 0}, {1, 0}, {0, 1}};
  const std::vector<BodyDef> ring = MakeChainBodies(loop);
  ASSERT_EQ(ring.size(), 3u);
  EXPECT_TRUE(VecNear(ring[0].shape.chainSegment.ghost1, {0, 1}, 0));
  EXPECT_TRUE(VecNear(ring[2].shape.chainSegment.segment.point2, {0, 0}, 0));
  EXPECT_TRUE(VecNear(ring[2].shape.chainSegment.ghost2, {1, 0}, 0));
  // A counter-clockwise loop faces outwards: a circle resting on top of a box-shaped loop.
  World world;
  ChainDef square;
  square.isLoop = true;
  square.points = {{-2, -1}, {2, -1}, {2, 1}, {-2, 1}};
  world.CreateChain(square);
  const BodyId ball = AddCircle(world, {Real(0.5), 2}, Real(0.25));
  StepN(world, 120);
  EXPECT_NEAR(world.GetPosition(ball).y, 1.25, 0.02);
}

TEST(SegmentTest, QueriesSeeTheLine) {
  World world(NoGravityDef());
  const BodyId seg = AddSegment(world, {-1, 0}, {1, 0});
  ChainDef def;  // a chain segment from (1, 3) to (-1, 3): its face is up
  def.points = {{2, 3}, {1, 3}, {-1, 3}, {-2, 3}};
  const BodyId chain = world.CreateChain(def).at(0);
  // A ray down hits the chain's face, then (from below the chain) the segment from above.
  auto hit = world.RayCastClosest({Real(0.5), 5}, {0, -10});
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(hit->body, chain);
  EXPECT_NEAR(hit->point.y, 3, 1e-6);
  EXPECT_TRUE(VecNear(hit->normal, {0, 1}, 1e-6));
  // Up from below: the two-sided segment from below (normal down), and the chain not at all.
  std::vector<RayHit> hits;
  world.RayCastAll({Real(0.5), -1}, {0, 10}, hits);
  ASSERT_EQ(hits.size(), 1u);
  EXPECT_EQ(hits[0].body, seg);
  EXPECT_TRUE(VecNear(hits[0].normal, {0, -1}, 1e-6));
  // Past the segment's end the ray misses; along its line too.
  EXPECT_FALSE(world.RayCastClosest({Real(1.2), -1}, {0, 2}).has_value());
  EXPECT_FALSE(world.RayCastClosest({-3, 0}, {6, 0}).has_value());
  // Boxes: crossing the segment counts, beside it not.
  std::vector<BodyId> found;
  world.QueryAABB({{Real(-0.1), Real(-0.1)}, {Real(0.1), Real(0.1)}}, found);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0], seg);
  world.QueryAABB({{Real(1.1), Real(-0.1)}, {Real(1.3), Real(0.1)}}, found);
  EXPECT_TRUE(found.empty());
  // A segment has no area: it contains no point, not even its own.
  world.QueryPoint({0, 0}, found);
  EXPECT_TRUE(found.empty());
  // A circle cast down stops its radius above the chain.
  const auto cast = world.CastCircle({0, 5}, Real(0.5), {0, -10});
  ASSERT_TRUE(cast.has_value());
  EXPECT_EQ(cast->body, chain);
  EXPECT_NEAR(cast->fraction * 10, 2 - 0.5, 1e-4);
  // A box cast up from below meets the two-sided segment.
  const Vec2 square[4] = {{Real(-0.2), -2}, {Real(0.2), -2}, {Real(0.2), Real(-1.6)}, {Real(-0.2), Real(-1.6)}};
  const auto boxCast = world.CastPolygon(square, {0, 4});
  ASSERT_TRUE(boxCast.has_value());
  EXPECT_EQ(boxCast->body, seg);
  EXPECT_NEAR(boxCast->fraction * 4, 1.6, 1e-4);
}

struct LineRecorder : DebugDraw {
  int circles = 0, polygons = 0, lines = 0;
  void DrawCircle(Vec2, Real, Real, Color) override { ++circles; }
  void DrawPolygon(std::span<const Vec2> v, Color) override {
    ++polygons;
    lines += v.size() == 2 ? 1 : 0;
  }
};

struct SegmentRecorder : LineRecorder {
  std::vector<Vec2> ends;
  void DrawSegment(Vec2 p1, Vec2 p2, Color) override { ends.push_back(p1), ends.push_back(p2); }
};

TEST(SegmentTest, DrawnAsALine) {
  World world;
  AddSegment(world, {-1, 0}, {1, 0}, BodyType::kStatic, {0, 2});
  ChainDef def;
  def.points = {{3, 0}, {2, 0}, {1, 0}, {0, 0}};
  world.CreateChain(def);
  SegmentRecorder rec;
  world.Draw(rec, kDrawShapes);
  ASSERT_EQ(rec.ends.size(), 4u);
  EXPECT_TRUE(VecNear(rec.ends[0], {-1, 2}, 1e-6));
  EXPECT_TRUE(VecNear(rec.ends[3], {1, 0}, 1e-6));
  EXPECT_EQ(rec.polygons, 0);
  // By default: a polygon of the two ends.
  LineRecorder plain;
  world.Draw(plain, kDrawShapes);
  EXPECT_EQ(plain.lines, 2);
}

TEST(SegmentTest, BadSegmentsAndChainsAreRefusedAndTheWorldIsUnchanged) {
  World world;
  AddGround(world);
  const uint64_t before = world.StateHash();
  const Real nan = std::nan(""), inf = INFINITY;
  auto create = [&](BodyType type, ShapeDef shape) {
    BodyDef def;
    def.type = type;
    def.shape = shape;
    world.CreateBody(def);
  };
  auto raw = [](Vec2 a, Vec2 b) {
    ShapeDef s;
    s.type = ShapeType::kSegment;
    s.segment = Segment{a, b};
    return s;
  };
  ExpectError([&] { create(BodyType::kDynamic, ShapeDef::MakeSegment({0, 0}, {1, 0})); },
              "a segment has no area (mass 0): only a static or kinematic body may carry it", "dynamic segment");
  ExpectError([&] { create(BodyType::kDynamic, ShapeDef::MakeChainSegment({-1, 0}, {0, 0}, {1, 0}, {2, 0})); },
              "a segment has no area", "dynamic chain segment");
  ExpectError([&] { create(BodyType::kStatic, raw({0, 0}, {Real(0.004), 0})); },
              "segment length must be at least 0.005 m, got 0.004000", "degenerate");
  ExpectError([&] { create(BodyType::kStatic, raw({nan, 0}, {1, 0})); }, "segment point is not finite", "nan");
  ExpectError([&] { create(BodyType::kKinematic, raw({0, 0}, {inf, 0})); }, "segment point is not finite", "inf");
  ExpectError([&] { create(BodyType::kStatic, raw({0, 0}, {Real(2e6), 0})); },
              "segment is beyond the coordinate limit of 1e6 m", "far");
  ExpectError([] { ShapeDef::MakeSegment({1, 1}, {1, 1}); }, "segment length must be at least 0.005 m", "MakeSegment");
  ExpectError([&] { ShapeDef::MakeChainSegment({nan, 0}, {0, 0}, {1, 0}, {2, 0}); },
              "chain segment ghost vertex is not finite", "ghost nan");
  ExpectError([] { ShapeDef::MakeChainSegment({-1, 0}, {0, 0}, {1, 0}, {Real(3e6), 0}); },
              "chain segment ghost vertex is beyond the coordinate limit of 1e6 m", "ghost far");
  ExpectError([] { ShapeDef::MakeChainSegment({0, 0}, {0, 0}, {1, 0}, {2, 0}); },
              "chain segment ghost vertex must be at least 0.005 m from its end, got 0.000000", "ghost on its end");
  // A body turned dynamic, or given a density, keeps its refusal.
  const BodyId seg = [&] {
    BodyDef def;
    def.type = BodyType::kKinematic;
    def.position = {0, 5};
    def.shape = ShapeDef::MakeSegment({0, 0}, {1, 0});
    return world.CreateBody(def);
  }();
  ExpectError([&] { world.SetType(seg, BodyType::kDynamic); }, "SetType: a segment has no area", "SetType");
  EXPECT_EQ(world.GetType(seg), BodyType::kKinematic);
  world.DestroyBody(seg);
  // Chains: too few points, a repeated point (named by its segment), nothing created.
  ChainDef three;
  three.points = {{2, 0}, {1, 0}, {0, 0}};
  ExpectError([&] { world.CreateChain(three); }, "ChainDef: an open chain needs at least 4 points, got 3", "3 open");
  ChainDef two;
  two.isLoop = true;
  two.points = {{1, 0}, {0, 0}};
  ExpectError([&] { world.CreateChain(two); }, "ChainDef: a loop needs at least 3 points, got 2", "2 loop");
  ChainDef repeated;
  repeated.points = {{3, 0}, {2, 0}, {1, 0}, {1, 0}, {0, 0}, {-1, 0}};
  ExpectError([&] { world.CreateChain(repeated); },
              "ChainDef: points 2 and 3 are 0.000000 m apart (at least 0.005 m)", "repeated");
  ChainDef far;
  far.points = {{3, 0}, {2, 0}, {1, 0}, {Real(2e6), 0}};
  ExpectError([&] { world.CreateChain(far); }, "ChainDef: segment 0 (points 1 to 2): chain segment ghost vertex is beyond",
              "far");
  EXPECT_EQ(world.GetBodyCount(), 1);
  EXPECT_EQ(world.StateHash(), before);
  // The quadrants scheme has no segment pairs.
  WorldDef quads;
  quads.scheme = ParallelScheme::kQuadrants;
  World q(quads);
  ExpectError([&] { AddSegment(q, {0, 0}, {1, 0}); }, "CreateBody: a segment needs ParallelScheme::kDeterministic",
              "quadrants");
  ExpectError([&] { q.CreateChain(def4()); }, "CreateBody: a segment needs ParallelScheme::kDeterministic",
              "quadrants chain");
  EXPECT_EQ(q.GetBodyCount(), 0);
}

TEST(ChainTest, APileOnAChainAndSegmentsHasTheSameHashOnOneAndTwoThreads) {
  uint64_t hashes[2] = {};
  for (int t = 1; t <= 2; ++t) {
    WorldDef def;
    def.threadCount = t;
    def.minParallelItems = 8;
    World world(def);
    // A bowl: a chain loop would face outwards, so an open chain, right to left, its face up.
    ChainDef bowl;
    for (int k = 0; k <= 24; ++k) {
      const double a = 3.14159265358979 * (1 - k / 24.0);  // pi .. 0: x from -6 to 6
      bowl.points.push_back({Real(-6 * std::cos(a)), Real(6 - 6 * std::sin(a))});
    }
    world.CreateChain(bowl);
    AddSegment(world, {-2, 3}, {2, Real(3.5)});  // a two-sided shelf in the middle
    for (int k = 0; k < 40; ++k) {
      const Vec2 p{Real(-3 + (k % 8) * 0.8), Real(5 + (k / 8) * 0.8)};
      if (k % 2) {
        AddBox(world, p, Real(0.25), Real(0.25), 1, Real(0.3 * k));
      } else {
        AddCircle(world, p, Real(0.25));
      }
    }
    StepN(world, 300);
    for (BodyId id : world.GetBodyIds()) {
      if (world.GetType(id) != BodyType::kDynamic) continue;
      const Vec2 p = world.GetPosition(id);
      ASSERT_TRUE(IsFinite(p));
      EXPECT_LT(Length(p - Vec2{0, 6}), 6.0);  // inside the bowl
    }
    hashes[t - 1] = world.StateHash();
  }
  EXPECT_EQ(hashes[0], hashes[1]);
}

}  // namespace
}  // namespace quadrant
