// The hard cases' runs and pass criteria (see hard_case_checks.h).
//
// Conventions shared by the cases:
// - Every case runs kWindowSeconds (60 s of simulated time, 3600 steps at 60 Hz; the soak its
//   soakSteps) and its criterion is checked over the whole run, at every sample, not only at the
//   end: a pile that stands for 10 s and falls at 13 s fails (issue #26).
// - "Standing" cases are judged from t = 1 s on: the first second lets every engine settle its
//   spawn state (Box2D 2.4's 0.01 m polygon skin pushes bodies that spawn touching 0.015 m apart
//   at every contact, which lifts a 10-row pile by 0.15 m; Bullet's margins do similar), which
//   is not the drift the cases are about. The settling itself is reported as "settle_*".
// - Penetration is sampled every 0.5 s and the largest is reported.
// - A non-finite read-back fails every case.
#include "hard_case_checks.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <string>
#include <utility>

#include "quadrant/error.h"

namespace quadrant::scene {
namespace {

constexpr int kStepsPerSecond = 60;  // every hard case runs at dt = 1/60
constexpr double kWindowSeconds = 60;  // every case's window (the soak: its own step count)

std::string Fixed(double v, int digits) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, v);
  return buffer;
}

// The world settings a case runs with, for the report (the same for every engine).
std::string SettingsText(const Scene& s) {
  char buffer[320];
  std::snprintf(buffer, sizeof buffer,
                "dt %.5g s, %d velocity + %d position iterations, %d pipeline repeat%s, gravity %s, restitution "
                "threshold %g m/s, continuous %s, warm starting %s, sleep %s",
                double(s.timeStep), s.velocityIterations, s.positionIterations, s.pipelineRepeats,
                s.pipelineRepeats == 1 ? "" : "s", s.effects.gravity ? "(0, -10)" : "off", double(s.restitutionThreshold),
                s.effects.continuous ? "on" : "off", s.effects.warmStarting ? "on" : "off",
                s.effects.sleep ? "on" : "off");
  return buffer;
}

// Progress lines during a case (HardCaseOptions::progressSeconds), set by RunHardCase for the
// case it runs: a 60-s window of a slow peer takes longer than the 10 s between lines.
struct Progress {
  double seconds = 0;  // 0: no lines
  std::string label;   // "case engine"
  std::chrono::steady_clock::time_point last;
};
thread_local Progress progress;

// One engine running one scene. Holds the scene itself: adapters may keep pointers into it.
// Records the scene's settings in the result before loading, so a refused scene has them too.
class Sim {
 public:
  Sim(HardCaseResult& r, std::string_view engine, Scene scene) : scene_(std::make_unique<Scene>(std::move(scene))) {
    r.settings = SettingsText(*scene_);
    adapter_ = MakeAdapter(engine);
    adapter_->Load(*scene_, 1);
    adapter_->ReadBodies(states_);
    finite_ = Finite();
  }

  /// Steps until `step` steps have been taken in total (no-op if already there).
  void RunTo(int step) {
    while (steps_ < step) {
      adapter_->Step();
      ++steps_;
      if (progress.seconds > 0 && steps_ % 100 == 0) {  // the clock read every 100 steps only
        const auto now = std::chrono::steady_clock::now();
        if (std::chrono::duration<double>(now - progress.last).count() >= progress.seconds) {
          progress.last = now;
          std::fprintf(stderr, "  %s: step %d (%.0f s simulated)\n", progress.label.c_str(), steps_,
                       double(steps_) / kStepsPerSecond);
          std::fflush(stderr);
        }
      }
    }
    adapter_->ReadBodies(states_);
    finite_ = finite_ && Finite();
  }
  void StepOnce() { RunTo(steps_ + 1); }

  const Scene& scene() const { return *scene_; }
  const std::vector<BodyState>& states() const { return states_; }
  int steps() const { return steps_; }
  bool finite() const { return finite_; }
  double KE() const { return KineticEnergy(*scene_, states_); }

 private:
  bool Finite() const {
    for (const BodyState& s : states_) {
      if (!IsFinite(s.position) || !IsFinite(s.angle) || !IsFinite(s.velocity) || !IsFinite(s.angularVelocity)) {
        return false;
      }
    }
    return true;
  }

  std::unique_ptr<Scene> scene_;
  std::unique_ptr<Adapter> adapter_;
  std::vector<BodyState> states_;
  int steps_ = 0;
  bool finite_ = true;
};

double Displacement(const BodyState& a, const BodyState& b) {
  return std::hypot(double(b.position.x) - a.position.x, double(b.position.y) - a.position.y);
}

// Largest displacement of the bodies [first, last) between two read-backs.
double MaxDisplacement(const std::vector<BodyState>& from, const std::vector<BodyState>& to, size_t first,
                       size_t last) {
  double worst = 0;
  for (size_t i = first; i < last; ++i) worst = std::max(worst, Displacement(from[i], to[i]));
  return worst;
}

double MaxSpeed(const Scene& scene, const std::vector<BodyState>& states) {
  double worst = 0;
  for (size_t i = 0; i < states.size(); ++i) {
    if (!scene.bodies[i].dynamic) continue;
    worst = std::max(worst, std::hypot(double(states[i].velocity.x), double(states[i].velocity.y)));
  }
  return worst;
}

// ---- Penetration from poses and exact shapes ---------------------------------------------

struct WorldShape {
  bool circle = false;
  double cx = 0, cy = 0, r = 0;  // circle centre and radius (cx, cy also: body origin)
  int count = 0;
  std::array<double, 8> x{}, y{};  // polygon vertices, counter-clockwise
  double bound = 0;                // radius about (cx, cy) that holds the shape
};

WorldShape Place(const BodyDesc& body, const BodyState& state) {
  WorldShape w;
  w.cx = state.position.x;
  w.cy = state.position.y;
  if (body.shape == ShapeKind::kCircle) {
    w.circle = true;
    w.r = body.radius;
    w.bound = body.radius;
    return w;
  }
  const double c = std::cos(double(state.angle)), s = std::sin(double(state.angle));
  w.count = static_cast<int>(body.vertices.size());
  for (int i = 0; i < w.count; ++i) {
    const double vx = body.vertices[i].x, vy = body.vertices[i].y;
    w.x[i] = w.cx + c * vx - s * vy;
    w.y[i] = w.cy + s * vx + c * vy;
    w.bound = std::max(w.bound, std::hypot(vx, vy));
  }
  return w;
}

// Largest over a's edges of the smallest signed distance of b's vertices to that edge's line.
double EdgeSeparation(const WorldShape& a, const WorldShape& b) {
  double best = -1e300;
  for (int i = 0; i < a.count; ++i) {
    const int j = (i + 1) % a.count;
    const double ex = a.x[j] - a.x[i], ey = a.y[j] - a.y[i];
    const double len = std::hypot(ex, ey);
    const double nx = ey / len, ny = -ex / len;  // outward for counter-clockwise order
    double least = 1e300;
    for (int k = 0; k < b.count; ++k) least = std::min(least, nx * (b.x[k] - a.x[i]) + ny * (b.y[k] - a.y[i]));
    best = std::max(best, least);
  }
  return best;
}

double PolygonCircleSeparation(const WorldShape& p, const WorldShape& c) {
  // Inside (every edge's distance <= 0): the shallowest edge is the way out.
  double deepest = -1e300;
  for (int i = 0; i < p.count; ++i) {
    const int j = (i + 1) % p.count;
    const double ex = p.x[j] - p.x[i], ey = p.y[j] - p.y[i];
    const double len = std::hypot(ex, ey);
    deepest = std::max(deepest, (ey * (c.cx - p.x[i]) - ex * (c.cy - p.y[i])) / len);
  }
  if (deepest <= 0) return deepest - c.r;
  double nearest = 1e300;
  for (int i = 0; i < p.count; ++i) {
    const int j = (i + 1) % p.count;
    const double ex = p.x[j] - p.x[i], ey = p.y[j] - p.y[i];
    const double t = std::clamp(((c.cx - p.x[i]) * ex + (c.cy - p.y[i]) * ey) / (ex * ex + ey * ey), 0.0, 1.0);
    nearest = std::min(nearest, std::hypot(c.cx - (p.x[i] + t * ex), c.cy - (p.y[i] + t * ey)));
  }
  return nearest - c.r;
}

// Signed separation: exact depth (negative) for overlapping shapes, a positive lower bound of
// the distance otherwise (enough: only penetration is reported).
double Separation(const WorldShape& a, const WorldShape& b) {
  if (a.circle && b.circle) return std::hypot(a.cx - b.cx, a.cy - b.cy) - a.r - b.r;
  if (a.circle) return PolygonCircleSeparation(b, a);
  if (b.circle) return PolygonCircleSeparation(a, b);
  return std::max(EdgeSeparation(a, b), EdgeSeparation(b, a));
}

// Largest overlap over all pairs that are not both static.
double MaxPenetrationOf(const Scene& scene, const std::vector<BodyState>& states) {
  std::vector<WorldShape> shapes(states.size());
  for (size_t i = 0; i < states.size(); ++i) shapes[i] = Place(scene.bodies[i], states[i]);
  double worst = 0;
  for (size_t i = 0; i < shapes.size(); ++i) {
    for (size_t j = i + 1; j < shapes.size(); ++j) {
      if (!scene.bodies[i].dynamic && !scene.bodies[j].dynamic) continue;
      const WorldShape& a = shapes[i];
      const WorldShape& b = shapes[j];
      if (std::hypot(a.cx - b.cx, a.cy - b.cy) > a.bound + b.bound) continue;
      worst = std::max(worst, -Separation(a, b));
    }
  }
  return worst;
}

