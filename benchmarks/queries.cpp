// World queries timed against Box2D 2.4.1's b2World::QueryAABB and b2World::RayCast (issue 16):
// the same bodies (the stress scenes, circles and polygons, at their spawn positions) in both
// engines, the same random boxes and rays, exact answers on both sides.
//
//   queries/<kind>/<engine>/<scene>/<N>   kind: aabb, ray_closest, ray_all, aabb_after_move
//
// One iteration is 256 queries; counters give queries per second and the mean number of results.
// Box2D's QueryAABB reports fixtures whose fat tree box overlaps, so its callback adds the exact
// test (b2TestOverlap against the query box as a polygon) that Quadrant's QueryAABB includes.
// `aabb_after_move` is Quadrant's cost of the first query after a change (a step, SetTransform):
// the query structure is rebuilt from every body's box then (world.h); Box2D's tree is updated
// inside its step instead, so it has no such row. Box2D's exact test counts a box 0.01 m larger
// (b2_polygonRadius on the query polygon), so it reports slightly more bodies per box.
//
// Timings are not committed (shared machine); run with tools/quadrant's usual Google Benchmark
// flags, e.g. build/release/benchmarks/quadrant_queries --benchmark_repetitions=9.
#include <benchmark/benchmark.h>

#include <box2d/box2d.h>

#include <memory>
#include <random>
#include <string>
#include <vector>

#include "gbench_main.h"
#include "quadrant/world.h"
#include "scenes.h"

