// quadrant_validate --random N --seeds K: the randomised campaign's report (validate.cpp parses
// the arguments). The hits, runs and statistics live in benchmarks/scenes/random_hits.cpp, the
// ambiguity rule and the causes in random_hit_causes.cpp, shared with the tests; this file runs
// the seeds, gives each class's p90 as its median and range over them (all hits, and outside the
// ambiguous ones), holds each Box2D-compatible setting's worst class to 5 % on every seed, names
// the cause of every difference above 5 % in those settings, and writes it all out.
#include "validate_random.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "random_hit_causes.h"
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

// The machine's load averages (1, 5, 15 min) as the report is written: the report is not a
// timing, but the project records the load with every run.
std::string LoadAverage() {
  std::ifstream in("/proc/loadavg");
  std::string one, five, fifteen;
  if (!(in >> one >> five >> fifteen)) return "unknown";
  return one + " " + five + " " + fifteen;
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


// ---- Across seeds (issue #31) ----------------------------------------------------------------

const std::vector<std::string>& ClassList() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const char* pair : {"polygon-polygon", "circle-polygon", "circle-circle"}) {
      for (const char* e : {"0", "0.5", "1"}) n.push_back(std::string(pair) + " e=" + e);
    }
    return n;
  }();
  return names;
}

// A run's worst class p90 on each seed, and its median and range over the seeds.
struct SeedRunSummary {
  std::string engine, setting;
  size_t run = 0;
  std::vector<double> worst, worstAll;  ///< per seed: outside the ambiguous hits; all hits
  std::vector<std::string> worstClass;  ///< per seed, outside the ambiguous hits
  double median = 0, min = 0, max = 0;  ///< of `worst`
  double medianAll = 0, minAll = 0, maxAll = 0;
};

// One class and run: its p90 on each seed.
struct ClassSeries {
  std::string cls;
  size_t run = 0;
  std::vector<double> p90All, p90Clear;
  std::vector<int> nAll, nClear;
};

struct Diagnosed {
  uint64_t seed = 0;
  int index = 0;
  std::string cls;
  size_t run = 0;
  bool ambiguous = false;
  double spread = 0;
  qs::CauseDiagnosis d;
};

struct Seeds {
  std::vector<uint64_t> seeds;
  std::vector<int> ambiguous;  ///< per seed
  int ambiguousTotal = 0;
  std::vector<double> spread;     ///< per pooled hit: Box2D's perturbation spread
  std::vector<bool> isAmbiguous;  ///< per pooled hit
  std::vector<ClassSeries> classes;
  std::vector<SeedRunSummary> runs, compatible;
  std::vector<Diagnosed> diagnosed;
};

struct Range {
  double median = 0, min = 0, max = 0;
};
Range RangeOf(const std::vector<double>& v) {
  Range r;
  if (v.empty()) return r;
  r.median = qs::Distribution(v).median;
  r.min = *std::min_element(v.begin(), v.end());
  r.max = *std::max_element(v.begin(), v.end());
  return r;
}

