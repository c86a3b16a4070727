// quadrant_accuracy: what accuracy costs in time (issue 6). Sweeps solver settings of Quadrant
// (thesis; pgs with 1..32 velocity iterations; soft_step with 1..8 sub-steps; jacobi, the
// distributed world's deterministic solver, with 8..64 iterations), Box2D 2.4 with
// 1..32 velocity iterations, and Bullet and Chipmunk at their 8-iteration defaults over piles
// (vertical stack, base-20 pyramid, mass ratios 100 and 400, and issue #13's 30-box stack and
// 1000:1 boxes on small supports and on one slab) and the thesis's stress scenes
// (circles and polygons, N = 1000), and writes each setting's time per step next to error
// measures taken from the scene API's read-back only. Then it runs the hard cases of those piles
// on every Quadrant setting, so the report can name the cheapest setting that passes each.
//
//   quadrant_accuracy --out DIR [--json FILE] [--quick] [--settings a,b] [--scenes a,b]
//                     [--hard-cases a,b|none] [--steps N] [--repetitions R] [--count N]
//
// Writes FILE (default DIR/accuracy.json); tools/accuracy_report.py turns it into accuracy.md and
// accuracy.png (and merges the double-precision build's points into it). The precision of the
// binary (float or double, CMake option QUADRANT_DOUBLE) is recorded with every point.
//
// Method. Every (setting, scene) is run once untimed with a read-back after every step, which
// gives the error measures, then timed in `repetitions` runs with nothing but Step() inside the
// clock (steady_clock around the whole loop; Load outside). The timed runs interleave: each
// repetition goes over every scene and setting before the next starts, in alternating order, so
// a slow phase of this shared machine spreads over all settings. ms per step is the median.
// Exit status: 0, or 2 on bad arguments.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "cli_args.h"
#include "hard_case_checks.h"
#include "quadrant/error.h"
#include "report_common.h"
#include "scenes.h"

namespace qs = quadrant::scene;
namespace rp = quadrant::report;

