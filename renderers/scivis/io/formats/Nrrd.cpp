// NRRD headers (teem's format, https://teem.sourceforge.net/nrrd/format.html): "NRRD000X", then
// "field: value" lines (and "key:=value" pairs, ignored) up to a blank line; the data follows
// (attached) or lies in `data file`: one file, a LIST of files or a format string naming them
// (each file holds the next slices, `subdim` axes of the array). Read here: 3-D scalar arrays in
// every encoding (raw, gzip, bzip2, ascii, hex), `line skip` and `byte skip` (-1: the data ends
// the file), spacing from `spacings` or the lengths of `space directions` (axis-aligned),
// `space origin`.
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <string>

#include "base/Error.h"
#include "renderers/scivis/io/formats/ArrayHeader.h"
#include "renderers/scivis/io/formats/HeaderText.h"

namespace renderers::scivis {
namespace {

using namespace headertext;

FileType nrrdType(const std::string& t, const HeaderField& f) {
  static const struct {
    const char* name;
    FileType type;
  } kNames[] = {
      {"signed char", FileType::Int8},
      {"int8", FileType::Int8},
      {"int8_t", FileType::Int8},
      {"uchar", FileType::UInt8},
      {"unsigned char", FileType::UInt8},
      {"uint8", FileType::UInt8},
      {"uint8_t", FileType::UInt8},
      {"short", FileType::Int16},
      {"short int", FileType::Int16},
      {"signed short", FileType::Int16},
      {"signed short int", FileType::Int16},
      {"int16", FileType::Int16},
      {"int16_t", FileType::Int16},
      {"ushort", FileType::UInt16},
      {"unsigned short", FileType::UInt16},
      {"unsigned short int", FileType::UInt16},
      {"uint16", FileType::UInt16},
      {"uint16_t", FileType::UInt16},
      {"int", FileType::Int32},
      {"signed int", FileType::Int32},
      {"int32", FileType::Int32},
      {"int32_t", FileType::Int32},
      {"uint", FileType::UInt32},
      {"unsigned int", FileType::UInt32},
      {"uint32", FileType::UInt32},
      {"uint32_t", FileType::UInt32},
      {"float", FileType::Float32},
      {"double", FileType::Float64},
  };
  for (const auto& n : kNames)
    if (t == n.name) return n.type;
  f.fail("'" + t.substr(0, 80) +
         "' is not one dfbwall reads (int8, uint8, int16, uint16, int32, uint32, float, double)");
}

// "(x,y,z)" vectors.
std::vector<Vec3> vectors(std::string_view value, const HeaderField& f) {
  std::vector<Vec3> out;
  std::size_t i = 0;
  while (true) {
    while (i < value.size() && std::isspace(static_cast<unsigned char>(value[i]))) ++i;
    if (i >= value.size()) break;
    if (value[i] != '(') f.fail("'(x,y,z)' vectors expected", i);
    const std::size_t close = value.find(')', i);
    if (close == std::string_view::npos) f.fail("a vector misses its ')'", i);
    std::string inner(value.substr(i + 1, close - i - 1));
    for (char& c : inner)
      if (c == ',') c = ' ';
    const std::vector<double> v = numbers(inner, 3, f.at(i + 1));
    out.push_back({static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])});
    i = close + 1;
  }
  return out;
}

// Data files named by a format string with one integer conversion ("slice%03d.raw"), for the
// numbers min, min + step, ... up to max (either direction).
std::vector<std::string> formattedNames(const std::string& pattern, long long min, long long max,
                                        long long step, std::size_t count, const HeaderField& f) {
  std::size_t conversion = std::string::npos, end = 0;
  for (std::size_t i = 0; i < pattern.size(); ++i) {
    if (pattern[i] != '%') continue;
    if (i + 1 < pattern.size() && pattern[i + 1] == '%') {
      ++i;
      continue;
    }
    std::size_t j = i + 1;
    while (j < pattern.size() &&
           (std::isdigit(static_cast<unsigned char>(pattern[j])) || pattern[j] == '0'))
      ++j;
    if (conversion != std::string::npos || j >= pattern.size() ||
        (pattern[j] != 'd' && pattern[j] != 'i' && pattern[j] != 'u') || j - i > 4)
      f.fail("the file name format must have one integer conversion such as %03d");
    conversion = i, end = j + 1;
  }
  if (conversion == std::string::npos)
    f.fail("the file name format must have one integer conversion such as %03d");
  if (step == 0 || (max - min) / step < 0) f.fail("the numbers min, max, step never meet");
  const std::uint64_t n = static_cast<std::uint64_t>((max - min) / step) + 1;
  if (n != count)
    f.fail("names " + std::to_string(n) + " files, the sizes call for " + std::to_string(count));
  const std::string spec = pattern.substr(conversion, end - conversion - 1) + "lld";
  std::vector<std::string> names;
  for (long long v = min; names.size() < n; v += step) {
    char number[64];
    std::snprintf(number, sizeof number, spec.c_str(), v);
    std::string name = pattern.substr(0, conversion) + number + pattern.substr(end);
    for (std::size_t at = 0; (at = name.find("%%", at)) != std::string::npos; ++at)
      name.erase(at, 1);
    names.push_back(std::move(name));
  }
  return names;
}

}  // namespace