Seeds Analyse(const std::vector<qs::Campaign>& perSeed) {
  Seeds out;
  const std::vector<qs::CampaignRun>& runs = perSeed[0].runs;
  std::vector<std::vector<bool>> ambiguous;  // [seed][hit]
  for (const qs::Campaign& c : perSeed) {
    out.seeds.push_back(c.seed);
    std::vector<bool> a;
    int count = 0;
    for (const qs::RandomHit& h : c.hits) {
      const double spread = qs::Box2dPerturbationSpread(h);
      out.spread.push_back(spread);
      a.push_back(spread > qs::kAmbiguityTolerance);
      out.isAmbiguous.push_back(a.back());
      count += a.back();
    }
    out.ambiguous.push_back(count);
    out.ambiguousTotal += count;
    ambiguous.push_back(std::move(a));
  }
  for (const std::string& cls : ClassList()) {
    for (size_t r = 1; r < runs.size(); ++r) {
      ClassSeries series;
      series.cls = cls;
      series.run = r;
      for (size_t s = 0; s < perSeed.size(); ++s) {
        std::vector<double> all, clear;
        for (size_t i = 0; i < perSeed[s].hits.size(); ++i) {
          if (perSeed[s].hits[i].Class() != cls) continue;
          all.push_back(perSeed[s].cells[i][r].toBox2d);
          if (!ambiguous[s][i]) clear.push_back(perSeed[s].cells[i][r].toBox2d);
        }
        series.p90All.push_back(qs::Distribution(all).p90);
        series.p90Clear.push_back(qs::Distribution(clear).p90);
        series.nAll.push_back(int(all.size()));
        series.nClear.push_back(int(clear.size()));
      }
      out.classes.push_back(std::move(series));
    }
  }
  const std::vector<qs::CampaignRun> compatible = qs::CompatibleRuns();
  for (size_t r = 1; r < runs.size(); ++r) {
    SeedRunSummary sum;
    sum.engine = runs[r].engine;
    sum.setting = runs[r].setting;
    sum.run = r;
    for (size_t s = 0; s < perSeed.size(); ++s) {
      double worst = -1, worstAll = 0;
      std::string worstClass;
      for (const ClassSeries& series : out.classes) {
        if (series.run != r) continue;
        if (series.p90Clear[s] > worst) {
          worst = series.p90Clear[s];
          worstClass = series.cls;
        }
        worstAll = std::max(worstAll, series.p90All[s]);
      }
      sum.worst.push_back(worst);
      sum.worstAll.push_back(worstAll);
      sum.worstClass.push_back(worstClass);
    }
    const Range w = RangeOf(sum.worst), a = RangeOf(sum.worstAll);
    sum.median = w.median;
    sum.min = w.min;
    sum.max = w.max;
    sum.medianAll = a.median;
    sum.minAll = a.min;
    sum.maxAll = a.max;
    out.runs.push_back(sum);
    const bool isCompatible = std::any_of(compatible.begin(), compatible.end(),
                                          [&](const qs::CampaignRun& c) { return c.adapter == runs[r].adapter; });
    if (!isCompatible) continue;
    out.compatible.push_back(sum);
    for (size_t s = 0; s < perSeed.size(); ++s) {
      for (size_t i = 0; i < perSeed[s].hits.size(); ++i) {
        if (perSeed[s].cells[i][r].toBox2d <= qs::kCauseThreshold) continue;
        Diagnosed d;
        d.seed = perSeed[s].seed;
        d.index = perSeed[s].hits[i].index;
        d.cls = perSeed[s].hits[i].Class();
        d.run = r;
        d.ambiguous = ambiguous[s][i];
        d.spread = out.spread[s * perSeed[0].hits.size() + i];
        d.d = qs::DiagnoseHit(perSeed[s].hits[i], runs[r].adapter);
        out.diagnosed.push_back(d);
      }
    }
  }
  return out;
}

std::string Pct(double v) { return Percent(v); }
std::string RangeText(const std::vector<double>& v) {
  const Range r = RangeOf(v);
  return Pct(r.median) + " (" + Pct(r.min) + "-" + Pct(r.max) + ")";
}

