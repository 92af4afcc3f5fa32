#include "renderers/scivis/io/formats/HeaderText.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>

#include "base/Error.h"
#include "renderers/scivis/io/formats/ArrayHeader.h"

namespace renderers::scivis::headertext {

void HeaderField::fail(const std::string& what, std::size_t offset) const {
  throw base::Error(at(offset).where, "field '" + name + "': " + what);
}

HeaderField HeaderField::at(std::size_t offset) const {
  HeaderField f = *this;
  if (f.where.column > 0) f.where.column += static_cast<int>(offset);
  return f;
}

HeaderField fieldAt(const std::string& path, int lineNumber, std::string_view line,
                    std::string_view value, std::string name) {
  const auto column = value.data() >= line.data() && value.data() <= line.data() + line.size()
                          ? static_cast<int>(value.data() - line.data()) + 1
                          : 0;
  return {{path, lineNumber, column}, std::move(name)};
}

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

std::vector<double> numbers(std::string_view value, const HeaderField& f) {
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
      f.fail("'" + std::string(value.substr(i, std::min<std::size_t>(j - i, 80))) +
                 "' is not a number",
             i);
    out.push_back(v);
    i = j;
  }
  return out;
}

std::vector<double> numbers(std::string_view value, std::size_t count, const HeaderField& f) {
  std::vector<double> out = numbers(value, f);
  if (out.size() != count)
    f.fail(std::to_string(count) + " numbers expected, found " + std::to_string(out.size()));
  return out;
}

std::vector<long long> integers(std::string_view value, std::size_t count, long long lo,
                                long long hi, const HeaderField& f) {
  std::vector<long long> out;
  for (double v : numbers(value, count, f)) {
    if (v != std::floor(v) || v < static_cast<double>(lo) || v > static_cast<double>(hi))
      f.fail(std::to_string(v) + " is not an integer in [" + std::to_string(lo) + ", " +
             std::to_string(hi) + "]");
    out.push_back(static_cast<long long>(v));
  }
  return out;
}

Index3 fileDims(std::string_view value, const HeaderField& f) {
  const auto s = integers(value, 3, 0, 1LL << 40, f);
  for (int a = 0; a < 3; ++a)
    if (s[a] > kMaxFileDims)
      f.fail(std::to_string(s[a]) + " voxels along axis " + std::to_string(a) +
             ", more than the cap of " + std::to_string(kMaxFileDims));
  const Index3 dims{static_cast<int>(s[0]), static_cast<int>(s[1]), static_cast<int>(s[2])};
  if (const std::string problem = fileDimsProblem(dims); !problem.empty()) f.fail(problem);
  return dims;
}

std::string besideFile(const std::string& path, std::string_view name) {
  const std::filesystem::path p(name);
  if (p.is_absolute()) return p.string();
  return (std::filesystem::path(path).parent_path() / p).string();
}

}  // namespace renderers::scivis::headertext
