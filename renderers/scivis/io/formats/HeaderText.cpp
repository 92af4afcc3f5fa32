#include "renderers/scivis/io/formats/HeaderText.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>

#include "base/Error.h"
#include "renderers/scivis/io/formats/ArrayHeader.h"

namespace renderers::headertext {

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::vector<double> numbers(std::string_view value, const std::string& where) {
  std::vector<double> out;
  std::size_t i = 0;
  while (i < value.size()) {
    while (i < value.size() && std::isspace(static_cast<unsigned char>(value[i]))) ++i;
    std::size_t j = i;
    while (j < value.size() && !std::isspace(static_cast<unsigned char>(value[j]))) ++j;
    if (j == i) break;
    double v = 0;
    const auto [end, ec] = std::from_chars(value.data() + i, value.data() + j, v);
    if (ec != std::errc() || end != value.data() + j || !std::isfinite(v))
      throw base::Error(where + ": '" + std::string(value.substr(i, j - i)) + "' is not a number");
    out.push_back(v);
    i = j;
  }
  return out;
}

std::vector<double> numbers(std::string_view value, std::size_t count, const std::string& where) {
  std::vector<double> out = numbers(value, where);
  if (out.size() != count)
    throw base::Error(where + ": " + std::to_string(count) + " numbers expected, found " +
                      std::to_string(out.size()));
  return out;
}

std::vector<long long> integers(std::string_view value, std::size_t count, long long lo,
                                long long hi, const std::string& where) {
  std::vector<long long> out;
  for (double v : numbers(value, count, where)) {
    if (v != std::floor(v) || v < static_cast<double>(lo) || v > static_cast<double>(hi))
      throw base::Error(where + ": " + std::to_string(v) + " is not an integer in [" +
                        std::to_string(lo) + ", " + std::to_string(hi) + "]");
    out.push_back(static_cast<long long>(v));
  }
  return out;
}

Index3 fileDims(std::string_view value, const std::string& where) {
  const auto s = integers(value, 3, 0, 1LL << 40, where);
  for (int a = 0; a < 3; ++a)
    if (s[a] > kMaxFileDims)
      throw base::Error(where + ": " + std::to_string(s[a]) + " voxels along axis " +
                        std::to_string(a) + ", more than the cap of " +
                        std::to_string(kMaxFileDims));
  const Index3 dims{static_cast<int>(s[0]), static_cast<int>(s[1]), static_cast<int>(s[2])};
  checkFileDims(dims, where);
  return dims;
}

std::string besideFile(const std::string& path, std::string_view name) {
  const std::filesystem::path p(name);
  if (p.is_absolute()) return p.string();
  return (std::filesystem::path(path).parent_path() / p).string();
}

}  // namespace renderers::headertext
