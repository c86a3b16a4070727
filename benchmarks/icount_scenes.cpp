// quadrant_icount: steps ONE scene on the Quadrant engine a fixed number of times, for
// instruction counting under valgrind's callgrind (tools/icount.py drives it).
//
// Wall-clock benchmarks on a shared VM have a few per cent of noise; the number of instructions
// the engine executes for a given binary and input does not (callgrind counts it exactly, and
// the scenes are deterministic). So a change that makes the engine do more work shows up here
// even when it is smaller than the timing noise.
//
// Only the stepping is counted: the scene is built and loaded with callgrind's instrumentation
// off (run it with --instr-atstart=no --collect-atstart=no), and the client requests below
// switch instrumentation and collection on around the stepping loop only. Outside valgrind the
// requests are a few no-op instructions, so the program also runs natively.
//
// usage:
//   quadrant_icount --scene NAME --count N --steps S [--seed X]
//       prints one line "key=<key> scene=<name> source=<registry|builtin> bodies=<n> steps=<s>
//       hash=<16 hex digits>"; <key> (e.g. circle_stress_1000_60) names the count in icount.json
//       --engine quadrant:VARIANT steps a Quadrant variant instead of the default engine (to compare
//       solvers by hand; tools/icount.py always counts the default "quadrant")
//   quadrant_icount --info
//       prints the build: compiler=..., build_type=..., cxx_flags=..., extra_work=0|1
//
// The scene "pyramid" is taken from the scene registry (quadrant::scene::SceneNames) when it
// has one that gives a base-N pyramid; until then a base-N pyramid of 1 m boxes on a static
// ground is built here (key pyramid_builtin_<N>_<S>, so counts of the two never get mixed up).
//
// QUADRANT_ICOUNT_INJECT_EXTRA_WORK (CMake option, default OFF) compiles one more pass over the
// bodies into every step, so that the icount test proves --check catches more work (+11 % to
// +125 % instructions on the three scenes, well above the 2 % tolerance).
#include <valgrind/callgrind.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <string>
#include <vector>

#include "adapter.h"
#include "cli_args.h"
#include "cli_engines.h"
#include "quadrant/error.h"
#include "scene.h"
#include "scenes.h"

#ifndef QUADRANT_CXX_FLAGS
#define QUADRANT_CXX_FLAGS "unknown"
#endif
#ifndef QUADRANT_BUILD_TYPE
#define QUADRANT_BUILD_TYPE "unknown"
#endif
#ifndef QUADRANT_ICOUNT_INJECT_EXTRA_WORK
#define QUADRANT_ICOUNT_INJECT_EXTRA_WORK 0
#endif

