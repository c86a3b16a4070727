// quadrant_hardcases: runs every hard case on Quadrant (which must pass) and on the peers, and
// writes DIR/hardcases.json and DIR/hardcases.md.
//
//   quadrant_hardcases --out DIR [--peers box2d,bullet,chipmunk|none] [--cases a,b]
//                      [--soak-steps N]
//
// The cases, their scenes and their criteria live in benchmarks/scenes (hard_cases.cpp,
// hard_case_checks.cpp), shared with tests/adapters/hard_cases_test.cpp; every case but the soak
// runs 60 s of simulated time. Exit status: 0 when every Quadrant case passes (all 32 are
// required of the default engine), 1 when one fails (peers never change it), 2 on bad arguments.
// A line per case and engine goes to stderr as each finishes (a case takes seconds; the soak
// prints its progress every 10 s).
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
#include "hard_case_checks.h"
#include "quadrant/error.h"
#include "report_common.h"

namespace qs = quadrant::scene;
namespace rp = quadrant::report;

namespace {

std::vector<std::string> PeerNames() {
  std::vector<std::string> peers = qs::AdapterNames();
  peers.erase(peers.begin());  // "quadrant"
  return peers;
}

struct Args {
  std::string out = ".";
  std::vector<std::string> peers = PeerNames();  // the peers this build has
  std::vector<std::string> cases = qs::HardCaseNames();
  int soakSteps = 100000;
};

Args Parse(int argc, char** argv) {
  Args a;
  quadrant::cli::Parser p("quadrant_hardcases",
                          "Runs every hard case on Quadrant (which must pass) and on the peers, and writes "
                          "DIR/hardcases.json\nand DIR/hardcases.md. Exit status 0 when every Quadrant case "
                          "passes, 1 when one fails.");
  p.OutputDirectory("--out", &a.out, "the output directory");
  p.NameList("--peers", &a.peers, {}, "engine", "the peers to run the cases on too")
      .Accepts(quadrant::cli::kEngineList)
      .AllowNone()
      .Check(quadrant::cli::EngineProblem);  // before the first case runs, not minutes into them
  p.NameList("--cases", &a.cases, qs::HardCaseNames(), "case", "the cases to run").Default("all");
  p.Int("--soak-steps", &a.soakSteps, 1, 100000000, "steps of the soak case");
  p.Parse(argc, argv);
  return a;
}

std::string MeasuredJson(const qs::HardCaseResult& r) {
  std::string out = "{";
  for (size_t i = 0; i < r.measured.size(); ++i) {
    out += (i ? ", " : "") + rp::JsonString(r.measured[i].name) + ": " + rp::JsonNumber(r.measured[i].value);
  }
  return out + "}";
}

std::string MeasuredText(const qs::HardCaseResult& r) {
  if (!r.supported) return "unsupported: " + r.unsupported;
  std::string out;
  for (const qs::Measured& m : r.measured) out += (out.empty() ? "" : ", ") + m.name + " " + rp::Cell(m.value);
  return out;
}

std::string Verdict(const qs::HardCaseResult& r) {
  if (!r.supported) return "unsupported";
  return r.pass ? "pass" : "FAIL";
}

struct Row {
  qs::HardCaseResult quadrant;
  std::vector<qs::HardCaseResult> peers;
};

std::string Json(const std::vector<Row>& rows, const Args& args) {
  std::ostringstream o;
  o << "{\n  \"context\": {\"machine\": " << rp::JsonString(rp::Env("QUADRANT_MACHINE", "unknown"))
    << ", \"commit\": " << rp::JsonString(rp::Env("QUADRANT_COMMIT", "unknown"))
    << ", \"date\": " << rp::JsonString(rp::UtcNow()) << ", \"compiler\": " << rp::JsonString(__VERSION__)
    << ", \"threads\": 1, \"soak_steps\": " << args.soakSteps << "},\n  \"cases\": [\n";
  for (size_t i = 0; i < rows.size(); ++i) {
    const qs::HardCaseResult& q = rows[i].quadrant;
    o << "    {\"name\": " << rp::JsonString(q.name) << ", \"criterion\": " << rp::JsonString(q.criterion)
      << ", \"pass\": " << (q.pass ? "true" : "false") << ", \"seconds\": " << rp::JsonNumber(q.seconds);
    if (!q.supported) o << ", \"unsupported\": " << rp::JsonString(q.unsupported);
    o << ", \"settings\": " << rp::JsonString(q.settings);
    if (!q.note.empty()) o << ", \"note\": " << rp::JsonString(q.note);
    o << ",\n     \"measured\": " << MeasuredJson(q) << ",\n     \"peers\": {";
    for (size_t k = 0; k < rows[i].peers.size(); ++k) {
      const qs::HardCaseResult& p = rows[i].peers[k];
      o << (k ? ",\n               " : "") << rp::JsonString(p.engine) << ": {";
      if (p.supported) {
        o << "\"pass\": " << (p.pass ? "true" : "false") << ", \"seconds\": " << rp::JsonNumber(p.seconds)
          << ", \"measured\": " << MeasuredJson(p);
      } else {
        o << "\"pass\": null, \"unsupported\": " << rp::JsonString(p.unsupported);
      }
      o << "}";
    }
    o << "}}" << (i + 1 < rows.size() ? "," : "") << "\n";
  }
  o << "  ]\n}\n";
  return o.str();
}

std::string Markdown(const std::vector<Row>& rows, const Args& args) {
  std::ostringstream o;
  o << "# Hard cases\n\n"
    << "Machine `" << rp::Env("QUADRANT_MACHINE", "unknown") << "`, commit `" << rp::Env("QUADRANT_COMMIT", "unknown")
    << "`, " << rp::UtcNow() << ", compiler " << __VERSION__ << ". One thread per engine; every engine runs a "
    << "case with the same world settings (listed per case below: most cases at Box2D 2.4's 8 velocity and 3 "
    << "position iterations, a few with the larger budget their scene sets); every case but the soak runs 60 s "
    << "of simulated time and is checked over the whole window; soak " << args.soakSteps << " steps. Written by `tools/quadrant hardcases` "
    << "(benchmarks/hardcases.cpp); scenes in benchmarks/scenes/hard_cases.cpp, criteria in "
    << "benchmarks/scenes/hard_case_checks.cpp.\n\n"
    << "Materials are built per engine so that every engine simulates the same mixed coefficient: Box2D and "
    << "Quadrant mix friction as sqrt(f1 f2) and restitution as max(e1, e2), Bullet and Chipmunk multiply both; "
    << "one-material scenes give product-mixing engines sqrt of the coefficient on each body, the ramp and the "
    << "drop choose the ramp's or ground's value so that each box or ball mixes to its own.\n\n"
    << "heavy_on_slab (a 1000:1 box on one light slab) is beyond Box2D 2.4.1 and 3.2 at their default "
    << "budgets (issue #13 item 3); Quadrant's default engine holds it with its mass-ratio limit "
    << "(WorldDef::softMassRatioLimit), and every case is required of it.\n\n"
    << "| case | criterion | quadrant |";
  std::vector<std::string> peerNames;
  if (!rows.empty()) {
    for (const qs::HardCaseResult& p : rows[0].peers) peerNames.push_back(p.engine);
  }
  for (const std::string& p : peerNames) o << " " << p << " |";
  o << "\n|---|---|---|";
  for (size_t k = 0; k < peerNames.size(); ++k) o << "---|";
  o << "\n";
  for (const Row& row : rows) {
    o << "| " << row.quadrant.name << " | " << rp::CellText(row.quadrant.criterion) << " | **"
      << Verdict(row.quadrant) << "** |";
    for (const qs::HardCaseResult& p : row.peers) o << " " << Verdict(p) << " |";
    o << "\n";
  }
  o << "\n## Measured\n\n| case | engine | verdict | figures | seconds |\n|---|---|---|---|---|\n";
  for (const Row& row : rows) {
    auto line = [&](const qs::HardCaseResult& r) {
      o << "| " << r.name << " | " << r.engine << " | " << Verdict(r) << " | " << rp::CellText(MeasuredText(r))
        << " | " << rp::Cell(r.seconds) << " |\n";
    };
    line(row.quadrant);
    for (const qs::HardCaseResult& p : row.peers) line(p);
  }
  o << "\n## Settings\n\n| case | world settings (every engine) |\n|---|---|\n";
  for (const Row& row : rows) o << "| " << row.quadrant.name << " | " << rp::CellText(row.quadrant.settings) << " |\n";
  bool notes = false;
  for (const Row& row : rows) {
    if (row.quadrant.note.empty()) continue;
    if (!notes) o << "\n## Notes\n\n";
    notes = true;
    o << "- **" << row.quadrant.name << "**: " << row.quadrant.note << "\n";
  }
  return o.str();
}

void Write(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out) {
    std::cerr << "quadrant_hardcases: cannot write " << path << "\n";
    std::exit(2);
  }
}

}  // namespace