// ---- The cases ------------------------------------------------------------------------------

using CaseFn = void (*)(std::string_view engine, const HardCaseOptions& options, HardCaseResult& r);

void Add(HardCaseResult& r, std::string name, double value) { r.measured.push_back({std::move(name), value}); }

// Runs a standing pile from 0 to `seconds`, sampling every 0.5 s: penetration, and from t = `from`
// (1 s unless a case says; a multiple of 0.5 s) each body's displacement from where it was then
// (the largest over the samples, so a body that wanders off and comes back still counts). Fills
// the drift of the bodies [first, last), per body (`drift`) and their largest (`maxDrift`), and
// the settling before t = `from` (`atOne` holds the poses at t = `from`).
struct PileRun {
  double maxDrift = 0, settle = 0, maxPenetration = 0;
  std::vector<double> drift;  // per body index, largest displacement from its t = 1 s pose
  std::vector<double> dx, dy;  // per body index, largest |dx| and |dy| from its t = 1 s pose
  std::vector<BodyState> atOne, atEnd;
};

PileRun RunPile(Sim& sim, double seconds, size_t first, size_t last, double from = 1) {
  const int fromStep = int(std::lround(from * kStepsPerSecond));
  PileRun run;
  const std::vector<BodyState> start = sim.states();
  const size_t n = start.size();
  run.drift.assign(n, 0);
  run.dx.assign(n, 0);
  run.dy.assign(n, 0);
  const int end = int(std::lround(seconds * kStepsPerSecond));
  for (int step = kStepsPerSecond / 2; step <= end; step += kStepsPerSecond / 2) {
    sim.RunTo(step);
    run.maxPenetration = std::max(run.maxPenetration, MaxPenetrationOf(sim.scene(), sim.states()));
    if (step == fromStep) run.atOne = sim.states();
    if (step < fromStep) continue;
    for (size_t i = first; i < last; ++i) {
      const BodyState& a = run.atOne[i];
      const BodyState& b = sim.states()[i];
      run.drift[i] = std::max(run.drift[i], Displacement(a, b));
      run.dx[i] = std::max(run.dx[i], std::abs(double(b.position.x) - a.position.x));
      run.dy[i] = std::max(run.dy[i], std::abs(double(b.position.y) - a.position.y));
    }
  }
  sim.RunTo(end);
  run.atEnd = sim.states();
  for (size_t i = first; i < last; ++i) run.maxDrift = std::max(run.maxDrift, run.drift[i]);
  run.settle = MaxDisplacement(start, run.atOne, first, last);
  return run;
}

void VerticalStack(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "15 boxes of 1 m (friction 0.3, x offsets +-0.01 m): the top box's |dx| and |dy| from its "
                "pose at t = 1 s stay below 0.01 m each up to t = 60 s (sampled every 0.5 s)";
  Sim sim(r, engine, MakeVerticalStack(15, MixingOf(engine)));
  const size_t top = sim.scene().bodies.size() - 1;
  PileRun run = RunPile(sim, kWindowSeconds, 1, top + 1);
  const double dx = run.dx[top];
  const double dy = run.dy[top];
  Add(r, "top_max_dx_m", dx);
  Add(r, "top_max_dy_m", dy);
  Add(r, "top_x_at_60s_m", run.atEnd[top].position.x);
  Add(r, "max_box_drift_m", run.maxDrift);
  Add(r, "max_penetration_m", run.maxPenetration);
  Add(r, "settle_0_to_1s_m", run.settle);
  r.pass = sim.finite() && dx < 0.01 && dy < 0.01;
}

void Pyramid(std::string_view engine, HardCaseResult& r, Scene scene, bool far) {
  // Read-back is float in every engine here: at 1e5 m its resolution is 7.8 mm, so far from the
  // origin penetration is only known to about a centimetre and the drift alone decides.
  r.criterion = far ? "base-20 pyramid of 1 m boxes (friction 0.6) at (1e5, -8e4): apex drift from t = 1 s stays "
                      "below 0.02 m up to t = 60 s (penetration reported only: float read-back resolves 7.8 mm there)"
                    : "base-20 pyramid of 1 m boxes (friction 0.6): apex drift from t = 1 s stays below 0.02 m up to "
                      "t = 60 s and the largest penetration below 0.01 m (both sampled every 0.5 s)";
  Sim sim(r, engine, std::move(scene));
  const size_t apex = sim.scene().bodies.size() - 1;
  PileRun run = RunPile(sim, kWindowSeconds, 1, apex + 1);
  const double apexDrift = run.drift[apex];
  Add(r, "apex_drift_m", apexDrift);
  Add(r, "max_box_drift_m", run.maxDrift);
  Add(r, "max_penetration_m", run.maxPenetration);
  Add(r, "settle_0_to_1s_m", run.settle);
  r.pass = sim.finite() && apexDrift < 0.02 && (far || run.maxPenetration < 0.01);
}

void PyramidCase(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  Pyramid(engine, r, MakePyramid(20, {}, MixingOf(engine)), false);
}

void FarFromOrigin(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  Pyramid(engine, r, MakeFarFromOrigin(MixingOf(engine)), true);
}

void MassRatio(std::string_view engine, HardCaseResult& r, int ratio) {
  r.criterion = ratio == 100
                    ? "a 100 kg box (1 m, density 100) on the apex of a base-10 pyramid of 1 kg boxes: no body moves "
                      "more than 0.05 m from its t = 1 s pose up to t = 60 s, largest penetration below 0.02 m"
                    : "a 20 m x 1 m plank of 400 kg on two 1 kg boxes (1 m, at x = +-9): no body moves more than "
                      "0.05 m from its t = 1 s pose up to t = 60 s, largest penetration below 0.02 m";
  Sim sim(r, engine, MakeMassRatio(ratio, MixingOf(engine)));
  const size_t n = sim.scene().bodies.size();
  PileRun run = RunPile(sim, kWindowSeconds, 1, n);
  Add(r, "max_body_drift_m", run.maxDrift);
  Add(r, "heavy_drift_m", run.drift[n - 1]);
  Add(r, "max_penetration_m", run.maxPenetration);
  Add(r, "settle_0_to_1s_m", run.settle);
  r.pass = sim.finite() && run.maxDrift < 0.05 && run.maxPenetration < 0.02;
}

void MassRatio100(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) { MassRatio(engine, r, 100); }
void MassRatio400(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) { MassRatio(engine, r, 400); }

// Issue #13's stability cases run at the default budget and are judged from t = 0 (the levels
// they compare with are Box2D 3's from the start: a 30-stack's top moves about 0.02 m sideways
// and sinks about 0.01 m per box by soft compliance; a 1000:1 box on small supports sinks about
// 0.13 m). A rise is not judged: Box2D 2.4's skin lifts bodies that spawn touching.

// Largest sideways move and largest sink (start y minus the lowest y) of body `k`, sampled every
// 0.5 s over `seconds`, with the largest penetration over the same samples.
struct SinkRun {
  double maxDx = 0, maxSink = 0, maxPenetration = 0;
  double otherMaxSink = 0;  // the largest sink of body `other`, if one is given
};
SinkRun RunSink(Sim& sim, double seconds, size_t k, size_t other = size_t(-1)) {
  SinkRun run;
  const BodyState start = sim.states()[k];
  const double otherStartY = other != size_t(-1) ? double(sim.states()[other].position.y) : 0;
  const int end = int(std::lround(seconds * kStepsPerSecond));
  for (int step = kStepsPerSecond / 2; step <= end; step += kStepsPerSecond / 2) {
    sim.RunTo(step);
    const BodyState& s = sim.states()[k];
    run.maxDx = std::max(run.maxDx, std::abs(double(s.position.x) - start.position.x));
    run.maxSink = std::max(run.maxSink, double(start.position.y) - s.position.y);
    if (other != size_t(-1)) run.otherMaxSink = std::max(run.otherMaxSink, otherStartY - sim.states()[other].position.y);
    run.maxPenetration = std::max(run.maxPenetration, MaxPenetrationOf(sim.scene(), sim.states()));
  }
  return run;
}

// The sink allowed: 0.35 m for 30 boxes (issue #13), 1.2 m for 50. Box2D 3 (617d32ab, 4 sub-steps,
// built from its source outside the suite, 3600 steps) sinks 0.323 m and 1.110 m, and its top
// moves 0.025 m and 0.044 m sideways; each contact sags by the load above it, so the sink grows
// faster than the height.
void TallStack(std::string_view engine, HardCaseResult& r, int count) {
  const double sinkLimit = count == 30 ? 0.35 : 1.2;
  r.criterion = std::to_string(count) +
                " boxes of 1 m exactly touching and aligned (friction 0.6), default budget: over 60 s (sampled "
                "every 0.5 s) the top box moves less than 0.05 m sideways and sinks less than " +
                Fixed(sinkLimit, 2) + " m";
  Sim sim(r, engine, MakeTallStack(count, MixingOf(engine)));
  const size_t top = sim.scene().bodies.size() - 1;
  const SinkRun run = RunSink(sim, kWindowSeconds, top);
  Add(r, "top_max_dx_m", run.maxDx);
  Add(r, "top_max_sink_m", run.maxSink);
  Add(r, "top_y_at_60s_m", sim.states()[top].position.y);
  Add(r, "max_penetration_m", run.maxPenetration);
  r.note = "Box2D 3 (617d32ab) at its default 4 sub-steps, 3600 steps: the 30-box top moves at most 0.025 m "
           "sideways and sinks 0.323 m, the 50-box top 0.044 m and 1.110 m (soft contacts); a toppled stack moves "
           "its top by metres.";
  r.pass = sim.finite() && run.maxDx < 0.05 && run.maxSink < sinkLimit;
}

