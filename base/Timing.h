#pragma once
// The clock every timer in dfbwall reads, and the two ways we print a span of it. A steady clock
// is system-wide on Linux, so time points of different ranks on one host compare.
// Per-pixel stage timers read the calling thread's CPU clock instead: on cores shared by more
// ranks than cores, elapsed time inside a stage includes whatever ran while the thread was
// preempted (elapsed stage timers read 5-10x the CPU cost on a loaded machine).
#include <time.h>

#include <chrono>
#include <cstdint>

namespace base {

using Clock = std::chrono::steady_clock;

inline double msBetween(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

inline std::int64_t nsBetween(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(b - a).count();
}

// CPU time of the calling thread / of the whole process, in nanoseconds (a system call, some
// 100 ns: one or two reads per tile or piece, not per pixel).
inline std::int64_t threadCpuNs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return std::int64_t{t.tv_sec} * 1000000000 + t.tv_nsec;
}

inline std::int64_t processCpuNs() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return std::int64_t{t.tv_sec} * 1000000000 + t.tv_nsec;
}

}  // namespace base
