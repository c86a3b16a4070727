// Scene names to scene builders: the one place a scene is looked up by name.
#include <cstdint>
#include <string>

#include "quadrant/error.h"
#include "scenes.h"

namespace quadrant::scene {

std::vector<std::string> SceneNames() {
  return {"circle_stress", "polygon_stress", "circle_stress_clumped", "polygon_stress_clumped",
          "many_pyramids", "tumbler", "joint_grid", "junkyard", "smash", "spinner", "rain", "compounds", "washer",
          // The hard cases (hard_cases.cpp): fixed size except pyramid, where `count` is the
          // number of boxes and the base the largest b with b (b + 1) / 2 <= count (210 -> base
          // 20, 5050 -> base 100).
          "vertical_stack", "pyramid", "mass_ratio_100", "mass_ratio_400", "arch", "card_house",
          "friction_ramp", "restitution_drop", "overlap_recovery", "confined", "far_from_origin",
          "newtons_cradle", "tall_stack", "tall_stack_50", "heavy_on_supports", "heavy_on_slab", "closed_box", "heavy_chain", "ragdoll_pile", "prismatic_stop", "weld_beam",
          "wheel_terrain", "hanging_grid",
          // Solver2D's contact scenes (issue #26 item 2).
          "single_box", "warm_start_energy", "high_mass_ratio_1", "high_mass_ratio_2", "high_mass_ratio_3", "rush",
          "double_domino", "circle_stack", "far_stack", "far_recovery"};
}

Scene MakeScene(std::string_view name, int count, uint64_t seed) {
  StressParams p;
  p.count = count;
  p.seed = seed;
  if (name == "circle_stress" || name == "polygon_stress" || name == "circle_stress_clumped" ||
      name == "polygon_stress_clumped") {
    p.shape = name.starts_with("circle") ? ShapeKind::kCircle : ShapeKind::kPolygon;
    p.clumped = name.ends_with("_clumped");
    Scene s = MakeStressScene(p);
    s.name = std::string(name);
    return s;
  }
  if (name == "pyramid") {
    if (count < 1) throw Error("pyramid: count must be >= 1 box, got " + std::to_string(count));
    int base = 1;
    while (int64_t(base + 1) * (base + 2) / 2 <= count) ++base;
    return MakePyramid(base);
  }
  if (name == "many_pyramids") return MakeManyPyramids(count);
  if (name == "tumbler") return MakeTumbler(count);
  if (name == "joint_grid") return MakeJointGrid(count);
  if (name == "junkyard") return MakeJunkyard(count);
  if (name == "smash") return MakeSmash(count);
  if (name == "spinner") return MakeSpinner(count);
  if (name == "rain") return MakeRain(count);
  if (name == "compounds") return MakeCompounds(count);
  if (name == "washer") return MakeWasher(count);
  if (name == "vertical_stack") return MakeVerticalStack();
  if (name == "mass_ratio_100") return MakeMassRatio(100);
  if (name == "mass_ratio_400") return MakeMassRatio(400);
  if (name == "arch") return MakeArch();
  if (name == "card_house") return MakeCardHouse();
  if (name == "friction_ramp") return MakeFrictionRamp();
  if (name == "restitution_drop") return MakeRestitutionDrop();
  if (name == "overlap_recovery") return MakeOverlapRecovery();
  if (name == "confined") return MakeConfined(25, seed);
  if (name == "far_from_origin") return MakeFarFromOrigin();
  if (name == "newtons_cradle") return MakeNewtonsCradle();
  if (name == "tall_stack") return MakeTallStack();
  if (name == "tall_stack_50") return MakeTallStack(50);
  if (name == "heavy_on_supports") return MakeHeavyOnSupports();
  if (name == "heavy_on_slab") return MakeHeavyOnSlab();
  if (name == "closed_box") return MakeClosedBox(2000, seed);
  if (name == "heavy_chain") return MakeHeavyChain();
  if (name == "ragdoll_pile") return MakeRagdollPile();
  if (name == "prismatic_stop") return MakePrismaticStop();
  if (name == "weld_beam") return MakeWeldBeam();
  if (name == "wheel_terrain") return MakeWheelTerrain();
  if (name == "hanging_grid") return MakeHangingGrid();
  if (name == "single_box") return MakeSingleBox();
  if (name == "warm_start_energy") return MakeWarmStartEnergy();
  if (name == "high_mass_ratio_1") return MakeHighMassRatio(1);
  if (name == "high_mass_ratio_2") return MakeHighMassRatio(2);
  if (name == "high_mass_ratio_3") return MakeHighMassRatio(3);
  if (name == "rush") return MakeRush();
  if (name == "double_domino") return MakeDoubleDomino();
  if (name == "circle_stack") return MakeCircleStack();
  if (name == "far_stack") return MakeFarStack(kFarStackOrigin);
  if (name == "far_recovery") return MakeFarRecovery(kFarRecoveryOrigin);
  std::string known;
  for (const std::string& n : SceneNames()) known += (known.empty() ? "" : ", ") + n;
  throw Error("unknown scene '" + std::string(name) + "' (known: " + known + ")");
}

bool IsDenseScene(std::string_view name) {
  return name == "pyramid" || name == "many_pyramids" || name == "tumbler" || name == "joint_grid" || name == "junkyard" ||
         name == "smash" || name == "spinner" || name == "rain" || name == "compounds" || name == "washer";
}

std::vector<std::string> DefaultBenchScenes() {
  return {"circle_stress", "polygon_stress", "pyramid", "many_pyramids", "tumbler"};
}

std::vector<int> DefaultBenchCounts(std::string_view name) {
  if (name.starts_with("circle_stress") || name.starts_with("polygon_stress")) return {1000, 2000, 4000, 8000, 16000};
  // Dense scenes: every body is in contact, and Bullet and Box2D 2.4 are single-threaded, so
  // each gets two sizes chosen to add a few minutes to the default run: the pyramid at Box2D 3's
  // large size (base 100) and base 50, the tumbler at Box2D 3's 45 x 45 and 32 x 32, and
  // many_pyramids at an eighth and a sixteenth of Box2D 3's 22000 (in one trial on a loaded
  // machine, 5500 boxes cost Box2D 2.4, Bullet and Chipmunk 1.1-1.4x what the base-100 pyramid
  // does per step; --counts 22000 runs Box2D 3's size).
  if (name == "pyramid") return {1275, 5050};
  if (name == "many_pyramids") return {1375, 2750};
  if (name == "tumbler") return {1024, 2025};
  // Box2D 3's sizes and a quarter of them (not in the default run).
  if (name == "joint_grid") return {2493, 9993};  // N = 50 and Box2D 3's N = 100
  if (name == "junkyard") return {2000, 8000};
  if (name == "smash") return {2400, 9600};
  if (name == "spinner") return {1519, 6076};
  if (name == "rain") return {2200, 11000};  // ragdoll bodies at most: 1 and Box2D 3's 5 storeys
  if (name == "compounds") return {760, 3000};
  if (name == "washer") return {2025, 8100};
  throw Error("no default bench counts for scene '" + std::string(name) + "'");
}

namespace {
struct Box2d3Entry {
  const char* scene;
  int count, steps;
};
// benchmark/main.c's table and shared/benchmarks.c's sizes.
constexpr Box2d3Entry kBox2d3[] = {{"compounds", 3000, 500}, {"joint_grid", 9993, 500}, {"junkyard", 8000, 800}, {"pyramid", 5050, 500},
                                   {"many_pyramids", 22000, 200}, {"rain", 11000, 1000}, {"smash", 9600, 300},
                                   {"spinner", 6076, 500}, {"tumbler", 2025, 750},
                                   {"washer", 8100, 500}};
const Box2d3Entry& FindBox2d3(std::string_view name) {
  for (const Box2d3Entry& e : kBox2d3) {
    if (name == e.scene) return e;
  }
  throw Error("'" + std::string(name) + "' is not one of Box2D 3's benchmark scenes in the suite");
}
}  // namespace

std::vector<std::string> Box2d3Scenes() {
  std::vector<std::string> out;
  for (const Box2d3Entry& e : kBox2d3) out.push_back(e.scene);
  return out;
}
int Box2d3Count(std::string_view name) { return FindBox2d3(name).count; }
int Box2d3Steps(std::string_view name) { return FindBox2d3(name).steps; }

}  // namespace quadrant::scene