namespace {

using namespace quadrant;
using namespace quadrant::scene;

constexpr int kQueriesPerIteration = 256;

struct Probe {
  std::vector<AABB> boxes;
  std::vector<Vec2> origins, translations;
};

// Boxes of 1-4 m and rays of 5-20 m inside the scene's bounds, seeded.
Probe MakeProbe(const Scene& scene) {
  std::mt19937 rng(7);
  const AABB b = scene.bounds;
  std::uniform_real_distribution<float> x(b.lower.x, b.upper.x), y(b.lower.y, b.upper.y), size(1, 4), len(5, 20),
      angle(-3.14159f, 3.14159f);
  Probe p;
  for (int i = 0; i < kQueriesPerIteration; ++i) {
    const Vec2 lo{x(rng), y(rng)};
    p.boxes.push_back({lo, lo + Vec2{size(rng), size(rng)}});
    const float a = angle(rng), l = len(rng);
    p.origins.push_back({x(rng), y(rng)});
    p.translations.push_back({l * std::cos(a), l * std::sin(a)});
  }
  return p;
}

std::unique_ptr<World> LoadQuadrant(const Scene& scene) {
  auto world = std::make_unique<World>();
  for (const BodyDesc& d : scene.bodies) world->CreateBody(ToBodyDef(d));
  return world;
}

std::unique_ptr<b2World> LoadBox2d(const Scene& scene) {
  auto world = std::make_unique<b2World>(b2Vec2(0, 0));
  for (const BodyDesc& d : scene.bodies) {
    b2BodyDef def;
    def.type = d.dynamic ? b2_dynamicBody : b2_staticBody;
    def.position.Set(d.position.x, d.position.y);
    def.angle = d.angle;
    b2Body* body = world->CreateBody(&def);
    if (d.shape == ShapeKind::kCircle) {
      b2CircleShape c;
      c.m_radius = d.radius;
      body->CreateFixture(&c, 1);
    } else {
      std::vector<b2Vec2> v;
      for (Vec2 p : d.vertices) v.emplace_back(p.x, p.y);
      b2PolygonShape poly;
      poly.Set(v.data(), int32(v.size()));
      body->CreateFixture(&poly, 1);
    }
  }
  return world;
}

class Box2dQuery : public b2QueryCallback {
 public:
  b2PolygonShape box;
  int found = 0;
  bool ReportFixture(b2Fixture* f) override {
    if (b2TestOverlap(f->GetShape(), 0, &box, 0, f->GetBody()->GetTransform(), b2Transform(b2Vec2(0, 0), b2Rot(0)))) ++found;
    return true;
  }
};

class Box2dRay : public b2RayCastCallback {
 public:
  bool closest = true;
  int hits = 0;
  float best = 1;
  float ReportFixture(b2Fixture*, const b2Vec2&, const b2Vec2&, float fraction) override {
    ++hits;
    if (closest) {
      best = fraction;
      return fraction;  // clip the ray: only nearer fixtures from now on
    }
    return 1;  // every hit
  }
};

enum class Kind { kAabb, kRayClosest, kRayAll, kAabbAfterMove };

void RunQuadrant(benchmark::State& state, const std::string& name, Kind kind) {
  const Scene scene = MakeScene(name, int(state.range(0)));
  std::unique_ptr<World> world = LoadQuadrant(scene);
  const Probe probe = MakeProbe(scene);
  const BodyId moved = world->GetBodyIds().back();
  const Vec2 at = world->GetPosition(moved);
  std::vector<BodyId> bodies;
  std::vector<RayHit> hits;
  int64_t results = 0;
  for (auto _ : state) {
    for (int i = 0; i < kQueriesPerIteration; ++i) {
      switch (kind) {
        case Kind::kAabbAfterMove:
          world->SetTransform(moved, at, 0);  // a change: the next query rebuilds
          [[fallthrough]];
        case Kind::kAabb:
          world->QueryAABB(probe.boxes[i], bodies);
          results += int64_t(bodies.size());
          break;
        case Kind::kRayClosest:
          results += world->RayCastClosest(probe.origins[i], probe.translations[i]).has_value() ? 1 : 0;
          break;
        case Kind::kRayAll:
          world->RayCastAll(probe.origins[i], probe.translations[i], hits);
          results += int64_t(hits.size());
          break;
      }
    }
  }
  state.counters["queries_per_s"] = benchmark::Counter(double(state.iterations()) * kQueriesPerIteration,
                                                       benchmark::Counter::kIsRate);
  state.counters["results_per_query"] = double(results) / (double(state.iterations()) * kQueriesPerIteration);
  state.counters["bodies"] = double(scene.bodies.size());
}

void RunBox2d(benchmark::State& state, const std::string& name, Kind kind) {
  const Scene scene = MakeScene(name, int(state.range(0)));
  std::unique_ptr<b2World> world = LoadBox2d(scene);
  const Probe probe = MakeProbe(scene);
  Box2dQuery query;
  Box2dRay ray;
  ray.closest = kind == Kind::kRayClosest;
  int64_t results = 0;
  for (auto _ : state) {
    for (int i = 0; i < kQueriesPerIteration; ++i) {
      if (kind == Kind::kAabb) {
        const AABB& b = probe.boxes[i];
        b2AABB box;
        box.lowerBound.Set(b.lower.x, b.lower.y);
        box.upperBound.Set(b.upper.x, b.upper.y);
        query.box.SetAsBox(0.5f * (b.upper.x - b.lower.x), 0.5f * (b.upper.y - b.lower.y),
                           b2Vec2(0.5f * (b.lower.x + b.upper.x), 0.5f * (b.lower.y + b.upper.y)), 0);
        query.found = 0;
        world->QueryAABB(&query, box);
        results += query.found;
      } else {
        const Vec2 o = probe.origins[i], e = probe.origins[i] + probe.translations[i];
        ray.hits = 0;
        ray.best = 1;
        world->RayCast(&ray, b2Vec2(o.x, o.y), b2Vec2(e.x, e.y));
        results += ray.closest ? (ray.hits > 0 ? 1 : 0) : ray.hits;
      }
    }
  }
  state.counters["queries_per_s"] = benchmark::Counter(double(state.iterations()) * kQueriesPerIteration,
                                                       benchmark::Counter::kIsRate);
  state.counters["results_per_query"] = double(results) / (double(state.iterations()) * kQueriesPerIteration);
  state.counters["bodies"] = double(scene.bodies.size());
}

void Register() {
  const std::pair<Kind, const char*> kinds[] = {
      {Kind::kAabb, "aabb"}, {Kind::kRayClosest, "ray_closest"}, {Kind::kRayAll, "ray_all"}, {Kind::kAabbAfterMove, "aabb_after_move"}};
  for (const char* scene : {"circle_stress", "polygon_stress"}) {
    for (const auto& [kind, kindName] : kinds) {
      const std::string s = scene;
      const Kind k = kind;
      benchmark::RegisterBenchmark(("queries/" + std::string(kindName) + "/quadrant/" + s).c_str(),
                                   [s, k](benchmark::State& st) { RunQuadrant(st, s, k); })
          ->Arg(1000)->Arg(8000)->Arg(32000)->Unit(benchmark::kMicrosecond);
      if (k == Kind::kAabbAfterMove) continue;
      benchmark::RegisterBenchmark(("queries/" + std::string(kindName) + "/box2d/" + s).c_str(),
                                   [s, k](benchmark::State& st) { RunBox2d(st, s, k); })
          ->Arg(1000)->Arg(8000)->Arg(32000)->Unit(benchmark::kMicrosecond);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  Register();
  return quadrant::cli::GoogleBenchmarkMain("quadrant_queries",
                                            "World queries (QueryAABB, ray casts) timed against Box2D 2.4.1's on "
                                            "the stress scenes, named\nqueries/<kind>/<engine>/<scene>/<N>. No "
                                            "options of its own.",
                                            argc, argv);
}
