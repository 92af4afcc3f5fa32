// MetaImage headers (ITK's .mhd / .mha, https://itk.org/Wiki/ITK/MetaIO/Documentation):
// "Key = Value" lines ending with ElementDataFile, which is LOCAL (the data follows that line,
// .mha) or a file name (.mhd + .raw). Read here: 3-D single-channel images, raw or zlib
// compressed (CompressedData), spacing from ElementSpacing (or ElementSize), origin from
// Offset / Origin / Position; TransformMatrix is taken as the identity.
#include <cmath>
#include <string>

#include "base/Error.h"
#include "renderers/scivis/io/formats/ArrayHeader.h"
#include "renderers/scivis/io/formats/HeaderText.h"

namespace renderers::scivis {
namespace {

using namespace headertext;

FileType metaType(const std::string& t, const HeaderField& f) {
  static const struct {
    const char* name;
    FileType type;
  } kNames[] = {{"MET_CHAR", FileType::Int8},     {"MET_UCHAR", FileType::UInt8},
                {"MET_SHORT", FileType::Int16},   {"MET_USHORT", FileType::UInt16},
                {"MET_INT", FileType::Int32},     {"MET_UINT", FileType::UInt32},
                {"MET_LONG", FileType::Int32},    {"MET_ULONG", FileType::UInt32},
                {"MET_FLOAT", FileType::Float32}, {"MET_DOUBLE", FileType::Float64}};
  for (const auto& n : kNames)
    if (t == n.name) return n.type;
  f.fail("'" + t.substr(0, 80) +
         "' is not one dfbwall reads (MET_CHAR, MET_UCHAR, MET_SHORT, MET_USHORT, MET_INT, "
         "MET_UINT, MET_FLOAT, MET_DOUBLE)");
}

bool boolean(std::string_view v, const HeaderField& f) {
  const std::string b = lower(v);
  if (b == "true" || b == "1") return true;
  if (b == "false" || b == "0") return false;
  f.fail("must be True or False, not '" + std::string(v.substr(0, 80)) + "'");
}

Vec3 vec3(std::string_view value, const HeaderField& f) {
  const std::vector<double> v = numbers(value, 3, f);
  return {static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])};
}

}  // namespace

ArrayHeader parseMetaImageHeader(std::string_view bytes, const std::string& path) {
  ArrayHeader h;
  bool haveDims = false, haveType = false, haveNDims = false, ended = false;
  long long headerSize = 0;
  std::string dataFile;
  std::size_t at = 0;
  int lineNumber = 0;
  while (at < bytes.size() && !ended) {
    std::size_t end = bytes.find('\n', at);
    if (end == std::string_view::npos) end = bytes.size();
    const std::string_view raw = bytes.substr(at, end - at);  // columns count from its start
    at = std::min(end + 1, bytes.size());
    ++lineNumber;
    const std::string_view line = trim(raw);
    if (line.empty()) continue;
    const std::size_t eq = line.find('=');
    if (eq == std::string_view::npos)
      throw base::Error(fieldAt(path, lineNumber, raw, line, "").where,
                        "'" + std::string(line.substr(0, 80)) + "' is not a 'Key = Value' line");
    const std::string key(trim(line.substr(0, eq)));
    const std::string_view value = trim(line.substr(eq + 1));
    const HeaderField fw = fieldAt(path, lineNumber, raw, value, key);
    if (key == "ObjectType") {
      if (lower(value) != "image") fw.fail("only Image objects are read");
    } else if (key == "NDims") {
      if (integers(value, 1, 0, 1 << 20, fw)[0] != 3)
        fw.fail("dfbwall reads 3-D images, not " + std::string(value) + "-D");
      haveNDims = true;
    } else if (key == "DimSize") {
      h.dims = fileDims(value, fw);
      haveDims = true;
    } else if (key == "ElementSpacing" || key == "ElementSize") {
      const Vec3 s = vec3(value, fw);
      if (!(s.x != 0 && s.y != 0 && s.z != 0)) fw.fail("must not be 0");
      if (key == "ElementSpacing" || h.spacing == Vec3{1.0f})
        h.spacing = {std::fabs(s.x), std::fabs(s.y), std::fabs(s.z)};
    } else if (key == "Offset" || key == "Origin" || key == "Position") {
      h.origin = vec3(value, fw);
    } else if (key == "ElementType") {
      h.data.type = metaType(std::string(value), fw);
      haveType = true;
    } else if (key == "BinaryDataByteOrderMSB" || key == "ElementByteOrderMSB") {
      h.data.bigEndian = boolean(value, fw);
    } else if (key == "CompressedData") {
      h.data.encoding = boolean(value, fw) ? Encoding::Zlib : Encoding::Raw;
    } else if (key == "ElementNumberOfChannels") {
      if (integers(value, 1, 0, 1 << 20, fw)[0] != 1)
        fw.fail("only single-channel (scalar) images are read");
    } else if (key == "HeaderSize") {
      headerSize = integers(value, 1, 0, 1LL << 50, fw)[0];
    } else if (key == "ElementDataFile") {
      if (value.empty()) fw.fail("empty");
      if (value != "LOCAL") {
        if (value.find('%') != std::string_view::npos || lower(value).rfind("list", 0) == 0)
          fw.fail("only one data file is read");
        dataFile = besideFile(path, value);
      }
      ended = true;
    } else if (key == "CompressedDataSize" || key == "BinaryData" || key == "TransformMatrix" ||
               key == "CenterOfRotation" || key == "AnatomicalOrientation" || key == "Comment" ||
               key == "Name" || key == "ID" || key == "ParentID" || key == "Color" ||
               key == "Rotation" || key == "Orientation" || key == "ElementMin" ||
               key == "ElementMax" || key == "Modality" || key == "ObjectSubType" ||
               key == "ElementNBits" || key == "ElementToIntensityFunctionSlope" ||
               key == "ElementToIntensityFunctionOffset" || key == "AcquisitionDate") {
      // Not needed to place a scalar grid.
    } else {
      fw.fail("unknown MetaImage field");
    }
    if (!ended && at >= kMaxTextHeader)
      throw base::Error(base::SourceLocation{path},
                        "the MetaImage header does not end (ElementDataFile) within " +
                            std::to_string(kMaxTextHeader) + " bytes");
  }
  // Missing fields belong to the header as a whole: no line.
  const base::SourceLocation file{path};
  if (!ended)
    throw base::Error(file, "MetaImage header misses field 'ElementDataFile' (its last line)");
  if (!haveNDims) throw base::Error(file, "MetaImage header misses field 'NDims'");
  if (!haveDims) throw base::Error(file, "MetaImage header misses field 'DimSize'");
  if (!haveType) throw base::Error(file, "MetaImage header misses field 'ElementType'");
  h.data.path = dataFile.empty() ? path : dataFile;
  h.data.fileOffset = dataFile.empty() ? at : static_cast<std::uint64_t>(headerSize);
  return h;
}

}  // namespace renderers::scivis
