// The hard cases that 2D solvers are judged on (anchors.md), built once for every engine.
//
// Each builder writes out every world setting instead of relying on the Scene defaults, so a
// change of a default elsewhere cannot silently change a hard case. Materials go through Coef():
// where every contact of a scene is between two bodies of one material, an engine that multiplies
// coefficients gets the square root of the coefficient on each body, so every engine simulates
// the same mixed value.
#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "adapter.h"
#include "quadrant/error.h"
#include "scenes.h"

namespace quadrant::scene {
namespace {

// The value each body of a one-material scene gets so that two of them mix to `mixed`.
Real Coef(Mixing mixing, Real mixed) {
  return mixing == Mixing::kBox2d ? mixed : Real(std::sqrt(double(mixed)));
}

Scene BaseScene(const char* name) {
  Scene s;
  s.name = name;
  s.gravity = {0, Real(-10)};
  s.timeStep = Real(1.0 / 60.0);
  s.pipelineRepeats = 1;
  s.velocityIterations = 8;
  s.positionIterations = 3;
  s.restitutionThreshold = 1;  // Box2D 2.4's default; cases about bouncing set their own
  s.effects.gravity = true;
  s.effects.friction = true;
  s.effects.restitution = false;  // stacking cases have restitution 0 everywhere: nothing to do
  s.effects.rotation = true;
  s.effects.warmStarting = true;
  s.effects.sleep = false;        // a sleeping pile cannot drift: the cases must see every step
  s.effects.continuous = false;
  s.effects.damping = false;
  s.seed = 0;
  return s;
}

BodyDesc Box(Vec2 position, Real hx, Real hy, bool dynamic, Real friction, Real density = 1,
             Real angle = 0) {
  BodyDesc b = MakeBoxBody(position, hx, hy, dynamic);
  b.angle = angle;
  b.density = density;
  b.friction = friction;
  b.restitution = 0;
  return b;
}

BodyDesc Ball(Vec2 position, Real radius, Real friction, Real restitution) {
  BodyDesc b = MakeCircleBody(position, radius);
  b.density = 1;
  b.friction = friction;
  b.restitution = restitution;
  return b;
}

// A static slab 1 m thick whose top face is at offset.y, centred on offset.x.
BodyDesc Ground(Vec2 offset, Real halfWidth, Real friction) {
  return Box({offset.x, offset.y - Real(0.5)}, halfWidth, Real(0.5), /*dynamic=*/false, friction, 0);
}

AABB Bounds(Vec2 lower, Vec2 upper) { return {lower, upper}; }

void RequireRange(int value, int lo, int hi, const char* what) {
  if (value < lo || value > hi) {
    throw Error(std::string(what) + " must be in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                "], got " + std::to_string(value));
  }
}

// Pyramid rows: row r (from 0 at the bottom) holds base - r boxes, centred, so each row sits
// half a pitch in from the one below and every upper box rests on two lower ones.
void AddPyramidBoxes(Scene& s, int base, Vec2 offset, Real pitchX, Real pitchY, Real friction,
                     Real density = 1) {
  for (int r = 0; r < base; ++r) {
    const int n = base - r;
    for (int j = 0; j < n; ++j) {
      const double x = offset.x + (j - 0.5 * (n - 1)) * pitchX;
      const double y = offset.y + 0.5 + r * double(pitchY);
      s.bodies.push_back(Box({Real(x), Real(y)}, Real(0.5), Real(0.5), true, friction, density));
    }
  }
}

}  // namespace

Mixing MixingOf(std::string_view engine) {
  if (engine == "quadrant" || engine.starts_with("quadrant:") || engine == "box2d") return Mixing::kBox2d;
  if (engine == "bullet" || engine == "chipmunk") return Mixing::kProduct;
  throw Error("MixingOf: unknown engine '" + std::string(engine) + "'");
}

Real MixFriction(Mixing mixing, Real a, Real b) {
  return mixing == Mixing::kBox2d ? Real(std::sqrt(double(a) * double(b))) : a * b;
}

Real MixRestitution(Mixing mixing, Real a, Real b) {
  return mixing == Mixing::kBox2d ? (a > b ? a : b) : a * b;
}

Scene MakeVerticalStack(int count, Mixing mixing) {
  RequireRange(count, 1, 1000, "vertical stack box count");
  Scene s = BaseScene("vertical_stack");
  // The solver budget this case needs (given to every engine alike): at Box2D's default of 8
  // velocity iterations Quadrant's 15-box stack creeps 0.017 m between 1 s and 10 s (limit
  // 0.01 m) and Box2D 2.4's collapses; 16 hold it (results/<machine>/accuracy.md shows the
  // cost of each setting).
  s.velocityIterations = 16;
  const Real f = Coef(mixing, Real(0.3));
  s.bodies.push_back(Ground({0, 0}, 20, f));
  for (int i = 0; i < count; ++i) {
    // Alternating offsets: a perfectly aligned stack would hide a solver's lateral drift.
    const Real x = i % 2 == 0 ? Real(0.01) : Real(-0.01);
    s.bodies.push_back(Box({x, Real(0.5) + Real(i)}, Real(0.5), Real(0.5), true, f));
  }
  s.bounds = Bounds({-20, -1}, {20, Real(count) + 1});
  return s;
}

Scene MakePyramid(int base, Vec2 offset, Mixing mixing) {
  RequireRange(base, 1, 1000, "pyramid base");
  if (!IsFinite(offset)) throw Error("pyramid offset is not finite");
  Scene s = BaseScene("pyramid");
  const Real f = Coef(mixing, Real(0.6));
  // Pitch 1.1 m: a 0.1 m gap between neighbours in a row, so only vertical contacts carry load.
  const Real pitch = Real(1.1);
  const Real halfWidth = std::max(Real(20), Real(0.5) * pitch * Real(base) + 5);
  s.bodies.push_back(Ground(offset, halfWidth, f));
  AddPyramidBoxes(s, base, offset, pitch, 1, f);
  s.bounds = Bounds({offset.x - halfWidth, offset.y - 1}, {offset.x + halfWidth, offset.y + Real(base) + 1});
  return s;
}

Scene MakePyramidField(int pyramids, int base, Mixing mixing) {
  RequireRange(pyramids, 1, 10000, "pyramid field count");
  RequireRange(base, 1, 100, "pyramid field base");
  Scene s = BaseScene("pyramid_field");
  const Real f = Coef(mixing, Real(0.6));
  const Real pitch = Real(1.1);
  // Neighbouring pyramids 2 m apart at their bases, so they never touch.
  const Real spacing = pitch * Real(base) + 2;
  const Real halfWidth = Real(0.5) * spacing * Real(pyramids) + 5;
  s.bodies.push_back(Ground({0, 0}, halfWidth, f));
  for (int k = 0; k < pyramids; ++k) {
    const Real x = (Real(k) - Real(0.5) * Real(pyramids - 1)) * spacing;
    AddPyramidBoxes(s, base, {x, 0}, pitch, 1, f);
  }
  s.bounds = Bounds({-halfWidth, -1}, {halfWidth, Real(base) + 1});
  return s;
}

Scene MakeMassRatio(int ratio, Mixing mixing) {
  const Real f = Coef(mixing, Real(0.6));
  if (ratio == 100) {
    Scene s = BaseScene("mass_ratio_100");
    // Solver budget, as for the vertical stack: 8 iterations let the heavy box sink 0.04 m
    // into the apex; 16 hold it within 0.012 m (limit 0.02 m).
    s.velocityIterations = 16;
    s.bodies.push_back(Ground({0, 0}, 20, f));
    AddPyramidBoxes(s, 10, {0, 0}, Real(1.1), 1, f);
    // On the apex (row 9, centre y = 9.5): a 1 m box of density 100, i.e. 100 kg on 1 kg boxes.
    s.bodies.push_back(Box({0, Real(10.5)}, Real(0.5), Real(0.5), true, f, 100));
    s.bounds = Bounds({-20, -1}, {20, 12});
    return s;
  }
  if (ratio == 400) {
    Scene s = BaseScene("mass_ratio_400");
    // Solver budget: 400:1 needs 32 velocity iterations (16 leave 0.025 m of penetration).
    s.velocityIterations = 32;
    s.bodies.push_back(Ground({0, 0}, 20, f));
    s.bodies.push_back(Box({-9, Real(0.5)}, Real(0.5), Real(0.5), true, f));
    s.bodies.push_back(Box({9, Real(0.5)}, Real(0.5), Real(0.5), true, f));
    // 20 m x 1 m at density 20: 400 kg resting on two 1 kg boxes.
    s.bodies.push_back(Box({0, Real(1.5)}, 10, Real(0.5), true, f, 20));
    s.bounds = Bounds({-20, -1}, {20, 3});
    return s;
  }
  throw Error("mass ratio must be 100 or 400, got " + std::to_string(ratio));
}

Scene MakeTallStack(int count, Mixing mixing) {
  RequireRange(count, 1, 1000, "tall stack box count");
  Scene s = BaseScene("tall_stack");
  if (count != 30) s.name = "tall_stack_" + std::to_string(count);  // the hard case tall_stack_50
  // The default budget (8 velocity + 3 position iterations; soft_step 4 sub-steps): issue #13
  // asks for Box2D 3's level at its defaults, where a 30-box stack stands.
  const Real f = Coef(mixing, Real(0.6));
  s.bodies.push_back(Ground({0, 0}, 50, f));
  // Exactly touching, exactly aligned: no offset helps or hides anything.
  for (int i = 0; i < count; ++i) s.bodies.push_back(Box({0, Real(0.5) + Real(i)}, Real(0.5), Real(0.5), true, f));
  s.bounds = Bounds({-50, -1}, {50, Real(count) + 1});
  return s;
}

Scene MakeHeavyOnSupports(Mixing mixing) {
  Scene s = BaseScene("heavy_on_supports");
  const Real f = Coef(mixing, Real(0.6));
  s.bodies.push_back(Ground({0, 0}, 20, f));
  // Three 1 m boxes of 1 kg at x = -9, 0, 9 under a 20 m x 2 m box of density 25: 1000 kg, 1000:1
  // (Box2D 3's "big box on small boxes" sample has 400:1 on two).
  for (int k = 0; k < 3; ++k) s.bodies.push_back(Box({Real(-9 + 9 * k), Real(0.5)}, Real(0.5), Real(0.5), true, f));
  s.bodies.push_back(Box({0, 2}, 10, 1, true, f, 25));
  s.bounds = Bounds({-20, -1}, {20, 4});
  return s;
}

Scene MakeHeavyOnSlab(Mixing mixing) {
  Scene s = BaseScene("heavy_on_slab");
  const Real f = Coef(mixing, Real(0.6));
  s.bodies.push_back(Ground({0, 0}, 20, f));
  // A 4 m x 0.2 m slab of density 1.25 (1 kg) on the ground, and on it a 2 m box of density 250
  // (1000 kg): one light body carries the whole heavy one, 1000:1.
  s.bodies.push_back(Box({0, Real(0.1)}, 2, Real(0.1), true, f, Real(1.25)));
  s.bodies.push_back(Box({0, Real(1.2)}, 1, 1, true, f, 250));
  s.bounds = Bounds({-20, -1}, {20, 3});
  return s;
}

Scene MakeArch(Mixing mixing) {
  Scene s = BaseScene("arch");
  const Real f = Coef(mixing, Real(0.6));
  s.bodies.push_back(Ground({0, 0}, 20, f));
  // A semicircular arch of radial joints. Thickness 1 m on a 4.5 m centre-line radius (t/R =
  // 0.22) is twice the least thickness a semicircular arch of rigid blocks needs to stand
  // (Heyman: t/R = 0.107), so a correct solver keeps it up; the joints near the springing, where
  // the thrust is most inclined, need a friction coefficient of about 0.3 (0.6 is given).
  constexpr int kBlocks = 17;
  const double inner = 4, outer = 5;
  for (int k = 0; k < kBlocks; ++k) {
    const double t0 = std::numbers::pi * k / kBlocks, t1 = std::numbers::pi * (k + 1) / kBlocks;
    // Counter-clockwise: inner and outer points of the joint at t0, then outer and inner at t1.
    const double px[4] = {inner * std::cos(t0), outer * std::cos(t0), outer * std::cos(t1), inner * std::cos(t1)};
    const double py[4] = {inner * std::sin(t0), outer * std::sin(t0), outer * std::sin(t1), inner * std::sin(t1)};
    // The body origin is the block's centroid, so every engine rotates it about the same point.
    double area = 0, cx = 0, cy = 0;
    for (int i = 0; i < 4; ++i) {
      const int j = (i + 1) % 4;
      const double cross = px[i] * py[j] - px[j] * py[i];
      area += 0.5 * cross;
      cx += (px[i] + px[j]) * cross / 6;
      cy += (py[i] + py[j]) * cross / 6;
    }
    cx /= area;
    cy /= area;
    BodyDesc b = Box({Real(cx), Real(cy)}, Real(0.5), Real(0.5), true, f);
    for (int i = 0; i < 4; ++i) b.vertices[i] = {Real(px[i] - cx), Real(py[i] - cy)};
    s.bodies.push_back(b);
  }
  s.bounds = Bounds({-20, -1}, {20, 6});
  return s;
}

Scene MakeCardHouse(int levels, Mixing mixing) {
  RequireRange(levels, 1, 20, "card house levels");
  Scene s = BaseScene("card_house");
  const Real f = Coef(mixing, Real(0.7));
  // Cards 1 m x 0.02 m leaning 0.35 rad (20 deg) from the vertical in pairs whose top corners
  // meet. A pair stands if the floor's friction carries tan(lean)/2 = 0.18 of the weight, well
  // under 0.7. Pair apexes are 1.004 m apart: a flat card (1 m) bridging two apexes rests on the
  // outer top corner of each (0.0188 m beyond the apex) and leaves a 4 mm gap to its neighbour.
  const double length = 1, thickness = 0.02, lean = 0.35, gap = 0.004;
  const double a = 0.5 * length, b = 0.5 * thickness;
  const double sinL = std::sin(lean), cosL = std::cos(lean);
  const double pitch = length + gap;
  const double peak = length * cosL + thickness * sinL;  // floor to the top corners of a pair
  s.bodies.push_back(Ground({0, 0}, 20, f));
  double floor = 0;
  for (int level = 0; level < levels; ++level) {
    const int pairs = levels - level;
    const double x0 = -0.5 * (pairs - 1) * pitch;
    // Centre of a leaning card whose lowest corner is on the floor and whose inner top corner is
    // at the apex x: offsets from the apex of b cos + a sin across and b sin + a cos up.
    const double dx = b * cosL + a * sinL, cy = floor + b * sinL + a * cosL;
    for (int i = 0; i < pairs; ++i) {
      const double apex = x0 + i * pitch;
      s.bodies.push_back(Box({Real(apex - dx), Real(cy)}, Real(b), Real(a), true, f, 1, Real(-lean)));
      s.bodies.push_back(Box({Real(apex + dx), Real(cy)}, Real(b), Real(a), true, f, 1, Real(lean)));
    }
    if (level + 1 == levels) break;
    // Flat cards bridging neighbouring apexes; the next storey's pairs stand on them.
    for (int i = 0; i + 1 < pairs; ++i) {
      const double cx = x0 + (i + 0.5) * pitch;
      s.bodies.push_back(Box({Real(cx), Real(floor + peak + b)}, Real(a), Real(b), true, f));
    }
    floor += peak + thickness;
  }
  s.bounds = Bounds({-20, -1}, {20, Real(floor + peak + 1)});
  return s;
}

Scene MakeFrictionRamp(Mixing mixing) {
  Scene s = BaseScene("friction_ramp");
  const double angle = 0.25;  // tan(0.25) = 0.2553: friction at or above it holds a box
  const Real targets[5] = {Real(0.75), Real(0.5), Real(0.35), Real(0.1), Real(0)};
  const double c = std::cos(angle), sn = std::sin(angle);
  // Ramps of friction 1: under sqrt mixing a box of friction mu^2 then mixes to mu, under product
  // mixing a box of friction mu does.
  const Real rampFriction = 1;
  for (int k = 0; k < 5; ++k) {
    // Ramp k: 10 m x 0.5 m centred at (12 k, 0), its top face 0.25 m above the centre line.
    const double rx = 12.0 * k, ry = 0;
    BodyDesc ramp = Box({Real(rx), Real(ry)}, 5, Real(0.25), false, rampFriction, 0, Real(angle));
    s.bodies.push_back(ramp);
    const Real mu = targets[k];
    const Real boxFriction = mixing == Mixing::kBox2d ? mu * mu : mu;
    // 3 m up the slope from the ramp's centre, touching its top face: room to slide 8 m down.
    const double along = 3, up = 0.25 + 0.5;
    const double bx = rx + along * c - up * sn, by = ry + along * sn + up * c;
    s.bodies.push_back(Box({Real(bx), Real(by)}, Real(0.5), Real(0.5), true, boxFriction, 1, Real(angle)));
  }
  s.bounds = Bounds({-6, -3}, {54, 3});
  return s;
}

Scene MakeRestitutionDrop(Mixing mixing) {
  Scene s = BaseScene("restitution_drop");
  s.effects.friction = false;     // a bounce straight down needs none, and spin would need it
  // The rebound height depends on where the impact happens within a step: the case calls for
  // continuous collision (Box2D: its time of impact against static bodies; Quadrant: contacts
  // swept over the step). Without it a 6.3 m/s ball sinks up to 0.1 m before it bounces.
  s.effects.continuous = true;
  s.effects.restitution = true;
  s.restitutionThreshold = 0;     // every approach speed bounces, as e^2 assumes
  // The ground's restitution makes each ball's own value the mixed one: max(0, e) = e and
  // 1 * e = e. (There is no single ground value for both rules: max(1, e) = 1.)
  const Real groundE = mixing == Mixing::kBox2d ? Real(0) : Real(1);
  BodyDesc ground = Ground({0, 0}, 10, 0);
  ground.restitution = groundE;
  s.bodies.push_back(ground);
  const Real es[5] = {0, Real(0.25), Real(0.5), Real(0.75), 1};
  for (int k = 0; k < 5; ++k) {
    // Bottom 2 m above the ground: impact at 6.32 m/s after 0.632 s.
    s.bodies.push_back(Ball({Real(-4 + 2 * k), Real(2.5)}, Real(0.5), 0, es[k]));
  }
  s.bounds = Bounds({-10, -1}, {10, 4});
  return s;
}

Scene MakeOverlapRecovery(int base, Mixing mixing) {
  RequireRange(base, 1, 100, "overlap recovery base");
  Scene s = BaseScene("overlap_recovery");
  // Solver budget: pulling 20 rows apart by 0.25 m each within 60 steps takes 20 position
  // iterations per step (3 leave 0.1 m of overlap after 60 steps, as Box2D 2.4 leaves 0.07 m).
  s.positionIterations = 20;
  const Real f = Coef(mixing, Real(0.6));
  s.bodies.push_back(Ground({0, 0}, 20, f));
  // Pitch 0.75 m for 1 m boxes in both directions: every box overlaps each neighbour by 0.25 m.
  AddPyramidBoxes(s, base, {0, 0}, Real(0.75), Real(0.75), f);
  s.bounds = Bounds({-20, -1}, {20, Real(base) + 2});
  return s;
}

// Four static 1 m thick walls around the square [-half, half]^2 (friction f, restitution 0).
static void AddClosingWalls(Scene& s, double half, Real f) {
  auto wall = [&](double cx, double cy, double hx, double hy) {
    s.bodies.push_back(Box({Real(cx), Real(cy)}, Real(hx), Real(hy), false, f, 0));
  };
  wall(0, -half - 0.5, half + 1, 0.5);
  wall(0, half + 0.5, half + 1, 0.5);
  wall(-half - 0.5, 0, 0.5, half);
  wall(half + 0.5, 0, 0.5, half);
}

Scene MakeConfined(int side, uint64_t seed, Mixing mixing) {
  RequireRange(side, 1, 100, "confined grid side");
  Scene s = BaseScene("confined");
  s.seed = seed;
  s.gravity = {0, 0};
  s.effects.gravity = false;
  const Real f = Coef(mixing, Real(0.6));
  // Inner side 25 m for 25 x 25 circles: area fraction 0.785, so they can all separate (random
  // close packing of discs is about 0.82) but end up crowded.
  const double half = 0.5 * side;
  AddClosingWalls(s, half, f);
  Random rng(seed);
  const double pitch = 0.8;
  const double start = -0.5 * (side - 1) * pitch;
  for (int i = 0; i < side; ++i) {
    for (int j = 0; j < side; ++j) {
      // A small jitter so the push-out is not a perfectly symmetric lattice problem.
      const double x = start + j * pitch + rng.Uniform(-0.02, 0.02);
      const double y = start + i * pitch + rng.Uniform(-0.02, 0.02);
      s.bodies.push_back(Ball({Real(x), Real(y)}, Real(0.5), f, 0));
    }
  }
  s.bounds = Bounds({Real(-half), Real(-half)}, {Real(half), Real(half)});
  return s;
}

Scene MakeClosedBox(int count, uint64_t seed, Mixing mixing) {
  RequireRange(count, 1, 100000, "closed box circle count");
  Scene s = BaseScene("closed_box");
  s.seed = seed;
  const Real f = Coef(mixing, Real(0.6));
  const double r = 0.5, fraction = 0.85;
  const double side = std::sqrt(count * std::numbers::pi * r * r / fraction);
  const double half = 0.5 * side;
  AddClosingWalls(s, half, f);
  // A hexagonal lattice of touching circles (pitch 2r) from the floor up; rows alternate by r.
  const double pitch = 2 * r + 1e-4, rowPitch = pitch * std::sqrt(3.0) / 2;
  const int perRow = int((side - 2 * r - r) / pitch) + 1;  // room for the odd rows' shift
  Random rng(seed);
  for (int k = 0; k < count; ++k) {
    const int row = k / perRow, col = k % perRow;
    const double x = -half + r + col * pitch + (row % 2 ? r : 0);
    const double y = -half + r + row * rowPitch;
    if (y > half - r) throw Error("closed box: the lattice does not fit the box");
    BodyDesc b = Ball({Real(x), Real(y)}, Real(r), f, 0);
    b.velocity = {Real(rng.Uniform(-2, 2)), Real(rng.Uniform(-2, 2))};
    s.bodies.push_back(b);
  }
  s.bounds = Bounds({Real(-half), Real(-half)}, {Real(half), Real(half)});
  return s;
}

Scene MakeFarFromOrigin(Mixing mixing) {
  Scene s = MakePyramid(20, {Real(1e5), Real(-8e4)}, mixing);
  s.name = "far_from_origin";
  return s;
}

Scene MakeNewtonsCradle(Mixing mixing) {
  Scene s = BaseScene("newtons_cradle");
  // Hanging needs joints, which the scene API does not have: a free row in zero gravity shows
  // the same transfer of momentum and energy along a chain of touching balls.
  s.gravity = {0, 0};
  s.effects.gravity = false;
  s.effects.friction = false;
  s.effects.restitution = true;
  s.restitutionThreshold = 0;
  const Real e = Coef(mixing, 1);
  for (int k = 0; k < 5; ++k) {
    BodyDesc b = Ball({Real(k), 0}, Real(0.5), 0, e);
    if (k == 0) b.velocity = {1, 0};
    s.bodies.push_back(b);
  }
  s.bounds = Bounds({-10, -1}, {20, 1});
  return s;
}

// ---- Joint hard cases (issue #27 item 5) -----------------------------------------------------

Scene MakeHeavyChain(Mixing mixing) {
  Scene s = BaseScene("heavy_chain");
  (void)mixing;  // nothing touches: no material is mixed
  // A static pin at (0, 40); 30 links of 0.5 m x 0.2 m (density 1: 0.1 kg), each pinned to the one
  // above at their shared end; a ball of 1000 links' mass (100 kg, r = 5.64 m) pinned below.
  const Real top = 40, length = Real(0.5);
  const int links = 30;
  BodyDesc pin = MakeCircleBody({0, top}, Real(0.05), /*dynamic=*/false);
  s.bodies.push_back(pin);
  for (int k = 0; k < links; ++k) {
    s.bodies.push_back(Box({0, top - length * (Real(k) + Real(0.5))}, Real(0.1), length / 2, true, Real(0.6)));
    s.joints.push_back(JointDesc{int(s.bodies.size()) - 2, int(s.bodies.size()) - 1, {0, top - length * Real(k)}});
  }
  const Real linkMass = Real(0.2) * length;
  const Real radius = Real(std::sqrt(1000.0 * double(linkMass) / 3.14159265358979323846));
  BodyDesc heavy = Ball({0, top - length * Real(links) - radius}, radius, Real(0.6), 0);
  s.bodies.push_back(heavy);
  s.joints.push_back(JointDesc{int(s.bodies.size()) - 2, int(s.bodies.size()) - 1, {0, top - length * Real(links)}});
  s.bounds = Bounds({-20, top - 40}, {20, top + 1});
  return s;
}

namespace {

// A capsule body along its x axis (centres +-halfLength), turned by `angle`.
BodyDesc Limb(Vec2 centre, Real halfLength, Real radius, Real angle, Real friction) {
  BodyDesc b = MakeCapsuleBody(centre, halfLength, radius);
  b.angle = angle;
  b.friction = friction;
  return b;
}

}  // namespace

Scene MakeRagdollPile(int count, Mixing mixing) {
  RequireRange(count, 1, 200, "ragdoll count");
  Scene s = BaseScene("ragdoll_pile");
  const Real f = Coef(mixing, Real(0.6));
  // A box 8 m wide and 20 m high: the ground and two walls.
  s.bodies.push_back(Ground({0, 0}, 5, f));
  s.bodies.push_back(Box({-4.5f, 10}, Real(0.5), 10, false, f, 0));
  s.bodies.push_back(Box({4.5f, 10}, Real(0.5), 10, false, f, 0));
  const Real up = Real(3.14159265358979323846 / 2);
  // Each ragdoll: torso, head, two arms, two upper and two lower legs (capsules, the head a
  // circle), 9 bodies and 8 revolute joints with limits and a little joint friction (a motor of
  // speed 0 and 0.2 N m), standing, feet 0.1 m up. Columns of four, rows 2 m apart.
  for (int n = 0; n < count; ++n) {
    const Vec2 o{Real(-2.4) + Real(1.6) * Real(n % 4), Real(1) + Real(2.2) * Real(n / 4)};
    const int torso = int(s.bodies.size());
    s.bodies.push_back(Limb(o + Vec2{0, Real(1.2)}, Real(0.2), Real(0.13), up, f));
    auto limb = [&](Vec2 centre, Real half, Real radius) {
      s.bodies.push_back(Limb(o + centre, half, radius, up, f));
      return int(s.bodies.size()) - 1;
    };
    auto join = [&](int a, int b, Vec2 anchor, Real lower, Real upper) {
      JointDesc j{a, b, o + anchor};
      j.enableLimit = true;
      j.lowerAngle = lower;
      j.upperAngle = upper;
      j.enableMotor = true;
      j.maxMotorTorque = Real(0.2);
      s.joints.push_back(j);
    };
    BodyDesc head = Ball(o + Vec2{0, Real(1.65)}, Real(0.12), f, 0);
    s.bodies.push_back(head);
    join(torso, int(s.bodies.size()) - 1, {0, Real(1.53)}, Real(-0.5), Real(0.5));
    for (Real side : {Real(-1), Real(1)}) {
      const int arm = limb({side * Real(0.27), Real(1.15)}, Real(0.22), Real(0.06));
      join(torso, arm, {side * Real(0.27), Real(1.43)}, Real(-2.5), Real(2.5));
      const int thigh = limb({side * Real(0.09), Real(0.75)}, Real(0.18), Real(0.08));
      join(torso, thigh, {side * Real(0.09), Real(1.0)}, Real(-1.5), Real(1.5));
      const int shin = limb({side * Real(0.09), Real(0.3)}, Real(0.16), Real(0.07));
      join(thigh, shin, {side * Real(0.09), Real(0.52)}, Real(-2.0), Real(0.05));
    }
  }
  s.bounds = Bounds({-5, -1}, {5, 20});
  return s;
}

Scene MakePrismaticStop(Mixing mixing) {
  Scene s = BaseScene("prismatic_stop");
  const Real f = Coef(mixing, Real(0.6));
  // A static 0.2 m post at (0, 5) and a 1 m box of 1 kg on a horizontal prismatic joint through the
  // post's centre (the box's centre), travel limited to [-2, 2] m, launched at 10 m/s along it:
  // gravity pulls it across the axis, the stop is hit at full speed.
  s.bodies.push_back(Box({0, 5}, Real(0.1), Real(0.1), false, f, 0));
  BodyDesc slider = Box({0, 5}, Real(0.5), Real(0.5), true, f);
  slider.velocity = {10, 0};
  s.bodies.push_back(slider);
  JointDesc j{0, 1, {0, 5}};
  j.kind = JointKind::kPrismatic;
  j.axis = {1, 0};
  j.enableLimit = true;
  j.lowerTranslation = -2;
  j.upperTranslation = 2;
  s.joints.push_back(j);
  s.bounds = Bounds({-5, 0}, {5, 10});
  return s;
}

Scene MakeWeldBeam(Mixing mixing) {
  Scene s = BaseScene("weld_beam");
  const Real f = Coef(mixing, Real(0.6));
  // A cantilever: a static 1 m wall block at (-0.5, 10) and ten 1 m x 0.2 m segments (0.2 kg
  // each) welded end to end from its face at x = 0, level, under gravity.
  s.bodies.push_back(Box({Real(-0.5), 10}, Real(0.5), Real(0.5), false, f, 0));
  for (int k = 0; k < 10; ++k) {
    s.bodies.push_back(Box({Real(k) + Real(0.5), 10}, Real(0.5), Real(0.1), true, f));
    JointDesc j{int(s.bodies.size()) - 2, int(s.bodies.size()) - 1, {Real(k), 10}};
    j.kind = JointKind::kWeld;
    s.joints.push_back(j);
  }
  s.bounds = Bounds({-2, 0}, {12, 12});
  return s;
}


// The bumpy road of wheel_terrain, y(x), shared by the scene and its criterion.
double TerrainHeight(double x) { return 0.2 * std::sin(0.8 * x) + 0.1 * std::sin(1.9 * x); }

Scene MakeWheelTerrain(Mixing mixing) {
  Scene s = BaseScene("wheel_terrain");
  // A chain of 1 m segments along y = TerrainHeight(x) from x = -10 to 230 m (slopes up to 0.35),
  // running right to left so that it collides from above; its two end segments are ghosts.
  std::vector<Vec2> points;
  for (int x = 231; x >= -11; --x) points.push_back({Real(x), Real(TerrainHeight(x))});
  for (BodyDesc& b : MakeChainBodyDescs(points, /*isLoop=*/false, Coef(mixing, Real(0.9)))) s.bodies.push_back(b);
  // A 2 m x 0.5 m chassis of 2 kg on two wheels (r = 0.4 m, 0.5 kg) pinned 0.7 m either side of
  // its centre, both driven by revolute motors at -6 rad/s (2.4 m/s forwards) with up to 20 N m.
  const Vec2 c{0, Real(TerrainHeight(0) + 1.2)};
  BodyDesc chassis = Box(c, 1, Real(0.25), true, Coef(mixing, Real(0.9)), 2);
  const int body = int(s.bodies.size());
  s.bodies.push_back(chassis);
  for (Real side : {Real(-0.7), Real(0.7)}) {
    BodyDesc wheel = Ball(c + Vec2{side, Real(-0.45)}, Real(0.4), Coef(mixing, Real(0.9)), 0);
    wheel.density = Real(0.5 / (3.14159265358979323846 * 0.16));
    s.bodies.push_back(wheel);
    JointDesc j{body, int(s.bodies.size()) - 1, c + Vec2{side, Real(-0.45)}};
    j.enableMotor = true;
    j.motorSpeed = -6;
    j.maxMotorTorque = 20;
    s.joints.push_back(j);
  }
  s.bounds = Bounds({-15, -5}, {235, 20});
  return s;
}

Scene MakeHangingGrid(Mixing mixing) {
  (void)mixing;  // the circles are filtered never to collide: no material is mixed
  // Box2D 3's joint_grid at 30 x 30 (893 dynamic circles of r = 0.4 m, 1 m apart, each pinned to
  // its neighbours above and to the left, hung from the top row's seven middle bodies), at the
  // hard cases' settings, with air drag (linear and angular damping 0.1 /s) so that the net's
  // swing dies out: it falls from level, sags and must come to rest without jitter.
  Scene grid = MakeJointGrid(30 * 30 - 7);
  Scene s = BaseScene("hanging_grid");
  s.effects.damping = true;
  s.bodies = std::move(grid.bodies);
  for (BodyDesc& b : s.bodies) {
    b.linearDamping = Real(0.1);
    b.angularDamping = Real(0.1);
  }
  s.joints = std::move(grid.joints);
  s.bounds = Bounds({-31, -61}, {61, 2});
  return s;
}

// ---- Solver2D's contact scenes (issue #26 item 2) --------------------------------------------
//
// erincatto/solver2d's samples/collection/sample_contact.cpp and sample_far.cpp, rebuilt with the
// same sizes and layouts. Grounds are 1 m thick static boxes (top face at y = 0) where Solver2D
// has a segment, so that Bullet, which has no segment in its 2D mode, runs them too; only
// high_mass_ratio_2 keeps Solver2D's segment, since a segment ground is what tells it from
// high_mass_ratio_3.

Scene MakeSingleBox(Mixing mixing) {
  Scene s = BaseScene("single_box");
  const Real f = Coef(mixing, Real(0.5));
  s.bodies.push_back(Ground({0, 0}, 66, f));
  // A 2 m box (4 kg) whose bottom is 3 m above the ground: it lands at 7.75 m/s.
  s.bodies.push_back(Box({0, 4}, 1, 1, true, f));
  s.bounds = Bounds({-66, -1}, {66, 6});
  return s;
}

Scene MakeWarmStartEnergy(Mixing mixing) {
  Scene s = BaseScene("warm_start_energy");
  const Real f = Coef(mixing, Real(0.6));
  s.bodies.push_back(Ground({0, 0}, 10, f));
  // Three touching balls (r = 0.5 m) in a column, the top one 100 times as dense (78.5 kg on two
  // balls of 0.785 kg).
  for (int k = 0; k < 3; ++k) {
    BodyDesc b = Ball({0, Real(0.5) + Real(k)}, Real(0.5), f, 0);
    if (k == 2) b.density = 100;
    s.bodies.push_back(b);
  }
  // Solver2D destroys the heavy ball at step 120; the adapters cannot destroy a body, so from
  // step 120 on the driver lifts it straight up at 20 m/s (0.33 m per step: it leaves the column
  // within a step and is 1.2 km up at 60 s). Either way the light balls lose their load at once
  // while their contacts still hold the impulses it needed: a solver that warm-starts them
  // without a check launches the balls.
  s.driver = [](int step, Adapter& adapter) {
    if (step >= kWarmStartLiftStep) adapter.SetVelocity(3, {0, 20}, 0);
  };
  s.bounds = Bounds({-10, -1}, {10, 4});
  return s;
}

Scene MakeHighMassRatio(int variant, Mixing mixing) {
  RequireRange(variant, 1, 3, "high mass ratio variant");
  if (variant == 1) {
    Scene s = BaseScene("high_mass_ratio_1");
    const Real f = Coef(mixing, Real(0.5));
    s.bodies.push_back(Ground({0, 0}, 66, f));
    // Three base-10 pyramids of touching 2 m boxes (4 kg), 2 m apart; on each apex, dropped from
    // 2 m above its resting place, a 2 m box of density 100, 200 and 300 (400, 800, 1200 kg).
    for (int j = 0; j < 3; ++j) {
      const double offset = -20 + 22.0 * j;
      for (int row = 0; row < 10; ++row) {
        const int n = 10 - row;
        const bool apex = n == 1;
        const double y = 1 + 2.0 * row + (apex ? 2 : 0);
        for (int i = 0; i < n; ++i) {
          const double x = offset + 2.0 * (i - 0.5 * n);
          s.bodies.push_back(Box({Real(x), Real(y)}, 1, 1, true, f, apex ? Real(100 * (j + 1)) : Real(1)));
        }
      }
    }
    s.bounds = Bounds({-66, -1}, {66, 24});
    return s;
  }
  Scene s = BaseScene(variant == 2 ? "high_mass_ratio_2" : "high_mass_ratio_3");
  const Real f = Coef(mixing, Real(0.6));
  if (variant == 2) {
    // Solver2D's segment ground, 40 m long.
    BodyDesc ground = MakeSegmentBody({0, 0}, {-20, 0}, {20, 0});
    ground.friction = f;
    s.bodies.push_back(ground);
  } else {
    // Solver2D's thick ground: an 80 m x 4 m box, its top face at y = 0.
    s.bodies.push_back(Box({0, -2}, 40, 2, false, f, 0));
  }
  // Two 1 m boxes (1 kg) at x = -9 and 9, and a 20 m box (400 kg) whose bottom is 15 m above
  // them: it lands on both at 17.3 m/s, 400:1.
  s.bodies.push_back(Box({-9, Real(0.5)}, Real(0.5), Real(0.5), true, f));
  s.bodies.push_back(Box({9, Real(0.5)}, Real(0.5), Real(0.5), true, f));
  s.bodies.push_back(Box({0, 26}, 10, 10, true, f));
  s.bounds = Bounds({-40, -4}, {40, 36});
  return s;
}

Scene MakeRush(Mixing mixing) {
  Scene s = BaseScene("rush");
  s.gravity = {0, 0};
  s.effects.gravity = false;  // Solver2D: gravity scale 0; a central pull instead (the driver)
  const Real f = Coef(mixing, Real(0.2));
  // A static ball (r = 0.5 m) at the origin and 400 balls (r = 0.5 m, density 100: 78.5 kg) on a
  // spiral around it: the first 5 m out, each next one 0.05 m farther and 0.2 rad further round.
  BodyDesc core = Ball({0, 0}, Real(0.5), f, 0);
  core.dynamic = false;
  core.density = 0;
  s.bodies.push_back(core);
  double distance = 5, angle = 0;
  for (int i = 0; i < kRushCount; ++i) {
    BodyDesc b = Ball({Real(distance * std::cos(angle)), Real(distance * std::sin(angle))}, Real(0.5), f, 0);
    b.density = 100;
    s.bodies.push_back(b);
    angle += 1.0 / 5.0;
    distance += 0.05;
  }
  // Every step a 1000 N pull toward the origin on each ball (as Solver2D's ApplyForceToCenter),
  // given through the velocity, v += dt F / m: what a force does over one step.
  const double mass = 100 * std::numbers::pi * 0.25;
  const double dv = 1000.0 / mass * double(s.timeStep);
  auto states = std::make_shared<std::vector<BodyState>>();
  s.driver = [states, dv](int, Adapter& adapter) {
    adapter.ReadBodies(*states);
    for (size_t i = 1; i < states->size(); ++i) {
      const BodyState& b = (*states)[i];
      const double d = std::hypot(double(b.position.x), double(b.position.y));
      if (d < 0.1) continue;
      const Vec2 v{Real(b.velocity.x - dv * b.position.x / d), Real(b.velocity.y - dv * b.position.y / d)};
      adapter.SetVelocity(int(i), v, b.angularVelocity);
    }
  };
  s.bounds = Bounds({-26, -26}, {26, 26});
  return s;
}

Scene MakeDoubleDomino(Mixing mixing) {
  Scene s = BaseScene("double_domino");
  const Real f = Coef(mixing, Real(0.6));
  s.bodies.push_back(Ground({0, 0}, 100, f));
  // 15 dominoes of 0.25 m x 1 m (0.25 kg) standing 1 m apart from x = -7.5; the first gets
  // Solver2D's push, an impulse of 0.2 N s to the right at its top (y = 1 m), as a velocity:
  // v = J / m = 0.8 m/s and w = -(0.5 m)(0.2 N s) / I with I = m (0.25^2 + 1^2) / 12.
  for (int i = 0; i < kDominoCount; ++i) {
    BodyDesc b = Box({Real(-7.5 + i), Real(0.5)}, Real(0.125), Real(0.5), true, f);
    if (i == 0) {
      const double m = 0.25, inertia = m * (0.25 * 0.25 + 1.0) / 12;
      b.velocity = {Real(0.2 / m), 0};
      b.angularVelocity = Real(-0.5 * 0.2 / inertia);
    }
    s.bodies.push_back(b);
  }
  s.bounds = Bounds({-100, -1}, {100, 2});
  return s;
}

Scene MakeCircleStack(Mixing mixing) {
  Scene s = BaseScene("circle_stack");
  const Real f = Coef(mixing, Real(0.6));
  s.bodies.push_back(Ground({0, 0}, 40, f));
  // Ten balls of radius 1 m in a column at x = 0, centres at y = 4, 7, ..., 31: each falls 1 m
  // onto the one below (the first 3 m onto the ground), bottom to top.
  for (int i = 0; i < kCircleStackCount; ++i) s.bodies.push_back(Ball({0, Real(4 + 3 * i)}, 1, f, 0));
  s.bounds = Bounds({-40, -1}, {40, 33});
  return s;
}

Scene MakeFarStack(Vec2 origin, Mixing mixing) {
  if (!IsFinite(origin)) throw Error("far stack origin is not finite");
  Scene s = BaseScene("far_stack");
  const Real f = Coef(mixing, Real(0.6));
  auto at = [&](double x, double y) { return Vec2{Real(double(origin.x) + x), Real(double(origin.y) + y)}; };
  // Solver2D's far stack (at (4e4, -2.5e4) there): a 20 m x 2 m ground box (top at y = 0), a ball
  // (r = 0.1 m) and a 0.2 m x 0.25 m box 2.5 cm up, a 4 m x 0.1 m plank resting on the box 5 cm
  // above the ball, and two squares (0.5 m, 1 m) dropped 0.275 m and 0.05 m onto it.
  s.bodies.push_back(Box(at(0, -1), 10, 1, false, f, 0));
  s.bodies.push_back(Ball(at(1.875, 0.125), Real(0.1), f, 0));
  s.bodies.push_back(Box(at(-1.875, 0.15), Real(0.1), Real(0.125), true, f));
  s.bodies.push_back(Box(at(0, 0.325), 2, Real(0.05), true, f));
  s.bodies.push_back(Box(at(-0.5, 0.9), Real(0.25), Real(0.25), true, f));
  s.bodies.push_back(Box(at(-0.55, 1.7), Real(0.5), Real(0.5), true, f));
  s.bounds = Bounds(at(-10, -2), at(10, 3));
  return s;
}

Scene MakeFarRecovery(Vec2 origin, Mixing mixing) {
  if (!IsFinite(origin)) throw Error("far recovery origin is not finite");
  Scene s = BaseScene("far_recovery");
  const Real f = Coef(mixing, Real(0.6));
  s.bodies.push_back(Ground(origin, 40, f));
  // Solver2D's far recovery (at (8e4, -7e4) there): a base-4 pyramid of 1 m boxes at 0.75 m
  // pitch in both directions (each overlaps its neighbours by 25 %), at the default budget.
  Scene pile = BaseScene("");
  AddPyramidBoxes(pile, 4, {0, 0}, Real(0.75), Real(0.75), f);
  for (BodyDesc b : pile.bodies) {
    b.position = {Real(double(origin.x) + double(b.position.x)), Real(double(origin.y) + double(b.position.y))};
    s.bodies.push_back(b);
  }
  s.bounds = Bounds({origin.x - 40, origin.y - 1}, {origin.x + 40, origin.y + 5});
  return s;
}

}  // namespace quadrant::scene