std::string SeedsJson(const qs::Campaign& c, const Seeds& all) {
  std::ostringstream o;
  o << ",\n \"seeds\": [";
  for (size_t k = 0; k < all.seeds.size(); ++k) o << (k ? ", " : "") << all.seeds[k];
  o << "],\n \"ambiguity\": {\"rule\": \"Box2D's own difference under a 1e-4 m / 1e-4 rad perturbation of the mover "
       "above 5 %\", \"tolerance\": "
    << JsonNumber(qs::kAmbiguityTolerance) << ", \"perturbation\": " << JsonNumber(qs::kPerturbation)
    << ", \"hits\": " << all.ambiguousTotal << ", \"per_seed\": [";
  for (size_t k = 0; k < all.ambiguous.size(); ++k) o << (k ? ", " : "") << all.ambiguous[k];
  o << "]},\n \"runs_across_seeds\": [";
  for (size_t k = 0; k < all.runs.size(); ++k) {
    const SeedRunSummary& s = all.runs[k];
    const bool compatible = std::any_of(all.compatible.begin(), all.compatible.end(),
                                        [&](const SeedRunSummary& x) { return x.run == s.run; });
    o << (k ? ",\n  " : "\n  ") << "{\"engine\": " << JsonString(s.engine) << ", \"setting\": " << JsonString(s.setting)
      << ", \"compatible\": " << (compatible ? "true" : "false") << ", \"worst_class_p90_clear\": [";
    for (size_t j = 0; j < s.worst.size(); ++j) o << (j ? ", " : "") << JsonNumber(s.worst[j]);
    o << "], \"worst_class\": [";
    for (size_t j = 0; j < s.worstClass.size(); ++j) o << (j ? ", " : "") << JsonString(s.worstClass[j]);
    o << "], \"worst_class_p90_all\": [";
    for (size_t j = 0; j < s.worstAll.size(); ++j) o << (j ? ", " : "") << JsonNumber(s.worstAll[j]);
    o << "], \"median\": " << JsonNumber(s.median) << ", \"min\": " << JsonNumber(s.min) << ", \"max\": " << JsonNumber(s.max)
      << ", \"holds\": " << (s.max < qs::kCauseThreshold ? "true" : "false") << "}";
  }
  o << "],\n \"classes_across_seeds\": [";
  for (size_t k = 0; k < all.classes.size(); ++k) {
    const ClassSeries& cs = all.classes[k];
    const Range a = RangeOf(cs.p90All), b = RangeOf(cs.p90Clear);
    o << (k ? ",\n  " : "\n  ") << "{\"class\": " << JsonString(cs.cls) << ", \"engine\": " << JsonString(c.runs[cs.run].engine)
      << ", \"setting\": " << JsonString(c.runs[cs.run].setting) << ", \"p90_median\": " << JsonNumber(a.median)
      << ", \"p90_min\": " << JsonNumber(a.min) << ", \"p90_max\": " << JsonNumber(a.max)
      << ", \"p90_clear_median\": " << JsonNumber(b.median) << ", \"p90_clear_min\": " << JsonNumber(b.min)
      << ", \"p90_clear_max\": " << JsonNumber(b.max) << "}";
  }
  o << "],\n \"differences_above_5_percent\": [";
  for (size_t k = 0; k < all.diagnosed.size(); ++k) {
    const Diagnosed& d = all.diagnosed[k];
    o << (k ? ",\n  " : "\n  ") << "{\"seed\": " << d.seed << ", \"hit\": " << d.index << ", \"class\": " << JsonString(d.cls)
      << ", \"engine\": " << JsonString(c.runs[d.run].engine) << ", \"setting\": " << JsonString(c.runs[d.run].setting)
      << ", \"difference\": " << JsonNumber(d.d.difference) << ", \"box2d_spread\": " << JsonNumber(d.spread)
      << ", \"ambiguous\": " << (d.ambiguous ? "true" : "false") << ", \"cause\": " << JsonString(qs::CauseName(d.d.cause))
      << ", \"at_separation\": " << JsonNumber(d.d.atSeparation) << ", \"new_point_approach\": " << JsonNumber(d.d.recontactSpeed)
      << ", \"points_box2d\": " << d.d.maxTouching[0] << ", \"points_run\": " << d.d.maxTouching[1]
      << ", \"order_shift\": " << JsonNumber(d.d.orderShift) << "}";
  }
  o << "]";
  return o.str();
}

