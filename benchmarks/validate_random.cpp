// quadrant_validate --random N: the randomised campaign's report (validate.cpp parses the
// arguments). The hits, runs and statistics live in benchmarks/scenes/random_hits.cpp, shared
// with tests/adapters/random_hits_test.cpp; this file only writes them out.
#include "validate_random.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "random_hits.h"
#include "report_common.h"

namespace quadrant::report {
namespace {

namespace qs = quadrant::scene;

std::string RowJson(const qs::CampaignRow& r) {
  std::ostringstream o;
  o << "{\"class\": " << JsonString(r.cls) << ", \"engine\": " << JsonString(r.engine)
    << ", \"setting\": " << JsonString(r.setting) << ", \"n\": " << r.n << ", \"median\": " << JsonNumber(r.median)
    << ", \"p90\": " << JsonNumber(r.p90) << ", \"max\": " << JsonNumber(r.max) << "}";
  return o.str();
}

std::string Percent(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.2f", 100 * v);
  return b;
}

// Momentum and energy balance per run over all hits.
struct Balance {
  double maxMomentum = 0;
  double minEnergy = 1e30, maxEnergy = 0;
  double medianEnergy = 0;
  double singlePointContactSteps = 0;
  int twoPointHits = 0;
};

std::vector<Balance> Balances(const qs::Campaign& c) {
  std::vector<Balance> out(c.runs.size());
  for (size_t r = 0; r < c.runs.size(); ++r) {
    std::vector<double> energy;
    for (size_t i = 0; i < c.hits.size(); ++i) {
      const qs::Campaign::Cell& cell = c.cells[i][r];
      out[r].maxMomentum = std::max(out[r].maxMomentum, cell.momentumError);
      out[r].minEnergy = std::min(out[r].minEnergy, cell.energyRatio);
      out[r].maxEnergy = std::max(out[r].maxEnergy, cell.energyRatio);
      out[r].twoPointHits += cell.maxPoints >= 2;
      energy.push_back(cell.energyRatio);
    }
    out[r].medianEnergy = qs::Distribution(energy).median;
  }
  return out;
}

std::string Json(const qs::Campaign& c, const std::vector<qs::CampaignRow>& rows,
                 const std::vector<qs::CampaignRow>& analytic) {
  std::ostringstream o;
  o << "{\"hits\": " << c.hits.size() << ", \"seed\": " << c.seed << ", \"machine\": "
    << JsonString(Env("QUADRANT_MACHINE", "unknown")) << ", \"commit\": " << JsonString(Env("QUADRANT_COMMIT", "unknown"))
    << ", \"date\": " << JsonString(UtcNow()) << ", \"compiler\": " << JsonString(__VERSION__)
    << ",\n \"settings\": {\"gravity\": 0, \"dt\": 0.0166666667, \"velocity_iterations\": 8, \"position_iterations\": 3, "
       "\"restitution_threshold\": 1, \"steps\": "
    << qs::kRandomHitSteps << ", \"sleep\": false, \"continuous\": false, \"warm_starting\": true},\n"
    << " \"difference\": \"largest over both bodies of |v - v_box2d| and |w - w_box2d| x circumradius after the "
       "steps, as a fraction of the mover's speed\",\n \"analytic_single_point_hits\": "
    << std::count(c.singlePoint.begin(), c.singlePoint.end(), true) << ", \"analytic_jams\": " << c.analyticJams
    << ", \"analytic_recontacts\": " << c.analyticRecontacts << ",\n \"runs\": [";
  const std::vector<Balance> balance = Balances(c);
  for (size_t r = 0; r < c.runs.size(); ++r) {
    o << (r ? ",\n  " : "\n  ") << "{\"engine\": " << JsonString(c.runs[r].engine) << ", \"setting\": "
      << JsonString(c.runs[r].setting) << ", \"adapter\": " << JsonString(c.runs[r].adapter)
      << ", \"max_momentum_error\": " << JsonNumber(balance[r].maxMomentum)
      << ", \"energy_ratio_min\": " << JsonNumber(balance[r].minEnergy)
      << ", \"energy_ratio_median\": " << JsonNumber(balance[r].medianEnergy)
      << ", \"energy_ratio_max\": " << JsonNumber(balance[r].maxEnergy)
      << ", \"hits_with_two_points\": " << balance[r].twoPointHits << "}";
  }
  o << "],\n \"classes\": [";
  for (size_t k = 0; k < rows.size(); ++k) o << (k ? ",\n  " : "\n  ") << RowJson(rows[k]);
  o << "],\n \"analytic_distance\": [";
  for (size_t k = 0; k < analytic.size(); ++k) o << (k ? ",\n  " : "\n  ") << RowJson(analytic[k]);
  o << "]}\n";
  return o.str();
}

// One row per hit; per run its difference to Box2D, its distance from the analytic answer
// (empty where the hit has none) and the most points of a manifold. 4 significant digits: the
// plot's resolution, and a file small enough to commit (about 0.4 MB for 2000 hits).
std::string Csv(const qs::Campaign& c) {
  auto num = [](double v) {
    if (std::isnan(v)) return std::string();
    char b[32];
    std::snprintf(b, sizeof b, "%.4g", v);
    return std::string(b);
  };
  std::ostringstream o;
  o << "hit,class,friction,mass_ratio,speed,spin,single_point,analytic:to_box2d";
  for (const qs::CampaignRun& r : c.runs) {
    const std::string run = r.engine + "/" + r.setting;
    o << "," << run << ":to_box2d," << run << ":to_analytic," << run << ":points";
  }
  o << "\n";
  for (size_t i = 0; i < c.hits.size(); ++i) {
    const qs::RandomHit& h = c.hits[i];
    o << h.index << "," << h.Class() << "," << h.friction << "," << num(h.massRatio) << "," << num(h.speed) << ","
      << num(h.moverSpin) << "," << (c.singlePoint[i] ? 1 : 0) << "," << num(c.analyticToBox2d[i]);
    for (size_t r = 0; r < c.runs.size(); ++r) {
      const qs::Campaign::Cell& cell = c.cells[i][r];
      o << "," << (r == 0 ? "" : num(cell.toBox2d)) << "," << num(cell.toAnalytic) << "," << cell.maxPoints;
    }
    o << "\n";
  }
  return o.str();
}

std::string Label(const qs::CampaignRow& r) { return r.engine + (r.setting == "default" ? "" : " / " + r.setting); }

// One table: a row per class, a column per run, cells "median / p90 / max" in percent.
void Table(std::ostringstream& o, const std::vector<qs::CampaignRow>& rows) {
  std::vector<std::string> columns, classes;
  std::map<std::pair<std::string, std::string>, const qs::CampaignRow*> cell;
  for (const qs::CampaignRow& r : rows) {
    const std::string label = Label(r);
    if (std::find(columns.begin(), columns.end(), label) == columns.end()) columns.push_back(label);
    if (std::find(classes.begin(), classes.end(), r.cls) == classes.end()) classes.push_back(r.cls);
    cell[{r.cls, label}] = &r;
  }
  o << "| class | n |";
  for (const std::string& col : columns) o << " " << col << " |";
  o << "\n|---|---:|";
  for (size_t k = 0; k < columns.size(); ++k) o << "---|";
  o << "\n";
  for (const std::string& cls : classes) {
    int n = 0;
    for (const std::string& col : columns) {
      auto it = cell.find({cls, col});
      if (it != cell.end()) n = std::max(n, it->second->n);
    }
    o << "| " << cls << " | " << n << " |";
    for (const std::string& col : columns) {
      auto it = cell.find({cls, col});
      if (it == cell.end() || it->second->n == 0) {
        o << " - |";
        continue;
      }
      const qs::CampaignRow& r = *it->second;
      const bool over = r.p90 > 0.05;
      o << " " << Percent(r.median) << " / " << (over ? "**" : "") << Percent(r.p90) << (over ? "**" : "") << " / "
        << Percent(r.max) << (r.n != n ? " (n " + std::to_string(r.n) + ")" : "") << " |";
    }
    o << "\n";
  }
}

std::string Markdown(const qs::Campaign& c, const std::vector<qs::CampaignRow>& rows,
                     const std::vector<qs::CampaignRow>& analytic) {
  std::ostringstream o;
  int single = 0;
  for (bool s : c.singlePoint) single += s;
  o << "# Contact responses against Box2D 2.4.1: the random campaign\n\n"
    << "Machine `" << Env("QUADRANT_MACHINE", "unknown") << "`, commit `" << Env("QUADRANT_COMMIT", "unknown") << "`, "
    << UtcNow() << ", compiler " << __VERSION__ << ". Written by `tools/quadrant validate --random " << c.hits.size()
    << " --seed " << c.seed << "` (benchmarks/validate_random.cpp; hits in benchmarks/scenes/random_hits.cpp, the "
    << "analytic impact in benchmarks/scenes/impact_analytic.cpp). Not a timing: the numbers do not depend on the "
       "machine's load.\n\n"
    << "**" << c.hits.size() << " hits**, each run on Box2D 2.4.1 and on every Quadrant run below through the scene "
    << "API with identical settings: zero gravity, dt = 1/60, 8 velocity and 3 position iterations, restitution "
    << "threshold 1 m/s, warm starting, no sleep, no continuous collision, " << qs::kRandomHitSteps
    << " steps. A body moving at 2-8 m/s (up to 60 degrees off the normal, spin up to 8 rad/s) touches a resting "
       "one at one point at the start: a polygon vertex or a circle against a polygon face or a circle; random "
       "convex 3- to 8-gons and circles of circumradius 0.35-0.5 m; mass ratio 1-100 (log-uniform, either body "
       "the heavier); restitution 0 / 0.5 / 1 and friction 0 / 0.3, the same on both bodies.\n\n"
    << "**Difference** of a run on a hit: the largest, over both bodies, of |v - v_ref| and |w - w_ref| x the body's "
       "circumradius after the "
    << qs::kRandomHitSteps
    << " steps, as a fraction of the mover's speed. Cells are median / p90 / max in percent; p90 above 5 % in "
       "bold. `validation_random_hits.csv` holds every hit and run; `validation_random.png` plots the "
       "distributions.\n\n";

  o << "## Against Box2D 2.4.1\n\n";
  Table(o, rows);
  o << "\n`analytic / single_point` is the analytic impact's own difference to Box2D on the " << single
    << " single-point hits.\n\n";

  o << "## Against the analytic impact (" << single << " single-point hits)\n\n"
    << "The analytic answer (Coulomb friction, Newton restitution, stick / slide / slip reversal integrated over the "
       "normal impulse, as Stronge does) applies to hits whose impact is one instantaneous impact at one point: it "
       "does not jam, and the two bodies, moving on with the analytic velocities, do not meet again within the "
    << qs::kRandomHitSteps << " steps (1.5 mm deeper than they start). Of the " << c.hits.size() << " hits, "
    << c.analyticJams << " jam (the normal contact velocity would not rise with the normal impulse) and "
    << c.analyticRecontacts << " meet again. Same cells, distance from the analytic velocities.\n\n";
  Table(o, analytic);

  o << "\n## Classes above 5 %, and the choices that remove each\n\n"
    << "Every class whose p90 difference to Box2D exceeds 5 % under a run, with the same class's p90 under each "
       "run of that engine that switches the same choices and more (a setting is its choices joined by '+'; "
       "README \"validation\" names each). Settings: `box2d_restitution` = `WorldDef::restitution = "
       "RestitutionPolicy::kBox2d` (adapter token `b2rest`: Box2D 2.4.1's velocity bias -e vn, solved with "
       "friction, instead of a frictionless pairwise collision before the iterations or sub-steps); `box2d_skin` "
       "= `WorldDef::polygonSkin = 0.01` (`b2skin`: Box2D's polygon radius, so points within the skins are "
       "touching rows); `relaxfriction` = `WorldDef::softFrictionEveryRelaxPass` (soft_step solves friction in its "
       "last relax pass only, after the normal rows, which leaves the two unconverged where a lever arm couples "
       "them; `relax4`: four relax passes instead of two); `coupled` = `WorldDef::thesisCoupledImpulse` (the thesis's one impulse with "
       "its normal and friction parts solved together); `points` = `WorldDef::thesisPointImpulses` (an impulse "
       "at each touching point in turn instead of the thesis's one at their centroid); `box2d_positions` = "
       "`WorldDef::thesisPositionPass` (`b2pos`: the penetration removed after the positions are integrated by "
       "Box2D 2.4.1's position pass, which turns the bodies too, instead of the thesis's translation push before "
       "the impulses); `accumulated` = `WorldDef::thesisAccumulatedImpulse` (`accum`: each point's impulse a "
       "total over the step's passes, clamped as a total, so a later pass can take back what an earlier one "
       "gave a point, as Box2D's iterations do; `passes8`: `WorldDef::thesisPasses = 8`, Box2D's 8 velocity "
       "iterations; either alone changes nothing); others are Quadrant "
       "adapter variants given with `--runs`.\n\n"
    << "| class | engine | setting | p90 | p90 with more choices switched |\n|---|---|---|---:|---|\n";
  auto tokens = [](const std::string& setting) {
    std::vector<std::string> out;
    if (setting == "default") return out;
    size_t start = 0;
    while (true) {
      const size_t end = setting.find('+', start);
      out.push_back(setting.substr(start, end == std::string::npos ? std::string::npos : end - start));
      if (end == std::string::npos) return out;
      start = end + 1;
    }
  };
  auto extends = [&](const std::string& more, const std::string& base) {
    const std::vector<std::string> m = tokens(more), b = tokens(base);
    if (m.size() <= b.size()) return false;
    for (const std::string& t : b) {
      if (std::find(m.begin(), m.end(), t) == m.end()) return false;
    }
    return true;
  };
  for (const qs::CampaignRow& r : rows) {
    if (r.engine == "analytic" || r.cls == "all" || r.p90 <= 0.05) continue;
    o << "| " << r.cls << " | " << r.engine << " | " << r.setting << " | " << Percent(r.p90) << " |";
    bool any = false;
    for (const qs::CampaignRow& s : rows) {
      if (s.cls != r.cls || s.engine != r.engine || !extends(s.setting, r.setting)) continue;
      o << (any ? ", " : " ") << "`" << s.setting << "` " << Percent(s.p90);
      any = true;
    }
    o << (any ? "" : " none measured") << " |\n";
  }
  o << "\n## Momentum and energy\n\n| run | max momentum error | energy after / before: min, median, max | hits "
       "with a two-point manifold |\n|---|---:|---|---:|\n";
  const std::vector<Balance> balance = Balances(c);
  for (size_t r = 0; r < c.runs.size(); ++r) {
    o << "| " << c.runs[r].engine << (c.runs[r].setting == "default" ? "" : " / " + c.runs[r].setting) << " | "
      << Cell(balance[r].maxMomentum) << " | " << Cell(balance[r].minEnergy) << ", " << Cell(balance[r].medianEnergy)
      << ", " << Cell(balance[r].maxEnergy) << " | " << balance[r].twoPointHits << " |\n";
  }
  std::vector<double> analyticEnergy;
  int gains = 0;
  for (double e : c.analyticEnergyRatio) {
    if (std::isnan(e)) continue;
    analyticEnergy.push_back(e);
    gains += e > 1 + 1e-6;
  }
  const qs::CampaignRow ae = qs::Distribution(analyticEnergy);
  o << "| analytic (" << ae.n << " single-point hits) | 0 | " << Cell(*std::min_element(analyticEnergy.begin(), analyticEnergy.end()))
    << ", " << Cell(ae.median) << ", " << Cell(ae.max) << " | - |\n";
  o << "\nMomentum error: |P after - P before| / (mover mass x speed). Energy: Newton's restitution with friction "
       "can create energy where friction and the normal impulse are coupled (Kane and Levinson's paradox): "
    << gains << " of the " << ae.n
    << " analytic single-point impacts end with more kinetic energy than they start with. Box2D's restitution (and "
       "`box2d_restitution`) is Newton's law solved with friction, so it shares that gain (the maxima above 1 in "
       "the table); Quadrant's default restitution in pgs and soft_step (a frictionless collision, then friction "
       "rows that only remove slip) keeps the energy maximum at 1.\n";
  return o.str();
}

void Write(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out) throw Error("cannot write " + path.string());
}

}  // namespace

