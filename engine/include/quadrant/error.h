// Quadrant: the one error type of the engine.
//
// Every refused input (NaN, infinities, non-positive sizes, bad polygons, stale ids, bad
// step parameters) throws quadrant::Error before anything is modified, so a caller that
// catches it still has the world exactly as it was.
#pragma once

#include <stdexcept>
#include <string>

namespace quadrant {

class Error : public std::invalid_argument {
 public:
  explicit Error(const std::string& what) : std::invalid_argument(what) {}
};

}  // namespace quadrant
