// Engine names on the benchmark programs' command lines (cli_args.h): what an --engines, --peers
// or --engine option accepts, and the check of one name, so a mistyped engine or Quadrant variant
// is refused in one line before anything runs.
#pragma once

#include <string>

#include "adapter.h"
#include "quadrant/error.h"

namespace quadrant::cli {

/// What an engine-list option accepts (the error line and help say it after the problem).
inline const char* const kEngineList =
    "a comma-separated list of engines (quadrant, quadrant:<variant>, box2d, bullet, chipmunk)";

/// The problem with an engine name, or "": MakeAdapter's refusal (an unknown engine, an unknown
/// Quadrant variant with the variants it knows, a peer this build lacks). The list of engines an
/// unknown name gets is left out: kEngineList says it.
inline std::string EngineProblem(const std::string& name) {
  try {
    scene::MakeAdapter(name);
  } catch (const Error& e) {
    std::string problem = e.what();
    const size_t known = problem.find(" (known: quadrant, ");
    return known == std::string::npos ? problem : problem.substr(0, known);
  }
  return "";
}

}  // namespace quadrant::cli