void TallStack30(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) { TallStack(engine, r, 30); }
void TallStack50(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) { TallStack(engine, r, 50); }

void HeavyOnSupports(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "a 20 m x 2 m box of 1000 kg on three 1 m boxes of 1 kg (1000:1, friction 0.6), default budget: "
                "over 60 s (sampled every 0.5 s) the heavy box sinks less than 0.15 m and moves less than 0.1 m "
                "sideways";
  Sim sim(r, engine, MakeHeavyOnSupports(MixingOf(engine)));
  const size_t heavy = sim.scene().bodies.size() - 1;
  const SinkRun run = RunSink(sim, kWindowSeconds, heavy);
  Add(r, "heavy_max_sink_m", run.maxSink);
  Add(r, "heavy_max_dx_m", run.maxDx);
  Add(r, "max_penetration_m", run.maxPenetration);
  r.note = "Box2D 3.2 at its default 4 sub-steps holds a 1000:1 box on small boxes, sinking about 0.13 m; a box "
           "that falls through sinks by the supports' height, 1 m.";
  r.pass = sim.finite() && run.maxSink < 0.15 && run.maxDx < 0.1;
}

void HeavyOnSlab(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "a 2 m box of 1000 kg on one 4 m x 0.2 m slab of 1 kg on the ground (1000:1, friction 0.6), "
                "default budget: over 60 s (sampled every 0.5 s) the heavy box sinks less than 0.1 m (half the "
                "slab) and the slab less than 0.05 m (at every sample)";
  Sim sim(r, engine, MakeHeavyOnSlab(MixingOf(engine)));
  const size_t slab = 1, heavy = 2;
  const SinkRun run = RunSink(sim, kWindowSeconds, heavy, slab);
  const double slabSink = run.otherMaxSink;
  Add(r, "heavy_max_sink_m", run.maxSink);
  Add(r, "slab_max_sink_m", slabSink);
  Add(r, "max_penetration_m", run.maxPenetration);
  r.note = "Beyond the peers (issue #13 item 3): Box2D 2.4.1 and 3.2 both let the box fall through the slab.";
  r.pass = sim.finite() && run.maxSink < 0.1 && slabSink < 0.05;
}

void Arch(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "semicircular arch of 17 blocks (inner radius 4 m, outer 5 m, friction 0.6): no block moves more "
                "than 0.05 m from its t = 1 s pose up to t = 61 s (60 s, sampled every 0.5 s)";
  Sim sim(r, engine, MakeArch(MixingOf(engine)));
  const size_t n = sim.scene().bodies.size();
  PileRun run = RunPile(sim, 1 + kWindowSeconds, 1, n);
  const size_t crown = 1 + 8;  // the middle of 17 blocks
  Add(r, "max_block_drift_m", run.maxDrift);
  Add(r, "crown_drop_at_61s_m", double(run.atOne[crown].position.y) - run.atEnd[crown].position.y);
  Add(r, "max_penetration_m", run.maxPenetration);
  Add(r, "settle_0_to_1s_m", run.settle);
  r.note = "Box2D 2.4's 0.01 m polygon skin pushes the 18 spawned-touching joints (ground included) about "
           "0.015 m apart each in the first second, lifting its crown by several centimetres; the window from "
           "t = 1 s excludes that settling (settle_0_to_1s_m).";
  r.pass = sim.finite() && run.maxDrift < 0.05;
}

void CardHouse(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "card house of 5 storeys, 40 cards of 1 m x 0.02 m (friction 0.7): the top pair's cards move "
                "less than 0.05 m from their t = 1 s poses up to t = 61 s (60 s, sampled every 0.5 s)";
  Sim sim(r, engine, MakeCardHouse(5, MixingOf(engine)));
  const size_t n = sim.scene().bodies.size();
  PileRun run = RunPile(sim, 1 + kWindowSeconds, 1, n);
  const double top = std::max(run.drift[n - 1], run.drift[n - 2]);
  Add(r, "top_pair_drift_m", top);
  Add(r, "max_card_drift_m", run.maxDrift);
  Add(r, "max_penetration_m", run.maxPenetration);
  Add(r, "settle_0_to_1s_m", run.settle);
  r.note = "Box2D 2.4 collides every polygon 0.01 m larger than the scene says (its skin): its cards act 0.04 m "
           "thick instead of 0.02 m and every card contact starts 0.02 m overlapped, so its house is not the "
           "scene's house.";
  r.pass = sim.finite() && top < 0.05;
}

void FrictionRamp(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  const double angle = 0.25, g = 10, t = 2;
  r.criterion = "boxes at rest on a 0.25 rad ramp, mixed friction 0.75, 0.5, 0.35, 0.1, 0 (sticks iff mu >= "
                "tan 0.25 = 0.2553): a sticking box moves less than 0.01 m at any step up to t = 60 s; a sliding "
                "one has slid 0.5 g (sin - mu cos) t^2 down the slope within 5 % at t = 2 s (it leaves the "
                "ramp at about 2.5-4 s)";
  const Mixing mixing = MixingOf(engine);
  Sim sim(r, engine, MakeFrictionRamp(mixing));
  const std::vector<BodyState> start = sim.states();
  const double downX = -std::cos(angle), downY = -std::sin(angle);
  // The sticking boxes' largest move from their spawn, at every step of the window.
  std::array<double, 5> stuckMove{};
  std::vector<BodyState> end;
  while (sim.steps() < int(kWindowSeconds * kStepsPerSecond)) {
    sim.StepOnce();
    if (sim.steps() == int(t * kStepsPerSecond)) end = sim.states();
    for (int k = 0; k < 5; ++k) stuckMove[k] = std::max(stuckMove[k], Displacement(start[2 * k + 1], sim.states()[2 * k + 1]));
  }
  bool pass = sim.finite();
  for (int k = 0; k < 5; ++k) {
    const BodyDesc& ramp = sim.scene().bodies[2 * k];
    const BodyDesc& box = sim.scene().bodies[2 * k + 1];
    const double mu = MixFriction(mixing, box.friction, ramp.friction);
    const BodyState& a = start[2 * k + 1];
    const BodyState& b = end[2 * k + 1];
    const double along = (double(b.position.x) - a.position.x) * downX + (double(b.position.y) - a.position.y) * downY;
    const std::string label = "mu_" + Fixed(mu, 2);
    if (mu >= std::tan(angle)) {
      Add(r, label + "_max_moved_m", stuckMove[k]);
      pass = pass && stuckMove[k] < 0.01;
    } else {
      const double expected = 0.5 * g * (std::sin(angle) - mu * std::cos(angle)) * t * t;
      Add(r, label + "_slid_m", along);
      Add(r, label + "_expected_m", expected);
      Add(r, label + "_error_pct", 100 * (along - expected) / expected);
      pass = pass && std::abs(along - expected) <= 0.05 * expected;
    }
  }
  r.note = "Each box spawns touching its ramp at rest, so nothing settles first; the discrete (symplectic Euler) "
           "distance exceeds 0.5 a t^2 by dt/t = 0.8 %.";
  r.pass = pass;
}