namespace {

namespace qs = quadrant::scene;

int DynamicBodies(const qs::Scene& scene) {
  return int(std::count_if(scene.bodies.begin(), scene.bodies.end(),
                           [](const qs::BodyDesc& b) { return b.dynamic; }));
}

std::vector<quadrant::Vec2> Box(quadrant::Real hx, quadrant::Real hy) {
  return {{-hx, -hy}, {hx, -hy}, {hx, hy}, {-hx, hy}};  // counter-clockwise
}

/// A pyramid of 1 m boxes with `base` boxes in its bottom row (base (base + 1) / 2 boxes), each
/// row centred on the one below and resting on it, on a static ground whose top is y = 0.
/// Gravity, friction 0.6, no restitution: the classic stacking test (Box2D's "pyramid").
qs::Scene BuiltinPyramid(int base) {
  if (base < 1 || base > 1000) throw quadrant::Error("pyramid: base must be in [1, 1000]");
  qs::Scene scene;
  scene.name = "pyramid";
  const quadrant::Real half = quadrant::Real(0.5);
  const quadrant::Real groundHalfWidth = quadrant::Real(base) + 10;
  qs::BodyDesc ground;
  ground.dynamic = false;
  ground.shape = qs::ShapeKind::kPolygon;
  ground.vertices = Box(groundHalfWidth, half);
  ground.position = {0, -half};
  scene.bodies.push_back(ground);
  for (int row = 0; row < base; ++row) {
    const int count = base - row;
    for (int i = 0; i < count; ++i) {
      qs::BodyDesc box;
      box.shape = qs::ShapeKind::kPolygon;
      box.vertices = Box(half, half);
      box.position = {quadrant::Real(i) - quadrant::Real(count - 1) / 2, half + quadrant::Real(row)};
      scene.bodies.push_back(box);
    }
  }
  scene.bounds = {{-groundHalfWidth, -1}, {groundHalfWidth, quadrant::Real(base) + 1}};
  return scene;
}

struct Made {
  qs::Scene scene;
  std::string source;  // "registry" or "builtin"
};

Made MakeIcountScene(const std::string& name, int count, uint64_t seed) {
  if (name != "pyramid") return {qs::MakeScene(name, count, seed), "registry"};
  const std::vector<std::string> names = qs::SceneNames();
  if (std::find(names.begin(), names.end(), "pyramid") == names.end())
    return {BuiltinPyramid(count), "builtin"};
  // The registry's pyramid: its count may be the base or the number of boxes.
  const int boxes = count * (count + 1) / 2;
  for (int tryCount : {count, boxes}) {
    qs::Scene scene = qs::MakeScene("pyramid", tryCount, seed);
    if (DynamicBodies(scene) == boxes) return {std::move(scene), "registry"};
  }
  throw quadrant::Error("the scene registry's 'pyramid' gives no base-" + std::to_string(count) +
                        " pyramid (" + std::to_string(boxes) +
                        " boxes) for count = base or count = boxes: adapt MakeIcountScene in "
                        "benchmarks/icount_scenes.cpp");
}

struct Args {
  std::string scene;
  int count = 0;
  int steps = 0;
  uint64_t seed = 42;
  bool info = false;
  std::string engine = "quadrant";
};

Args ParseArgs(int argc, char** argv) {
  Args a;
  std::vector<std::string> scenes = qs::SceneNames();
  if (std::find(scenes.begin(), scenes.end(), "pyramid") == scenes.end()) scenes.push_back("pyramid");
  quadrant::cli::Parser p("quadrant_icount",
                          "Steps one scene on the Quadrant engine a fixed number of times, for instruction "
                          "counts under callgrind\n(tools/icount.py); prints key=... scene=... source=... "
                          "bodies=... steps=... hash=....");
  p.Name("--scene", &a.scene, scenes, "scene", "the scene (required unless --info)");
  p.Int("--count", &a.count, 1, 1000000, "its count (required unless --info; pyramid: the base)").Default("");
  p.Int("--steps", &a.steps, 1, 1000000, "steps counted (required unless --info)").Default("");
  p.Int("--seed", &a.seed, 0, INT64_MAX, "the scene's seed");
  p.Name("--engine", &a.engine, {}, "engine", "a Quadrant variant to step instead (quadrant:VARIANT)")
      .Check(quadrant::cli::EngineProblem);
  p.Flag("--info", &a.info, "print the build (compiler, build type, flags, extra_work) and exit");
  p.Parse(argc, argv);
  if (!a.info) {
    for (const char* name : {"--scene", "--count", "--steps"}) {
      if (!p.Given(name)) p.FailMissing(name);
    }
  }
  return a;
}

const char* Compiler() {
#if defined(__clang__)
  return __VERSION__;
#elif defined(__GNUC__)
  return "GCC " __VERSION__;  // the same spelling as quadrant_bench's JSON context
#else
  return __VERSION__;
#endif
}

}  // namespace

int main(int argc, char** argv) {
  const Args args = ParseArgs(argc, argv);
  if (args.info) {
    std::printf("compiler=%s\nbuild_type=%s\ncxx_flags=%s\nextra_work=%d\n", Compiler(),
                QUADRANT_BUILD_TYPE, QUADRANT_CXX_FLAGS, QUADRANT_ICOUNT_INJECT_EXTRA_WORK);
    return 0;
  }
  try {
    // Not counted: building the scene, the adapter and the world.
    Made made = MakeIcountScene(args.scene, args.count, args.seed);
    std::unique_ptr<qs::Adapter> adapter = qs::MakeAdapter(args.engine);
    adapter->Load(made.scene, 1);
#if QUADRANT_ICOUNT_INJECT_EXTRA_WORK
    std::vector<qs::BodyState> states;
    states.reserve(made.scene.bodies.size());  // no allocation inside the counted loop
    volatile double sink = 0;
#endif

    // Counted: exactly args.steps steps.
    CALLGRIND_START_INSTRUMENTATION;
    CALLGRIND_TOGGLE_COLLECT;
    for (int i = 0; i < args.steps; ++i) {
      adapter->Step();
#if QUADRANT_ICOUNT_INJECT_EXTRA_WORK
      adapter->ReadBodies(states);
      sink = sink + qs::KineticEnergy(made.scene, states);
#endif
    }
    CALLGRIND_TOGGLE_COLLECT;
    CALLGRIND_STOP_INSTRUMENTATION;

    const std::string key = args.scene + (made.source == "builtin" ? "_builtin_" : "_") +
                            std::to_string(args.count) + "_" + std::to_string(args.steps);
    std::printf("key=%s scene=%s source=%s bodies=%d steps=%d hash=%016llx\n", key.c_str(),
                args.scene.c_str(), made.source.c_str(), int(made.scene.bodies.size()), args.steps,
                static_cast<unsigned long long>(adapter->StateHash()));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "quadrant_icount: %s\n", e.what());
    return 1;
  }
  return 0;
}
