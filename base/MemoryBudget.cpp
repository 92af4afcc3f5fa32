#include "base/MemoryBudget.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>

namespace base {
namespace {

constexpr std::uint64_t kMax = std::numeric_limits<std::uint64_t>::max();

std::atomic<std::uint64_t> givenLimit{0};
std::atomic<int> ranksOnHost{1};

// The memory of the machine, or of the cgroup or address-space limit this process runs under.
std::uint64_t machineMemory() {
  std::uint64_t bytes = kMax;
  const long pages = ::sysconf(_SC_PHYS_PAGES), pageSize = ::sysconf(_SC_PAGESIZE);
  if (pages > 0 && pageSize > 0)
    bytes = bytesTimes(static_cast<std::uint64_t>(pages), static_cast<std::uint64_t>(pageSize));
  // cgroup v2 (v1's memory.limit_in_bytes when v2 is absent): "max" or a number.
  for (const char* file :
       {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
    std::ifstream in(file);
    unsigned long long cgroup = 0;
    if (in >> cgroup && cgroup > 0) {
      bytes = std::min<std::uint64_t>(bytes, cgroup);
      break;
    }
  }
  struct rlimit limit {};
  if (::getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY)
    bytes = std::min<std::uint64_t>(bytes, limit.rlim_cur);
  return bytes;
}

std::string number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, value < 100 ? "%.3g" : "%.0f", value);
  return buffer;
}

}  // namespace

std::uint64_t memoryLimit() {
  if (const std::uint64_t given = givenLimit.load()) return given;
  static const std::uint64_t machine = machineMemory();
  return machine / static_cast<std::uint64_t>(std::max(1, ranksOnHost.load()));
}

std::string memoryLimitText() {
  const std::uint64_t limit = memoryLimit();
  std::string source;
  if (givenLimit.load()) {
    source = "--memory-limit";
  } else {
    const int ranks = ranksOnHost.load();
    source = "the memory this process may use on this host" +
             (ranks > 1 ? ", shared by " + std::to_string(ranks) + " ranks" : std::string()) +
             "; --memory-limit sets it";
  }
  return byteText(limit) + " (" + std::to_string(limit) + " bytes: " + source + ")";
}

void setMemoryLimit(std::uint64_t bytes) { givenLimit.store(bytes); }

void setRanksOnHost(int ranks) { ranksOnHost.store(std::max(1, ranks)); }

std::string memoryProblem(std::uint64_t bytes) {
  if (bytes <= memoryLimit()) return {};
  return "needs " + byteText(bytes) + " (" +
         (bytes == kMax ? std::string("more than 2^64") : std::to_string(bytes)) +
         " bytes), more than this rank may hold: " + memoryLimitText();
}

std::uint64_t bytesTimes(std::uint64_t a, std::uint64_t b) {
  std::uint64_t out = 0;
  return __builtin_mul_overflow(a, b, &out) ? kMax : out;
}

std::uint64_t bytesPlus(std::uint64_t a, std::uint64_t b) {
  std::uint64_t out = 0;
  return __builtin_add_overflow(a, b, &out) ? kMax : out;
}

std::string byteText(std::uint64_t bytes) {
  static const char* const units[] = {"KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  if (bytes < 1024) return std::to_string(bytes) + (bytes == 1 ? " byte" : " bytes");
  double value = static_cast<double>(bytes);
  int unit = -1;
  while (value >= 1024 && unit < 5) value /= 1024, ++unit;
  return number(value) + " " + units[unit];
}

std::optional<std::uint64_t> parseByteSize(std::string_view text) {
  std::size_t digits = 0;
  while (digits < text.size() &&
         (std::isdigit(static_cast<unsigned char>(text[digits])) || text[digits] == '.'))
    ++digits;
  if (digits == 0) return std::nullopt;
  const std::string numberPart(text.substr(0, digits));
  if (numberPart.find('.') != numberPart.rfind('.')) return std::nullopt;  // two dots
  std::string suffix;
  for (char c : text.substr(digits)) suffix += static_cast<char>(std::tolower(c));
  double scale = 1;
  if (!suffix.empty()) {
    static const std::string letters = "kmgt";
    const std::size_t power = letters.find(suffix[0]);
    const std::string rest = suffix.substr(1);
    if (power == std::string::npos || !(rest.empty() || rest == "b" || rest == "ib"))
      return std::nullopt;
    scale = std::pow(1024.0, static_cast<double>(power + 1));
  } else if (numberPart.find('.') != std::string::npos) {
    return std::nullopt;  // a fraction of a byte
  }
  const double value = std::strtod(numberPart.c_str(), nullptr) * scale;
  if (!(value >= 1) || value > 9.2e18) return std::nullopt;
  return static_cast<std::uint64_t>(value);
}

}  // namespace base