ArrayHeader parseNrrdHeader(std::string_view bytes, const std::string& path) {
  if (bytes.substr(0, 4) != "NRRD")
    throw base::Error(base::SourceLocation{path, 1, 1},
                      "not an NRRD file (it does not start with \"NRRD\")");
  ArrayHeader h;
  bool haveType = false, haveSizes = false, haveDimension = false, haveEndian = false,
       ended = false;
  std::string encoding = "raw", dataFile;
  long long byteSkip = 0, lineSkip = 0;
  // A list of data files: the names (or the format, numbers and place of the field), subdim.
  std::vector<std::string> listed;
  std::string format;
  std::vector<long long> formatNumbers;
  long long subdim = 2;
  bool list = false;
  HeaderField listField;
  std::size_t at = 0, dataStart = bytes.size();
  int lineNumber = 0;
  while (at < bytes.size()) {
    std::size_t end = bytes.find('\n', at);
    if (end == std::string_view::npos) {
      if (bytes.size() >= kMaxTextHeader)
        throw base::Error(
            base::SourceLocation{path},
            "the NRRD header does not end within " + std::to_string(kMaxTextHeader) + " bytes");
      end = bytes.size();
    }
    std::string_view line = bytes.substr(at, end - at);
    at = end + 1;
    ++lineNumber;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (lineNumber == 1) continue;  // the magic
    if (line.empty()) {
      ended = true;
      dataStart = std::min(at, bytes.size());
      break;
    }
    if (list) {  // after 'data file: LIST', each line names a data file
      listed.push_back(besideFile(path, trim(line)));
      continue;
    }
    if (line.front() == '#') continue;
    if (line.find(":=") != std::string_view::npos) continue;  // key/value pairs
    const std::size_t colon = line.find(": ");
    if (colon == std::string_view::npos)
      throw base::Error(base::SourceLocation{path, lineNumber, 1},
                        "'" + std::string(line.substr(0, 80)) + "' is not a 'field: value' line");
    const std::string field = lower(trim(line.substr(0, colon)));
    const std::string_view value = trim(line.substr(colon + 2));
    const HeaderField fw = fieldAt(path, lineNumber, line, value, field);
    if (field == "type") {
      h.data.type = nrrdType(lower(value), fw);
      haveType = true;
    } else if (field == "dimension") {
      if (integers(value, 1, 0, 1 << 20, fw)[0] != 3)
        fw.fail("dfbwall reads 3-D scalar volumes, not dimension " + std::string(value));
      haveDimension = true;
    } else if (field == "sizes") {
      h.dims = fileDims(value, fw);
      haveSizes = true;
    } else if (field == "spacings") {
      const auto s = numbers(value, 3, fw);
      for (double v : s)
        if (!(v != 0)) fw.fail("spacings must not be 0");
      h.spacing = {std::fabs(static_cast<float>(s[0])), std::fabs(static_cast<float>(s[1])),
                   std::fabs(static_cast<float>(s[2]))};
    } else if (field == "space directions") {
      const auto d = vectors(value, fw);
      if (d.size() != 3) fw.fail("3 vectors expected");
      float s[3];
      for (int a = 0; a < 3; ++a) {
        s[a] = std::sqrt(d[a].x * d[a].x + d[a].y * d[a].y + d[a].z * d[a].z);
        if (!(s[a] > 0) || !std::isfinite(s[a])) fw.fail("a direction of length 0");
      }
      h.spacing = {s[0], s[1], s[2]};
    } else if (field == "space origin") {
      const auto o = vectors(value, fw);
      if (o.size() != 1) fw.fail("one '(x,y,z)' vector expected");
      h.origin = o[0];
    } else if (field == "encoding") {
      encoding = lower(value);
      if (encoding == "gz") encoding = "gzip";
      if (encoding == "bz2") encoding = "bzip2";
      if (encoding == "txt" || encoding == "text") encoding = "ascii";
      if (encoding != "raw" && encoding != "gzip" && encoding != "bzip2" && encoding != "ascii" &&
          encoding != "hex")
        fw.fail("'" + std::string(value.substr(0, 80)) +
                "' is not one dfbwall reads (raw, gzip, bzip2, ascii, hex)");
    } else if (field == "endian") {
      const std::string e = lower(value);
      if (e != "little" && e != "big") fw.fail("must be 'little' or 'big'");
      h.data.bigEndian = e == "big";
      haveEndian = true;
    } else if (field == "data file" || field == "datafile") {
      if (value.empty()) fw.fail("names no file");
      const std::vector<std::string_view> words = [&] {
        std::vector<std::string_view> w;
        for (std::size_t i = 0; i < value.size();) {
          while (i < value.size() && std::isspace(static_cast<unsigned char>(value[i]))) ++i;
          std::size_t j = i;
          while (j < value.size() && !std::isspace(static_cast<unsigned char>(value[j]))) ++j;
          if (j > i) w.push_back(value.substr(i, j - i));
          i = j;
        }
        return w;
      }();
      listField = fw;
      if (lower(words[0]) == "list") {
        // The names follow, one a line, to the end of the header.
        if (words.size() > 2) fw.fail("'LIST' takes at most a subdim");
        if (words.size() == 2)
          subdim = integers(words[1], 1, 1, 3, fw.at(words[1].data() - value.data()))[0];
        list = true;
      } else if (words.size() >= 4 && words[0].find('%') != std::string_view::npos) {
        if (words.size() > 5) fw.fail("a format string takes min, max, step and a subdim");
        format = std::string(words[0]);
        for (std::size_t w = 1; w < 4; ++w)
          formatNumbers.push_back(integers(words[w], 1, -(1LL << 40), 1LL << 40,
                                           fw.at(words[w].data() - value.data()))[0]);
        if (words.size() == 5)
          subdim = integers(words[4], 1, 1, 3, fw.at(words[4].data() - value.data()))[0];
      } else {
        dataFile = besideFile(path, value);
      }
    } else if (field == "byte skip" || field == "byteskip") {
      byteSkip = integers(value, 1, -1, 1LL << 50, fw)[0];
    } else if (field == "line skip" || field == "lineskip") {
      lineSkip = integers(value, 1, 0, 1LL << 30, fw)[0];
    } else if (field == "kinds" || field == "centers" || field == "centerings" ||
               field == "space" || field == "space dimension" || field == "space units" ||
               field == "units" || field == "labels" || field == "content" || field == "min" ||
               field == "max" || field == "old min" || field == "old max" ||
               field == "measurement frame" || field == "sample units" || field == "axis mins" ||
               field == "axismins" || field == "axis maxs" || field == "axismaxs" ||
               field == "thicknesses" || field == "block size") {
      // Not needed to place a scalar grid.
    } else {
      fw.fail("unknown NRRD field");
    }
  }
  // Missing fields belong to the header as a whole: no line.
  const base::SourceLocation file{path};
  if (!haveDimension) throw base::Error(file, "NRRD header misses field 'dimension'");
  if (!haveType) throw base::Error(file, "NRRD header misses field 'type'");
  if (!haveSizes) throw base::Error(file, "NRRD header misses field 'sizes'");
  if (fileTypeBytes(h.data.type) > 1 && !haveEndian && encoding != "ascii")  // text has none
    throw base::Error(file, std::string("NRRD header misses field 'endian' (needed for ") +
                                fileTypeName(h.data.type) + ")");
  h.data.encoding = encoding == "gzip"    ? Encoding::Zlib
                    : encoding == "bzip2" ? Encoding::Bzip2
                    : encoding == "ascii" ? Encoding::Ascii
                    : encoding == "hex"   ? Encoding::Hex
                                          : Encoding::Raw;
  // Text is turned into voxels in this machine's byte order.
  if (h.data.encoding == Encoding::Ascii)
    h.data.bigEndian = std::endian::native == std::endian::big;
  if (list || !format.empty()) {
    const std::uint64_t perFile =
        subdim == 1 ? static_cast<std::uint64_t>(h.dims.x)
        : subdim == 2
            ? static_cast<std::uint64_t>(h.dims.x) * static_cast<std::uint64_t>(h.dims.y)
            : static_cast<std::uint64_t>(h.dims.x) * static_cast<std::uint64_t>(h.dims.y) *
                  static_cast<std::uint64_t>(h.dims.z);
    const std::uint64_t files = static_cast<std::uint64_t>(h.dims.x) *
                                static_cast<std::uint64_t>(h.dims.y) *
                                static_cast<std::uint64_t>(h.dims.z) / perFile;
    if (list) {
      if (listed.size() != files)
        listField.fail("the list names " + std::to_string(listed.size()) +
                       " files, the sizes and subdim " + std::to_string(subdim) + " call for " +
                       std::to_string(files));
      h.data.paths = std::move(listed);
    } else {
      for (std::string& name : formattedNames(format, formatNumbers[0], formatNumbers[1],
                                              formatNumbers[2], files, listField))
        h.data.paths.push_back(besideFile(path, name));
    }
    h.data.path = h.data.paths.front();
    h.data.voxelsPerFile = perFile;
  } else if (dataFile.empty()) {
    if (!ended)
      throw base::Error(file, "NRRD header has no blank line before the data and no 'data file'");
    h.data.path = path;
    h.data.fileOffset = dataStart;
  } else {
    h.data.path = dataFile;
  }
  h.data.lineSkip = static_cast<std::uint64_t>(lineSkip);
  if (byteSkip == -1) {
    if (h.data.encoding != Encoding::Raw)
      throw base::Error(file,
                        "NRRD 'byte skip: -1' (data at the end of the file) is for raw "
                        "data only, not " +
                            encoding);
    h.data.atEnd = true;
  } else if (h.data.compressed()) {  // skipped in the decoded stream, as teem does
    h.data.streamSkip = static_cast<std::uint64_t>(byteSkip);
  } else {
    h.data.byteSkip = static_cast<std::uint64_t>(byteSkip);
  }
  return h;
}

}  // namespace renderers::scivis
