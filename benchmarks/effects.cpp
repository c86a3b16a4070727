// quadrant_effects: what each effect of the scene API costs Quadrant (issue 6: simulate only the
// effects a scene calls for). For each effect, Quadrant's time per step with the effect on and off
// on a scene where it matters, and the stress scenes with only the effects they need against all
// effects on. Writes DIR/effects.json and DIR/effects.md.
//
//   quadrant_effects --out DIR [--quick] [--count N] [--steps S] [--warmup W] [--repetitions R]
//
// Scenes: the effects the engine has flags for (gravity, friction, restitution, rotation,
// warmStarting, damping) on polygon_stress (N = 8000; --quick: 1000), a copy of the scene with
// the one flag flipped; sleep on 56 pyramids of 36 boxes (2016 boxes) spawned at rest; continuous on
// a fast body (a 0.5 m box at 50 m/s falling onto a 0.2 m static plank). An effect the adapter
// refuses (Adapter::Load throws Unsupported) is recorded with its reason; no number stands in for
// it. Every run is one thread; W untimed steps, then S steps inside steady_clock; on and off runs
// alternate within every repetition (which side goes first alternates too); medians are reported.
// Exit status: 0, 1 on an engine error, 2 on bad arguments.
#include <fmt/format.h>

#include <algorithm>
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

#include "adapter.h"
#include "cli_args.h"
#include "quadrant/error.h"
#include "report_common.h"
#include "scenes.h"

namespace qs = quadrant::scene;
namespace rp = quadrant::report;

namespace {

using Clock = std::chrono::steady_clock;
constexpr const char* kEngine = "quadrant";

struct Args {
  std::string out = ".";
  bool quick = false;
  int count = 0;        // 0: 8000, 1000 with --quick
  int steps = 0;        // 0: 120, 20 with --quick
  int warmup = -1;      // -1: 30, 5 with --quick
  int repetitions = 3;
};

// One side (on or off) of a comparison: its scene, and what came of running it.
struct Side {
  std::unique_ptr<qs::Scene> scene;
  std::string unsupported;
  std::vector<double> ms;
  std::vector<qs::BodyState> final;  // read-back after the first timed run
};

struct Comparison {
  std::string name;     // the effect (or "all" for the all-on comparisons)
  std::string variant;  // what exactly is flipped and what is kept
  std::string scene;
  int steps = 0, warmup = 0;
  Side on, off;
  std::string note;
};

double Median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

// Runs a side once: Load, `warmup` untimed steps, `steps` timed ones. Unsupported is recorded on
// the side (and the side is not run again); other errors propagate.
void RunSide(Side& side, int warmup, int steps) {
  if (!side.unsupported.empty()) return;
  std::unique_ptr<qs::Adapter> adapter = qs::MakeAdapter(kEngine);
  try {
    adapter->Load(*side.scene, 1);
  } catch (const qs::Unsupported& e) {
    side.unsupported = e.what();
    return;
  }
  for (int i = 0; i < warmup; ++i) adapter->Step();
  const Clock::time_point t0 = Clock::now();
  for (int i = 0; i < steps; ++i) adapter->Step();
  const Clock::time_point t1 = Clock::now();
  side.ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count() / steps);
  if (side.final.empty()) adapter->ReadBodies(side.final);
}

struct EffectFlag {
  const char* name;
  bool qs::Effects::*flag;
};
constexpr EffectFlag kEffectFlags[] = {
    {"gravity", &qs::Effects::gravity},   {"friction", &qs::Effects::friction},
    {"restitution", &qs::Effects::restitution}, {"rotation", &qs::Effects::rotation},
    {"warmStarting", &qs::Effects::warmStarting}, {"sleep", &qs::Effects::sleep},
    {"continuous", &qs::Effects::continuous}, {"damping", &qs::Effects::damping}};

std::string EffectsText(const qs::Effects& e) {
  std::string out;
  for (const EffectFlag& f : kEffectFlags) {
    if (e.*f.flag) out += (out.empty() ? "" : ", ") + std::string(f.name);
  }
  return out.empty() ? "none" : out;
}

