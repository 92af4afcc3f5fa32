#include "apps/ThreadCpu.h"

#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

namespace app {

std::int64_t cpuNsOfThreadsNamed(std::string_view prefix) {
  std::int64_t total = 0;
  std::error_code error;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task", error)) {
    std::ifstream comm(task.path() / "comm");
    std::string name;
    if (!std::getline(comm, name) || name.compare(0, prefix.size(), prefix) != 0) continue;
    std::ifstream schedstat(task.path() / "schedstat");  // "run-ns wait-ns timeslices"
    std::int64_t ns = 0;
    if (schedstat >> ns) total += ns;
  }
  return total;
}

}  // namespace app
