#pragma once
// The clock every timer in dfbwall reads, and the two ways we print a span of it. A steady clock
// is system-wide on Linux, so time points of different ranks on one host compare.
#include <chrono>
#include <cstdint>

namespace dfb {

using Clock = std::chrono::steady_clock;

inline double msBetween(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

inline std::int64_t nsBetween(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(b - a).count();
}

}  // namespace dfb