// "All on" for a scene: the scene's flags plus every effect the adapter accepts, each tried on
// its own (Load with that one added); the refused ones stay off and are listed with the reason.
qs::Effects AllOn(const qs::Scene& base, std::vector<std::string>& refused) {
  qs::Effects on = base.effects;
  for (const EffectFlag& f : kEffectFlags) {
    if (on.*f.flag) continue;
    qs::Scene probe = base;
    probe.effects.*f.flag = true;
    try {
      qs::MakeAdapter(kEngine)->Load(probe, 1);
      on.*f.flag = true;
    } catch (const qs::Unsupported& e) {
      refused.push_back(std::string(f.name) + " (" + e.what() + ")");
    }
  }
  return on;
}

// The fast-body case: a static plank 4 m x 0.2 m (top face at y = 0.1) and a 0.5 m box whose
// bottom starts 2.9 m above it, falling at 50 m/s: 0.83 m per step, more than the plank and box
// together (0.7 m), so only a swept or speculative test catches it.
qs::Scene MakeFastBody() {
  qs::Scene s;
  s.name = "fast_body";
  s.gravity = {0, quadrant::Real(-10)};
  s.timeStep = quadrant::Real(1.0 / 60.0);
  s.restitutionThreshold = 1;
  s.effects.restitution = false;
  s.effects.continuous = false;
  // A static plank 4 m x 0.2 m at the origin.
  s.bodies.push_back(qs::MakeBoxBody({0, 0}, 2, quadrant::Real(0.1), /*dynamic=*/false));
  qs::BodyDesc box = qs::MakeBoxBody({0, quadrant::Real(3.25)}, quadrant::Real(0.25), quadrant::Real(0.25));
  box.velocity = {0, -50};
  s.bodies.push_back(box);
  s.bounds = {{-3, -1}, {3, 4}};
  return s;
}

Comparison Make(std::string name, std::string variant, const qs::Scene& base, int steps, int warmup) {
  Comparison c;
  c.name = std::move(name);
  c.variant = std::move(variant);
  c.scene = base.name;
  c.steps = steps;
  c.warmup = warmup;
  c.on.scene = std::make_unique<qs::Scene>(base);
  c.off.scene = std::make_unique<qs::Scene>(base);
  return c;
}

// A comparison that flips one flag of `base` (on in one copy, off in the other).
Comparison Flip(std::string name, bool qs::Effects::*flag, std::string variant, const qs::Scene& base, int steps,
                int warmup) {
  Comparison c = Make(std::move(name), std::move(variant), base, steps, warmup);
  c.on.scene->effects.*flag = true;
  c.off.scene->effects.*flag = false;
  return c;
}

std::string Ms(const Side& s) { return s.unsupported.empty() ? rp::JsonNumber(Median(s.ms)) : "null"; }

std::string SidesJson(const Comparison& c) {
  std::string out = fmt::format("\"on_ms\": {}, \"off_ms\": {}", Ms(c.on), Ms(c.off));
  auto samples = [](const Side& s) {
    std::string t = "[";
    for (size_t i = 0; i < s.ms.size(); ++i) t += (i ? ", " : "") + rp::JsonNumber(s.ms[i]);
    return t + "]";
  };
  out += ", \"on_samples\": " + samples(c.on) + ", \"off_samples\": " + samples(c.off);
  out += ", \"on_effects\": " + rp::JsonString(EffectsText(c.on.scene->effects)) +
         ", \"off_effects\": " + rp::JsonString(EffectsText(c.off.scene->effects));
  if (!c.on.unsupported.empty() || !c.off.unsupported.empty()) {
    // The spec's one field: the refused side's reason (on's if both were refused).
    out += ", \"unsupported\": " + rp::JsonString(!c.on.unsupported.empty() ? c.on.unsupported : c.off.unsupported);
    out += ", \"unsupported_side\": " +
           rp::JsonString(!c.on.unsupported.empty() && !c.off.unsupported.empty() ? "both"
                          : !c.on.unsupported.empty()                             ? "on"
                                                                                  : "off");
  }
  return out;
}