namespace {

using Clock = std::chrono::steady_clock;
constexpr int kStepsPerSecond = 60;  // every scene here runs at dt = 1/60
constexpr const char* kPrecision = sizeof(quadrant::Real) == sizeof(double) ? "double" : "float";

// ---- Settings ---------------------------------------------------------------------------------

// One point of the sweep: how an engine is asked to run. `id` is what --settings takes and what
// the report prints; `adapter` is the name MakeAdapter takes; `iterations` > 0 overrides the
// scene's velocity iterations (Box2D, Bullet and Chipmunk take them from the scene, they have no
// variant names; the piles' builders now give some cases a larger budget, which the sweep
// overrides so that a setting means the same on every scene).
struct Setting {
  std::string id;
  std::string adapter;
  std::string engine;
  std::string solver;
  std::string setting;
  int iterations = 0;
};

Setting QuadrantSetting(const std::string& variant, const std::string& solver, const std::string& setting,
                        int iterations = 0) {
  return {"quadrant:" + variant, "quadrant:" + variant, "quadrant", solver, setting, iterations};
}

std::vector<Setting> AllSettings() {
  std::vector<Setting> s;
  s.push_back(QuadrantSetting("thesis", "thesis", "one impulse per contact"));
  for (int it : {1, 2, 4, 8, 16, 32}) {
    s.push_back(QuadrantSetting("pgs+it" + std::to_string(it), "pgs", "it" + std::to_string(it), it));
  }
  for (int sub : {1, 2, 4, 8}) {
    s.push_back(QuadrantSetting("soft_step+sub" + std::to_string(sub), "soft_step", "sub" + std::to_string(sub)));
  }
  // What the distributed world's bit-identical option costs against soft_step (issue #30).
  for (int it : {8, 16, 32, 64}) {
    s.push_back(QuadrantSetting("jacobi+it" + std::to_string(it), "jacobi", "it" + std::to_string(it), it));
  }
  for (int it : {1, 2, 4, 8, 16, 32}) {
    const std::string n = std::to_string(it);
    s.push_back({"box2d:it" + n, "box2d", "box2d", "pgs (Box2D 2.4.1)", "it" + n, it});
  }
  s.push_back({"bullet", "bullet", "bullet", "sequential impulse (Bullet 3.24)", "default (8 it)", 8});
  s.push_back({"chipmunk", "chipmunk", "chipmunk", "impulse (Chipmunk 7)", "default (8 it)", 8});
  return s;
}

// --quick: one cheap and one default point per family, enough to exercise every code path.
const std::vector<std::string> kQuickSettings = {
    "quadrant:thesis",         "quadrant:pgs+it1", "quadrant:pgs+it8", "quadrant:soft_step+sub1",
    "quadrant:soft_step+sub4", "box2d:it8",        "bullet",           "chipmunk"};

// ---- Scenes -----------------------------------------------------------------------------------

enum class Kind { kPile, kStress };

Kind KindOf(const std::string& scene) {
  return scene == "circle_stress" || scene == "polygon_stress" ? Kind::kStress : Kind::kPile;
}

// Issue #13's cases (tall_stack, heavy_on_supports, heavy_on_slab) are piles at the default budget.
const std::vector<std::string> kAllScenes = {"vertical_stack", "pyramid",           "mass_ratio_100",
                                             "mass_ratio_400", "tall_stack",        "heavy_on_supports",
                                             "heavy_on_slab",  "circle_stress",     "polygon_stress"};
const std::vector<std::string> kHardCases = {"vertical_stack", "pyramid",           "mass_ratio_100", "mass_ratio_400",
                                             "tall_stack",     "heavy_on_supports", "heavy_on_slab"};

// Piles are built with the engine's material mixing, as the hard cases are, so every engine
// simulates the same mixed friction; the stress scenes mix to friction 0 and restitution 1 under
// either rule.
qs::Scene BuildScene(const std::string& name, const Setting& setting, int stressCount) {
  const qs::Mixing mixing = qs::MixingOf(setting.adapter);
  qs::Scene scene;
  if (name == "vertical_stack") {
    scene = qs::MakeVerticalStack(15, mixing);
  } else if (name == "pyramid") {
    scene = qs::MakePyramid(20, {}, mixing);
  } else if (name == "mass_ratio_100") {
    scene = qs::MakeMassRatio(100, mixing);
  } else if (name == "mass_ratio_400") {
    scene = qs::MakeMassRatio(400, mixing);
  } else if (name == "tall_stack") {
    scene = qs::MakeTallStack(30, mixing);
  } else if (name == "heavy_on_supports") {
    scene = qs::MakeHeavyOnSupports(mixing);
  } else if (name == "heavy_on_slab") {
    scene = qs::MakeHeavyOnSlab(mixing);
  } else {
    scene = qs::MakeScene(name, stressCount, 42);
  }
  if (setting.iterations > 0) scene.velocityIterations = setting.iterations;
  return scene;
}

// ---- Error measures from the read-back --------------------------------------------------------

struct Aabb {
  double lx, ly, ux, uy;
};

// The world box of a body at a read-back pose (exact for polygons: their rotated vertices).
Aabb BodyBox(const qs::BodyDesc& b, const qs::BodyState& s) {
  const double px = s.position.x, py = s.position.y;
  if (b.shape == qs::ShapeKind::kCircle) return {px - b.radius, py - b.radius, px + b.radius, py + b.radius};
  const double c = std::cos(double(s.angle)), sn = std::sin(double(s.angle));
  Aabb box{1e300, 1e300, -1e300, -1e300};
  for (const quadrant::Vec2& v : b.vertices) {
    const double x = px + c * v.x - sn * v.y, y = py + sn * v.x + c * v.y;
    box = {std::min(box.lx, x), std::min(box.ly, y), std::max(box.ux, x), std::max(box.uy, y)};
  }
  return box;
}

// Penetration depths of every overlapping pair (not both static) at one read-back: candidate
// pairs by sweep and prune on x over exact boxes, then circle pairs from centres and radii and
// every other pair through hard_case_checks' MaxPenetration on a two-body scene (so polygon
// depths come from the same separating-axis code as the hard cases').
class PenetrationMeter {
 public:
  explicit PenetrationMeter(const qs::Scene& scene) : scene_(scene) {
    pair_.bodies.resize(2);
    pairStates_.resize(2);
  }

