// quadrant_validate --random N (validate_random.cpp).
#pragma once

#include <cstdint>
#include <string>

#include "quadrant/error.h"

namespace quadrant::report {

/// Runs the random campaign (hits 0..hits-1 of seed `seed`) and writes validation_random.json,
/// validation_random.md and validation_random_hits.csv into outDir. Throws quadrant::Error.
int RunRandomCampaign(const std::string& outDir, int hits, uint64_t seed);

}  // namespace quadrant::report
