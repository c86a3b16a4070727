// The ambiguity rule and the causes of large differences (random_hit_causes.h).
#include "random_hit_causes.h"

#include <algorithm>
#include <cmath>

#include "quadrant/error.h"

namespace quadrant::scene {
namespace {

// Approach speed (m/s, positive when closing) of body 0 on body 1 at `p` along the unit normal
// `n` from body 0 to body 1.
double Approach(const std::vector<BodyState>& s, Vec2 p, Vec2 n) {
  auto pointVelocity = [&](const BodyState& b, double& vx, double& vy) {
    const double rx = double(p.x) - double(b.position.x), ry = double(p.y) - double(b.position.y);
    vx = double(b.velocity.x) - double(b.angularVelocity) * ry;
    vy = double(b.velocity.y) + double(b.angularVelocity) * rx;
  };
  double ax, ay, bx, by;
  pointVelocity(s[0], ax, ay);
  pointVelocity(s[1], bx, by);
  return (ax - bx) * double(n.x) + (ay - by) * double(n.y);
}

// The approach speed nearest the 1 m/s threshold at any step after the first, where a contact
// gains touching points (a new contact or a second point), in m/s; -1 if none.
double NewPointApproach(const HitTrace& t, double threshold) {
  double best = -1;
  for (int k = 2; k <= kRandomHitSteps; ++k) {
    const size_t i = size_t(k - 1);
    if (t.touching[i] <= t.touching[i - 1]) continue;
    for (int p = 0; p < std::min(t.touching[i], 2); ++p) {
      const double v = std::abs(Approach(t.states[size_t(k - 1)], p == 0 ? t.point[i] : t.point2[i], t.normal[i]));
      if (best < 0 || std::abs(v - threshold) < std::abs(best - threshold)) best = v;
    }
  }
  return best;
}

}  // namespace

std::vector<RandomHit> PerturbedHits(const RandomHit& hit) {
  std::vector<RandomHit> out;
  for (int axis = 0; axis < 3; ++axis) {
    for (double sign : {1.0, -1.0}) {
      RandomHit h = hit;
      BodyDesc& m = h.scene.bodies[0];
      const Real d = Real(sign * kPerturbation);
      if (axis == 0) m.position.x += d;
      if (axis == 1) m.position.y += d;
      if (axis == 2) m.angle += d;
      out.push_back(std::move(h));
    }
  }
  return out;
}

double Box2dPerturbationSpread(const RandomHit& hit) {
  const HitRun base = RunRandomHit(hit, "box2d");
  double spread = 0;
  for (const RandomHit& h : PerturbedHits(hit)) {
    spread = std::max(spread, VelocityDifference(hit, RunRandomHit(h, "box2d").final, base.final));
  }
  return spread;
}

std::string CauseName(HitCause c) {
  switch (c) {
    case HitCause::kRestitutionThreshold: return "restitution threshold";
    case HitCause::kRecontact: return "re-contact";
    case HitCause::kSpeculative: return "speculative contact";
    case HitCause::kSkin: return "skin";
    case HitCause::kPointOrder: return "order of points";
    case HitCause::kSimultaneous: return "simultaneous points";
    case HitCause::kSolver: return "solver difference";
  }
  return "?";
}

std::vector<CampaignRun> CompatibleRuns() {
  std::vector<CampaignRun> out;
  for (const char* adapter : {"quadrant:pgs+b2rest+b2skin+nospec+b2clip+b2possolve",
                              "quadrant:soft_step+b2rest+b2skin+relax32+relaxfriction+nospec+b2clip+b2possolve",
                              "quadrant:thesis+coupled+points+b2skin+b2pos+accum+passes8+nospec+b2clip+block+b2possolve"}) {
    for (const CampaignRun& r : DefaultCampaignRuns()) {
      if (r.adapter == adapter) out.push_back(r);
    }
  }
  return out;
}

HitTrace TraceRandomHit(const RandomHit& hit, std::string_view engine, bool mirrored) {
  Scene scene = hit.scene;
  if (mirrored) {
    // x -> -x: the same hit, its polygons wound the other way round (reversed to stay CCW).
    for (BodyDesc& b : scene.bodies) {
      b.position.x = -b.position.x;
      b.angle = -b.angle;
      b.velocity.x = -b.velocity.x;
      b.angularVelocity = -b.angularVelocity;
      for (Vec2& v : b.vertices) v.x = -v.x;
      std::reverse(b.vertices.begin(), b.vertices.end());
    }
  }
  auto adapter = MakeAdapter(engine);
  adapter->Load(scene, 1);
  HitTrace t;
  auto read = [&] {
    std::vector<BodyState> s;
    adapter->ReadBodies(s);
    if (mirrored) {
      for (BodyState& b : s) {
        b.position.x = -b.position.x;
        b.angle = -b.angle;
        b.velocity.x = -b.velocity.x;
        b.angularVelocity = -b.angularVelocity;
      }
    }
    t.states.push_back(std::move(s));
  };
  read();
  const bool box2d = engine == "box2d";
  // Quadrant reports raw separations; with its polygon skin (variant token b2skin, 0.01 m per
  // polygon of the pair, as Box2D) a point within the skins is a touching row.
  double skin = 0;
  if (!box2d && (std::string(engine) + "+").find("+b2skin+") != std::string::npos) {
    for (const BodyDesc& b : hit.scene.bodies) skin += b.shape == ShapeKind::kPolygon ? 0.01 : 0;
  }
  for (int step = 0; step < kRandomHitSteps; ++step) {
    adapter->Step();
    read();
    int touching = 0, speculative = 0;
    Vec2 normal, point, point2;
    bool first = true;
    for (const ContactReadback& c : adapter->Contacts()) {
      const int a = c.bodyA;
      for (int k = 0; k < c.pointCount && k < 2; ++k) {
        // Box2D reports touching manifolds only; Quadrant also speculative points, which count
        // here where they pushed (a normal impulse).
        if (box2d || double(c.separations[k]) <= skin + 1e-6) ++touching;
        else if (c.normalImpulses[k] > 0) ++speculative;
      }
      if (first && c.pointCount > 0) {
        normal = a == 0 ? c.normal : Vec2{-c.normal.x, -c.normal.y};
        point = c.points[0];
        point2 = c.pointCount > 1 ? c.points[1] : c.points[0];
        first = false;
      }
    }
    t.touching.push_back(touching);
    t.speculative.push_back(speculative);
    t.normal.push_back(normal);
    t.point.push_back(point);
    t.point2.push_back(point2);
  }
  return t;
}

CauseDiagnosis DiagnoseHit(const RandomHit& hit, std::string_view engine) {
  if (engine == "box2d") throw Error("DiagnoseHit: compares an engine with box2d, not box2d with itself");
  const HitTrace b = TraceRandomHit(hit, "box2d"), r = TraceRandomHit(hit, engine);
  CauseDiagnosis d;
  d.difference = VelocityDifference(hit, r.states.back(), b.states.back());

  // Both first separate: the first step with no touching point in either, after both touched.
  int separation = 0;
  {
    bool touchedB = false, touchedR = false;
    for (int k = 1; k <= kRandomHitSteps; ++k) {
      const size_t i = size_t(k - 1);
      touchedB = touchedB || b.touching[i] > 0;
      touchedR = touchedR || r.touching[i] > 0;
      if (touchedB && touchedR && b.touching[i] == 0 && r.touching[i] == 0) {
        separation = k;
        break;
      }
    }
  }
  if (separation > 0) d.atSeparation = VelocityDifference(hit, r.states[size_t(separation)], b.states[size_t(separation)]);
  const int firstEnd = separation > 0 ? separation : kRandomHitSteps + 1;

  // A point that arrives near the threshold, in either engine (the hit's first impact is drawn
  // at >= 1.25 m/s, so only later points can sit at it).
  const double threshold = double(hit.scene.restitutionThreshold);
  for (const HitTrace* t : {&b, &r}) {
    const double v = NewPointApproach(*t, threshold);
    if (v >= 0 && (d.recontactSpeed < 0 || std::abs(v - threshold) < std::abs(d.recontactSpeed - threshold))) {
      d.recontactSpeed = v;
    }
  }
  for (int k = 1; k < firstEnd; ++k) {
    d.maxTouching[0] = std::max(d.maxTouching[0], b.touching[size_t(k - 1)]);
    d.maxTouching[1] = std::max(d.maxTouching[1], r.touching[size_t(k - 1)]);
  }

  if (hit.restitution > 0 && d.recontactSpeed >= 0.8 * threshold && d.recontactSpeed <= 1.25 * threshold) {
    d.cause = HitCause::kRestitutionThreshold;
    return d;
  }
  // The difference arises after both first separate: a second contact, touching or speculative.
  if (separation > 0 && d.atSeparation <= kCauseThreshold) {
    // The step where the difference first exceeds the threshold: a touching contact in either
    // engine there is a re-contact; a velocity change with none is a speculative row acting
    // before the shapes touch (Box2D 2.4.1 has none: it meets such a graze a step later, or not).
    int k = separation + 1;
    while (k < kRandomHitSteps &&
           VelocityDifference(hit, r.states[size_t(k)], b.states[size_t(k)]) <= kCauseThreshold) {
      ++k;
    }
    const size_t i = size_t(k - 1);
    d.cause = b.touching[i] > 0 || r.touching[i] > 0 ? HitCause::kRecontact : HitCause::kSpeculative;
    return d;
  }
  // Otherwise in the first contact.
  bool speculative = false, skin = false;
  for (int k = 1; k < firstEnd; ++k) {
    const size_t i = size_t(k - 1);
    if (r.speculative[i] > 0 && b.touching[i] < r.touching[i] + r.speculative[i]) speculative = true;
    else if (b.touching[i] != r.touching[i]) skin = true;
  }
  if (speculative || skin) {
    d.cause = speculative ? HitCause::kSpeculative : HitCause::kSkin;
    return d;
  }
  if (d.maxTouching[0] >= 2 && d.maxTouching[1] >= 2) {
    const HitTrace bs = TraceRandomHit(hit, "box2d", true), rs = TraceRandomHit(hit, engine, true);
    d.orderShift = std::max(VelocityDifference(hit, bs.states.back(), b.states.back()),
                            VelocityDifference(hit, rs.states.back(), r.states.back()));
    d.cause = d.orderShift > kCauseThreshold ? HitCause::kPointOrder : HitCause::kSimultaneous;
    return d;
  }
  d.cause = HitCause::kSolver;
  return d;
}

}  // namespace quadrant::scene