void RestitutionDrop(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "balls (r = 0.5 m) dropped from 2 m (bottom to ground) with mixed restitution 0, 0.25, 0.5, 0.75, "
                "1, threshold 0, no friction: first rebound height / 2 m within 5 % of e^2; for e = 0 the "
                "rebound above the final resting height below 0.01 m; over 60 s no ball rises above its first "
                "rebound by more than 5 % of the drop (no energy gained)";
  const Mixing mixing = MixingOf(engine);
  Sim sim(r, engine, MakeRestitutionDrop(mixing));
  const Scene& scene = sim.scene();
  const int balls = 5;
  const double radius = 0.5, drop = double(scene.bodies[1].position.y) - radius;
  // Per ball: the step of the first bounce (velocity turns upward), then the highest point
  // within 1.5 s after it (the second bounce is lower, or equal for e = 1).
  std::vector<int> bounce(balls + 1, -1);
  std::vector<double> peak(balls + 1, -1e300);
  std::vector<double> prevVy(balls + 1, 0);
  std::vector<double> later(balls + 1, -1e300);  // highest point after the first rebound's window
  const int end = int(kWindowSeconds * kStepsPerSecond);
  while (sim.steps() < end) {
    sim.StepOnce();
    for (int k = 1; k <= balls; ++k) {
      const BodyState& s = sim.states()[k];
      if (bounce[k] < 0 && prevVy[k] < 0 && s.velocity.y >= 0) bounce[k] = sim.steps();
      if (bounce[k] >= 0 && sim.steps() <= bounce[k] + 3 * kStepsPerSecond / 2) {
        peak[k] = std::max(peak[k], double(s.position.y));
      } else if (bounce[k] >= 0) {
        later[k] = std::max(later[k], double(s.position.y));
      }
      prevVy[k] = s.velocity.y;
    }
  }
  bool pass = sim.finite();
  for (int k = 1; k <= balls; ++k) {
    const double e = MixRestitution(mixing, scene.bodies[k].restitution, scene.bodies[0].restitution);
    const std::string label = "e_" + Fixed(e, 2);
    if (bounce[k] < 0) {
      Add(r, label + "_no_bounce_found", 1);
      pass = false;
      continue;
    }
    Add(r, label + "_later_rise_m", std::max(0.0, later[k] - peak[k]));
    pass = pass && later[k] - peak[k] <= 0.05 * drop;
    if (e == 0) {
      const double rest = sim.states()[k].position.y;
      Add(r, label + "_rebound_m", peak[k] - rest);
      Add(r, label + "_rest_height_m", rest - radius);
      pass = pass && peak[k] - rest < 0.01;
    } else {
      const double ratio = (peak[k] - radius) / drop;
      Add(r, label + "_ratio", ratio);
      Add(r, label + "_error_pct", 100 * (ratio - e * e) / (e * e));
      pass = pass && std::abs(ratio - e * e) <= 0.05 * e * e;
    }
  }
  r.note = "Materials mix to e in every engine: ground restitution 0 under max mixing (Box2D, Quadrant), 1 under "
           "product mixing (Bullet, Chipmunk). Heights are of the ball's bottom above the ground's face (Box2D's "
           "skin lifts both the drop and the rebound by 0.01 m, 0.5 % of the drop). The scene turns continuous "
           "collision on: without it a ball meets the ground up to v dt = 0.105 m deep at the 6.3 m/s impact and "
           "its rebound depends on where in the step the impact falls. Chipmunk has no continuous collision and "
           "reports the case unsupported.";
  r.pass = pass;
}

void OverlapRecovery(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "base-10 pyramid of 1 m boxes spawned at 0.75 m pitch (25 % overlap, friction 0.6): after 60 "
                "steps no pair overlaps by more than 0.02 m nor does later (checked every step up to t = 60 s), and "
                "no body is faster than 2 m/s at any step";
  Sim sim(r, engine, MakeOverlapRecovery(10, MixingOf(engine)));
  const double initial = MaxPenetrationOf(sim.scene(), sim.states());
  double maxSpeed = 0, laterOverlap = 0;
  int separatedAt = -1;
  for (int step = 1; step <= int(kWindowSeconds * kStepsPerSecond); ++step) {
    sim.StepOnce();
    maxSpeed = std::max(maxSpeed, MaxSpeed(sim.scene(), sim.states()));
    const double pen = MaxPenetrationOf(sim.scene(), sim.states());
    if (separatedAt < 0 && pen <= 0.02) separatedAt = step;
    if (step == kStepsPerSecond) Add(r, "max_overlap_at_60_steps_m", pen);
    if (step >= kStepsPerSecond) laterOverlap = std::max(laterOverlap, pen);
  }
  Add(r, "initial_overlap_m", initial);
  Add(r, "first_step_overlap_le_0.02m", separatedAt);
  Add(r, "max_speed_mps", maxSpeed);
  Add(r, "max_overlap_after_60_steps_m", laterOverlap);
  r.pass = sim.finite() && laterOverlap <= 0.02 && maxSpeed < 2;
}

void Confined(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "625 circles (r = 0.5 m) spawned overlapping by 0.2 m in a closed 25 m box, zero gravity, at rest: "
                "no NaN, every centre stays in the box, no body faster than 2 m/s, and after the push-out (t >= "
                "1 s) the kinetic energy never rises above its value at t = 1 s by more than 1 % (+1e-6 J); every "
                "step up to t = 60 s";
  Sim sim(r, engine, MakeConfined(25, 42, MixingOf(engine)));
  const Scene& scene = sim.scene();
  const double half = 12.5;
  double maxSpeed = 0, peakKe = 0, keAtOne = 0, worstRise = 0, outside = 0;
  const double initial = MaxPenetrationOf(scene, sim.states());
  const int end = int(kWindowSeconds * kStepsPerSecond);
  for (int step = 1; step <= end; ++step) {
    sim.StepOnce();
    const double ke = sim.KE();
    maxSpeed = std::max(maxSpeed, MaxSpeed(scene, sim.states()));
    peakKe = std::max(peakKe, ke);
    if (step == kStepsPerSecond) keAtOne = ke;
    if (step > kStepsPerSecond) worstRise = std::max(worstRise, ke - keAtOne);
    for (size_t i = 0; i < scene.bodies.size(); ++i) {
      if (!scene.bodies[i].dynamic) continue;
      const Vec2 p = sim.states()[i].position;
      outside = std::max({outside, std::abs(double(p.x)) - half, std::abs(double(p.y)) - half});
    }
  }
  Add(r, "initial_overlap_m", initial);
  Add(r, "peak_ke_J", peakKe);
  Add(r, "ke_at_1s_J", keAtOne);
  Add(r, "max_ke_rise_after_1s_J", worstRise);
  Add(r, "ke_at_60s_J", sim.KE());
  Add(r, "max_speed_mps", maxSpeed);
  Add(r, "max_overlap_at_60s_m", MaxPenetrationOf(scene, sim.states()));
  Add(r, "most_outside_box_m", std::max(0.0, outside));
  r.note = "Engines that push overlap out through positions (Box2D, Chipmunk, Quadrant) create no kinetic energy "
           "here at all; the overlap still left at 60 s is reported (max_overlap_at_60s_m), not judged.";
  r.pass = sim.finite() && outside <= 0 && maxSpeed < 2 && worstRise <= 0.01 * keAtOne + 1e-6;
}

// Issue #26 item 4: every solver must bring a closed box of circles under gravity to rest.
void ClosedBox(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "2000 circles (r = 0.5 m, friction 0.6, restitution 0) in a closed box at area fraction 0.85 "
                "with gravity, spawned touching with random speeds up to 2.8 m/s: no centre ever leaves the "
                "box, and at t = 60 s no body is faster than 0.5 m/s and the kinetic energy is below 1 % of "
                "its peak";
  Sim sim(r, engine, MakeClosedBox(2000, 42, MixingOf(engine)));
  const Scene& scene = sim.scene();
  const double half = double(scene.bounds.upper.x);
  double peakKe = sim.KE(), outside = 0, maxSpeedLast10 = 0;
  const int end = int(kWindowSeconds * kStepsPerSecond);
  while (sim.steps() < end) {
    sim.StepOnce();
    peakKe = std::max(peakKe, sim.KE());
    if (sim.steps() > end - 10 * kStepsPerSecond) maxSpeedLast10 = std::max(maxSpeedLast10, MaxSpeed(scene, sim.states()));
    for (size_t i = 0; i < scene.bodies.size(); ++i) {
      if (!scene.bodies[i].dynamic) continue;
      const Vec2 p = sim.states()[i].position;
      outside = std::max({outside, std::abs(double(p.x)) - half, std::abs(double(p.y)) - half});
    }
  }
  const double keEnd = sim.KE(), speedEnd = MaxSpeed(scene, sim.states());
  Add(r, "peak_ke_J", peakKe);
  Add(r, "ke_at_60s_J", keEnd);
  Add(r, "ke_fraction_at_60s", keEnd / peakKe);
  Add(r, "max_speed_at_60s_mps", speedEnd);
  Add(r, "max_speed_50_to_60s_mps", maxSpeedLast10);
  Add(r, "most_outside_box_m", std::max(0.0, outside));
  r.note = "The fastest body over the last 10 s is reported too (max_speed_50_to_60s_mps), not judged.";
  r.pass = sim.finite() && outside <= 0 && speedEnd < 0.5 && keEnd < 0.01 * peakKe;
}

void NewtonsCradle(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "five touching balls, zero gravity, friction 0, restitution 1, the first at 1 m/s: after 2 s the "
                "last moves at 1 m/s within 5 %; at every step up to t = 60 s momentum is conserved within 1e-3 "
                "(relative) and kinetic energy has not grown (by more than 1e-3 relative)";
  Sim sim(r, engine, MakeNewtonsCradle(MixingOf(engine)));
  const Scene& scene = sim.scene();
  const double v0 = scene.bodies[0].velocity.x;
  const Vec2 p0 = LinearMomentum(scene, sim.states());
  const double ke0 = sim.KE();
  double vLast = 0, others = 0, dp = 0, ke1 = 0;
  while (sim.steps() < int(kWindowSeconds * kStepsPerSecond)) {
    sim.StepOnce();
    const Vec2 p1 = LinearMomentum(scene, sim.states());
    dp = std::max(dp, std::hypot(double(p1.x) - p0.x, double(p1.y) - p0.y) / std::hypot(double(p0.x), double(p0.y)));
    ke1 = std::max(ke1, sim.KE());
    if (sim.steps() == 2 * kStepsPerSecond) {
      vLast = sim.states()[4].velocity.x;
      for (int k = 0; k < 4; ++k) others = std::max(others, std::abs(double(sim.states()[k].velocity.x)));
    }
  }
  Add(r, "last_ball_vx_mps", vLast);
  Add(r, "max_other_ball_speed_mps", others);
  Add(r, "max_momentum_rel_error", dp);
  Add(r, "max_ke_ratio", ke1 / ke0);
  r.pass = sim.finite() && std::abs(vLast - v0) <= 0.05 * std::abs(v0) && dp <= 1e-3 && ke1 <= ke0 * (1 + 1e-3);
}

