#pragma once
// Elapsed time for tests that check a wait ends at (or well before) its deadline.
#include <chrono>

namespace testutil {

using Clock = std::chrono::steady_clock;

inline double secondsSince(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

}  // namespace testutil
