// The thesis's Figure 13: a 5000-circle stress scene under the quadrants scheme with 4
// threads, written as CSV (one line per body: x, y, radius, owner thread or -1 for the master)
// for tools/figure13.py to draw with the quad-tree. Usage: quadrant_figure13 OUT.csv [bodies] [steps]
#include <cstdio>
#include <cstdlib>
#include <string>

#include "cli_args.h"
#include "quadrant/world.h"
#include "scenes.h"

int main(int argc, char** argv) {
  std::string path;
  int count = 5000, steps = 120;
  quadrant::cli::Parser p("quadrant_figure13",
                          "The thesis's Figure 13: a circle stress scene under the quadrants scheme with 4 "
                          "threads, as CSV\n(x, y, radius, owner thread or -1 for the master, dynamic) for "
                          "tools/figure13.py.");
  p.String("OUT.csv", &path, "", "the CSV file to write").Required();
  p.Int("bodies", &count, 1, 10000000, "circles in the scene");
  p.Int("steps", &steps, 0, 100000000, "steps before the owners are written");
  p.Parse(argc, argv);
  try {
    const quadrant::scene::Scene s = quadrant::scene::MakeScene("circle_stress", count, 42);
    quadrant::WorldDef def;
    def.gravity = s.gravity;
    def.restitutionThreshold = s.restitutionThreshold;
    def.effects.gravity = false;
    def.effects.friction = false;
    def.threadCount = 4;
    def.scheme = quadrant::ParallelScheme::kQuadrants;
    def.broadPhase = quadrant::BroadPhaseType::kQuadTree;
    quadrant::World world(def);
    for (const quadrant::scene::BodyDesc& b : s.bodies) {
      quadrant::BodyDef bd;
      bd.type = b.dynamic ? quadrant::BodyType::kDynamic : quadrant::BodyType::kStatic;
      bd.position = b.position;
      bd.linearVelocity = b.velocity;
      bd.shape = b.shape == quadrant::scene::ShapeKind::kCircle
                     ? quadrant::ShapeDef::MakeCircle(b.radius)
                     : quadrant::ShapeDef::FromPolygon(quadrant::MakePolygon(b.vertices));
      bd.shape.friction = b.friction;
      bd.shape.restitution = b.restitution;
      world.CreateBody(bd);
    }
    for (int i = 0; i < steps; ++i) world.Step(s.timeStep);
    const std::vector<int> owners = world.GetOwners();
    const std::vector<quadrant::BodyId> ids = world.GetBodyIds();
    FILE* out = std::fopen(path.c_str(), "w");
    if (!out) {
      std::fprintf(stderr, "quadrant_figure13: cannot write %s\n", path.c_str());
      return 1;
    }
    const quadrant::AABB region = world.GetPartitionRegion();
    std::fprintf(out, "# region %g %g %g %g, %d bodies after %d steps, 4 threads, quadrants scheme\n",
                 region.lower.x, region.lower.y, region.upper.x, region.upper.y, count, steps);
    std::fprintf(out, "x,y,radius,owner,dynamic\n");
    for (size_t k = 0; k < ids.size(); ++k) {
      const quadrant::AABB box = world.GetAABB(ids[k]);
      const quadrant::Vec2 p = world.GetPosition(ids[k]);
      const bool dynamic = world.GetType(ids[k]) == quadrant::BodyType::kDynamic;
      const float radius = dynamic ? 0.5f * (box.upper.x - box.lower.x) : 0.0f;
      std::fprintf(out, "%.4f,%.4f,%.4f,%d,%d\n", p.x, p.y, radius, owners[k], dynamic ? 1 : 0);
    }
    std::fclose(out);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "quadrant_figure13: %s\n", e.what());
    return 1;
  }
  return 0;
}
