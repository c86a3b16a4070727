// Scenes, defined once and used by every adapter, test and benchmark.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "scene.h"

namespace quadrant::scene {

/// The thesis's stress scenes (its Figures 14 and 15) as anchors.md fixes them: N bodies with
/// random speeds in random directions in a closed square box sized for a given area fraction,
/// no gravity, restitution 1, friction 0, no sleeping, dt = 1/60.
struct StressParams {
  int count = 1000;                 ///< N > 0
  ShapeKind shape = ShapeKind::kCircle;
  Real radius = Real(0.5);          ///< circles (m)
  Real minCircumradius = Real(0.35);///< polygons (m)
  Real maxCircumradius = Real(0.5);
  Real areaFraction = Real(0.25);   ///< body area / box area, in (0, 0.9)
  Real minSpeed = 1;                ///< m/s
  Real maxSpeed = 5;
  bool clumped = false;             ///< all bodies in the lower-left quadrant of a box twice as wide
                                    ///< (same density there; the load-imbalance case)
  uint64_t seed = 42;
};

/// Throws quadrant::Error on malformed parameters (N <= 0, non-positive sizes, area fraction
/// outside (0, 0.9), min > max, non-finite values).
Scene MakeStressScene(const StressParams& params);

// ---- Dense, solver-bound scenes (dense.cpp; `pyramid` is the third) ------------------------

/// The world settings of Box2D 3's benchmark scenes in the scene API: gravity, friction, 8/3
/// iterations, no restitution, warm starting, no sleep, no continuous collision, 60 Hz.
Scene Box2d3BenchmarkBase(const char* name);

/// Box2D 3's "many pyramids": `count` 1 m boxes (rounded down to a multiple of 55, at least 55) as
/// base-10 pyramids of touching boxes, in a near-square grid of rows, each row on its own thin
/// static shelf 11 m above the one below; friction 0.6, gravity, 8/3 iterations, no sleep.
/// Bodies: the shelves bottom to top, then the pyramids row by row. Box2D 3 runs 22000.
Scene MakeManyPyramids(int count);
/// Box2D 3's "tumbler": four kinematic 1 m thick walls of a 20 m square centred at (0, 10),
/// turned at 25 degrees per second by the scene's driver (bodies 0..3), and `count` 0.25 m boxes
/// (1 <= count <= 2116) on a 0.4 m grid inside; friction 0.6, gravity, 8/3 iterations, no sleep.
/// Box2D 3 runs 2025 (45 x 45). Engines without kinematic bodies driven by velocity (Bullet)
/// report it unsupported.
Scene MakeTumbler(int count);

// ---- Box2D 3's benchmark scenes beyond the dense ones (box2d3.cpp) ---------------------------

/// Box2D 3's "joint_grid" (500 steps there): an N x N grid of circles of radius 0.4 1 m apart, N the
/// smallest with N x N - 7 >= count (57 <= count <= 1000000; the dynamic bodies), each joined by a revolute joint to the one above and to its left (2 N (N - 1)
/// joints), the top row's middle seven static, filtered never to collide; gravity, no sleep.
/// Box2D 3 runs N = 100 (count 9993, 19800 joints). Engines whose adapter loads no joints report it unsupported.
Scene MakeJointGrid(int count);
/// Box2D 3's "junkyard" (800 steps there): a 4 x 8 m kinematic pusher (body 0) driven to x = 60
/// sin(0.2 t) by velocity, 261 static 1 m ground and wall boxes, and `count` pentagons of
/// circumradius 0.25 in 200 columns (count / 200 rows, 200 <= count <= 200000) dropped from 15 m;
/// sleep on. Box2D 3 runs 8000. Bullet reports it unsupported (kinematic bodies by velocity).
Scene MakeJunkyard(int count);
/// Box2D 3's "smash" (300 steps there): zero gravity, an 8 m box of density 8 at 40 m/s (body 0)
/// into a wall of touching 0.4 m boxes created asleep, 80 rows of count / 80 columns
/// (80 <= count <= 1000000); sleep on. Box2D 3 runs 9600.
Scene MakeSmash(int count);
/// Box2D 3's "compounds": `count` dynamic bodies of two triangles each (20 columns; Box2D 3's
/// 3000), walls of static boxes and a segment far below. Box2D 3 runs it 500 steps.
Scene MakeCompounds(int count);
/// Box2D 3's "washer": a kinematic drum of 40 polygons on one body (body 0) turning at 25 deg/s
/// around the largest square grid of small boxes within `count` (Box2D 3's 90 x 90 = 8100). Box2D 3 runs it 500 steps with
/// hit events on the boxes; the scene API has no hit-event setting, so none are asked for here.
Scene MakeWasher(int count);

/// Box2D 3's "spinner" (500 steps there): a loop of 360 one-sided chain segments on a circle of
/// radius 40 m about (0, 32) facing in (bodies 0..359, static), a 40 m paddle turned about (0, 12)
/// at 5 rad/s by a revolute motor of unbounded torque (body 360; its joint's bodyA is body 0), and
/// `count` bodies (1 <= count <= 10000) in turn a capsule, a circle and a square, density 0.25,
/// friction 0.1, restitution 0.1, in rows of 92 from (-23, 2); sleep on. Box2D 3 runs 6076.
Scene MakeSpinner(int count);
/// Box2D 3's "rain" (1000 steps there): storeys of 501 static 0.5 m boxes 45 m apart (bodies, all
/// static), and a driver that every 8 steps from step 0 adds a column of ragdoll groups (five
/// ragdolls of 11 capsules and 10 revolute joints with limits, springs and joint friction, one group
/// per storey, Adapter::AddGroup) 40 m above each floor until there are 40 columns, then removes the
/// oldest column's groups and adds them again. `count` is the ragdoll bodies at most (groupBodies:
/// 2200 a storey, rounded down, 2200 <= count <= 44000); sleep and damping on. Box2D 3 runs 5
/// storeys (11000 bodies, 2505 boxes).
Scene MakeRain(int count);

/// Scene names known to the suite: the stress scenes, the dense scenes and the hard cases.
std::vector<std::string> SceneNames();

/// Whether `name` is a dense, solver-bound scene (pyramid, many_pyramids, tumbler, joint_grid, junkyard, smash,
/// spinner, rain) rather than a
/// sparse one (the stress scenes: about 4 % of the bodies touch at any moment).
bool IsDenseScene(std::string_view name);

/// The scenes `tools/quadrant bench` runs by default, sparse then dense.
std::vector<std::string> DefaultBenchScenes();

/// The body counts `tools/quadrant bench` runs `name` at when --counts is not given: 1000..16000
/// for the stress scenes, sizes of their own for the dense ones (chosen so the dense scenes add a
/// few minutes to the default run). Throws quadrant::Error for a scene the suite does not bench.
std::vector<int> DefaultBenchCounts(std::string_view name);

/// Box2D 3's benchmark protocol (its benchmark/main.c) for the eight of its ten scenes the suite
/// has (compounds and washer need several shapes per body): the scene names (its large_pyramid is
/// `pyramid` at 5050 boxes), the count that builds each at Box2D 3's size, and its step count
/// (Box2D 3 runs the first step untimed and times the others; 4 sub-steps or 8 velocity
/// iterations; continuous collision on). Box2d3Count and Box2d3Steps throw quadrant::Error for
/// other scenes.
std::vector<std::string> Box2d3Scenes();
int Box2d3Count(std::string_view name);
int Box2d3Steps(std::string_view name);

/// Builds a named scene with `count` bodies (ignored by fixed-size scenes) and a seed.
/// Throws quadrant::Error for unknown names or bad counts.
Scene MakeScene(std::string_view name, int count, uint64_t seed = 42);

// ---- The hard cases of anchors.md (hard_cases.cpp) ------------------------------------------
//
// Every hard case is at dt = 1/60 with 8 velocity and 3 position iterations, gravity (0, -10)
// unless it says otherwise, no sleep, no continuous collision, settings written out in the
// builder. Ground tops are at y = 0 (plus the offset where there is one). Body order is part of
// each builder's contract (the checks in hard_case_checks.cpp rely on it).

/// How an engine mixes two bodies' friction and restitution. No one material pair gives the same
/// mixed value under both rules (only 0 and 1 do), so builders take the rule of the engine that
/// will run them and choose per-body values that mix to the coefficient the case is about.
enum class Mixing : uint8_t {
  kBox2d,    ///< friction sqrt(f1 f2), restitution max(e1, e2): Box2D 2.4 and Quadrant
  kProduct,  ///< friction f1 f2, restitution e1 e2: Bullet and Chipmunk
};
/// quadrant, quadrant:<variant>, box2d -> kBox2d; bullet, chipmunk -> kProduct. Throws
/// quadrant::Error for other names.
Mixing MixingOf(std::string_view engine);
Real MixFriction(Mixing mixing, Real a, Real b);
Real MixRestitution(Mixing mixing, Real a, Real b);

/// Ground, then `count` 1 m boxes bottom to top (friction 0.3, x = +0.01, -0.01, ...).
Scene MakeVerticalStack(int count = 15, Mixing mixing = Mixing::kBox2d);
/// Ground, then base (base+1)/2 1 m boxes row by row from the bottom (friction 0.6, centres 1.1 m
/// apart in a row, rows 1 m apart), everything shifted by `offset`. The last body is the apex.
Scene MakePyramid(int base = 20, Vec2 offset = {}, Mixing mixing = Mixing::kBox2d);
/// Ground, then `pyramids` pyramids of base `base` as MakePyramid builds them, side by side 2 m
/// apart, left to right: a wide pile of small stacks that comes to rest (the effects tool's sleep
/// scene; a single pyramid of 2000 boxes does not settle at 8 iterations).
Scene MakePyramidField(int pyramids, int base, Mixing mixing = Mixing::kBox2d);
/// ratio 100: ground, a base-10 pyramid of 1 m boxes (density 1), then a 1 m box of density 100
/// on its apex. ratio 400: ground, two 1 m boxes (1 kg) at x = -9 and 9, then a 20 m x 1 m plank
/// of 400 kg (density 20) on them. Friction 0.6. Throws quadrant::Error for other ratios.
Scene MakeMassRatio(int ratio, Mixing mixing = Mixing::kBox2d);
/// Issue #13's stability cases, at the default budget (8 velocity + 3 position iterations):
/// ground (100 m wide), then `count` 1 m boxes bottom to top, exactly touching and exactly aligned
/// (centres at x = 0, y = 0.5 + i; friction 0.6). The last body is the top box. Named
/// "tall_stack" for 30 boxes, "tall_stack_<count>" otherwise.
Scene MakeTallStack(int count = 30, Mixing mixing = Mixing::kBox2d);
/// Ground, then three 1 m boxes of 1 kg at x = -9, 0, 9, then a 20 m x 2 m box of 1000 kg
/// (density 25) resting on them: 1000:1 on several supports. Friction 0.6.
Scene MakeHeavyOnSupports(Mixing mixing = Mixing::kBox2d);
/// Ground, then a 4 m x 0.2 m slab of 1 kg (density 1.25) on it, then a 2 m box of 1000 kg
/// (density 250) on the slab: 1000:1 on a single light body. Friction 0.6.
Scene MakeHeavyOnSlab(Mixing mixing = Mixing::kBox2d);
/// Ground, then 17 voussoirs of a semicircular arch (inner radius 4 m, outer 5 m, centre on the
/// ground at the origin, radial joints every pi/17), left to right; friction 0.6.
Scene MakeArch(Mixing mixing = Mixing::kBox2d);
/// Ground, then a card house of `levels` storeys (levels = 5: 30 leaning + 10 flat = 40 cards of
/// 1 m x 0.02 m, friction 0.7), storey by storey from the bottom; the last two are the top pair.
Scene MakeCardHouse(int levels = 5, Mixing mixing = Mixing::kBox2d);
/// Five static ramps at 0.25 rad (friction 1) side by side, each with a 1 m box at rest on it that
/// mixes with the ramp to friction 0.75, 0.5, 0.35, 0.1, 0. Bodies: ramp k = 2k, box k = 2k + 1.
Scene MakeFrictionRamp(Mixing mixing = Mixing::kBox2d);
/// Ground, then five balls (r = 0.5 m, bottom 2 m above the ground) that mix with the ground to
/// restitution 0, 0.25, 0.5, 0.75, 1; friction off, restitution threshold 0.
Scene MakeRestitutionDrop(Mixing mixing = Mixing::kBox2d);
/// Ground, then a pyramid of 1 m boxes whose centres are 0.75 m apart in both directions (each box
/// overlaps its neighbours by 25 %), bottom row resting on the ground; friction 0.6.
Scene MakeOverlapRecovery(int base = 10, Mixing mixing = Mixing::kBox2d);
/// Four walls of a closed 25 m x 25 m box, then side x side circles (r = 0.5 m) on a grid of
/// 0.8 m pitch (each overlaps its neighbours by 0.2 m) with a seeded jitter of +-0.02 m; zero
/// gravity, at rest, friction 0.6, restitution 0.
Scene MakeConfined(int side = 25, uint64_t seed = 42, Mixing mixing = Mixing::kBox2d);
/// Issue #26's closed box: `count` circles (r = 0.5 m, friction 0.6, restitution 0) in a closed
/// square box of static walls sized for area fraction 0.85, gravity (0, -10), spawned touching on
/// a hexagonal lattice from the floor up with random velocities up to 2 m/s (seeded). Walls first
/// (4 bodies), then the circles.
Scene MakeClosedBox(int count = 2000, uint64_t seed = 42, Mixing mixing = Mixing::kBox2d);
/// Issue #27's heavy chain: 30 links of 0.5 m x 0.2 m (0.1 kg) hanging from a static pin by
/// revolute joints, a ball of 1000 links' mass (100 kg) pinned at the bottom. Bodies: the pin, the
/// links top down, the ball.
Scene MakeHeavyChain(Mixing mixing = Mixing::kBox2d);
/// Issue #27's ragdoll pile: `count` ragdolls (9 bodies: capsule limbs and torso, a circle head; 8
/// revolute joints with limits and 0.2 N m of joint friction) dropped in columns of four into a box
/// 8 m wide. Bodies: ground, two walls, then each ragdoll's torso, head, and per side arm, thigh, shin.
Scene MakeRagdollPile(int count = 12, Mixing mixing = Mixing::kBox2d);
/// Issue #27's prismatic stop: a 1 kg box on a horizontal prismatic joint (travel [-2, 2] m) through
/// a static post, launched at 10 m/s into its stop, under gravity. Bodies: the post, the box.
Scene MakePrismaticStop(Mixing mixing = Mixing::kBox2d);
/// Issue #27's weld beam: ten 1 m x 0.2 m segments welded end to end, cantilevered from a static
/// block under gravity. Bodies: the block, the segments from the root out.
Scene MakeWeldBeam(Mixing mixing = Mixing::kBox2d);
/// Issue #27's wheel on a chain terrain: a 2 m chassis on two motorised wheels (revolute motors at
/// -6 rad/s, 20 N m) on a bumpy one-sided chain road y = TerrainHeight(x), x from -10 to 230 m.
/// Bodies: the chain's segments, the chassis, the rear and the front wheel.
Scene MakeWheelTerrain(Mixing mixing = Mixing::kBox2d);
double TerrainHeight(double x);
/// Issue #27's joint grid that sags and settles: Box2D 3's joint_grid at 30 x 30 hung from the top
/// row's seven middle bodies, with linear and angular damping 0.1 /s. Bodies and joints as
/// MakeJointGrid(893).
Scene MakeHangingGrid(Mixing mixing = Mixing::kBox2d);
/// MakePyramid(20) at (1e5, -8e4).
Scene MakeFarFromOrigin(Mixing mixing = Mixing::kBox2d);
/// Five touching balls (r = 0.5 m) in a row at x = 0, 1, 2, 3, 4, zero gravity, friction 0,
/// restitution 1, threshold 0; body 0 moves at +1 m/s into the others, which are at rest.
Scene MakeNewtonsCradle(Mixing mixing = Mixing::kBox2d);

// Solver2D's contact scenes (erincatto/solver2d, samples/collection; issue #26 item 2), with
// Solver2D's sizes. Grounds are 1 m thick static boxes, top face at y = 0, except where noted.
inline constexpr int kWarmStartLiftStep = 120;  ///< the step from which the heavy ball is lifted away
inline constexpr int kRushCount = 400;
inline constexpr int kDominoCount = 15;
inline constexpr int kCircleStackCount = 10;
/// Ground (friction 0.5), then a 2 m box (4 kg) whose bottom is 3 m above it.
Scene MakeSingleBox(Mixing mixing = Mixing::kBox2d);
/// Ground, then three touching balls (r = 0.5 m) in a column bottom to top, densities 1, 1 and
/// 100; a driver lifts the heavy one (body 3) away at 20 m/s from step kWarmStartLiftStep on
/// (Solver2D destroys it there).
Scene MakeWarmStartEnergy(Mixing mixing = Mixing::kBox2d);
/// Solver2D's high mass ratio 1 to 3. 1: ground (friction 0.5), then three base-10 pyramids of
/// touching 2 m boxes (4 kg), left to right, each row by row from the bottom, each apex a box of
/// density 100 (j + 1) dropped from 2 m above its place (the apex is the last body of each
/// pyramid). 2 and 3: ground (2: a 40 m segment, 3: an 80 m x 4 m box), two 1 m boxes (1 kg) at
/// x = -9 and 9, then a 20 m box (400 kg) whose bottom is 15 m above them. Friction 0.6.
/// Throws quadrant::Error for other variants.
Scene MakeHighMassRatio(int variant, Mixing mixing = Mixing::kBox2d);
/// Zero gravity: a static ball (r = 0.5 m) at the origin, then kRushCount balls (r = 0.5 m,
/// 78.5 kg, friction 0.2) on a spiral from 5 m out; a driver pulls each toward the origin with
/// 1000 N every step.
Scene MakeRush(Mixing mixing = Mixing::kBox2d);
/// Ground, then kDominoCount dominoes of 0.25 m x 1 m standing 1 m apart from x = -7.5, left to
/// right; the first starts with the velocity of a 0.2 N s push to the right at its top.
Scene MakeDoubleDomino(Mixing mixing = Mixing::kBox2d);
/// Ground, then kCircleStackCount balls of radius 1 m at x = 0, y = 4, 7, ..., bottom to top.
Scene MakeCircleStack(Mixing mixing = Mixing::kBox2d);
/// Solver2D's far stack about `origin` (Solver2D: (4e4, -2.5e4)): a 20 m x 2 m ground box, a
/// ball (r = 0.1 m), a 0.2 m x 0.25 m box, a 4 m x 0.1 m plank on them, a 0.5 m and a 1 m square
/// dropped onto it, in that order.
Scene MakeFarStack(Vec2 origin, Mixing mixing = Mixing::kBox2d);
/// Solver2D's far recovery about `origin` (Solver2D: (8e4, -7e4)): ground (top at origin.y), then
/// a base-4 pyramid of 1 m boxes at 0.75 m pitch (25 % overlap), row by row from the bottom.
Scene MakeFarRecovery(Vec2 origin, Mixing mixing = Mixing::kBox2d);
/// Where Solver2D puts its far stack and far recovery.
inline constexpr Vec2 kFarStackOrigin{40000, -25000};
inline constexpr Vec2 kFarRecoveryOrigin{80000, -70000};

/// A small deterministic random source (splitmix64), so a seed gives the same scene with any
/// standard library.
class Random {
 public:
  explicit Random(uint64_t seed) : state_(seed) {}
  uint64_t Next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  /// Uniform in [lo, hi).
  double Uniform(double lo, double hi) { return lo + (hi - lo) * double(Next() >> 11) * 0x1.0p-53; }
  int UniformInt(int lo, int hiInclusive) { return lo + int(Next() % uint64_t(hiInclusive - lo + 1)); }

 private:
  uint64_t state_;
};

/// A random convex polygon of 3..8 vertices on a circle of `circumradius`, counter-clockwise,
/// centred on its centroid (the stress scenes' polygons; also the random validation hits').
std::vector<Vec2> RandomConvexPolygon(Random& rng, Real circumradius);

}  // namespace quadrant::scene
