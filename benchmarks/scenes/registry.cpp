// Scene names to scene builders: the one place a scene is looked up by name.
#include <string>

#include "quadrant/error.h"
#include "scenes.h"

namespace quadrant::scene {

std::vector<std::string> SceneNames() { return {"circle_stress", "polygon_stress", "circle_stress_clumped", "polygon_stress_clumped"}; }

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
  std::string known;
  for (const std::string& n : SceneNames()) known += (known.empty() ? "" : ", ") + n;
  throw Error("unknown scene '" + std::string(name) + "' (known: " + known + ")");
}

}  // namespace quadrant::scene
