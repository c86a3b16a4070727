// The clock the stages time themselves with (Profile's wall-clock milliseconds), written once.
#pragma once

#include <chrono>

namespace quadrant {

using StageClock = std::chrono::steady_clock;

/// Milliseconds from a to b.
inline double Ms(StageClock::time_point a, StageClock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

}  // namespace quadrant