  void Sample(const std::vector<qs::BodyState>& states) {
    const size_t n = states.size();
    boxes_.resize(n);
    order_.resize(n);
    for (size_t i = 0; i < n; ++i) {
      boxes_[i] = BodyBox(scene_.bodies[i], states[i]);
      order_[i] = i;
    }
    std::sort(order_.begin(), order_.end(), [this](size_t a, size_t b) { return boxes_[a].lx < boxes_[b].lx; });
    int overlaps = 0;
    for (size_t k = 0; k < n; ++k) {
      const size_t i = order_[k];
      for (size_t m = k + 1; m < n && boxes_[order_[m]].lx <= boxes_[i].ux; ++m) {
        const size_t j = order_[m];
        if (!scene_.bodies[i].dynamic && !scene_.bodies[j].dynamic) continue;
        if (boxes_[j].ly > boxes_[i].uy || boxes_[i].ly > boxes_[j].uy) continue;
        const double depth = Depth(i, j, states);
        if (depth > 0) {
          ++overlaps;
          sum_ += depth;
          max_ = std::max(max_, depth);
        }
      }
    }
    count_ += overlaps;
    ++samples_;
  }

  double Max() const { return max_; }
  double Mean() const { return count_ > 0 ? sum_ / double(count_) : 0.0; }
  double OverlapsPerSample() const { return samples_ > 0 ? double(count_) / samples_ : 0.0; }

 private:
  double Depth(size_t i, size_t j, const std::vector<qs::BodyState>& states) {
    const qs::BodyDesc& a = scene_.bodies[i];
    const qs::BodyDesc& b = scene_.bodies[j];
    if (a.shape == qs::ShapeKind::kCircle && b.shape == qs::ShapeKind::kCircle) {
      const double dx = double(states[i].position.x) - states[j].position.x;
      const double dy = double(states[i].position.y) - states[j].position.y;
      return double(a.radius) + b.radius - std::hypot(dx, dy);
    }
    pair_.bodies[0] = a;
    pair_.bodies[1] = b;
    pairStates_[0] = states[i];
    pairStates_[1] = states[j];
    return qs::MaxPenetration(pair_, pairStates_);
  }