int main(int argc, char** argv) {
  const Args args = Parse(argc, argv);
  std::vector<Row> rows;
  bool allPass = true;
  try {
    qs::HardCaseOptions options;
    options.soakSteps = args.soakSteps;
    options.progressSeconds = 10;  // a line at least every 10 s during the minutes-long soaks
    for (const std::string& name : args.cases) {
      Row row;
      row.quadrant = qs::RunHardCase(name, "quadrant", options);
      allPass = allPass && row.quadrant.pass;
      std::fprintf(stderr, "%-18s quadrant %-11s (%.1f s) %s\n", name.c_str(), Verdict(row.quadrant).c_str(),
                   row.quadrant.seconds, MeasuredText(row.quadrant).c_str());
      for (const std::string& peer : args.peers) {
        row.peers.push_back(qs::RunHardCase(name, peer, options));
        const qs::HardCaseResult& p = row.peers.back();
        std::fprintf(stderr, "%-18s %-8s %-11s (%.1f s) %s\n", name.c_str(), peer.c_str(), Verdict(p).c_str(),
                     p.seconds, MeasuredText(p).c_str());
      }
      rows.push_back(std::move(row));
    }
  } catch (const quadrant::Error& e) {
    std::fprintf(stderr, "quadrant_hardcases: %s\n", e.what());
    return 2;
  }

  std::filesystem::create_directories(args.out);
  const std::filesystem::path dir(args.out);
  const std::string markdown = Markdown(rows, args);
  Write(dir / "hardcases.json", Json(rows, args));
  Write(dir / "hardcases.md", markdown);
  std::cout << markdown << std::flush;  // before the closing line on stderr, so a 2>&1 pipe keeps them apart
  std::fprintf(stderr, "quadrant_hardcases: wrote %s and %s; Quadrant %s\n", (dir / "hardcases.json").c_str(),
               (dir / "hardcases.md").c_str(), allPass ? "passes every case" : "FAILS a case");
  return allPass ? 0 : 1;
}
