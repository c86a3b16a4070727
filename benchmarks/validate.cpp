// quadrant_validate: runs the canonical validation cases on Quadrant and Box2D 2.4.1 and writes
// DIR/validation.json and DIR/validation.md; or, with --random N, the randomised campaign of N
// oblique hits (benchmarks/scenes/random_hits.h) on every Quadrant solver and setting and on
// Box2D, against Box2D and the analytic single-point impact, and writes
// DIR/validation_random.json, DIR/validation_random.md and DIR/validation_random_hits.csv (a
// row per hit, for the plot: tools/validation_random_plot.py).
//
//   quadrant_validate --out DIR [--cases a,b]
//   quadrant_validate --out DIR --random N [--seed S] [--seeds K] [--runs quadrant:VARIANT,...]
//
// --seeds K runs the campaign on seeds S, S+1, ..., S+K-1 (default 10) and reports each class's
// p90 as its median and range over the seeds, the ambiguous hits (Box2D against itself under a
// 1e-4 perturbation) and the cause of every difference above 5 % in a Box2D-compatible setting
// (benchmarks/scenes/random_hit_causes.h).
// --runs adds Quadrant variants (adapter names, e.g. quadrant:soft_step+sub16) to the campaign's
// runs, reported as engine "quadrant:<solver>" and setting "<the other tokens>": how a
// difference is traced to one modelling choice.
//
// The cases, their tolerances and the reasons for them live in
// benchmarks/scenes/validation_cases.cpp, shared with tests/adapters/validation_test.cpp. Exit
// status: 0 when every case passes (for --random: when every compatible setting's worst class
// p90 stays under 5 % on every seed outside the ambiguous hits), 1 otherwise, 2 on bad arguments.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "cli_args.h"
#include "cli_engines.h"
#include "quadrant/error.h"
#include "random_hits.h"
#include "report_common.h"
#include "validate_random.h"
#include "validation_cases.h"

namespace qs = quadrant::scene;
namespace rp = quadrant::report;

