#include "renderers/scivis/io/VolumeSeries.h"

#include <glob.h>

#include <algorithm>
#include <memory>

#include "base/Error.h"

namespace renderers::scivis {

SeriesNaming seriesNaming(const std::string& file) {
  if (file.find('%') != std::string::npos) return SeriesNaming::Pattern;
  if (file.find_first_of("*?[") != std::string::npos) return SeriesNaming::Glob;
  return SeriesNaming::One;
}

std::string patternFile(const std::string& pattern, std::uint64_t step) {
  std::string out;
  int fields = 0;
  for (std::size_t i = 0; i < pattern.size(); ++i) {
    if (pattern[i] != '%') {
      out += pattern[i];
      continue;
    }
    if (i + 1 < pattern.size() && pattern[i + 1] == '%') {
      out += '%';
      ++i;
      continue;
    }
    // %[0][width]d, parsed by hand: the pattern comes from a file, never a format string.
    std::size_t j = i + 1;
    const bool zeros = j < pattern.size() && pattern[j] == '0';
    if (zeros) ++j;
    std::size_t width = 0;
    while (j < pattern.size() && pattern[j] >= '0' && pattern[j] <= '9' && width <= 20)
      width = width * 10 + static_cast<std::size_t>(pattern[j++] - '0');
    if (j >= pattern.size() || pattern[j] != 'd' || width > 20)
      throw base::Error("the pattern '" + pattern +
                        "' has a conversion other than %d, %Nd or %0Nd (N up to 20) at '" +
                        pattern.substr(i, std::min<std::size_t>(j + 1, pattern.size()) - i) +
                        "' (write %% for a '%')");
    if (++fields > 1) throw base::Error("the pattern '" + pattern + "' has more than one %d field");
    std::string digits = std::to_string(step);
    if (digits.size() < width) digits.insert(0, width - digits.size(), zeros ? '0' : ' ');
    out += digits;
    i = j;
  }
  if (fields == 0) throw base::Error("the pattern '" + pattern + "' has no %d field");
  return out;
}

std::vector<std::string> globFiles(const std::string& pattern) {
  glob_t found{};
  const int rc = glob(pattern.c_str(), GLOB_ERR, nullptr, &found);
  const std::unique_ptr<glob_t, void (*)(glob_t*)> owned(&found, globfree);
  if (rc == GLOB_NOMATCH) throw base::Error("no file matches '" + pattern + "'");
  if (rc != 0) throw base::Error("cannot list the files matching '" + pattern + "'");
  std::vector<std::string> files(found.gl_pathv, found.gl_pathv + found.gl_pathc);
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace renderers::scivis