// Largest distance between the two sides' final positions (same scene, same steps): zero or
// round-off when the flipped effect changes only work, not the motion.
std::optional<double> PositionDifference(const Comparison& c) {
  if (c.on.final.empty() || c.on.final.size() != c.off.final.size()) return std::nullopt;
  double worst = 0;
  for (size_t i = 0; i < c.on.final.size(); ++i) {
    worst = std::max(worst, std::hypot(double(c.on.final[i].position.x) - c.off.final[i].position.x,
                                       double(c.on.final[i].position.y) - c.off.final[i].position.y));
  }
  return worst;
}

Args Parse(int argc, char** argv) {
  Args a;
  quadrant::cli::Parser p("quadrant_effects",
                          "What each effect of the scene API costs Quadrant (issue 6): time per step with the "
                          "effect on and off,\nand the stress scenes with only the effects they need against "
                          "all effects on. Writes DIR/effects.json\nand DIR/effects.md.");
  p.OutputDirectory("--out", &a.out, "the output directory");
  p.Flag("--quick", &a.quick, "fewer bodies and steps");
  p.Int("--count", &a.count, 1, 1000000, "bodies in the stress scenes").Default("8000; 1000 with --quick");
  p.Int("--steps", &a.steps, 1, 1000000, "timed steps per run").Default("120; 20 with --quick");
  p.Int("--warmup", &a.warmup, 0, 1000000, "untimed steps before timing").Default("30; 5 with --quick");
  p.Int("--repetitions", &a.repetitions, 1, 1000, "timed runs of every side (the median is reported)");
  p.Parse(argc, argv);
  if (a.count == 0) a.count = a.quick ? 1000 : 8000;
  if (a.steps == 0) a.steps = a.quick ? 20 : 120;
  if (a.warmup < 0) a.warmup = a.quick ? 5 : 30;
  return a;
}

std::string Cell(const Side& s) {
  if (!s.unsupported.empty()) return "unsupported: " + rp::CellText(s.unsupported);
  return fmt::format("{:.4f} ({:.0f} steps/s)", Median(s.ms), 1000.0 / Median(s.ms));
}

std::string Ratio(const Comparison& c) {
  if (!c.on.unsupported.empty() || !c.off.unsupported.empty()) return "-";
  return fmt::format("{:.3f}", Median(c.on.ms) / Median(c.off.ms));
}

}  // namespace