int RunRandomCampaign(const std::string& outDir, int hits, uint64_t seed, const std::vector<std::string>& extraRuns) {
  std::vector<qs::CampaignRun> runs = qs::DefaultCampaignRuns();
  for (const std::string& adapter : extraRuns) {
    if (!adapter.starts_with("quadrant:")) throw Error("--runs takes quadrant:<variant> adapter names, got '" + adapter + "'");
    qs::MakeAdapter(adapter);  // an unknown variant is refused here, before any hit runs
    const std::string variant = adapter.substr(9);
    const size_t plus = variant.find('+');
    const std::string solver = variant.substr(0, plus);
    const bool named = solver == "pgs" || solver == "soft_step" || solver == "thesis";
    runs.push_back({named ? "quadrant:" + solver : "quadrant:pgs",
                    named ? (plus == std::string::npos ? "default" : variant.substr(plus + 1)) : variant, adapter});
  }
  const qs::Campaign c = qs::RunCampaign(seed, hits, runs);
  const std::vector<qs::CampaignRow> rows = c.Box2dRows(), analytic = c.AnalyticRows();
  std::filesystem::create_directories(outDir);
  const std::filesystem::path dir(outDir);
  Write(dir / "validation_random.json", Json(c, rows, analytic));
  Write(dir / "validation_random.md", Markdown(c, rows, analytic));
  Write(dir / "validation_random_hits.csv", Csv(c));
  for (const qs::CampaignRow& r : rows) {
    if (r.cls == "all") {
      std::fprintf(stderr, "%-20s %-22s n %5d  median %6.2f %%  p90 %6.2f %%  max %7.2f %%\n", r.engine.c_str(),
                   r.setting.c_str(), r.n, 100 * r.median, 100 * r.p90, 100 * r.max);
    }
  }
  std::fprintf(stderr, "quadrant_validate: wrote %s/validation_random.{json,md} and validation_random_hits.csv\n",
               outDir.c_str());
  return 0;
}

}  // namespace quadrant::report