namespace {

struct Args {
  std::string out = ".";
  std::vector<std::string> cases = qs::ValidationCaseNames();
  int random = 0;  ///< hits of the random campaign; 0: the canonical cases
  uint64_t seed = 17;
  int seeds = 10;  ///< --seeds: how many consecutive seeds the random campaign runs
  std::vector<std::string> extraRuns;  ///< --runs: more Quadrant variants for the campaign
};

/// A --runs item the campaign cannot run (not quadrant:<variant>, or an unknown variant), or "".
std::string RunProblem(const std::string& name) {
  if (!name.starts_with("quadrant:")) return "'" + name + "' is not quadrant:<variant>";
  return quadrant::cli::EngineProblem(name);
}

Args Parse(int argc, char** argv) {
  Args a;
  quadrant::cli::Parser p("quadrant_validate",
                          "Runs the canonical validation cases on Quadrant and Box2D 2.4.1 and writes "
                          "DIR/validation.json and\nDIR/validation.md; or, with --random N, the randomised "
                          "campaign of N oblique hits, written to\nDIR/validation_random.{json,md} and "
                          "DIR/validation_random_hits.csv. Exit status 0 when every case\npasses, 1 when one "
                          "fails.");
  p.OutputDirectory("--out", &a.out, "the output directory");
  p.NameList("--cases", &a.cases, qs::ValidationCaseNames(), "case", "the canonical cases to run").Default("all");
  p.Int("--random", &a.random, 1, 1000000, "run the random campaign of this many hits instead of the cases")
      .Default("");
  p.Int("--seed", &a.seed, 0, 2147483647, "the random campaign's first seed");
  p.Int("--seeds", &a.seeds, 1, 1000, "how many consecutive seeds the random campaign runs");
  p.NameList("--runs", &a.extraRuns, {}, "run", "more Quadrant variants for the random campaign")
      .Accepts("a comma-separated list of quadrant:<variant> adapter names (e.g. quadrant:soft_step+sub16)")
      .Value("quadrant:V,...")
      .Check(RunProblem);
  p.Parse(argc, argv);
  return a;
}

std::string Json(const std::vector<qs::ValidationResult>& results) {
  std::ostringstream o;
  o << "{\"cases\": [\n";
  for (size_t i = 0; i < results.size(); ++i) {
    const qs::ValidationResult& r = results[i];
    o << "  {\"name\": " << rp::JsonString(r.name) << ", \"pass\": " << (r.pass ? "true" : "false")
      << ", \"quantities\": {\n";
    for (size_t k = 0; k < r.quantities.size(); ++k) {
      const qs::ValidationQuantity& q = r.quantities[k];
      o << "    " << rp::JsonString(q.name) << ": {\"quadrant\": " << rp::JsonNumber(q.quadrant)
        << ", \"box2d\": " << rp::JsonNumber(q.box2d)
        << ", \"analytic\": " << (q.analytic ? rp::JsonNumber(*q.analytic) : "null")
        << ", \"tolerance\": " << rp::JsonNumber(q.tolerance) << ", \"pass\": " << (q.pass ? "true" : "false")
        << ", \"reason\": " << rp::JsonString(q.reason) << "}" << (k + 1 < r.quantities.size() ? "," : "") << "\n";
    }
    o << "  }}" << (i + 1 < results.size() ? "," : "") << "\n";
  }
  o << "]}\n";
  return o.str();
}

std::string Markdown(const std::vector<qs::ValidationResult>& results) {
  int passed = 0;
  for (const qs::ValidationResult& r : results) passed += r.pass ? 1 : 0;
  std::ostringstream o;
  o << "# Validation against Box2D 2.4.1\n\n"
    << "Machine `" << rp::Env("QUADRANT_MACHINE", "unknown") << "`, commit `" << rp::Env("QUADRANT_COMMIT", "unknown")
    << "`, " << rp::UtcNow() << ", compiler " << __VERSION__ << ". Written by `tools/quadrant validate` "
    << "(benchmarks/validate.cpp); cases in benchmarks/scenes/validation_cases.cpp.\n\n"
    << "**" << passed << " of " << results.size() << " cases pass.**\n\n"
    << "Both engines run each case through the scene API with the same settings: dt = 1/60, 8 velocity and 3 "
    << "position iterations, no sleep, no continuous collision, equal materials on both bodies of a contact (so "
    << "the two mixing rules agree), and bodies that start touching or meet exactly at a step boundary. A "
    << "quantity passes when |quadrant - box2d| <= tolerance and, where physics gives an answer, |quadrant - "
    << "analytic| <= tolerance. Box2D's 0.01 m polygon skin is subtracted where it matters (quantities named "
    << "`..._minus_skin`), never absorbed by a tolerance. The one Box2D effect that cannot be subtracted, its "
    << "friction acting half its slop inside a resting circle (`spinning_circle_lands`: it rolls 0.5 % fast), "
    << "is named with its size in those quantities' reasons.\n\n"
    << "| case | quantity | quadrant | box2d | analytic | tolerance | verdict |\n|---|---|---|---|---|---|---|\n";
  for (const qs::ValidationResult& r : results) {
    for (const qs::ValidationQuantity& q : r.quantities) {
      o << "| " << r.name << " | " << q.name << " | " << rp::Cell(q.quadrant) << " | " << rp::Cell(q.box2d) << " | "
        << (q.analytic ? rp::Cell(*q.analytic) : "-") << " | " << rp::Cell(q.tolerance) << " | "
        << (q.pass ? "pass" : "**FAIL**") << " |\n";
    }
  }
  o << "\n## Cases and the reasons for each tolerance\n";
  for (const qs::ValidationResult& r : results) {
    o << "\n### " << r.name << (r.pass ? "" : " (FAILS)") << "\n\n" << r.description << "\n\n";
    for (const qs::ValidationQuantity& q : r.quantities) o << "- `" << q.name << "`: " << q.reason << "\n";
  }
  return o.str();
}

void Write(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out) {
    std::cerr << "quadrant_validate: cannot write " << path.string() << "\n";
    std::exit(2);
  }
}

}  // namespace

int main(int argc, char** argv) {
  const Args args = Parse(argc, argv);
  if (args.random > 0) {
    try {
      return quadrant::report::RunRandomCampaign(args.out, args.random, args.seed, args.seeds, args.extraRuns);
    } catch (const quadrant::Error& e) {
      std::fprintf(stderr, "quadrant_validate: %s\n", e.what());
      return 2;
    }
  }
  std::vector<qs::ValidationResult> results;
  bool allPass = true;
  try {
    for (const std::string& name : args.cases) {
      results.push_back(qs::RunValidationCase(name));
      const qs::ValidationResult& r = results.back();
      allPass = allPass && r.pass;
      std::fprintf(stderr, "%-24s %s\n", r.name.c_str(), r.pass ? "pass" : "FAIL");
      for (const qs::ValidationQuantity& q : r.quantities) {
        if (!q.pass) {
          std::fprintf(stderr, "    %-32s quadrant %.9g box2d %.9g analytic %s tolerance %g\n", q.name.c_str(),
                       q.quadrant, q.box2d, q.analytic ? rp::JsonNumber(*q.analytic).c_str() : "-", q.tolerance);
        }
      }
    }
  } catch (const quadrant::Error& e) {
    std::fprintf(stderr, "quadrant_validate: %s\n", e.what());
    return 2;
  }
  std::filesystem::create_directories(args.out);
  const std::filesystem::path dir(args.out);
  Write(dir / "validation.json", Json(results));
  Write(dir / "validation.md", Markdown(results));
  std::fprintf(stderr, "quadrant_validate: wrote %s and %s; %s\n", (dir / "validation.json").c_str(),
               (dir / "validation.md").c_str(), allPass ? "every case passes" : "a case FAILS");
  return allPass ? 0 : 1;
}
