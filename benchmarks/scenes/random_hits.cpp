// The random hits of the validation campaign (random_hits.h).
#include "random_hits.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "quadrant/error.h"
#include "scenes.h"
#include "validation_cases.h"

namespace quadrant::scene {
namespace {

struct D2 {
  double x = 0, y = 0;
};
D2 Of(Vec2 v) { return {double(v.x), double(v.y)}; }
Vec2 ToVec(D2 v) { return {Real(v.x), Real(v.y)}; }
D2 Rotated(D2 v, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {c * v.x - s * v.y, s * v.x + c * v.y};
}

constexpr double kMinRadius = 0.35, kMaxRadius = 0.5;  // the stress scenes' polygon sizes (m)
constexpr double kMinSpeed = 2, kMaxSpeed = 8;         // m/s
constexpr double kMaxAngle = std::numbers::pi / 3;     // off the normal (rad)
constexpr double kMaxSpin = 8;                         // rad/s
// The contact point must approach faster than the restitution threshold (1 m/s) by a margin, so
// float rounding cannot decide whether a hit bounces.
constexpr double kMinApproach = 1.25;  // m/s

// The mover starts this far (m) into the target along the normal. Exactly touching, float
// rounding left some circle pairs a hair apart, and Box2D creates a contact only for shapes that
// overlap: it missed the contact in the first step and met the target a step later at another
// point. 0.5 mm is a tenth of the linear slop, so no engine's position pass acts on it.
constexpr double kStartOverlap = 0.0005;

// A shape placed in the world (double precision), for the re-contact test of the analytic answer.
struct Placed {
  bool circle = false;
  D2 center;
  double radius = 0;
  std::vector<D2> vertices;
};

Placed Place(const BodyDesc& b, double x, double y, double angle) {
  Placed p;
  p.circle = b.shape == ShapeKind::kCircle;
  p.center = {x, y};
  p.radius = b.radius;
  for (Vec2 v : b.vertices) {
    const D2 r = Rotated(Of(v), angle);
    p.vertices.push_back({x + r.x, y + r.y});
  }
  return p;
}

// Overlap of two projections along a unit axis (negative: a gap).
double AxisOverlap(const Placed& a, const Placed& b, D2 axis) {
  auto range = [&](const Placed& s, double& lo, double& hi) {
    if (s.circle) {
      const double c = s.center.x * axis.x + s.center.y * axis.y;
      lo = c - s.radius;
      hi = c + s.radius;
      return;
    }
    lo = 1e300;
    hi = -1e300;
    for (D2 v : s.vertices) {
      const double d = v.x * axis.x + v.y * axis.y;
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
  };
  double aLo, aHi, bLo, bHi;
  range(a, aLo, aHi);
  range(b, bLo, bHi);
  return std::min(aHi - bLo, bHi - aLo);
}

// Penetration depth of two convex shapes (m; <= 0 when apart), by separating axes: the edge
// normals of the polygons, and for a circle the axis to the nearest vertex (or centre).
double Depth(const Placed& a, const Placed& b) {
  double depth = 1e300;
  std::vector<D2> axes;
  for (const Placed* s : {&a, &b}) {
    const size_t n = s->vertices.size();
    for (size_t i = 0; i < n; ++i) {
      const D2 e{s->vertices[(i + 1) % n].x - s->vertices[i].x, s->vertices[(i + 1) % n].y - s->vertices[i].y};
      const double len = std::hypot(e.x, e.y);
      axes.push_back({e.y / len, -e.x / len});
    }
  }
  for (const Placed* c : {&a, &b}) {
    if (!c->circle) continue;
    const Placed& other = c == &a ? b : a;
    D2 nearest = other.center;
    double best = 1e300;
    for (D2 v : other.vertices) {
      const double d = std::hypot(v.x - c->center.x, v.y - c->center.y);
      if (d < best) {
        best = d;
        nearest = v;
      }
    }
    const double len = std::hypot(nearest.x - c->center.x, nearest.y - c->center.y);
    if (len > 0) axes.push_back({(nearest.x - c->center.x) / len, (nearest.y - c->center.y) / len});
  }
  for (D2 axis : axes) depth = std::min(depth, AxisOverlap(a, b, axis));
  return depth;
}

double Circumradius(const BodyDesc& b) {
  if (b.shape == ShapeKind::kCircle) return b.radius;
  double r = 0;
  for (Vec2 v : b.vertices) r = std::max(r, std::hypot(double(v.x), double(v.y)));
  return r;
}

}  // namespace

std::string RandomHit::Class() const {
  char e[16];
  std::snprintf(e, sizeof e, "%g", restitution);
  return pair + " e=" + e;
}

RandomHit MakeRandomHit(uint64_t seed, int index) {
  Random rng(seed * 0x9E3779B97F4A7C15ull + uint64_t(index) * 0xD1B54A32D192ED03ull + 1);
  RandomHit hit;
  hit.index = index;
  const int kind = rng.UniformInt(0, 2);  // 0 polygon-polygon, 1 circle-polygon, 2 circle-circle
  const bool moverIsCircle = kind == 2 || (kind == 1 && rng.UniformInt(0, 1) == 0);
  const bool targetIsCircle = kind == 2 || (kind == 1 && !moverIsCircle);
  hit.pair = kind == 0 ? "polygon-polygon" : kind == 1 ? "circle-polygon" : "circle-circle";

  // The target rests with its centre of mass at the origin and presents a point p with outward
  // normal `out`: a point on a face (20-80 % along it) or on a circle.
  BodyDesc target;
  D2 p, out;
  if (targetIsCircle) {
    target = MakeCircleBody({0, 0}, Real(rng.Uniform(kMinRadius, kMaxRadius)));
    const double phi = rng.Uniform(0, 2 * std::numbers::pi);
    out = {std::cos(phi), std::sin(phi)};
    p = {target.radius * out.x, target.radius * out.y};
  } else {
    target.shape = ShapeKind::kPolygon;
    target.vertices = RandomConvexPolygon(rng, Real(rng.Uniform(kMinRadius, kMaxRadius)));
    const int n = int(target.vertices.size());
    const int face = rng.UniformInt(0, n - 1);
    const D2 a = Of(target.vertices[face]), b = Of(target.vertices[(face + 1) % n]);
    const double u = rng.Uniform(0.2, 0.8);
    p = {a.x + u * (b.x - a.x), a.y + u * (b.y - a.y)};
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    out = {(b.y - a.y) / len, -(b.x - a.x) / len};  // right perpendicular of a CCW edge
  }
  const D2 n{-out.x, -out.y};  // from the mover to the target
  hit.point = ToVec(p);
  hit.normal = ToVec(n);
  p = {p.x + kStartOverlap * n.x, p.y + kStartOverlap * n.y};  // where the mover's feature starts

  // The mover touches p from outside: a circle with its centre on the outward normal, or a
  // polygon turned so that one vertex is its unique support point in direction n (the direction
  // lies 20-80 % across the vertex's normal cone, so its neighbours stay clear of the face).
  BodyDesc mover;
  if (moverIsCircle) {
    mover = MakeCircleBody({0, 0}, Real(rng.Uniform(kMinRadius, kMaxRadius)));
    mover.position = ToVec({p.x + mover.radius * out.x, p.y + mover.radius * out.y});
    mover.angle = Real(rng.Uniform(-std::numbers::pi, std::numbers::pi));
  } else {
    mover.shape = ShapeKind::kPolygon;
    mover.vertices = RandomConvexPolygon(rng, Real(rng.Uniform(kMinRadius, kMaxRadius)));
    const int m = int(mover.vertices.size());
    const int i = rng.UniformInt(0, m - 1);
    const D2 prev = Of(mover.vertices[(i + m - 1) % m]), v = Of(mover.vertices[i]), next = Of(mover.vertices[(i + 1) % m]);
    const double a0 = std::atan2(-(v.x - prev.x), v.y - prev.y);  // outward normal of the edge into v
    double a1 = std::atan2(-(next.x - v.x), next.y - v.y);         // and of the edge out of it
    while (a1 < a0) a1 += 2 * std::numbers::pi;
    const double support = a0 + rng.Uniform(0.2, 0.8) * (a1 - a0);
    const double angle = std::atan2(n.y, n.x) - support;
    const D2 tip = Rotated(v, angle);
    mover.angle = Real(std::remainder(angle, 2 * std::numbers::pi));
    mover.position = ToVec({p.x - tip.x, p.y - tip.y});
  }

  // Materials and masses: the same coefficients on both bodies; the mass ratio log-uniform in
  // 1-100 with either body the heavier.
  hit.restitution = 0.5 * rng.UniformInt(0, 2);
  hit.friction = 0.3 * rng.UniformInt(0, 1);
  hit.massRatio = std::exp(rng.Uniform(0, std::log(100.0)));
  const double moverMass = ComputeMassProperties(mover).mass, targetMass = ComputeMassProperties(target).mass;
  if (rng.UniformInt(0, 1) == 0) {
    mover.density = Real(hit.massRatio * targetMass / moverMass);
  } else {
    target.density = Real(hit.massRatio * moverMass / targetMass);
  }
  for (BodyDesc* b : {&mover, &target}) {
    b->friction = Real(hit.friction);
    b->restitution = Real(hit.restitution);
  }

  // Motion: the mover's velocity within 60 degrees of n, its spin redrawn until its contact point
  // approaches fast enough.
  hit.speed = rng.Uniform(kMinSpeed, kMaxSpeed);
  hit.approachAngle = rng.Uniform(-kMaxAngle, kMaxAngle);
  const D2 v = Rotated({hit.speed * n.x, hit.speed * n.y}, hit.approachAngle);
  const D2 r{p.x - double(mover.position.x), p.y - double(mover.position.y)};
  for (int attempt = 0;; ++attempt) {
    hit.moverSpin = attempt < 32 ? rng.Uniform(-kMaxSpin, kMaxSpin) : 0;
    const double vn = (v.x - hit.moverSpin * r.y) * n.x + (v.y + hit.moverSpin * r.x) * n.y;
    if (vn >= kMinApproach || attempt >= 32) break;
  }
  mover.velocity = ToVec(v);
  mover.angularVelocity = Real(hit.moverSpin);

  Scene& s = hit.scene;
  s = ValidationWorld("random_hit", false);
  s.restitutionThreshold = 1;
  s.bodies = {mover, target};
  s.seed = seed;
  hit.radius[0] = Circumradius(mover);
  hit.radius[1] = Circumradius(target);
  return hit;
}

HitRun RunRandomHit(const RandomHit& hit, std::string_view engine) {
  auto adapter = MakeAdapter(engine);
  adapter->Load(hit.scene, 1);
  HitRun run;
  std::vector<BodyState> start;
  adapter->ReadBodies(start);
  for (int step = 0; step < kRandomHitSteps; ++step) {
    adapter->Step();
    if (adapter->ContactCount() > 0) ++run.contactSteps;
    for (const ContactReadback& c : adapter->Contacts()) run.maxPoints = std::max(run.maxPoints, c.pointCount);
  }
  adapter->ReadBodies(run.final);
  const Vec2 p0 = LinearMomentum(hit.scene, start), p1 = LinearMomentum(hit.scene, run.final);
  const double moverMass = ComputeMassProperties(hit.scene.bodies[0]).mass;
  run.momentumError = std::hypot(double(p1.x - p0.x), double(p1.y - p0.y)) / (moverMass * hit.speed);
  run.energyRatio = KineticEnergy(hit.scene, run.final) / KineticEnergy(hit.scene, start);
  return run;
}

double VelocityDifference(const RandomHit& hit, const std::vector<BodyState>& x, const std::vector<BodyState>& y) {
  double worst = 0;
  for (size_t k = 0; k < 2 && k < x.size() && k < y.size(); ++k) {
    const double dv = std::hypot(double(x[k].velocity.x) - double(y[k].velocity.x),
                                 double(x[k].velocity.y) - double(y[k].velocity.y));
    const double dw = std::abs(double(x[k].angularVelocity) - double(y[k].angularVelocity)) * hit.radius[k];
    worst = std::max({worst, dv, dw});
  }
  return worst / hit.speed;
}

ImpactResult AnalyticHit(const RandomHit& hit) {
  ImpactInput in;
  ImpactBody* bodies[2] = {&in.a, &in.b};
  for (int k = 0; k < 2; ++k) {
    const BodyDesc& d = hit.scene.bodies[size_t(k)];
    const MassProperties mp = ComputeMassProperties(d);
    ImpactBody& b = *bodies[k];
    b.invMass = 1.0 / double(mp.mass);
    b.invInertia = 1.0 / double(mp.inertia);
    b.vx = d.velocity.x;
    b.vy = d.velocity.y;
    b.w = d.angularVelocity;
    // The scene's bodies are centred on their centres of mass (RandomConvexPolygon, circles).
    b.rx = double(hit.point.x) - double(d.position.x);
    b.ry = double(hit.point.y) - double(d.position.y);
  }
  in.nx = hit.normal.x;
  in.ny = hit.normal.y;
  in.friction = hit.friction;
  in.restitution = hit.restitution;
  return SolveImpact(in);
}

bool AnalyticRecontacts(const RandomHit& hit, const ImpactResult& r) {
  const ImpactBody* v[2] = {&r.a, &r.b};
  const double depth0 = kStartOverlap;
  // Samples every quarter step over the campaign's steps.
  const int samples = 4 * kRandomHitSteps;
  const double dt = double(hit.scene.timeStep) / 4;
  for (int k = 1; k <= samples; ++k) {
    const double t = k * dt;
    Placed shapes[2];
    for (int b = 0; b < 2; ++b) {
      const BodyDesc& d = hit.scene.bodies[size_t(b)];
      shapes[b] = Place(d, double(d.position.x) + v[b]->vx * t, double(d.position.y) + v[b]->vy * t,
                        double(d.angle) + v[b]->w * t);
    }
    // Deeper than the start by more than 1.5 mm: a second impact the model does not include.
    if (Depth(shapes[0], shapes[1]) > depth0 + 0.0015) return true;
  }
  return false;
}

std::vector<BodyState> AnalyticStates(const RandomHit& hit, const ImpactResult& r) {
  std::vector<BodyState> states(2);
  const ImpactBody* bodies[2] = {&r.a, &r.b};
  for (int k = 0; k < 2; ++k) {
    states[size_t(k)].position = hit.scene.bodies[size_t(k)].position;
    states[size_t(k)].angle = hit.scene.bodies[size_t(k)].angle;
    states[size_t(k)].velocity = {Real(bodies[k]->vx), Real(bodies[k]->vy)};
    states[size_t(k)].angularVelocity = Real(bodies[k]->w);
  }
  return states;
}

}  // namespace quadrant::scene

namespace quadrant::scene {

CampaignRow Distribution(std::vector<double> values) {
  std::erase_if(values, [](double v) { return std::isnan(v); });
  CampaignRow row;
  row.n = int(values.size());
  if (values.empty()) return row;
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  row.median = n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
  row.p90 = values[size_t(std::ceil(0.9 * double(n))) - 1];
  row.max = values.back();
  return row;
}

std::vector<CampaignRun> DefaultCampaignRuns() {
  return {
      {"box2d", "default", "box2d"},
      {"quadrant:pgs", "default", "quadrant:pgs"},
      {"quadrant:soft_step", "default", "quadrant:soft_step"},
      {"quadrant:thesis", "default", "quadrant:thesis"},
      {"quadrant:pgs", "box2d_restitution", "quadrant:pgs+b2rest"},
      {"quadrant:pgs", "box2d_skin", "quadrant:pgs+b2skin"},
      {"quadrant:pgs", "box2d_restitution+box2d_skin", "quadrant:pgs+b2rest+b2skin"},
      {"quadrant:soft_step", "box2d_restitution", "quadrant:soft_step+b2rest"},
      {"quadrant:soft_step", "box2d_skin", "quadrant:soft_step+b2skin"},
      {"quadrant:soft_step", "relaxfriction", "quadrant:soft_step+relaxfriction"},
      {"quadrant:soft_step", "box2d_restitution+box2d_skin", "quadrant:soft_step+b2rest+b2skin"},
      {"quadrant:soft_step", "box2d_restitution+box2d_skin+relaxfriction", "quadrant:soft_step+b2rest+b2skin+relaxfriction"},
      {"quadrant:soft_step", "box2d_restitution+box2d_skin+relax4+relaxfriction",
       "quadrant:soft_step+b2rest+b2skin+relax4+relaxfriction"},
      {"quadrant:thesis", "coupled", "quadrant:thesis+coupled"},
      {"quadrant:thesis", "coupled+points", "quadrant:thesis+coupled+points"},
      {"quadrant:thesis", "coupled+box2d_skin", "quadrant:thesis+coupled+b2skin"},
      {"quadrant:thesis", "coupled+points+box2d_skin", "quadrant:thesis+coupled+points+b2skin"},
      {"quadrant:thesis", "coupled+points+box2d_skin+box2d_positions", "quadrant:thesis+coupled+points+b2skin+b2pos"},
      {"quadrant:thesis", "coupled+points+box2d_skin+accumulated+passes8",
       "quadrant:thesis+coupled+points+b2skin+accum+passes8"},
      {"quadrant:thesis", "coupled+points+box2d_skin+box2d_positions+accumulated+passes8",
       "quadrant:thesis+coupled+points+b2skin+b2pos+accum+passes8"},
      // Box2D 2.4.1's contacts (issue #31): touching points only, its polygon clip.
      {"quadrant:pgs", "box2d_restitution+box2d_skin+touching", "quadrant:pgs+b2rest+b2skin+nospec"},
      {"quadrant:pgs", "box2d_restitution+box2d_skin+box2d_clip", "quadrant:pgs+b2rest+b2skin+b2clip"},
      {"quadrant:pgs", "box2d_restitution+box2d_skin+touching+box2d_clip", "quadrant:pgs+b2rest+b2skin+nospec+b2clip"},
      {"quadrant:soft_step", "box2d_restitution+box2d_skin+relax4+relaxfriction+touching+box2d_clip",
       "quadrant:soft_step+b2rest+b2skin+relax4+relaxfriction+nospec+b2clip"},
      {"quadrant:thesis", "coupled+points+box2d_skin+box2d_positions+accumulated+passes8+touching+box2d_clip",
       "quadrant:thesis+coupled+points+b2skin+b2pos+accum+passes8+nospec+b2clip"},
      // Box2D 2.4.1's solver where it still differed: its position pass's geometry, and the
      // thesis solver's two-point impulses solved together.
      {"quadrant:pgs", "box2d_restitution+box2d_skin+touching+box2d_clip+box2d_position_solve",
       "quadrant:pgs+b2rest+b2skin+nospec+b2clip+b2possolve"},
      {"quadrant:soft_step", "box2d_restitution+box2d_skin+relax4+relaxfriction+touching+box2d_clip+box2d_position_solve",
       "quadrant:soft_step+b2rest+b2skin+relax4+relaxfriction+nospec+b2clip+b2possolve"},
      {"quadrant:soft_step", "box2d_restitution+box2d_skin+relax16+relaxfriction+touching+box2d_clip+box2d_position_solve",
       "quadrant:soft_step+b2rest+b2skin+relax16+relaxfriction+nospec+b2clip+b2possolve"},
      {"quadrant:soft_step", "box2d_restitution+box2d_skin+relax32+relaxfriction+touching+box2d_clip+box2d_position_solve",
       "quadrant:soft_step+b2rest+b2skin+relax32+relaxfriction+nospec+b2clip+b2possolve"},
      {"quadrant:thesis", "coupled+points+box2d_skin+box2d_positions+accumulated+passes8+touching+box2d_clip+block",
       "quadrant:thesis+coupled+points+b2skin+b2pos+accum+passes8+nospec+b2clip+block"},
      {"quadrant:thesis",
       "coupled+points+box2d_skin+box2d_positions+accumulated+passes8+touching+box2d_clip+block+box2d_position_solve",
       "quadrant:thesis+coupled+points+b2skin+b2pos+accum+passes8+nospec+b2clip+block+b2possolve"},
  };
}

Campaign RunCampaign(uint64_t seed, int count, const std::vector<CampaignRun>& runs) {
  if (runs.empty() || runs[0].adapter != "box2d") throw Error("campaign: the first run must be box2d (the reference)");
  if (count < 1) throw Error("campaign: the number of hits must be >= 1");
  Campaign c;
  c.seed = seed;
  c.runs = runs;
  for (int i = 0; i < count; ++i) {
    RandomHit hit = MakeRandomHit(seed, i);
    std::vector<HitRun> results;
    for (const CampaignRun& run : runs) results.push_back(RunRandomHit(hit, run.adapter));
    const ImpactResult analytic = AnalyticHit(hit);
    const bool recontacts = analytic.ok && AnalyticRecontacts(hit, analytic);
    const bool single = analytic.ok && !recontacts;
    c.analyticJams += analytic.ok ? 0 : 1;
    c.analyticRecontacts += recontacts ? 1 : 0;
    const std::vector<BodyState> exact = single ? AnalyticStates(hit, analytic) : std::vector<BodyState>{};
    std::vector<Campaign::Cell> row;
    for (const HitRun& r : results) {
      Campaign::Cell cell;
      cell.toBox2d = VelocityDifference(hit, r.final, results[0].final);
      cell.toAnalytic = single ? VelocityDifference(hit, r.final, exact) : std::nan("");
      cell.momentumError = r.momentumError;
      cell.energyRatio = r.energyRatio;
      cell.maxPoints = r.maxPoints;
      cell.contactSteps = r.contactSteps;
      row.push_back(cell);
    }
    c.analyticToBox2d.push_back(single ? VelocityDifference(hit, exact, results[0].final) : std::nan(""));
    ImpactBody before[2];
    for (int k = 0; k < 2; ++k) {
      const BodyDesc& d = hit.scene.bodies[size_t(k)];
      const MassProperties mp = ComputeMassProperties(d);
      before[k].invMass = 1.0 / double(mp.mass);
      before[k].invInertia = 1.0 / double(mp.inertia);
      before[k].vx = d.velocity.x;
      before[k].vy = d.velocity.y;
      before[k].w = d.angularVelocity;
    }
    c.analyticEnergyRatio.push_back(single ? ImpactKineticEnergy(analytic.a, analytic.b) /
                                                 ImpactKineticEnergy(before[0], before[1])
                                           : std::nan(""));
    c.singlePoint.push_back(single);
    c.cells.push_back(std::move(row));
    c.hits.push_back(std::move(hit));
  }
  return c;
}

namespace {

// The classes in report order: every pair and restitution, then "all".
std::vector<std::string> ClassNames() {
  std::vector<std::string> names;
  for (const char* pair : {"polygon-polygon", "circle-polygon", "circle-circle"}) {
    for (const char* e : {"0", "0.5", "1"}) names.push_back(std::string(pair) + " e=" + e);
  }
  names.push_back("all");
  return names;
}

template <class Value>
std::vector<CampaignRow> Rows(const Campaign& c, Value value, bool analyticRow) {
  std::vector<CampaignRow> rows;
  for (const std::string& cls : ClassNames()) {
    auto collect = [&](auto get) {
      std::vector<double> v;
      for (size_t i = 0; i < c.hits.size(); ++i) {
        if (cls == "all" || c.hits[i].Class() == cls) v.push_back(get(i));
      }
      return v;
    };
    for (size_t r = 0; r < c.runs.size(); ++r) {
      CampaignRow row = Distribution(collect([&](size_t i) { return value(i, r); }));
      row.cls = cls;
      row.engine = c.runs[r].engine;
      row.setting = c.runs[r].setting;
      rows.push_back(row);
    }
    if (analyticRow) {
      CampaignRow row = Distribution(collect([&](size_t i) { return c.analyticToBox2d[i]; }));
      row.cls = cls;
      row.engine = "analytic";
      row.setting = "single_point";
      rows.push_back(row);
    }
  }
  return rows;
}

}  // namespace

std::vector<CampaignRow> Campaign::Box2dRows() const {
  std::vector<CampaignRow> rows = Rows(*this, [&](size_t i, size_t r) { return cells[i][r].toBox2d; }, true);
  std::erase_if(rows, [](const CampaignRow& row) { return row.engine == "box2d"; });  // itself: 0
  return rows;
}

std::vector<CampaignRow> Campaign::AnalyticRows() const {
  return Rows(*this, [&](size_t i, size_t r) { return cells[i][r].toAnalytic; }, false);
}

}  // namespace quadrant::scene