void Soak(std::string_view engine, const HardCaseOptions& o, HardCaseResult& r) {
  r.criterion = "polygon_stress with N = 1000 for " + std::to_string(o.soakSteps) +
                " steps: no NaN and no body outside the box at any step (outside: its centre beyond a wall's "
                "inner face by more than its circumradius, so all of it is past the face)";
  Sim sim(r, engine, MakeScene("polygon_stress", 1000, 42));
  const Scene& scene = sim.scene();
  const AABB box = scene.bounds;
  std::vector<double> reach(scene.bodies.size(), 0);
  for (size_t i = 0; i < scene.bodies.size(); ++i) {
    for (Vec2 v : scene.bodies[i].vertices) reach[i] = std::max(reach[i], std::hypot(double(v.x), double(v.y)));
  }
  const double ke0 = sim.KE();
  // Deepest centre excursion past an inner face, bodies ever outside, first step one was.
  double deepest = 0, farthest = 0;
  int firstOutside = -1;
  std::vector<bool> everOutside(scene.bodies.size(), false);
  const auto start = std::chrono::steady_clock::now();
  auto lastReport = start;
  while (sim.steps() < o.soakSteps && sim.finite()) {
    sim.StepOnce();
    if (o.progressSeconds > 0 && sim.steps() % 100 == 0) {  // the clock read every 100 steps only
      const auto now = std::chrono::steady_clock::now();
      if (std::chrono::duration<double>(now - lastReport).count() >= o.progressSeconds) {
        lastReport = now;
        const double elapsed = std::chrono::duration<double>(now - start).count();
        const double eta = elapsed / sim.steps() * (o.soakSteps - sim.steps());
        std::fprintf(stderr, "  soak %s: step %d/%d (%.0f %%), %.0f steps/s, %.0f s elapsed, ETA %.0f s\n",
                     std::string(engine).c_str(), sim.steps(), o.soakSteps, 100.0 * sim.steps() / o.soakSteps,
                     sim.steps() / elapsed, elapsed, eta);
        std::fflush(stderr);
      }
    }
    for (size_t i = 0; i < scene.bodies.size(); ++i) {
      if (!scene.bodies[i].dynamic) continue;
      const Vec2 p = sim.states()[i].position;
      const double past = std::max({double(box.lower.x) - p.x, double(p.x) - box.upper.x,
                                    double(box.lower.y) - p.y, double(p.y) - box.upper.y});
      deepest = std::max(deepest, past);
      if (past > reach[i]) {
        everOutside[i] = true;
        farthest = std::max(farthest, past);
        if (firstOutside < 0) firstOutside = sim.steps();
      }
    }
  }
  const int outside = int(std::count(everOutside.begin(), everOutside.end(), true));
  Add(r, "steps", sim.steps());
  Add(r, "bodies_ever_outside", outside);
  Add(r, "first_step_outside", firstOutside);
  Add(r, "farthest_outside_m", farthest);
  Add(r, "deepest_centre_past_inner_face_m", deepest);
  Add(r, "ke_ratio_end_to_start", sim.KE() / ke0);
  Add(r, "max_speed_mps", MaxSpeed(scene, sim.states()));
  r.note = "The kinetic energy ratio is reported, not judged: elastic spinning polygons gain or lose energy "
           "over long runs in every engine here. A body is outside only when all of it is past a wall's inner "
           "face; a centre a little past the face (deepest_centre_past_inner_face_m) is a deep transient "
           "penetration, which fast-spinning triangles cause in every engine.";
  r.pass = sim.finite() && outside == 0;
}

// Issue #27's joint cases.
void HeavyChain(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "30 links of 0.5 m x 0.2 m (0.1 kg) on revolute joints under a static pin, a 100 kg ball (1000 "
                "links' mass) pinned below, default budget: over 60 s (sampled every 0.5 s) the pin-to-ball "
                "length stretches less than 1 % and the ball moves less than 0.05 m sideways";
  Sim sim(r, engine, MakeHeavyChain(MixingOf(engine)));
  const Scene& scene = sim.scene();
  const size_t ball = scene.bodies.size() - 1;
  const double radius = scene.bodies[ball].radius, length = 15.0;
  const Vec2 pin = scene.bodies[0].position;
  double stretch = 0, dx = 0;
  for (int step = kStepsPerSecond / 2; step <= int(kWindowSeconds * kStepsPerSecond); step += kStepsPerSecond / 2) {
    sim.RunTo(step);
    const Vec2 p = sim.states()[ball].position;
    stretch = std::max(stretch, (std::hypot(double(p.x - pin.x), double(p.y - pin.y)) - radius) / length - 1);
    dx = std::max(dx, std::abs(double(p.x)));
  }
  Add(r, "max_stretch", stretch);
  Add(r, "ball_max_dx_m", dx);
  r.note = "Quadrant solves a chain's revolute joints as one system per sub-step (WorldDef::jointChainSolve); "
           "joint by joint they stretch by tens of per cent at this ratio.";
  r.pass = sim.finite() && stretch < 0.01 && dx < 0.05;
}

// Each joint's anchor on both of its bodies, from the poses at load (the scene gives one world
// anchor); Max() is the widest the two have come apart since.
class JointGaps {
 public:
  JointGaps(const Scene& scene, const std::vector<BodyState>& states) : joints_(&scene.joints) {
    for (const JointDesc& j : scene.joints) {
      locals_.push_back({ToLocal(states[size_t(j.bodyA)], j.anchor), ToLocal(states[size_t(j.bodyB)], j.anchor)});
    }
  }
  double Max(const std::vector<BodyState>& states) const {
    double gap = 0;
    for (size_t k = 0; k < locals_.size(); ++k) {
      const Vec2 a = ToWorld(states[size_t((*joints_)[k].bodyA)], locals_[k][0]);
      const Vec2 b = ToWorld(states[size_t((*joints_)[k].bodyB)], locals_[k][1]);
      gap = std::max(gap, double(Length(a - b)));
    }
    return gap;
  }

 private:
  static Vec2 ToLocal(const BodyState& s, Vec2 p) {
    const Vec2 d = p - s.position;
    const double c = std::cos(double(s.angle)), sn = std::sin(double(s.angle));
    return Vec2{Real(c * d.x + sn * d.y), Real(-sn * d.x + c * d.y)};
  }
  static Vec2 ToWorld(const BodyState& s, Vec2 p) {
    const double c = std::cos(double(s.angle)), sn = std::sin(double(s.angle));
    return Vec2{Real(c * p.x - sn * p.y + s.position.x), Real(sn * p.x + c * p.y + s.position.y)};
  }
  const std::vector<JointDesc>* joints_;
  std::vector<std::array<Vec2, 2>> locals_;
};

void RagdollPile(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "12 ragdolls (9 bodies, 8 revolute joints with limits and 0.2 N m joint friction each) dropped "
                "into an 8 m box: no body ever leaves it, every joint's anchors stay within 0.05 m of each other, "
                "and at t = 60 s no body is faster than 0.5 m/s and the kinetic energy is below 1 % of its peak";
  Sim sim(r, engine, MakeRagdollPile(12, MixingOf(engine)));
  const Scene& scene = sim.scene();
  double peakKe = sim.KE(), outside = 0, gap = 0;
  const JointGaps gaps(scene, sim.states());
  const int end = int(kWindowSeconds * kStepsPerSecond);
  while (sim.steps() < end) {
    sim.StepOnce();
    peakKe = std::max(peakKe, sim.KE());
    for (size_t i = 3; i < scene.bodies.size(); ++i) {
      const Vec2 p = sim.states()[i].position;
      outside = std::max({outside, std::abs(double(p.x)) - 4.0, -double(p.y)});
    }
    if (sim.steps() % (kStepsPerSecond / 2) == 0) gap = std::max(gap, gaps.Max(sim.states()));
  }
  const double keEnd = sim.KE(), speedEnd = MaxSpeed(scene, sim.states());
  Add(r, "peak_ke_J", peakKe);
  Add(r, "ke_fraction_at_60s", keEnd / peakKe);
  Add(r, "max_speed_at_60s_mps", speedEnd);
  Add(r, "max_joint_gap_m", gap);
  Add(r, "most_outside_box_m", std::max(0.0, outside));
  r.pass = sim.finite() && outside <= 0 && gap < 0.05 && speedEnd < 0.5 && keEnd < 0.01 * peakKe;
}