  const qs::Scene& scene_;
  qs::Scene pair_;
  std::vector<qs::BodyState> pairStates_;
  std::vector<Aabb> boxes_;
  std::vector<size_t> order_;
  double max_ = 0, sum_ = 0;
  long count_ = 0;
  int samples_ = 0;
};

bool Finite(const std::vector<qs::BodyState>& states) {
  for (const qs::BodyState& s : states) {
    if (!quadrant::IsFinite(s.position) || !quadrant::IsFinite(s.angle) || !quadrant::IsFinite(s.velocity) ||
        !quadrant::IsFinite(s.angularVelocity)) {
      return false;
    }
  }
  return true;
}

double Distance(const qs::BodyState& a, const qs::BodyState& b) {
  return std::hypot(double(b.position.x) - a.position.x, double(b.position.y) - a.position.y);
}

using Errors = std::vector<std::pair<std::string, std::optional<double>>>;

// Penetration is sampled every 6 steps (0.1 s), denser than the hard cases' 0.5 s: the mean
// needs many samples, and a stress scene's overlaps last only a few steps.
constexpr int kSampleEvery = 6;
constexpr double kFallDistance = 0.5;  // m: a body this far from where it stood has fallen

// The untimed run with read-back after every step. Pile measures: drift of the top body (the
// last one: stack top, apex, heavy box, plank) and of any body between t = 1 s and the end, and
// the fall time. Stress measures: kinetic energy drift, momentum change, bodies that left the box.
Errors MeasureErrors(qs::Adapter& adapter, const qs::Scene& scene, int steps) {
  const Kind kind = KindOf(scene.name);
  std::vector<qs::BodyState> start, states, atOne;
  adapter.ReadBodies(start);
  PenetrationMeter pen(scene);
  const size_t n = start.size();
  // Stress: a body is outside when all of it is past a wall's inner face (as the soak case).
  std::vector<double> reach(n, 0);
  for (size_t i = 0; i < n; ++i) {
    const qs::BodyDesc& b = scene.bodies[i];
    reach[i] = b.shape == qs::ShapeKind::kCircle ? double(b.radius) : 0.0;
    for (const quadrant::Vec2& v : b.vertices) reach[i] = std::max(reach[i], std::hypot(double(v.x), double(v.y)));
  }
  std::vector<bool> everOutside(n, false);
  std::optional<double> fallTime;
  bool finite = Finite(start);
  const int oneSecond = std::min(kStepsPerSecond, steps);
  for (int step = 1; step <= steps && finite; ++step) {
    adapter.Step();
    adapter.ReadBodies(states);
    finite = Finite(states);
    if (!finite) break;
    if (step % kSampleEvery == 0 || step == steps) pen.Sample(states);
    if (step == oneSecond) atOne = states;
    if (kind == Kind::kPile && !fallTime) {
      // Up to t = 1 s from the spawn pose, then from the pose at t = 1 s: the settling of the
      // first second (Box2D's skin lifts a pile by centimetres) is far below 0.5 m, and a pile
      // that collapses at once still gets a fall time.
      const std::vector<qs::BodyState>& ref = step <= oneSecond ? start : atOne;
      for (size_t i = 0; i < n && !fallTime; ++i) {
        if (scene.bodies[i].dynamic && Distance(ref[i], states[i]) > kFallDistance) {
          fallTime = double(step) / kStepsPerSecond;
        }
      }
    }
    if (kind == Kind::kStress) {
      const quadrant::AABB box = scene.bounds;
      for (size_t i = 0; i < n; ++i) {
        if (!scene.bodies[i].dynamic) continue;
        const quadrant::Vec2 p = states[i].position;
        const double past = std::max({double(box.lower.x) - p.x, double(p.x) - box.upper.x,
                                      double(box.lower.y) - p.y, double(p.y) - box.upper.y});
        if (past > reach[i]) everOutside[i] = true;
      }
    }
  }
  Errors e;
  e.push_back({"finite", finite ? 1.0 : 0.0});
  if (!finite) return e;
  e.push_back({"max_penetration_m", pen.Max()});
  e.push_back({"mean_penetration_m", pen.Mean()});
  e.push_back({"overlaps_per_sample", pen.OverlapsPerSample()});
  if (kind == Kind::kPile) {
    const size_t top = n - 1;
    // Drift is from t = 1 s; the displacement from the spawn pose also counts a pile that fell in
    // the first second and then lay still (its drift after 1 s is small).
    double maxDrift = 0, maxDisplacement = 0;
    for (size_t i = 0; i < n; ++i) {
      if (!scene.bodies[i].dynamic) continue;
      maxDrift = std::max(maxDrift, Distance(atOne[i], states[i]));
      maxDisplacement = std::max(maxDisplacement, Distance(start[i], states[i]));
    }
    const bool window = steps > oneSecond;  // no drift window in runs of 1 s or less
    e.push_back({"top_drift_m", window ? std::optional<double>(Distance(atOne[top], states[top])) : std::nullopt});
    e.push_back({"max_drift_m", window ? std::optional<double>(maxDrift) : std::nullopt});
    e.push_back({"max_displacement_m", maxDisplacement});
    e.push_back({"fall_time_s", fallTime});
  } else {
    const double ke0 = qs::KineticEnergy(scene, start), ke1 = qs::KineticEnergy(scene, states);
    const quadrant::Vec2 p0 = qs::LinearMomentum(scene, start), p1 = qs::LinearMomentum(scene, states);
    double scale = 0;  // sum of m |v| at the start: the momentum the bodies carry, in any direction
    for (size_t i = 0; i < n; ++i) {
      if (!scene.bodies[i].dynamic) continue;
      scale += double(qs::ComputeMassProperties(scene.bodies[i]).mass) *
               std::hypot(double(start[i].velocity.x), double(start[i].velocity.y));
    }
    e.push_back({"ke_drift", ke1 / ke0 - 1});
    e.push_back({"momentum_change_rel", std::hypot(double(p1.x) - p0.x, double(p1.y) - p0.y) / scale});
    e.push_back({"tunnelled", double(std::count(everOutside.begin(), everOutside.end(), true))});
  }
  return e;
}

// ---- The sweep --------------------------------------------------------------------------------

struct Run {
  const Setting* setting = nullptr;
  std::string scene;
  int bodies = 0;
  int steps = 0;
  std::string unsupported;  // Load's reason, if the engine refused
  std::string failed;       // an error thrown while stepping
  Errors errors;
  std::vector<double> ms;   // ms per step, one per timed repetition
};

// A hard-case verdict and the setting it was run with, as the report names it.
struct HardRow {
  qs::HardCaseResult result;
  Setting setting;
};

double Median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

double TimedRun(const Setting& setting, const qs::Scene& scene, int steps) {
  std::unique_ptr<qs::Adapter> adapter = qs::MakeAdapter(setting.adapter);
  adapter->Load(scene, 1);
  const Clock::time_point t0 = Clock::now();
  for (int i = 0; i < steps; ++i) adapter->Step();
  const Clock::time_point t1 = Clock::now();
  return std::chrono::duration<double, std::milli>(t1 - t0).count() / steps;
}

struct Args {
  std::string out = ".";
  std::string json;
  bool quick = false;
  std::vector<std::string> settings;
  std::vector<std::string> scenes;
  std::vector<std::string> hardCases;
  bool hardCasesGiven = false;
  int steps = 0;  // 0: 600, or 120 with --quick
  int repetitions = 3;
  int count = 0;  // stress N; 0: 1000, or 200 with --quick
};

Args Parse(int argc, char** argv) {
  Args a;
  std::vector<std::string> settingIds;
  for (const Setting& s : AllSettings()) settingIds.push_back(s.id);
  std::string quick;
  for (const std::string& s : kQuickSettings) quick += (quick.empty() ? "" : ",") + s;
  quadrant::cli::Parser p("quadrant_accuracy",
                          "What accuracy costs in time (issue 6): solver settings swept over piles and stress "
                          "scenes,\ntime per step next to error measures from the read-back, then the piles' hard "
                          "cases on every\nQuadrant setting. Writes JSON for tools/accuracy_report.py.");
  p.OutputDirectory("--out", &a.out, "the output directory");
  p.String("--json", &a.json, "FILE", "the JSON file to write").Default("DIR/accuracy.json");
  p.Flag("--quick", &a.quick, "one cheap and one default setting per family, fewer steps and bodies");
  p.NameList("--settings", &a.settings, settingIds, "setting", "the settings to sweep")
      .Default("all; with --quick " + quick);
  p.NameList("--scenes", &a.scenes, kAllScenes, "scene", "the scenes to run").Default("all");
  p.NameList("--hard-cases", &a.hardCases, kHardCases, "hard case", "the hard cases run on every setting")
      .AllowNone()
      .Default("all; with --quick vertical_stack,mass_ratio_400");
  p.Int("--steps", &a.steps, 1, 1000000, "steps per run").Default("600; 120 with --quick");
  p.Int("--repetitions", &a.repetitions, 1, 1000, "timed runs of every setting and scene (the median is reported)");
  p.Int("--count", &a.count, 1, 1000000, "bodies in the stress scenes").Default("1000; 200 with --quick");
  p.Parse(argc, argv);
  a.hardCasesGiven = p.Given("--hard-cases");
  return a;
}

std::string ErrorsJson(const Errors& errors) {
  std::string out = "{";
  for (size_t i = 0; i < errors.size(); ++i) {
    const auto& [name, value] = errors[i];
    out += (i ? ", " : "") + rp::JsonString(name) + ": ";
    if (name == "finite") {
      out += value && *value > 0 ? "true" : "false";
    } else {
      out += value ? rp::JsonNumber(*value) : "null";
    }
  }
  return out + "}";
}

std::string Json(const std::vector<Run>& runs, const std::vector<HardRow>& hard, const Args& args,
                 double seconds) {
  std::ostringstream o;
  o << "{\n  \"context\": {\"machine\": " << rp::JsonString(rp::Env("QUADRANT_MACHINE", "unknown"))
    << ", \"commit\": " << rp::JsonString(rp::Env("QUADRANT_COMMIT", "unknown"))
    << ", \"date\": " << rp::JsonString(rp::UtcNow()) << ", \"compiler\": " << rp::JsonString(__VERSION__)
    << ", \"build_type\": " << rp::JsonString(QUADRANT_BUILD_TYPE) << ", \"precision\": " << rp::JsonString(kPrecision)
    << ", \"threads\": 1, \"repetitions\": " << args.repetitions << ", \"steps\": " << args.steps
    << ", \"stress_count\": " << args.count << ", \"penetration_sample_every_steps\": " << kSampleEvery
    << ", \"quick\": " << (args.quick ? "true" : "false") << ", \"seconds\": " << rp::JsonNumber(seconds)
    << ",\n              \"method\": "
    << rp::JsonString(fmt::format(
           "ms_per_step: median over {} timed runs of {} steps (steady_clock around the step loop only; runs "
           "interleaved: every repetition covers every scene and setting, in alternating order). Errors: one "
           "untimed run of the same steps with read-back after every step; penetration from read-back poses and "
           "the scene's exact shapes, sampled every {} steps; see tools/accuracy_report.py for each measure.",
           args.repetitions, args.steps, kSampleEvery))
    << "},\n  \"runs\": [\n";
  for (size_t i = 0; i < runs.size(); ++i) {
    const Run& r = runs[i];
    const Setting& s = *r.setting;
    o << "    {\"engine\": " << rp::JsonString(s.engine) << ", \"solver\": " << rp::JsonString(s.solver)
      << ", \"setting\": " << rp::JsonString(s.setting) << ", \"id\": " << rp::JsonString(s.id)
      << ", \"adapter\": " << rp::JsonString(s.adapter) << ", \"precision\": " << rp::JsonString(kPrecision);
    if (s.iterations > 0) o << ", \"iterations\": " << s.iterations;
    o << ", \"scene\": " << rp::JsonString(r.scene) << ", \"bodies\": " << r.bodies << ", \"steps\": " << r.steps;
    if (!r.unsupported.empty()) {
      o << ", \"ms_per_step\": null, \"unsupported\": " << rp::JsonString(r.unsupported) << ", \"errors\": {}";
    } else {
      o << ", \"ms_per_step\": " << rp::JsonNumber(Median(r.ms)) << ", \"ms_samples\": [";
      for (size_t k = 0; k < r.ms.size(); ++k) o << (k ? ", " : "") << rp::JsonNumber(r.ms[k]);
      o << "]";
      if (!r.failed.empty()) o << ", \"failed\": " << rp::JsonString(r.failed);
      o << ", \"errors\": " << ErrorsJson(r.errors);
    }
    o << "}" << (i + 1 < runs.size() ? "," : "") << "\n";
  }
  o << "  ],\n  \"hard_cases\": [\n";
  for (size_t i = 0; i < hard.size(); ++i) {
    const qs::HardCaseResult& h = hard[i].result;
    const Setting& s = hard[i].setting;
    o << "    {\"scene\": " << rp::JsonString(h.name) << ", \"engine\": " << rp::JsonString(s.engine)
      << ", \"solver\": " << rp::JsonString(s.solver) << ", \"setting\": " << rp::JsonString(s.setting)
      << ", \"id\": " << rp::JsonString(s.id);
    if (s.iterations > 0) o << ", \"iterations\": " << s.iterations;
    o << ", \"precision\": " << rp::JsonString(kPrecision) << ", \"pass\": " << (h.pass ? "true" : "false") << ", \"criterion\": " << rp::JsonString(h.criterion);
    if (!h.supported) o << ", \"unsupported\": " << rp::JsonString(h.unsupported);
    o << ", \"measured\": {";
    for (size_t k = 0; k < h.measured.size(); ++k) {
      o << (k ? ", " : "") << rp::JsonString(h.measured[k].name) << ": " << rp::JsonNumber(h.measured[k].value);
    }
    o << "}}" << (i + 1 < hard.size() ? "," : "") << "\n";
  }
  o << "  ]\n}\n";
  return o.str();
}

}  // namespace

