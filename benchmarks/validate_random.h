// quadrant_validate --random N (validate_random.cpp).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "quadrant/error.h"

namespace quadrant::report {

/// Runs the random campaign (hits 0..hits-1 of seed `seed`) and writes validation_random.json,
/// validation_random.md and validation_random_hits.csv into outDir. Throws quadrant::Error.
/// extraRuns: more adapter names ("quadrant:<variant>") run besides DefaultCampaignRuns().
int RunRandomCampaign(const std::string& outDir, int hits, uint64_t seed, const std::vector<std::string>& extraRuns);

}  // namespace quadrant::report