void WheelTerrain(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "a 2 m, 3 kg car on two wheels (r = 0.4 m) driven by revolute motors (-6 rad/s, 20 N m) along a "
                "bumpy one-sided chain road of 1 m segments (slopes up to 0.35): over 60 s (every step) no wheel "
                "sinks into the road by more than 0.02 m or drops through it, the chassis tilts less than 0.8 rad "
                "and the wheel pins open by less than 0.05 m; at t = 60 s the car has driven more than 100 m "
                "(it does not catch at the joins)";
  Sim sim(r, engine, MakeWheelTerrain(MixingOf(engine)));
  const Scene& scene = sim.scene();
  const size_t chassis = scene.bodies.size() - 3;
  const double startX = scene.bodies[chassis].position.x;
  const JointGaps gaps(scene, sim.states());
  // The road is the polyline through (x, TerrainHeight(x)) at whole metres.
  auto road = [](double x) {
    const double x0 = std::floor(x), t = x - x0;
    return (1 - t) * TerrainHeight(x0) + t * TerrainHeight(x0 + 1);
  };
  auto sink = [](Vec2 c, double radius) {  // how far a wheel's circle reaches below the road
    double nearest = 1e30;
    for (double x0 = std::floor(double(c.x)) - 2; x0 <= std::floor(double(c.x)) + 2; ++x0) {
      const double ax = x0, ay = TerrainHeight(x0), bx = x0 + 1, by = TerrainHeight(x0 + 1);
      const double dx = bx - ax, dy = by - ay;
      const double t = std::clamp(((c.x - ax) * dx + (c.y - ay) * dy) / (dx * dx + dy * dy), 0.0, 1.0);
      nearest = std::min(nearest, std::hypot(c.x - (ax + t * dx), c.y - (ay + t * dy)));
    }
    return radius - nearest;
  };
  double deepest = 0, tilt = 0, gap = 0;
  bool through = false;
  while (sim.steps() < int(kWindowSeconds * kStepsPerSecond)) {
    sim.StepOnce();
    for (size_t w = chassis + 1; w < chassis + 3; ++w) {
      const Vec2 c = sim.states()[w].position;
      deepest = std::max(deepest, sink(c, 0.4));
      through = through || double(c.y) < road(double(c.x));
    }
    tilt = std::max(tilt, std::abs(double(sim.states()[chassis].angle)));
    gap = std::max(gap, gaps.Max(sim.states()));
  }
  const double driven = sim.states()[chassis].position.x - startX;
  Add(r, "max_wheel_sink_m", std::max(0.0, deepest));
  Add(r, "max_tilt_rad", tilt);
  Add(r, "max_pin_gap_m", gap);
  Add(r, "driven_m", driven);
  Add(r, "wheel_below_road", through ? 1 : 0);
  r.pass = sim.finite() && !through && deepest < 0.02 && tilt < 0.8 && gap < 0.05 && driven > 100;
}

void HangingGrid(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "Box2D 3's joint grid at 30 x 30 (893 circles 1 m apart, 1740 revolute joints) hung from the top "
                "row's 7 middle bodies, falling from level, with damping 0.1 /s: every joint's anchors stay within "
                "0.05 m of each other (sampled every 0.5 s up to t = 60 s), and at t = 60 s no body is faster "
                "than 0.5 m/s and the kinetic energy is below 1 % of its peak";
  Sim sim(r, engine, MakeHangingGrid(MixingOf(engine)));
  const Scene& scene = sim.scene();
  const JointGaps gaps(scene, sim.states());
  double peakKe = sim.KE(), gap = 0, lowest = 0;
  while (sim.steps() < int(kWindowSeconds * kStepsPerSecond)) {
    sim.StepOnce();
    peakKe = std::max(peakKe, sim.KE());
    if (sim.steps() % (kStepsPerSecond / 2) == 0) gap = std::max(gap, gaps.Max(sim.states()));
  }
  for (const BodyState& b : sim.states()) lowest = std::min(lowest, double(b.position.y));
  const double keEnd = sim.KE(), speedEnd = MaxSpeed(scene, sim.states());
  Add(r, "peak_ke_J", peakKe);
  Add(r, "ke_fraction_at_60s", keEnd / peakKe);
  Add(r, "max_speed_at_60s_mps", speedEnd);
  Add(r, "max_joint_gap_m", gap);
  Add(r, "joint_gap_at_60s_m", gaps.Max(sim.states()));
  Add(r, "lowest_body_at_60s_m", lowest);
  r.pass = sim.finite() && gap < 0.05 && speedEnd < 0.5 && keEnd < 0.01 * peakKe;
}

void PrismaticStop(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "a 1 kg box on a horizontal prismatic joint (travel [-2, 2] m) launched at 10 m/s into its stop, "
                "gravity across the axis: over 60 s (every step) it passes the stop by less than 0.02 m, leaves "
                "the axis by less than 0.01 m and turns less than 0.01 rad, and it rebounds at under 1 m/s";
  Sim sim(r, engine, MakePrismaticStop(MixingOf(engine)));
  double beyond = 0, across = 0, turn = 0, rebound = 0;
  while (sim.steps() < int(kWindowSeconds * kStepsPerSecond)) {
    sim.StepOnce();
    const BodyState& b = sim.states()[1];
    beyond = std::max({beyond, double(b.position.x) - 2, -2 - double(b.position.x)});
    across = std::max(across, std::abs(double(b.position.y) - 5));
    turn = std::max(turn, std::abs(double(b.angle)));
    if (b.position.x > Real(1.5)) rebound = std::max(rebound, -double(b.velocity.x));
  }
  Add(r, "max_past_stop_m", std::max(0.0, beyond));
  Add(r, "max_off_axis_m", across);
  Add(r, "max_turn_rad", turn);
  Add(r, "max_rebound_mps", rebound);
  r.pass = sim.finite() && beyond < 0.02 && across < 0.01 && turn < 0.01 && rebound < 1;
}

void WeldBeam(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "ten 1 m x 0.2 m segments (0.2 kg) welded end to end, cantilevered level from a static block "
                "under gravity, default budget: over 60 s (every step) the tip sags less than 0.1 m (1 % of the "
                "span) and no weld opens by more than 0.01 m; at 60 s the tip is slower than 0.01 m/s";
  Sim sim(r, engine, MakeWeldBeam(MixingOf(engine)));
  const Scene& scene = sim.scene();
  const size_t tip = scene.bodies.size() - 1;
  const double tipY = scene.bodies[tip].position.y;
  double sag = 0, open = 0;
  auto end = [&](size_t i, double side) {  // a segment's end on its axis, side -1 (root) or +1
    const BodyState& b = sim.states()[i];
    return Vec2{Real(b.position.x + side * 0.5 * std::cos(double(b.angle))), Real(b.position.y + side * 0.5 * std::sin(double(b.angle)))};
  };
  while (sim.steps() < int(kWindowSeconds * kStepsPerSecond)) {
    sim.StepOnce();
    sag = std::max(sag, tipY - sim.states()[tip].position.y);
    for (size_t i = 2; i < scene.bodies.size(); ++i) open = std::max(open, double(Length(end(i, -1) - end(i - 1, 1))));
  }
  const double speed = Length(sim.states()[tip].velocity);
  Add(r, "tip_max_sag_m", sag);
  Add(r, "max_weld_gap_m", open);
  Add(r, "tip_speed_at_60s_mps", speed);
  r.note = "A weld is held by a stiff spring in Quadrant (WorldDef::jointHertz) and Box2D 3, by iterations in "
           "Box2D 2.4.1 and Chipmunk: the beam sags by what the welds give.";
  r.pass = sim.finite() && sag < 0.1 && open < 0.01 && speed < 0.01;
}

// ---- Solver2D's contact scenes (issue #26 item 2) --------------------------------------------

void SingleBox(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "a 2 m box dropped from 3 m onto the ground (friction 0.5): from t = 2 s to 60 s (every step) its "
                "centre stays within 0.01 m of its t = 2 s position and 0.02 m of its resting height (1 m), it "
                "turns less than 0.01 rad, and at 60 s it is slower than 0.01 m/s";
  Sim sim(r, engine, MakeSingleBox(MixingOf(engine)));
  const int from = 2 * kStepsPerSecond, end = int(kWindowSeconds * kStepsPerSecond);
  double drift = 0, height = 0, turn = 0, pen = 0;
  BodyState atFrom;
  while (sim.steps() < end) {
    sim.StepOnce();
    const BodyState& b = sim.states()[1];
    if (sim.steps() % (kStepsPerSecond / 2) == 0) pen = std::max(pen, MaxPenetrationOf(sim.scene(), sim.states()));
    if (sim.steps() == from) atFrom = b;
    if (sim.steps() < from) continue;
    drift = std::max(drift, Displacement(atFrom, b));
    height = std::max(height, std::abs(double(b.position.y) - 1));
    turn = std::max(turn, std::abs(double(b.angle)));
  }
  const double speed = MaxSpeed(sim.scene(), sim.states());
  Add(r, "max_drift_after_2s_m", drift);
  Add(r, "max_height_error_m", height);
  Add(r, "max_turn_rad", turn);
  Add(r, "speed_at_60s_mps", speed);
  Add(r, "max_penetration_m", pen);
  r.note = "Box2D 2.4.1's 0.01 m polygon skins keep its box about 0.015 m above the ground's face.";
  r.pass = sim.finite() && drift < 0.01 && height < 0.02 && turn < 0.01 && speed < 0.01;
}