void SeedsMarkdown(std::ostringstream& o, const qs::Campaign& c, const Seeds& all, int hitsPerSeed) {
  o << "## Across seeds\n\n"
    << all.seeds.size() << " seeds (";
  for (size_t k = 0; k < all.seeds.size(); ++k) o << (k ? ", " : "") << all.seeds[k];
  o << ") of " << hitsPerSeed << " hits each. A figure \"m (a-b)\" is the median over the seeds of the per-seed p90, "
       "and its range, in percent.\n\n"
    << "**Ambiguous hits** (the same rule for every engine and solver): a hit whose Box2D 2.4.1 response moves by "
       "more than 5 % (the tolerance itself) when the mover is moved by 1e-4 m in x or y or turned by 1e-4 rad, "
       "either sign, has no single right answer at that tolerance. "
    << all.ambiguousTotal << " of " << c.hits.size() << " hits are ambiguous (per seed: ";
  for (size_t k = 0; k < all.ambiguous.size(); ++k) o << (k ? ", " : "") << all.ambiguous[k];
  o << "). \"Clear\" below means outside that set.\n\n"
    << "### The Box2D-compatible settings\n\n"
    << "| engine | setting | worst class p90, clear hits: median (range) | worst class on its worst seed | worst class "
       "p90, all hits: median (range) | under 5 % on every seed (clear hits) |\n|---|---|---:|---|---:|---|\n";
  auto runRow = [&](const SeedRunSummary& s, bool verdict) {
    size_t worstSeed = size_t(std::max_element(s.worst.begin(), s.worst.end()) - s.worst.begin());
    o << "| " << s.engine << " | " << s.setting << " | " << RangeText(s.worst) << " | " << s.worstClass[worstSeed]
      << " (seed " << all.seeds[worstSeed] << ") | " << RangeText(s.worstAll) << " |";
    if (verdict) o << (s.max < qs::kCauseThreshold ? " **yes**" : " **no**") << " |";
    o << "\n";
  };
  for (const SeedRunSummary& s : all.compatible) runRow(s, true);
  o << "\nPer seed, the worst class p90 of each compatible setting outside the ambiguous hits (percent; bold: 5 % or "
       "more):\n\n| seed | ambiguous hits |";
  for (const SeedRunSummary& s : all.compatible) o << " " << s.engine << " |";
  o << "\n|---:|---:|";
  for (size_t k = 0; k < all.compatible.size(); ++k) o << "---:|";
  o << "\n";
  for (size_t k = 0; k < all.seeds.size(); ++k) {
    o << "| " << all.seeds[k] << " | " << all.ambiguous[k] << " |";
    for (const SeedRunSummary& s : all.compatible) {
      const bool over = s.worst[k] >= qs::kCauseThreshold;
      o << " " << (over ? "**" : "") << Pct(s.worst[k]) << (over ? "**" : "") << " (" << s.worstClass[k] << ") |";
    }
    o << "\n";
  }
  o << "\n### Every run\n\n| engine | setting | worst class p90, clear hits: median (range) | worst class on its worst "
       "seed | worst class p90, all hits: median (range) |\n|---|---|---:|---|---:|\n";
  for (const SeedRunSummary& s : all.runs) runRow(s, false);

  auto classTable = [&](bool clear) {
    o << "| run |";
    for (const std::string& cls : ClassList()) o << " " << cls << " |";
    o << "\n|---|";
    for (size_t k = 0; k < ClassList().size(); ++k) o << "---:|";
    o << "\n";
    for (size_t r = 1; r < c.runs.size(); ++r) {
      o << "| " << c.runs[r].engine << (c.runs[r].setting == "default" ? "" : " / " + c.runs[r].setting) << " |";
      for (const std::string& cls : ClassList()) {
        for (const ClassSeries& cs : all.classes) {
          if (cs.run != r || cs.cls != cls) continue;
          const std::vector<double>& v = clear ? cs.p90Clear : cs.p90All;
          const bool over = RangeOf(v).max > 0.05;
          o << " " << (over ? "**" : "") << RangeText(v) << (over ? "**" : "") << " |";
        }
      }
      o << "\n";
    }
  };
  o << "\n### p90 per class, all hits: median (range) over the seeds\n\nBold: above 5 % on some seed.\n\n";
  classTable(false);
  o << "\n### p90 per class, clear hits: median (range) over the seeds\n\n";
  classTable(true);

  o << "\n### Every difference above 5 % in a compatible setting, by cause\n\n"
    << "Each hit where a Box2D-compatible setting differs from Box2D by more than 5 % is classified by the first "
       "rule that holds (benchmarks/scenes/random_hit_causes.h; a reproducer per cause in "
       "tests/adapters/random_hit_causes_test.cpp): *restitution threshold*, a point arriving after the first step "
       "approaches at 0.8-1.25 m/s in either engine (e > 0); *re-contact*, either engine meets the other body again "
       "after both first separate, and the two agree within 5 % at that separation; *speculative contact*, during the "
       "first contact the run's touching points differ from Box2D's and its touching plus speculative ones match; "
       "*skin*, they differ otherwise; *order of points*, both hold two points and Box2D or the run moves by more than "
       "5 % when the scene lists its bodies the other way round; *simultaneous points*, two points, insensitive to "
       "that order; *solver difference*, one point throughout.\n\n"
    << "| engine | setting | hits above 5 % (ambiguous) |";
  for (qs::HitCause cause : qs::kAllCauses) o << " " << qs::CauseName(cause) << " |";
  o << "\n|---|---|---:|";
  for (size_t k = 0; k < std::size(qs::kAllCauses); ++k) o << "---:|";
  o << "\n";
  for (const SeedRunSummary& s : all.compatible) {
    int total = 0, amb = 0;
    std::map<qs::HitCause, std::pair<int, int>> count;
    for (const Diagnosed& d : all.diagnosed) {
      if (d.run != s.run) continue;
      ++total;
      amb += d.ambiguous;
      ++count[d.d.cause].first;
      count[d.d.cause].second += d.ambiguous;
    }
    o << "| " << s.engine << " | " << s.setting << " | " << total << " (" << amb << ") |";
    for (qs::HitCause cause : qs::kAllCauses) o << " " << count[cause].first << " (" << count[cause].second << ") |";
    o << "\n";
  }
  o << "\nCells: hits (of which ambiguous). Every one of them:\n\n"
    << "| seed | hit | class | engine / setting | difference | Box2D's spread | ambiguous | cause | at separation | "
       "new point's approach (m/s) | points Box2D / run | order shift |\n|---:|---:|---|---|---:|---:|---|---|---:|---:|---|---:|\n";
  for (const Diagnosed& d : all.diagnosed) {
    o << "| " << d.seed << " | " << d.index << " | " << d.cls << " | " << c.runs[d.run].engine << " / " << c.runs[d.run].setting
      << " | " << Pct(d.d.difference) << " % | " << Pct(d.spread) << " % | " << (d.ambiguous ? "yes" : "no") << " | "
      << qs::CauseName(d.d.cause) << " | " << (d.d.atSeparation < 0 ? std::string("-") : Pct(d.d.atSeparation) + " %") << " | "
      << (d.d.recontactSpeed < 0 ? std::string("-") : Cell(d.d.recontactSpeed)) << " | " << d.d.maxTouching[0] << " / "
      << d.d.maxTouching[1] << " | " << (d.d.orderShift > 0 ? Pct(d.d.orderShift) + " %" : std::string("-")) << " |\n";
  }
  o << "\n";
}

