// quadrant_validate --random N [--seeds K] (validate_random.cpp).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "quadrant/error.h"

namespace quadrant::report {

/// Runs the random campaign (hits 0..hits-1 of each of the seeds seed, seed+1, ..., seed+seeds-1)
/// and writes validation_random.json, validation_random.md and validation_random_hits.csv into
/// outDir. Throws quadrant::Error. extraRuns: more adapter names ("quadrant:<variant>") run
/// besides DefaultCampaignRuns(). Returns 0, or 1 when a Box2D-compatible setting's worst class
/// p90 reaches 5 % on a seed outside the ambiguous hits (random_hit_causes.h).
int RunRandomCampaign(const std::string& outDir, int hits, uint64_t seed, int seeds,
                      const std::vector<std::string>& extraRuns);

}  // namespace quadrant::report