int main(int argc, char** argv) {
  Args args = Parse(argc, argv);
  if (args.steps == 0) args.steps = args.quick ? 120 : 600;
  if (args.count == 0) args.count = args.quick ? 200 : 1000;
  if (args.scenes.empty()) args.scenes = kAllScenes;
  const std::vector<Setting> all = AllSettings();
  std::vector<const Setting*> settings;
  const std::vector<std::string> wanted =
      !args.settings.empty() ? args.settings : args.quick ? kQuickSettings : std::vector<std::string>{};
  for (const Setting& s : all) {
    if (wanted.empty() || std::find(wanted.begin(), wanted.end(), s.id) != wanted.end()) settings.push_back(&s);
  }
  if (!args.hardCasesGiven) {
    args.hardCases = args.quick ? std::vector<std::string>{"vertical_stack", "mass_ratio_400"} : kHardCases;
  }
  const std::string jsonPath = args.json.empty() ? (std::filesystem::path(args.out) / "accuracy.json").string()
                                                 : args.json;
  const Clock::time_point begin = Clock::now();

  try {
    // Scenes outlive every adapter that loads them (adapters may keep pointers into them).
    std::vector<Run> runs;
    std::vector<std::unique_ptr<qs::Scene>> scenes;
    for (const std::string& name : args.scenes) {
      for (const Setting* s : settings) {
        scenes.push_back(std::make_unique<qs::Scene>(BuildScene(name, *s, args.count)));
        Run r;
        r.setting = s;
        r.scene = name;
        r.bodies = int(scenes.back()->bodies.size());
        r.steps = args.steps;
        runs.push_back(std::move(r));
      }
    }

    // Errors: one untimed run each, which also warms every engine and allocator up.
    for (size_t i = 0; i < runs.size(); ++i) {
      Run& r = runs[i];
      std::cerr << fmt::format("quadrant_accuracy: errors {:>24} {:<15}", r.setting->id, r.scene) << std::flush;
      try {
        std::unique_ptr<qs::Adapter> adapter = qs::MakeAdapter(r.setting->adapter);
        adapter->Load(*scenes[i], 1);
        r.errors = MeasureErrors(*adapter, *scenes[i], args.steps);
      } catch (const qs::Unsupported& e) {
        r.unsupported = e.what();
      } catch (const quadrant::Error& e) {
        r.failed = e.what();
      }
      std::cerr << (r.unsupported.empty() ? (r.failed.empty() ? "ok" : "failed: " + r.failed)
                                          : "unsupported: " + r.unsupported)
                << "\n";
    }

    // Timing: repetition-major, alternating direction, so no setting always runs first or last.
    for (int rep = 0; rep < args.repetitions; ++rep) {
      std::cerr << "quadrant_accuracy: timing, repetition " << rep + 1 << " of " << args.repetitions << "\n";
      for (size_t k = 0; k < runs.size(); ++k) {
        const size_t i = rep % 2 == 0 ? k : runs.size() - 1 - k;
        Run& r = runs[i];
        if (!r.unsupported.empty() || !r.failed.empty()) continue;
        r.ms.push_back(TimedRun(*r.setting, *scenes[i], args.steps));
      }
    }

    // Hard cases: every Quadrant setting of the sweep (its it<N> overrides the case's iteration
    // budget; thesis and soft_step use none), plus each peer once, at the budget the case's
    // builder gives every engine (scene.velocityIterations: 16 for the stack and mass ratio 100,
    // 32 for mass ratio 400), which is what RunHardCase runs them with.
    std::vector<HardRow> hard;
    for (const std::string& name : args.hardCases) {
      const int budget = qs::MakeScene(name, 210).velocityIterations;
      std::vector<std::string> peersDone;
      for (const Setting* s : settings) {
        Setting label = *s;
        if (s->engine != "quadrant") {
          if (std::find(peersDone.begin(), peersDone.end(), s->engine) != peersDone.end()) continue;
          peersDone.push_back(s->engine);
          const std::string n = std::to_string(budget);
          label.iterations = budget;
          label.setting = "the case's budget (it" + n + ")";
          // Box2D at the case's budget is exactly the sweep's box2d:it<budget>, so its cost is known.
          label.id = s->engine == "box2d" ? "box2d:it" + n : s->engine + " (case budget: it" + n + ")";
        }
        std::cerr << fmt::format("quadrant_accuracy: hard case {:<15} {:>30} ", name, label.id) << std::flush;
        hard.push_back({qs::RunHardCase(name, s->adapter), label});
        const qs::HardCaseResult& r = hard.back().result;
        std::cerr << (r.supported ? (r.pass ? "pass" : "fail") : "unsupported") << "\n";
      }
    }

    const double seconds = std::chrono::duration<double>(Clock::now() - begin).count();
    const std::filesystem::path parent = std::filesystem::path(jsonPath).parent_path();
    if (!parent.empty()) std::filesystem::create_directories(parent);
    std::ofstream(jsonPath) << Json(runs, hard, args, seconds);
    std::cerr << fmt::format("quadrant_accuracy: wrote {} ({:.0f} s)\n", jsonPath, seconds);
  } catch (const quadrant::Error& e) {
    std::cerr << "quadrant_accuracy: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
