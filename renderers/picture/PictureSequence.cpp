#include "renderers/picture/PictureSequence.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <map>
#include <optional>
#include <system_error>

#include "base/Error.h"

namespace renderers::picture {
namespace {

// A name split at its number field: prefix, then the number (at least `width` digits, zero
// padded), then suffix.
struct NumberedName {
  std::string prefix, suffix;
  int width = 0;
  std::string name(std::uint64_t n) const {
    std::string digits = std::to_string(n);
    if (static_cast<int>(digits.size()) < width)
      digits.insert(0, static_cast<size_t>(width) - digits.size(), '0');
    return prefix + digits + suffix;
  }
};

// The argument's number field, or none for a plain file name.
std::optional<NumberedName> numberField(const std::string& argument) {
  std::optional<NumberedName> out;
  std::string literal;
  for (size_t i = 0; i < argument.size(); ++i) {
    if (argument[i] != '%') {
      literal += argument[i];
      continue;
    }
    if (i + 1 < argument.size() && argument[i + 1] == '%') {
      literal += '%';
      ++i;
      continue;
    }
    size_t j = i + 1;
    int width = 0;
    if (j < argument.size() && argument[j] == '0')
      for (++j; j < argument.size() && std::isdigit(static_cast<unsigned char>(argument[j])); ++j)
        width = std::min(width * 10 + (argument[j] - '0'), 32);
    if (j >= argument.size() || argument[j] != 'd' || (argument[i + 1] == '0' && width == 0))
      throw base::Error(argument +
                        ": a numbered sequence names its number as %d or %0Nd (e.g. "
                        "plot-%04d.png); a literal % is written %%");
    if (out) throw base::Error(argument + ": a numbered sequence has one number field, not two");
    out = NumberedName{literal, {}, width};
    literal.clear();
    i = j;
  }
  if (out) out->suffix = literal;
  return out;
}

std::vector<std::string> expandSequence(const std::string& argument, const NumberedName& field) {
  namespace fs = std::filesystem;
  const fs::path pattern(field.prefix + "0" + field.suffix);
  if (pattern.filename().string().find('/') != std::string::npos ||
      field.suffix.find('/') != std::string::npos)
    throw base::Error(argument + ": the number field must be in the file name, not a folder");
  const fs::path folder = pattern.parent_path().empty() ? fs::path(".") : pattern.parent_path();
  const std::string namePrefix = fs::path(field.prefix + "0").filename().string();
  const std::string prefix = namePrefix.substr(0, namePrefix.size() - 1);
  std::map<std::uint64_t, std::string> numbered;
  std::error_code error;
  for (fs::directory_iterator it(folder, error), end; !error && it != end; it.increment(error)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= prefix.size() + field.suffix.size() || name.rfind(prefix, 0) != 0 ||
        name.compare(name.size() - field.suffix.size(), field.suffix.size(), field.suffix) != 0)
      continue;
    const std::string digits =
        name.substr(prefix.size(), name.size() - prefix.size() - field.suffix.size());
    if (digits.size() > 18 || !std::all_of(digits.begin(), digits.end(), [](char c) {
          return std::isdigit(static_cast<unsigned char>(c));
        }))
      continue;
    const std::uint64_t n = std::stoull(digits);
    // Only the name printf would write for n: plot-%04d.png is not plot-00001.png.
    if (NumberedName{prefix, field.suffix, field.width}.name(n) == name)
      numbered[n] = (folder / name).string();
  }
  if (error)
    throw base::Error(argument + ": cannot list the folder " + folder.string() + ": " +
                      error.message());
  if (numbered.empty())
    throw base::Error(argument + ": no file in " + folder.string() + " matches the sequence");
  std::vector<std::string> files;
  const std::uint64_t first = numbered.begin()->first, last = numbered.rbegin()->first;
  for (std::uint64_t n = first; n <= last; ++n) {
    const auto it = numbered.find(n);
    if (it == numbered.end())
      throw base::Error(argument + ": the sequence has a gap: " + field.name(n) +
                        " is missing (between " + field.name(first) + " and " + field.name(last) +
                        ")");
    files.push_back(it->second);
  }
  return files;
}

}  // namespace

std::vector<std::string> expandPictures(const std::vector<std::string>& arguments) {
  std::vector<std::string> files;
  for (const std::string& argument : arguments) {
    if (const std::optional<NumberedName> field = numberField(argument)) {
      for (std::string& f : expandSequence(argument, *field)) files.push_back(std::move(f));
      continue;
    }
    std::error_code error;
    if (!std::filesystem::is_regular_file(argument, error))
      throw base::Error(argument + (std::filesystem::exists(argument, error) ? ": not a file"
                                                                             : ": no such file"));
    files.push_back(argument);
  }
  return files;
}

std::size_t pictureOfFrame(std::uint32_t frameId, std::size_t count, bool loop) {
  if (count == 0 || frameId == 0) return 0;
  const std::size_t k = frameId - 1;
  return loop ? k % count : std::min(k, count - 1);
}

}  // namespace renderers::picture