int main(int argc, char** argv) {
  const Args args = Parse(argc, argv);
  const Clock::time_point begin = Clock::now();
  try {
    const qs::Scene polygons = qs::MakeScene("polygon_stress", args.count, 42);
    const qs::Scene circles = qs::MakeScene("circle_stress", args.count, 42);
    std::vector<Comparison> rows;

    // Gravity and friction: the stress scene has neither (zero gravity vector, friction 0), so
    // each gets two rows: the flag alone with the scene's own values (the cost of the code path
    // the flag selects), and with values that make the effect act (g = (0, -10), friction 0.6
    // on every body, in both the on and the off copy; off ignores them).
    qs::Scene falling = polygons;
    falling.gravity = {0, quadrant::Real(-10)};
    rows.push_back(Flip("gravity", &qs::Effects::gravity,
                        "g = (0, -10) in both copies (bodies fall and pile up on the floor when on)", falling,
                        args.steps, args.warmup));
    rows.push_back(Flip("gravity", &qs::Effects::gravity, "flag only: the scene's zero gravity vector", polygons,
                        args.steps, args.warmup));
    qs::Scene rough = polygons;
    for (qs::BodyDesc& b : rough.bodies) b.friction = quadrant::Real(0.6);
    rows.push_back(Flip("friction", &qs::Effects::friction, "friction 0.6 on every body and wall in both copies",
                        rough, args.steps, args.warmup));
    rows.push_back(Flip("friction", &qs::Effects::friction, "flag only: the scene's friction 0", polygons, args.steps,
                        args.warmup));
    rows.push_back(Flip("restitution", &qs::Effects::restitution, "the scene's restitution 1 (off: inelastic)",
                        polygons, args.steps, args.warmup));
    rows.push_back(Flip("rotation", &qs::Effects::rotation, "the scene's polygons (off: no angular motion)", polygons,
                        args.steps, args.warmup));
    rows.push_back(Flip("warmStarting", &qs::Effects::warmStarting, "the scene's contacts", polygons, args.steps,
                        args.warmup));
    qs::Scene damped = polygons;
    for (qs::BodyDesc& b : damped.bodies) b.linearDamping = b.angularDamping = quadrant::Real(0.1);
    rows.push_back(Flip("damping", &qs::Effects::damping, "linear and angular damping 0.1 /s on every body in both copies",
                        damped, args.steps, args.warmup));
    // Sleep: a pile at rest, where a sleeping engine would stop simulating it; warmed up 2 s so
    // the pile has settled (Box2D sleeps a body after 0.5 s below its thresholds). Many small
    // pyramids, not one large one: a 2016-box pyramid (base 63) never comes to rest at 8
    // iterations, so nothing would sleep; 56 pyramids of base 8 (36 boxes) are all asleep
    // after 90 steps (measured: 0.018 ms per step from then on).
    const int pyramids = args.quick ? 6 : 56;
    const qs::Scene pile = qs::MakePyramidField(pyramids, 8);
    rows.push_back(Flip("sleep", &qs::Effects::sleep,
                        fmt::format("{} pyramids of 36 boxes ({} boxes) spawned at rest, after 120 untimed steps",
                                    pyramids, pile.bodies.size() - 1),
                        pile, args.steps, 120));
    // Continuous: the fast body. A two-body step is short, so 10 s are timed (a loop of tens of
    // milliseconds); a box that tunnels falls freely for the rest of the run, so off and on then
    // time different motions, which the row's note says.
    rows.push_back(Flip("continuous", &qs::Effects::continuous,
                        "0.5 m box at 50 m/s onto a 0.2 m static plank, g = (0, -10)", MakeFastBody(),
                        args.quick ? 120 : 600, 0));

    // All on against only the needed effects. "All on": every effect the Quadrant adapter
    // accepts switched on (AllOn), with the scene's materials and gravity vector unchanged (zero
    // gravity, friction 0), so the physics is the same and mostly the work differs (the
    // position difference after the run says how much the motion changed). "Needed": restitution
    // and warm starting for circles (frictionless circles get no torque, so rotation is a no-op
    // there), plus rotation for polygons.
    std::vector<Comparison> allOff;
    std::vector<std::string> refused;
    for (const qs::Scene* base : {&circles, &polygons}) {
      Comparison c = Make("all", "", *base, args.steps, args.warmup);
      refused.clear();
      c.on.scene->effects = AllOn(*base, refused);
      c.note = refused.empty() ? "none" : "";
      for (const std::string& r : refused) c.note += (c.note.empty() ? "" : "; ") + r;
      qs::Effects& needed = c.off.scene->effects;
      needed = qs::Effects{};
      needed.gravity = needed.friction = needed.sleep = needed.continuous = needed.damping = false;
      needed.restitution = needed.warmStarting = true;
      needed.rotation = base == &polygons;
      c.variant = "all on: " + EffectsText(c.on.scene->effects) + "; needed: " + EffectsText(needed);
      allOff.push_back(std::move(c));
    }

    for (int rep = 0; rep < args.repetitions; ++rep) {
      std::cerr << "quadrant_effects: repetition " << rep + 1 << " of " << args.repetitions << "\n";
      for (std::vector<Comparison>* list : {&rows, &allOff}) {
        for (Comparison& c : *list) {
          // Alternate which side runs first, so neither always follows the other.
          Side& first = rep % 2 == 0 ? c.on : c.off;
          Side& second = rep % 2 == 0 ? c.off : c.on;
          RunSide(first, c.warmup, c.steps);
          RunSide(second, c.warmup, c.steps);
        }
      }
    }

    // The fast body: where did the box end up in the runs that ran?
    for (Comparison& c : rows) {
      if (c.name != "continuous") continue;
      auto where = [](const Side& s) -> std::string {
        if (!s.unsupported.empty() || s.final.size() < 2) return "not run";
        const double y = s.final[1].position.y;
        return fmt::format("box centre at y = {:.3f} m after the run ({})", y,
                           y < -0.1 ? "tunnelled through the plank, then fell freely" : "caught by the plank");
      };
      c.note = "on: " + where(c.on) + "; off: " + where(c.off);
    }

    std::vector<double> speedups;
    for (const Comparison& c : allOff) {
      if (c.on.unsupported.empty() && c.off.unsupported.empty()) {
        speedups.push_back(Median(c.on.ms) / Median(c.off.ms));
      }
    }
    double logSum = 0;
    for (double s : speedups) logSum += std::log(s);
    const double geomean = speedups.empty() ? NAN : std::exp(logSum / double(speedups.size()));
    const double seconds = std::chrono::duration<double>(Clock::now() - begin).count();

    // ---- JSON ----
    std::ostringstream j;
    j << "{\n  \"context\": {\"machine\": " << rp::JsonString(rp::Env("QUADRANT_MACHINE", "unknown"))
      << ", \"commit\": " << rp::JsonString(rp::Env("QUADRANT_COMMIT", "unknown"))
      << ", \"date\": " << rp::JsonString(rp::UtcNow()) << ", \"compiler\": " << rp::JsonString(__VERSION__)
      << ", \"build_type\": " << rp::JsonString(QUADRANT_BUILD_TYPE) << ", \"engine\": \"quadrant\", \"threads\": 1"
      << ", \"count\": " << args.count << ", \"steps\": " << args.steps << ", \"warmup\": " << args.warmup
      << ", \"repetitions\": " << args.repetitions << ", \"quick\": " << (args.quick ? "true" : "false")
      << ", \"seconds\": " << rp::JsonNumber(seconds) << "},\n  \"effects\": [\n";
    for (size_t i = 0; i < rows.size(); ++i) {
      const Comparison& c = rows[i];
      j << "    {\"name\": " << rp::JsonString(c.name) << ", \"variant\": " << rp::JsonString(c.variant)
        << ", \"scene\": " << rp::JsonString(c.scene) << ", \"bodies\": " << c.on.scene->bodies.size()
        << ", \"steps\": " << c.steps << ", \"warmup\": " << c.warmup << ", " << SidesJson(c);
      if (!c.note.empty()) j << ", \"note\": " << rp::JsonString(c.note);
      j << "}" << (i + 1 < rows.size() ? "," : "") << "\n";
    }
    j << "  ],\n  \"all_off\": [\n";
    for (size_t i = 0; i < allOff.size(); ++i) {
      const Comparison& c = allOff[i];
      const std::optional<double> diff = PositionDifference(c);
      j << "    {\"scene\": " << rp::JsonString(c.scene) << ", \"bodies\": " << c.on.scene->bodies.size()
        << ", \"all_on_effects\": " << rp::JsonString(EffectsText(c.on.scene->effects))
        << ", \"needed_effects\": " << rp::JsonString(EffectsText(c.off.scene->effects))
        << ", \"all_on_ms\": " << Ms(c.on) << ", \"needed_ms\": " << Ms(c.off) << ", \"speedup\": "
        << (c.on.unsupported.empty() && c.off.unsupported.empty() ? rp::JsonNumber(Median(c.on.ms) / Median(c.off.ms))
                                                                   : "null")
        << ", \"max_position_difference_m\": " << (diff ? rp::JsonNumber(*diff) : "null")
        << ", \"refused_by_adapter\": " << rp::JsonString(c.note) << "}"
        << (i + 1 < allOff.size() ? "," : "") << "\n";
    }
    j << "  ],\n  \"all_off_speedup\": " << rp::JsonNumber(geomean) << "\n}\n";

    // ---- Markdown ----
    std::ostringstream m;
    m << "# What each effect costs (Quadrant)\n\n"
      << "Machine `" << rp::Env("QUADRANT_MACHINE", "unknown") << "`, commit `" << rp::Env("QUADRANT_COMMIT", "unknown")
      << "`, " << rp::UtcNow() << ", compiler " << __VERSION__ << ", build " << QUADRANT_BUILD_TYPE
      << ". Written by `tools/quadrant effects` (benchmarks/effects.cpp). One thread. Each figure is the median "
      << "ms per step of " << args.repetitions << " runs (" << args.warmup << " untimed steps, then " << args.steps
      << " timed; sleep: 120 untimed; the fast body: " << rows.back().steps << " timed), on and off runs "
      << "alternating" << (args.quick ? "; **--quick run: small scenes, few steps, not a measurement**" : "")
      << ".\n\n"
      << "Each row copies one scene and flips one effect flag of the scene API; everything else (materials, "
      << "gravity vector, solver settings) is the same in both copies. A side the Quadrant adapter refuses is "
      << "marked unsupported with its reason.\n\n"
      << "| effect | what is kept | scene | on: ms/step | off: ms/step | on/off |\n|---|---|---|---|---|---|\n";
    for (const Comparison& c : rows) {
      m << "| " << c.name << " | " << rp::CellText(c.variant) << " | " << c.scene << " (" << c.on.scene->bodies.size()
        << " bodies) | " << Cell(c.on) << " | " << Cell(c.off) << " | " << Ratio(c) << " |\n";
    }
    for (const Comparison& c : rows) {
      if (!c.note.empty()) m << "\n" << c.name << ": " << c.note << ".\n";
    }
    m << "\n## Only the needed effects against all on\n\n"
      << "\"All on\" switches on every effect the Quadrant adapter accepts (each tried on its own; the ones it "
      << "refuses stay off and are listed) and keeps the scene's materials and gravity vector (zero gravity, "
      << "friction 0, restitution 1), so the physics is the same and mostly the work differs. The position "
      << "column says how far apart the two runs' bodies ended: round-off (1e-5 m) means the same motion; the "
      << "scenes are chaotic, so any real change (continuous collision finds contacts earlier) grows to metres "
      << "within the run and the figure then says only that the motion changed. \"Needed\": restitution and "
      << "warm starting for circles (frictionless circles get no torque, so rotation does nothing there), plus "
      << "rotation for polygons. "
      << "all_off_speedup = time(all on) / time(needed only).\n\n"
      << "| scene | all on | needed only | all on: ms/step | needed only: ms/step | all_off_speedup | largest "
         "position difference after the run (m) | refused by the adapter |\n|---|---|---|---|---|---|---|---|\n";
    for (const Comparison& c : allOff) {
      const std::optional<double> diff = PositionDifference(c);
      m << "| " << c.scene << " (" << args.count << ") | " << EffectsText(c.on.scene->effects) << " | "
        << EffectsText(c.off.scene->effects) << " | " << Cell(c.on) << " | " << Cell(c.off) << " | " << Ratio(c)
        << " | " << (diff ? rp::Cell(*diff) : "-") << " | " << rp::CellText(c.note) << " |\n";
    }
    m << "\nall_off_speedup (geometric mean over both scenes): " << rp::Cell(geomean) << "\n";

    std::filesystem::create_directories(args.out);
    const std::filesystem::path dir(args.out);
    std::ofstream(dir / "effects.json") << j.str();
    std::ofstream(dir / "effects.md") << m.str();
    std::cout << m.str();
    std::cerr << fmt::format("quadrant_effects: wrote {}/effects.json and effects.md ({:.0f} s)\n", args.out, seconds);
  } catch (const quadrant::Error& e) {
    std::cerr << "quadrant_effects: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