std::string Json(const qs::Campaign& c, const std::vector<qs::CampaignRow>& rows,
                 const std::vector<qs::CampaignRow>& analytic, const Seeds& all) {
  std::ostringstream o;
  o << "{\"hits\": " << c.hits.size() << ", \"seed\": " << c.seed << ", \"machine\": "
    << JsonString(Env("QUADRANT_MACHINE", "unknown")) << ", \"commit\": " << JsonString(Env("QUADRANT_COMMIT", "unknown"))
    << ", \"date\": " << JsonString(UtcNow()) << ", \"compiler\": " << JsonString(__VERSION__)
    << ", \"load_average\": " << JsonString(LoadAverage()) << ",\n \"settings\": {\"gravity\": 0, \"dt\": 0.0166666667, \"velocity_iterations\": 8, \"position_iterations\": 3, "
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
  o << "]" << SeedsJson(c, all) << "}\n";
  return o.str();
}

// One row per hit; per run its difference to Box2D, its distance from the analytic answer
// (empty where the hit has none) and the most points of a manifold. 4 significant digits: the
// plot's resolution, and a file small enough to commit (about 0.9 MB for 10 seeds x 200 hits).
std::string Csv(const qs::Campaign& c, const Seeds& all) {
  auto num = [](double v) {
    if (std::isnan(v)) return std::string();
    char b[32];
    std::snprintf(b, sizeof b, "%.4g", v);
    return std::string(b);
  };
  std::ostringstream o;
  o << "seed,hit,box2d_spread,ambiguous,class,friction,mass_ratio,speed,spin,single_point,analytic:to_box2d";
  for (const qs::CampaignRun& r : c.runs) {
    const std::string run = r.engine + "/" + r.setting;
    o << "," << run << ":to_box2d," << run << ":to_analytic," << run << ":points";
  }
  o << "\n";
  for (size_t i = 0; i < c.hits.size(); ++i) {
    const qs::RandomHit& h = c.hits[i];
    o << h.scene.seed << "," << h.index << "," << num(all.spread[i]) << "," << (all.isAmbiguous[i] ? 1 : 0) << ","
      << h.Class() << "," << h.friction << "," << num(h.massRatio) << "," << num(h.speed) << ","
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
                     const std::vector<qs::CampaignRow>& analytic, const Seeds& all) {
  const int hitsPerSeed = int(c.hits.size() / all.seeds.size());
  std::ostringstream o;
  int single = 0;
  for (bool s : c.singlePoint) single += s;
  o << "# Contact responses against Box2D 2.4.1: the random campaign\n\n"
    << "Machine `" << Env("QUADRANT_MACHINE", "unknown") << "`, commit `" << Env("QUADRANT_COMMIT", "unknown") << "`, "
    << UtcNow() << ", compiler " << __VERSION__ << ", load average " << LoadAverage()
    << ". Written by `tools/quadrant validate --random " << hitsPerSeed
    << " --seed " << c.seed << " --seeds " << all.seeds.size() << "` (benchmarks/validate_random.cpp; hits in benchmarks/scenes/random_hits.cpp, the "
    << "analytic impact in benchmarks/scenes/impact_analytic.cpp). Not a timing: the numbers do not depend on the "
       "machine's load.\n\n"
    << "**" << c.hits.size() << " hits** (" << hitsPerSeed << " on each of " << all.seeds.size()
    << " seeds), each run on Box2D 2.4.1 and on every Quadrant run below through the scene "
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

  SeedsMarkdown(o, c, all, hitsPerSeed);
  o << "## Against Box2D 2.4.1, all seeds' hits pooled\n\n";
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
       "iterations; either alone changes nothing); `box2d_position_solve` = `WorldDef::box2dPositionSolve` "
       "(`b2possolve`: the position pass with Box2D 2.4.1's geometry, the reference face's normal turning with "
       "its body and the incident point with its own, instead of a normal fixed in the world); `block` = "
       "`WorldDef::thesisBlockImpulse` (the thesis's two touching points' normal impulses solved together, as "
       "Box2D's block solver, instead of one after the other); others are Quadrant "
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

int RunRandomCampaign(const std::string& outDir, int hits, uint64_t seed, int seeds,
                      const std::vector<std::string>& extraRuns) {
  if (seeds < 1) throw Error("--seeds must be >= 1");
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
  // Every seed's campaign, then one pooled campaign (hits of all seeds in seed order) for the
  // pooled tables, the CSV and the plot.
  std::vector<qs::Campaign> perSeed;
  Seeds all;
  for (int k = 0; k < seeds; ++k) {
    perSeed.push_back(qs::RunCampaign(seed + uint64_t(k), hits, runs));
    std::fprintf(stderr, "quadrant_validate: seed %llu: %d hits run\n", (unsigned long long)(seed + uint64_t(k)), hits);
  }
  all = Analyse(perSeed);
  qs::Campaign c = perSeed[0];
  for (size_t k = 1; k < perSeed.size(); ++k) {
    const qs::Campaign& p = perSeed[k];
    c.hits.insert(c.hits.end(), p.hits.begin(), p.hits.end());
    c.cells.insert(c.cells.end(), p.cells.begin(), p.cells.end());
    c.analyticToBox2d.insert(c.analyticToBox2d.end(), p.analyticToBox2d.begin(), p.analyticToBox2d.end());
    c.analyticEnergyRatio.insert(c.analyticEnergyRatio.end(), p.analyticEnergyRatio.begin(), p.analyticEnergyRatio.end());
    c.singlePoint.insert(c.singlePoint.end(), p.singlePoint.begin(), p.singlePoint.end());
    c.analyticJams += p.analyticJams;
    c.analyticRecontacts += p.analyticRecontacts;
  }
  const std::vector<qs::CampaignRow> rows = c.Box2dRows(), analytic = c.AnalyticRows();
  std::filesystem::create_directories(outDir);
  const std::filesystem::path dir(outDir);
  Write(dir / "validation_random.json", Json(c, rows, analytic, all));
  Write(dir / "validation_random.md", Markdown(c, rows, analytic, all));
  Write(dir / "validation_random_hits.csv", Csv(c, all));
  bool hold = true;
  for (const SeedRunSummary& s : all.compatible) {
    std::fprintf(stderr, "%-20s %-58s worst class p90 outside the ambiguous hits: median %5.2f %%, range %5.2f-%5.2f %% %s\n",
                 s.engine.c_str(), s.setting.c_str(), 100 * s.median, 100 * s.min, 100 * s.max,
                 s.max < qs::kCauseThreshold ? "(holds)" : "(FAILS on a seed)");
    hold = hold && s.max < qs::kCauseThreshold;
  }
  std::fprintf(stderr, "quadrant_validate: %d of %zu hits ambiguous; wrote %s/validation_random.{json,md} and validation_random_hits.csv\n",
               all.ambiguousTotal, c.hits.size(), outDir.c_str());
  return hold ? 0 : 1;
}

}  // namespace quadrant::report