void WarmStartEnergy(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "a 78.5 kg ball on two 0.785 kg balls (r = 0.5 m) in a column; at t = 2 s the heavy ball is lifted "
                "away at 20 m/s: from then to t = 60 s (every step) neither light ball rises more than 0.01 m above "
                "where it comes to rest (its height at 60 s), and at 60 s both are slower than 0.01 m/s";
  Sim sim(r, engine, MakeWarmStartEnergy(MixingOf(engine)));
  const int end = int(kWindowSeconds * kStepsPerSecond);
  double top[3] = {0, -1e300, -1e300}, rise = 0, pen = 0;
  while (sim.steps() < end) {
    sim.StepOnce();
    if (sim.steps() % (kStepsPerSecond / 2) == 0) {
      // The lifted ball is left out: only the column's own contacts.
      std::vector<BodyState> column(sim.states().begin(), sim.states().begin() + 3);
      Scene scene = sim.scene();
      scene.bodies.resize(3);
      pen = std::max(pen, MaxPenetrationOf(scene, column));
    }
    if (sim.steps() < kWarmStartLiftStep) continue;
    for (int k = 1; k <= 2; ++k) {
      top[k] = std::max(top[k], double(sim.states()[size_t(k)].position.y));
      rise = std::max(rise, double(sim.states()[size_t(k)].velocity.y));
    }
  }
  const double over = std::max(top[1] - sim.states()[1].position.y, top[2] - sim.states()[2].position.y);
  const double speed = std::max(Length(sim.states()[1].velocity), Length(sim.states()[2].velocity));
  Add(r, "max_rise_above_rest_m", over);
  Add(r, "max_upward_speed_after_lift_mps", rise);
  Add(r, "light_speed_at_60s_mps", speed);
  Add(r, "middle_height_at_60s_m", sim.states()[2].position.y);
  Add(r, "heavy_height_at_60s_m", sim.states()[3].position.y);
  Add(r, "max_penetration_m", pen);
  r.note = "Solver2D destroys the heavy ball at step 120; the adapters cannot destroy a body, so the scene's driver "
           "sets its velocity to 20 m/s upward at every step from step 120 on. The light balls' contacts still "
           "hold the impulses the 100:1 load needed: warm-starting them unchecked launches the balls.";
  r.pass = sim.finite() && over < 0.01 && speed < 0.01 && sim.states()[3].position.y > 10;
}

void HighMassRatio1(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "three base-10 pyramids of 2 m boxes (4 kg, friction 0.5) with a 400, 800 and 1200 kg box dropped "
                "2 m onto each apex (100:1 to 300:1): no box moves more than 0.05 m from its t = 2 s pose up to "
                "t = 60 s, largest penetration below 0.05 m (both sampled every 0.5 s)";
  Sim sim(r, engine, MakeHighMassRatio(1, MixingOf(engine)));
  const size_t n = sim.scene().bodies.size();
  PileRun run = RunPile(sim, kWindowSeconds, 1, n, 2);
  double heavy = 0;
  for (size_t j = 1; j <= 3; ++j) heavy = std::max(heavy, run.drift[1 + 55 * j - 1]);
  Add(r, "max_box_drift_m", run.maxDrift);
  Add(r, "heavy_max_drift_m", heavy);
  Add(r, "max_penetration_m", run.maxPenetration);
  Add(r, "settle_0_to_2s_m", run.settle);
  r.note = "The heavy boxes land at t = 0.63 s; the window starts at 2 s.";
  r.pass = sim.finite() && run.maxDrift < 0.05 && run.maxPenetration < 0.05;
}

void HighMassRatio23(std::string_view engine, HardCaseResult& r, int variant) {
  r.criterion = std::string("a 20 m box (400 kg) dropped 15 m onto two 1 m boxes (1 kg, friction 0.6) on a ") +
                (variant == 2 ? "segment" : "thick box") +
                " ground, 400:1, landing at 17.3 m/s: from t = 3 s to 60 s (sampled every 0.5 s) its bottom stays "
                "within 0.05 m of the small boxes' top (1 m), no body moves more than 0.05 m from its t = 3 s pose, "
                "and the largest penetration stays below 0.05 m";
  Sim sim(r, engine, MakeHighMassRatio(variant, MixingOf(engine)));
  const size_t big = 3;
  const int from = 3 * kStepsPerSecond;
  double low = 0;
  const std::vector<BodyState> start = sim.states();
  std::vector<BodyState> atFrom;
  double drift = 0, pen = 0, landPen = 0;
  for (int step = kStepsPerSecond / 2; step <= int(kWindowSeconds * kStepsPerSecond); step += kStepsPerSecond / 2) {
    sim.RunTo(step);
    const double p = MaxPenetrationOf(sim.scene(), sim.states());
    if (step < from) {
      landPen = std::max(landPen, p);
      continue;
    }
    if (step == from) atFrom = sim.states();
    pen = std::max(pen, p);
    low = std::max(low, 1 - (double(sim.states()[big].position.y) - 10));
    drift = std::max(drift, MaxDisplacement(atFrom, sim.states(), 1, 4));
  }
  Add(r, "big_bottom_below_supports_m", low);
  Add(r, "max_drift_after_3s_m", drift);
  Add(r, "max_penetration_m", pen);
  Add(r, "max_penetration_before_3s_m", landPen);
  r.note = "The big box lands at t = 1.73 s; the window starts at 3 s, the landing's penetration is reported only.";
  if (variant == 2) r.note += " Bullet has no segment shape in its 2D mode.";
  r.pass = sim.finite() && low < 0.05 && drift < 0.05 && pen < 0.05;
}

void HighMassRatio2(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) { HighMassRatio23(engine, r, 2); }
void HighMassRatio3(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) { HighMassRatio23(engine, r, 3); }

void Rush(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "400 balls (r = 0.5 m, 78.5 kg, friction 0.2) on a spiral, zero gravity, each pulled toward a static "
                "ball at the centre by 1000 N (a pile whose inner contacts carry tens of balls' pull): no ball ever "
                "comes within 0.75 m of the centre (a quarter of its diameter into the core), the largest "
                "penetration stays below 0.25 m (a quarter of a diameter; sampled every 0.5 s), and at 60 s no ball "
                "is faster than 0.5 m/s and the kinetic energy is below 1 % of its peak";
  Sim sim(r, engine, MakeRush(MixingOf(engine)));
  const Scene& scene = sim.scene();
  double peakKe = 0, closest = 1e300, pen = 0;
  while (sim.steps() < int(kWindowSeconds * kStepsPerSecond)) {
    sim.StepOnce();
    peakKe = std::max(peakKe, sim.KE());
    for (size_t i = 1; i < scene.bodies.size(); ++i) closest = std::min(closest, double(Length(sim.states()[i].position)));
    if (sim.steps() % (kStepsPerSecond / 2) == 0) pen = std::max(pen, MaxPenetrationOf(scene, sim.states()));
  }
  const double keEnd = sim.KE(), speedEnd = MaxSpeed(scene, sim.states());
  Add(r, "closest_to_centre_m", closest);
  Add(r, "max_penetration_m", pen);
  Add(r, "peak_ke_J", peakKe);
  Add(r, "ke_fraction_at_60s", keEnd / peakKe);
  Add(r, "max_speed_at_60s_mps", speedEnd);
  r.note = "The pull is given through the velocity each step (the scene's driver, v += dt F / m), as a force acts "
           "over one step. Every engine here lets the squeezed pile overlap by 0.15-0.22 m and the inner balls into "
           "the core by 0.11-0.15 m (measured at the case's making): the bounds say the pile is not crushed through, "
           "not that it is rigid.";
  r.pass = sim.finite() && closest > 0.75 && pen < 0.25 && speedEnd < 0.5 && keEnd < 0.01 * peakKe;
}

void DoubleDomino(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "15 dominoes (0.25 m x 1 m, 1 m apart, friction 0.6), the first pushed: each tips past 0.2 rad no "
                "earlier than the one before it, all 15 within 10 s, and they come to rest: from t = 50 s to 60 s "
                "(every step) no domino moves more than 0.01 m, and at 60 s none is faster than 0.01 m/s";
  Sim sim(r, engine, MakeDoubleDomino(MixingOf(engine)));
  std::vector<int> tipped(kDominoCount, -1);
  std::vector<BodyState> at50;
  double late = 0;
  const int settle = 50 * kStepsPerSecond;
  while (sim.steps() < int(kWindowSeconds * kStepsPerSecond)) {
    sim.StepOnce();
    for (int k = 0; k < kDominoCount; ++k) {
      if (tipped[k] < 0 && std::abs(double(sim.states()[size_t(k + 1)].angle)) > 0.2) tipped[k] = sim.steps();
    }
    if (sim.steps() == settle) at50 = sim.states();
    if (sim.steps() > settle) late = std::max(late, MaxDisplacement(at50, sim.states(), 1, size_t(kDominoCount + 1)));
  }
  bool inOrder = true;
  int fallen = 0, last = 0;
  for (int k = 0; k < kDominoCount; ++k) {
    if (tipped[k] < 0) continue;
    ++fallen;
    last = std::max(last, tipped[k]);
    if (k > 0 && (tipped[k - 1] < 0 || tipped[k] < tipped[k - 1])) inOrder = false;
  }
  const double speed = MaxSpeed(sim.scene(), sim.states());
  Add(r, "dominoes_tipped", fallen);
  Add(r, "tipped_in_order", inOrder ? 1 : 0);
  Add(r, "last_tip_s", double(last) / kStepsPerSecond);
  Add(r, "max_move_50_to_60s_m", late);
  Add(r, "max_speed_at_60s_mps", speed);
  r.pass = sim.finite() && fallen == kDominoCount && inOrder && last <= 10 * kStepsPerSecond && late < 0.01 &&
           speed < 0.01;
}

