#pragma once
// CPU time of threads this process did not start itself, found by name: the GL driver's
// rasterizer threads (Mesa's llvmpipe names them "llvmpipe-N"), so the wall's CPU per pixel can
// be told apart from GL's.
#include <cstdint>
#include <string_view>

namespace app {

// Summed CPU nanoseconds (/proc/self/task/*/schedstat) of this process's live threads whose name
// starts with `prefix`; 0 where /proc is missing. Threads that ended are not counted.
std::int64_t cpuNsOfThreadsNamed(std::string_view prefix);

}  // namespace app
