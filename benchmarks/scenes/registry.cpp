// Scene names to scene builders: the one place a scene is looked up by name.
#include <cstdint>
#include <string>

#include "quadrant/error.h"
#include "scenes.h"

namespace quadrant::scene {

std::vector<std::string> SceneNames() {
  return {"circle_stress", "polygon_stress", "circle_stress_clumped", "polygon_stress_clumped",
          // The hard cases (hard_cases.cpp): fixed size except pyramid, where `count` is the
          // number of boxes and the base the largest b with b (b + 1) / 2 <= count (210 -> base
          // 20, 5050 -> base 100).
          "vertical_stack", "pyramid", "mass_ratio_100", "mass_ratio_400", "arch", "card_house",
          "friction_ramp", "restitution_drop", "overlap_recovery", "confined", "far_from_origin",
          "newtons_cradle", "tall_stack", "heavy_on_supports", "heavy_on_slab"};
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
  if (name == "heavy_on_supports") return MakeHeavyOnSupports();
  if (name == "heavy_on_slab") return MakeHeavyOnSlab();
  std::string known;
  for (const std::string& n : SceneNames()) known += (known.empty() ? "" : ", ") + n;
  throw Error("unknown scene '" + std::string(name) + "' (known: " + known + ")");
}

}  // namespace quadrant::scene