void CircleStack(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "ten balls of radius 1 m dropped in a column (each 1 m onto the one below, friction 0.6): every "
                "centre stays within 0.01 m of x = 0 at every step up to t = 60 s, from t = 10 s ball k (0 at the "
                "bottom) is within 0.01 (k + 1) m of its resting height 1 + 2k m (1 cm per contact below it), and at "
                "60 s all are slower than 0.01 m/s";
  Sim sim(r, engine, MakeCircleStack(MixingOf(engine)));
  double side = 0, height = 0;
  while (sim.steps() < int(kWindowSeconds * kStepsPerSecond)) {
    sim.StepOnce();
    for (int k = 0; k < kCircleStackCount; ++k) {
      const BodyState& b = sim.states()[size_t(k + 1)];
      side = std::max(side, std::abs(double(b.position.x)));
      // Relative to the allowance: above 1 means a ball sits more than 1 cm per contact off its height.
      if (sim.steps() >= 10 * kStepsPerSecond) height = std::max(height, std::abs(double(b.position.y) - (1 + 2 * k)) / (0.01 * (k + 1)));
    }
  }
  const double speed = MaxSpeed(sim.scene(), sim.states());
  Add(r, "max_sideways_m", side);
  Add(r, "max_height_error_per_allowance", height);
  Add(r, "top_height_at_60s_m", sim.states().back().position.y);
  Add(r, "max_speed_at_60s_mps", speed);
  r.note = "Box2D 2.4.1 lets each contact overlap by its linear slop (0.005 m) and its ground box has a 0.01 m skin.";
  r.pass = sim.finite() && side < 0.01 && height <= 1 && speed < 0.01;
}

// A far scene against the same scene at the origin: the largest difference of any body's position
// relative to its scene's origin, sampled every 0.5 s from t = `from` to 60 s, with the near run's
// own drift from t = `from`.
struct FarRun {
  double maxDiff = 0, nearDrift = 0, farDrift = 0, farMaxSpeed = 0;
};
FarRun RunNearAndFar(Sim& near, Sim& far, Vec2 origin, double from) {
  FarRun run;
  const int fromStep = int(std::lround(from * kStepsPerSecond));
  std::vector<BodyState> nearFrom, farFrom;
  const size_t n = near.states().size();
  for (int step = 1; step <= int(kWindowSeconds * kStepsPerSecond); ++step) {
    near.RunTo(step);
    far.RunTo(step);
    run.farMaxSpeed = std::max(run.farMaxSpeed, MaxSpeed(far.scene(), far.states()));
    if (step % (kStepsPerSecond / 2) != 0 || step < fromStep) continue;
    if (step == fromStep) {
      nearFrom = near.states();
      farFrom = far.states();
    }
    for (size_t i = 0; i < n; ++i) {
      if (!near.scene().bodies[i].dynamic) continue;
      const BodyState& a = near.states()[i];
      const BodyState& b = far.states()[i];
      const double dx = (double(b.position.x) - double(origin.x)) - a.position.x;
      const double dy = (double(b.position.y) - double(origin.y)) - a.position.y;
      run.maxDiff = std::max(run.maxDiff, std::hypot(dx, dy));
    }
    run.nearDrift = std::max(run.nearDrift, MaxDisplacement(nearFrom, near.states(), 1, n));
    run.farDrift = std::max(run.farDrift, MaxDisplacement(farFrom, far.states(), 1, n));
  }
  return run;
}

void FarStack(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "Solver2D's far stack (a plank on a ball and a box, two squares dropped onto it) at (4e4, -2.5e4) "
                "and at the origin: from t = 1 s to 60 s (sampled every 0.5 s) every far body is within 0.02 m of "
                "the near one (relative to its origin; float read-back resolves 3.9 mm there) and no body of "
                "either run moves more than 0.02 m from its t = 1 s pose";
  const Mixing mixing = MixingOf(engine);
  HardCaseResult nearResult;
  Sim near(nearResult, engine, MakeFarStack({0, 0}, mixing));
  Sim far(r, engine, MakeFarStack(kFarStackOrigin, mixing));
  const FarRun run = RunNearAndFar(near, far, kFarStackOrigin, 1);
  Add(r, "max_far_minus_near_m", run.maxDiff);
  Add(r, "near_max_drift_m", run.nearDrift);
  Add(r, "far_max_drift_m", run.farDrift);
  r.pass = near.finite() && far.finite() && run.maxDiff < 0.02 && run.nearDrift < 0.02 && run.farDrift < 0.02;
}

void FarRecovery(std::string_view engine, const HardCaseOptions&, HardCaseResult& r) {
  r.criterion = "a base-4 pyramid of 1 m boxes spawned 25 % overlapped at (8e4, -7e4) and at the origin, default "
                "budget: no far box is ever faster than 2 m/s, and from t = 2 s to 60 s (sampled every 0.5 s) every "
                "far box is within 0.05 m of the near one (relative to its origin; float read-back resolves 7.8 mm "
                "there) and neither pile moves more than 0.02 m from its t = 2 s pose";
  const Mixing mixing = MixingOf(engine);
  HardCaseResult nearResult;
  Sim near(nearResult, engine, MakeFarRecovery({0, 0}, mixing));
  Sim far(r, engine, MakeFarRecovery(kFarRecoveryOrigin, mixing));
  const FarRun run = RunNearAndFar(near, far, kFarRecoveryOrigin, 2);
  Add(r, "max_far_minus_near_m", run.maxDiff);
  Add(r, "near_max_drift_m", run.nearDrift);
  Add(r, "far_max_drift_m", run.farDrift);
  Add(r, "far_max_speed_mps", run.farMaxSpeed);
  Add(r, "near_max_overlap_at_60s_m", MaxPenetrationOf(near.scene(), near.states()));
  r.pass = near.finite() && far.finite() && run.farMaxSpeed < 2 && run.maxDiff < 0.05 && run.nearDrift < 0.02 &&
           run.farDrift < 0.02;
}

struct CaseEntry {
  const char* name;
  CaseFn fn;
};

constexpr CaseEntry kCases[] = {
    {"vertical_stack", VerticalStack}, {"pyramid", PyramidCase},
    {"mass_ratio_100", MassRatio100},  {"mass_ratio_400", MassRatio400},
    {"arch", Arch},                    {"card_house", CardHouse},
    {"friction_ramp", FrictionRamp},   {"restitution_drop", RestitutionDrop},
    {"overlap_recovery", OverlapRecovery}, {"confined", Confined},
    {"far_from_origin", FarFromOrigin}, {"newtons_cradle", NewtonsCradle},
    {"soak", Soak},
    {"tall_stack", TallStack30},       {"tall_stack_50", TallStack50},
    {"heavy_on_supports", HeavyOnSupports},
    {"heavy_on_slab", HeavyOnSlab},      {"closed_box", ClosedBox},
    {"heavy_chain", HeavyChain},         {"ragdoll_pile", RagdollPile},
    {"prismatic_stop", PrismaticStop},   {"weld_beam", WeldBeam},
    {"wheel_terrain", WheelTerrain},     {"hanging_grid", HangingGrid},
    // Solver2D's contact scenes (issue #26 item 2).
    {"single_box", SingleBox},           {"warm_start_energy", WarmStartEnergy},
    {"high_mass_ratio_1", HighMassRatio1}, {"high_mass_ratio_2", HighMassRatio2},
    {"high_mass_ratio_3", HighMassRatio3}, {"rush", Rush},
    {"double_domino", DoubleDomino},     {"circle_stack", CircleStack},
    {"far_stack", FarStack},             {"far_recovery", FarRecovery},
};

}  // namespace

double HardCaseResult::Get(std::string_view figure) const {
  for (const Measured& m : measured) {
    if (m.name == figure) return m.value;
  }
  throw Error("hard case " + name + ": no measured figure '" + std::string(figure) + "'");
}

std::vector<std::string> HardCaseNames() {
  std::vector<std::string> names;
  for (const CaseEntry& c : kCases) names.push_back(c.name);
  return names;
}

double MaxPenetration(const Scene& scene, const std::vector<BodyState>& states) {
  return MaxPenetrationOf(scene, states);
}

HardCaseResult RunHardCase(std::string_view name, std::string_view engine, const HardCaseOptions& options) {
  if (options.soakSteps < 1) throw Error("hard cases: soak steps must be >= 1");
  const CaseEntry* entry = nullptr;
  for (const CaseEntry& c : kCases) {
    if (name == c.name) entry = &c;
  }
  if (!entry) {
    std::string known;
    for (const CaseEntry& c : kCases) known += (known.empty() ? "" : ", ") + std::string(c.name);
    throw Error("unknown hard case '" + std::string(name) + "' (known: " + known + ")");
  }
  MixingOf(engine);  // refuses unknown engine names before anything runs
  HardCaseResult r;
  r.name = entry->name;
  r.engine = std::string(engine);
  const auto t0 = std::chrono::steady_clock::now();
  // The soak prints its own progress lines (with a rate and an ETA).
  progress = {name == "soak" ? 0.0 : options.progressSeconds, std::string(name) + " " + std::string(engine), t0};
  try {
    entry->fn(engine, options, r);
  } catch (const Unsupported& e) {
    r.supported = false;
    r.unsupported = e.what();
    r.pass = false;
    r.measured.clear();
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace quadrant::scene
