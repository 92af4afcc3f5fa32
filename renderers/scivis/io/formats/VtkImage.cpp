// VTK's XML image data (https://docs.vtk.org/en/latest/design_documents/VTKFileFormats.html):
// <VTKFile type="ImageData" byte_order header_type compressor> <ImageData WholeExtent Origin
// Spacing> <Piece Extent> <PointData> <DataArray type Name format (offset)>, the data inline
// (ascii, or base64 "binary") or in <AppendedData encoding="raw|base64"> after its '_'. Appended
// raw data is not XML, so expat is fed the file only up to that element (or up to the chosen
// inline array's text) and stopped there; the voxels are read later, per brick.
#include "renderers/scivis/io/formats/VtkImage.h"

#include <expat.h>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <optional>

#include "base/Error.h"
#include "renderers/scivis/io/formats/ArrayHeader.h"
#include "renderers/scivis/io/formats/HeaderText.h"
#include "renderers/scivis/io/formats/StoredArray.h"

namespace renderers::scivis {
namespace {

struct DataArrayTag {
  std::string name, type, format;
  int components = 1;
  std::uint64_t offset = 0;     // appended: bytes (or base64 characters) after the '_'
  std::uint64_t textStart = 0;  // inline: the file byte after the start tag
  int line = 0;
};

// What the XML says, up to where reading stopped.
struct VtkXml {
  std::string fileType, byteOrder = "LittleEndian", headerType = "UInt32", compressor;
  std::map<std::string, std::string> image;                 // ImageData / PImageData attributes
  std::vector<std::pair<std::string, std::string>> pieces;  // Extent, Source
  std::vector<DataArrayTag> arrays;  // PointData's DataArray / PPointData's PDataArray
  std::optional<DataArrayTag> chosen;
  std::string appendedEncoding;
  std::uint64_t appendedTagEnd = 0;  // the file byte after <AppendedData ...>
  bool inPointData = false;
  std::string wanted;  // the array asked for (empty: the first)
};

struct Parse {
  XML_Parser parser;
  VtkXml* xml;
  std::string path;
  std::string error;
};

std::string attribute(const char** atts, const char* name) {
  for (int i = 0; atts[i]; i += 2)
    if (std::strcmp(atts[i], name) == 0) return atts[i + 1];
  return {};
}

bool hasAttribute(const char** atts, const char* name) {
  for (int i = 0; atts[i]; i += 2)
    if (std::strcmp(atts[i], name) == 0) return true;
  return false;
}

void XMLCALL onStart(void* data, const XML_Char* element, const XML_Char** atts) {
  auto* p = static_cast<Parse*>(data);
  VtkXml& x = *p->xml;
  const std::string e = element;
  const auto tagEnd = [&] {
    return static_cast<std::uint64_t>(XML_GetCurrentByteIndex(p->parser)) +
           static_cast<std::uint64_t>(XML_GetCurrentByteCount(p->parser));
  };
  if (e == "VTKFile") {
    x.fileType = attribute(atts, "type");
    if (hasAttribute(atts, "byte_order")) x.byteOrder = attribute(atts, "byte_order");
    if (hasAttribute(atts, "header_type")) x.headerType = attribute(atts, "header_type");
    x.compressor = attribute(atts, "compressor");
  } else if (e == "ImageData" || e == "PImageData") {
    for (int i = 0; atts[i]; i += 2) x.image[atts[i]] = atts[i + 1];
  } else if (e == "Piece") {
    x.pieces.emplace_back(attribute(atts, "Extent"), attribute(atts, "Source"));
  } else if (e == "PointData" || e == "PPointData") {
    x.inPointData = true;
  } else if ((e == "DataArray" || e == "PDataArray") && x.inPointData) {
    DataArrayTag a;
    a.name = attribute(atts, "Name");
    a.type = attribute(atts, "type");
    a.format = attribute(atts, "format");
    a.line = static_cast<int>(XML_GetCurrentLineNumber(p->parser));
    const std::string components = attribute(atts, "NumberOfComponents");
    if (!components.empty()) a.components = std::atoi(components.c_str());
    const std::string offset = attribute(atts, "offset");
    if (!offset.empty()) {
      const auto [end, ec] =
          std::from_chars(offset.data(), offset.data() + offset.size(), a.offset);
      if (ec != std::errc() || end != offset.data() + offset.size()) {
        p->error = "DataArray '" + a.name + "': attribute 'offset' is '" + offset.substr(0, 40) +
                   "', not a byte count";
        XML_StopParser(p->parser, XML_FALSE);
        return;
      }
    }
    a.textStart = tagEnd();
    x.arrays.push_back(a);
    if (!x.chosen && (x.wanted.empty() || x.wanted == a.name)) {
      x.chosen = a;
      // Inline text: nothing more is needed, and the text may be long.
      if (a.format == "ascii" || a.format == "binary") XML_StopParser(p->parser, XML_FALSE);
    }
  } else if (e == "AppendedData") {
    x.appendedEncoding = attribute(atts, "encoding");
    x.appendedTagEnd = tagEnd();
    XML_StopParser(p->parser, XML_FALSE);  // raw bytes follow: not XML
  }
}

void XMLCALL onEnd(void* data, const XML_Char* element) {
  auto* p = static_cast<Parse*>(data);
  const std::string e = element;
  if (e == "PointData" || e == "PPointData") p->xml->inPointData = false;
}

int fileDescriptor(const std::string& path, const char* what) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0) throw base::Error(path + ": cannot open " + what + " (" + std::strerror(errno) + ")");
  return fd;
}

VtkXml readXml(const std::string& path, const std::string& wanted) {
  VtkXml xml;
  xml.wanted = wanted;
  Parse p{XML_ParserCreate(nullptr), &xml, path, {}};
  struct Free {
    XML_Parser parser;
    ~Free() { XML_ParserFree(parser); }
  } freeParser{p.parser};
  XML_SetUserData(p.parser, &p);
  XML_SetElementHandler(p.parser, onStart, onEnd);
  const int fd = fileDescriptor(path, "the VTK file");
  struct Close {
    int fd;
    ~Close() { ::close(fd); }
  } closeFile{fd};
  char chunk[1 << 16];
  std::uint64_t total = 0;
  while (true) {
    const ssize_t n = ::read(fd, chunk, sizeof chunk);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw base::Error(path + ": read failed: " + std::strerror(errno));
    total += static_cast<std::uint64_t>(n);
    const XML_Status status = XML_Parse(p.parser, chunk, static_cast<int>(n), n == 0);
    if (!p.error.empty())
      throw base::Error(
          base::SourceLocation{path, static_cast<int>(XML_GetCurrentLineNumber(p.parser)),
                               static_cast<int>(XML_GetCurrentColumnNumber(p.parser)) + 1},
          p.error);
    if (status == XML_STATUS_ERROR) {
      if (XML_GetErrorCode(p.parser) == XML_ERROR_ABORTED) break;  // stopped where wanted
      throw base::Error(
          base::SourceLocation{path, static_cast<int>(XML_GetCurrentLineNumber(p.parser)),
                               static_cast<int>(XML_GetCurrentColumnNumber(p.parser)) + 1},
          std::string("not VTK XML: ") + XML_ErrorString(XML_GetErrorCode(p.parser)));
    }
    if (n == 0) break;
    if (total > (std::uint64_t{1} << 36))
      throw base::Error(path + ": no image data within 64 GiB of XML");
  }
  return xml;
}

std::string arrayNames(const VtkXml& x) {
  std::string names;
  for (const DataArrayTag& a : x.arrays) names += (names.empty() ? "" : ", ") + a.name;
  return names.empty() ? "none" : names;
}

// "x0 x1 y0 y1 z0 z1" (inclusive point indices) as a box of the whole extent starting at `base`.
VoxelBox extentBox(const std::string& text, const std::string& path, const std::string& what,
                   Index3 base = {}) {
  long long v[6];
  const char* at = text.data();
  const char* end = text.data() + text.size();
  for (long long& x : v) {
    while (at < end && std::isspace(static_cast<unsigned char>(*at))) ++at;
    const auto [next, ec] = std::from_chars(at, end, x);
    if (ec != std::errc())
      throw base::Error(path + ": attribute '" + what + "' is '" + text.substr(0, 80) +
                        "', not six integers");
    at = next;
  }
  while (at < end && std::isspace(static_cast<unsigned char>(*at))) ++at;
  if (at != end)
    throw base::Error(path + ": attribute '" + what + "' is '" + text.substr(0, 80) +
                      "', not six integers");
  VoxelBox b;
  for (int a = 0; a < 3; ++a) {
    if (v[2 * a + 1] < v[2 * a] || v[2 * a + 1] - v[2 * a] >= kMaxFileDims ||
        std::llabs(v[2 * a]) > (1LL << 30) || std::llabs(v[2 * a + 1]) > (1LL << 30))
      throw base::Error(path + ": attribute '" + what + "' is '" + text.substr(0, 80) + "': axis " +
                        std::to_string(a) + " runs from " + std::to_string(v[2 * a]) + " to " +
                        std::to_string(v[2 * a + 1]));
    (a == 0 ? b.lo.x : a == 1 ? b.lo.y : b.lo.z) = static_cast<int>(v[2 * a] - base[a]);
    (a == 0 ? b.hi.x : a == 1 ? b.hi.y : b.hi.z) = static_cast<int>(v[2 * a + 1] - base[a] + 1);
  }
  return b;
}

Vec3 threeNumbers(const VtkXml& x, const std::string& name, Vec3 fallback,
                  const std::string& path) {
  const auto it = x.image.find(name);
  if (it == x.image.end()) return fallback;
  double v[3];
  const char* at = it->second.data();
  const char* end = at + it->second.size();
  for (double& d : v) {
    while (at < end && std::isspace(static_cast<unsigned char>(*at))) ++at;
    const auto [next, ec] = std::from_chars(at, end, d);
    if (ec != std::errc() || !std::isfinite(d))
      throw base::Error(path + ": attribute '" + name + "' is '" + it->second.substr(0, 80) +
                        "', not three numbers");
    at = next;
  }
  return {static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])};
}

FileType vtkType(const std::string& type, const std::string& path, const std::string& array) {
  static const std::pair<const char*, FileType> kTypes[] = {
      {"Int8", FileType::Int8},       {"UInt8", FileType::UInt8},    {"Int16", FileType::Int16},
      {"UInt16", FileType::UInt16},   {"Int32", FileType::Int32},    {"UInt32", FileType::UInt32},
      {"Float32", FileType::Float32}, {"Float64", FileType::Float64}};
  for (const auto& [name, t] : kTypes)
    if (type == name) return t;
  throw base::Error(path + ": DataArray '" + array + "': type '" + type.substr(0, 40) +
                    "' is not one dfbwall reads (Int8, UInt8, Int16, UInt16, Int32, UInt32, "
                    "Float32, Float64)");
}

const DataArrayTag& chosenArray(const VtkXml& x, const std::string& path,
                                const std::string& wanted) {
  if (!x.chosen)
    throw base::Error(path + ": " +
                      (wanted.empty() ? std::string("no point data array")
                                      : "no point data array named '" + wanted + "'") +
                      " (point data arrays: " + arrayNames(x) + ")");
  if (x.chosen->components != 1)
    throw base::Error(path + ": point data array '" + x.chosen->name + "' has " +
                      std::to_string(x.chosen->components) +
                      " components; dfbwall reads scalar arrays");
  return *x.chosen;
}

struct VtiFile {
  VoxelBox extent;  // the piece's extent, in the whole extent's index space
  VoxelBox whole;   // the whole extent, from (0, 0, 0)
  Index3 wholeLo;
  Vec3 origin, spacing;
  StoredArray data;
};

// A .vti: its grid and where the chosen array's voxels are.
VtiFile readVti(const std::string& path, const std::string& wanted) {
  const VtkXml x = readXml(path, wanted);
  if (x.fileType != "ImageData")
    throw base::Error(path + ": VTKFile type is '" + x.fileType.substr(0, 40) +
                      "', not ImageData (a .vti)");
  if (!x.image.count("WholeExtent"))
    throw base::Error(path + ": ImageData has no attribute 'WholeExtent'");
  VtiFile v;
  const VoxelBox whole = extentBox(x.image.at("WholeExtent"), path, "WholeExtent");
  v.wholeLo = whole.lo;
  v.whole = {{0, 0, 0}, whole.size()};
  v.spacing = threeNumbers(x, "Spacing", Vec3{1.0f}, path);
  v.origin = threeNumbers(x, "Origin", Vec3{0.0f}, path);
  if (x.pieces.size() != 1)
    throw base::Error(path + ": " + std::to_string(x.pieces.size()) +
                      " pieces before the array; dfbwall reads a .vti of one piece (pieces of "
                      "their own files: .pvti)");
  v.extent = extentBox(x.pieces[0].first, path, "Piece Extent", whole.lo);
  const DataArrayTag& a = chosenArray(x, path, wanted);
  StoredArray& s = v.data;
  s.path = path;
  s.type = vtkType(a.type, path, a.name);
  if (x.byteOrder != "LittleEndian" && x.byteOrder != "BigEndian")
    throw base::Error(path + ": VTKFile byte_order is '" + x.byteOrder.substr(0, 40) +
                      "', not LittleEndian or BigEndian");
  s.bigEndian = x.byteOrder == "BigEndian";
  if (x.headerType != "UInt32" && x.headerType != "UInt64")
    throw base::Error(path + ": VTKFile header_type is '" + x.headerType.substr(0, 40) +
                      "', not UInt32 or UInt64");
  s.blockHeaderBytes = x.headerType == "UInt64" ? 8 : 4;
  Encoding blocks = Encoding::Raw;
  if (x.compressor == "vtkZLibDataCompressor")
    blocks = Encoding::ZlibBlocks;
  else if (x.compressor == "vtkLZ4DataCompressor")
    blocks = Encoding::Lz4Blocks;
  else if (!x.compressor.empty())
    throw base::Error(path + ": VTKFile compressor '" + x.compressor.substr(0, 60) +
                      "' is not one dfbwall reads (vtkZLibDataCompressor, vtkLZ4DataCompressor)");
  // Where the text or bytes start: the array's own text, or the appended data after its '_'.
  if (a.format == "ascii") {
    s.encoding = Encoding::Ascii;
    s.fileOffset = a.textStart;
    s.bigEndian = std::endian::native == std::endian::big;
    return v;
  }
  const bool appended = a.format == "appended";
  if (!appended && a.format != "binary")
    throw base::Error(path + ": DataArray '" + a.name + "': format '" + a.format.substr(0, 40) +
                      "' is not ascii, binary or appended");
  bool base64 = true;
  std::uint64_t start = 0;
  if (appended) {
    if (x.appendedEncoding.empty())
      throw base::Error(path + ": DataArray '" + a.name +
                        "' is appended, but the file has no AppendedData");
    if (x.appendedEncoding != "raw" && x.appendedEncoding != "base64")
      throw base::Error(path + ": AppendedData encoding '" + x.appendedEncoding.substr(0, 40) +
                        "' is not raw or base64");
    base64 = x.appendedEncoding == "base64";
    start = x.appendedTagEnd;
  } else {
    start = a.textStart;
  }
  // Skip the whitespace (and, appended, the '_' that marks the data's start).
  const int fd = fileDescriptor(path, "the VTK file");
  char buffer[4096];
  const ssize_t n = ::pread(fd, buffer, sizeof buffer, static_cast<off_t>(start));
  ::close(fd);
  ssize_t i = 0;
  while (i < n && std::isspace(static_cast<unsigned char>(buffer[i]))) ++i;
  if (appended) {
    if (i >= n || buffer[i] != '_')
      throw base::Error(path + ": AppendedData does not start with '_'");
    ++i;
  }
  start += static_cast<std::uint64_t>(i) + (appended ? a.offset : 0);
  s.fileOffset = start;
  s.base64 = base64;
  if (blocks != Encoding::Raw) {
    s.encoding = blocks;
  } else if (base64) {
    s.encoding = Encoding::Base64;  // one run of base64: the header's bytes, then the voxels
    s.streamSkip = static_cast<std::uint64_t>(s.blockHeaderBytes);
  } else {
    s.encoding = Encoding::Raw;
    s.fileOffset += static_cast<std::uint64_t>(s.blockHeaderBytes);
  }
  return v;
}

void checkDims(Index3 dims, const std::string& path) {
  if (const std::string problem = fileDimsProblem(dims); !problem.empty())
    throw base::Error(path + ": the extent: " + problem);
}

}  // namespace

void resolveVtkImage(VolumeSource& source) {
  VolumeFileParams& f = source.file;
  const std::string& path = f.path;
  if (f.time != 0)
    throw base::Error(path +
                      ": 'time' is for 4-D NIfTI, HDF5 and NetCDF data; VTK image data "
                      "is 3-D");
  std::string lower = path;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (lower.size() < 5 || lower.compare(lower.size() - 5, 5, ".pvti") != 0) {
    VtiFile v = readVti(path, f.array);
    if (!(v.extent.lo == v.whole.lo && v.extent.hi == v.whole.hi))
      throw base::Error(path + ": its one piece's extent is not the whole extent");
    checkDims(v.whole.size(), path);
    checkStoredArray(v.data, v.whole.size());
    f.stored = v.data;
    f.pieces.clear();
    source.grid.dims = v.whole.size();
    source.grid.spacing = v.spacing;
    source.grid.origin = v.origin + Vec3{static_cast<float>(v.wholeLo.x) * v.spacing.x,
                                         static_cast<float>(v.wholeLo.y) * v.spacing.y,
                                         static_cast<float>(v.wholeLo.z) * v.spacing.z};
    f.hasGeometry = true;
    source.type = heldVoxelType(f.stored);
    return;
  }
  const VtkXml x = readXml(path, f.array);
  if (x.fileType != "PImageData")
    throw base::Error(path + ": VTKFile type is '" + x.fileType.substr(0, 40) +
                      "', not PImageData (a .pvti)");
  if (!x.image.count("WholeExtent"))
    throw base::Error(path + ": PImageData has no attribute 'WholeExtent'");
  const VoxelBox whole = extentBox(x.image.at("WholeExtent"), path, "WholeExtent");
  const Index3 dims = whole.size();
  checkDims(dims, path);
  const DataArrayTag& a = chosenArray(x, path, f.array);
  StoredArray typeOnly;
  typeOnly.type = vtkType(a.type, path, a.name);
  if (x.pieces.empty()) throw base::Error(path + ": PImageData has no Piece");
  f.pieces.clear();
  // The pieces must cover the whole extent: count each voxel's first owner by volume.
  std::uint64_t covered = 0;
  for (const auto& [extent, pieceFile] : x.pieces) {
    if (pieceFile.empty()) throw base::Error(path + ": a Piece has no attribute 'Source'");
    FilePiece piece;
    piece.box = extentBox(extent, path, "Piece Extent", whole.lo);
    for (int ax = 0; ax < 3; ++ax)
      if (piece.box.lo[ax] < 0 || piece.box.hi[ax] > dims[ax])
        throw base::Error(path + ": Piece '" + pieceFile.substr(0, 80) + "' extent '" + extent +
                          "' reaches outside the WholeExtent");
    piece.path = headertext::besideFile(path, pieceFile);
    if (::access(piece.path.c_str(), R_OK) != 0)
      throw base::Error(path + ": piece '" + pieceFile.substr(0, 80) + "' is missing (" +
                        piece.path + ": " + std::strerror(errno) + ")");
    covered += piece.box.voxelCount();
    f.pieces.push_back(std::move(piece));
  }
  if (covered < whole.voxelCount())
    throw base::Error(path + ": the pieces hold " + std::to_string(covered) +
                      " voxels, fewer than the WholeExtent's " +
                      std::to_string(whole.voxelCount()));
  f.stored = StoredArray{};
  f.stored.type = typeOnly.type;
  source.grid.dims = dims;
  source.grid.spacing = threeNumbers(x, "Spacing", Vec3{1.0f}, path);
  const Vec3 origin = threeNumbers(x, "Origin", Vec3{0.0f}, path);
  source.grid.origin = origin + Vec3{static_cast<float>(whole.lo.x) * source.grid.spacing.x,
                                     static_cast<float>(whole.lo.y) * source.grid.spacing.y,
                                     static_cast<float>(whole.lo.z) * source.grid.spacing.z};
  f.hasGeometry = true;
  source.type = heldVoxelType(typeOnly);
}

Volume loadVtkImageBox(const VolumeSource& source, const VoxelBox& box) {
  const VolumeFileParams& f = source.file;
  if (f.pieces.empty()) return readStoredBox(f.stored, source.grid, box);
  Volume v;
  v.grid = source.grid;
  v.box = box;
  v.type = source.type;
  v.voxels = allocateVoxelBytes(box, v.type);
  const std::size_t width = voxelBytes(v.type);
  const Index3 size = box.size();
  for (const FilePiece& piece : f.pieces) {
    VoxelBox meet;
    for (int a = 0; a < 3; ++a) {
      (a == 0 ? meet.lo.x : a == 1 ? meet.lo.y : meet.lo.z) = std::max(box.lo[a], piece.box.lo[a]);
      (a == 0 ? meet.hi.x : a == 1 ? meet.hi.y : meet.hi.z) = std::min(box.hi[a], piece.box.hi[a]);
    }
    if (meet.empty()) continue;
    VtiFile file = readVti(piece.path, f.array);
    if (!(file.extent.lo == file.whole.lo && file.extent.hi == file.whole.hi))
      throw base::Error(piece.path + ": its piece's extent is not its whole extent");
    const Index3 pieceLo = piece.box.lo;
    if (!(file.whole.size() == piece.box.size()))
      throw base::Error(
          piece.path + ": its extent is " + std::to_string(file.whole.size().x) + "x" +
          std::to_string(file.whole.size().y) + "x" + std::to_string(file.whole.size().z) +
          " points, the .pvti's Piece says " + std::to_string(piece.box.size().x) + "x" +
          std::to_string(piece.box.size().y) + "x" + std::to_string(piece.box.size().z));
    if (heldVoxelType(file.data) != v.type)
      throw base::Error(piece.path + ": its array is " + fileTypeName(file.data.type) +
                        ", held as " + voxelTypeName(heldVoxelType(file.data)) +
                        " where the .pvti's is held as " + voxelTypeName(v.type));
    GridGeometry pieceGrid = source.grid;
    pieceGrid.dims = piece.box.size();
    const VoxelBox local{{meet.lo.x - pieceLo.x, meet.lo.y - pieceLo.y, meet.lo.z - pieceLo.z},
                         {meet.hi.x - pieceLo.x, meet.hi.y - pieceLo.y, meet.hi.z - pieceLo.z}};
    const Volume part = readStoredBox(file.data, pieceGrid, local);
    const Index3 ps = local.size();
    for (int k = 0; k < ps.z; ++k)
      for (int j = 0; j < ps.y; ++j) {
        const std::size_t from = (static_cast<std::size_t>(k) * ps.y + j) * ps.x * width;
        const std::size_t to = ((static_cast<std::size_t>(meet.lo.z - box.lo.z + k) * size.y +
                                 static_cast<std::size_t>(meet.lo.y - box.lo.y + j)) *
                                    size.x +
                                static_cast<std::size_t>(meet.lo.x - box.lo.x)) *
                               width;
        std::memcpy(v.voxels.data() + to, part.voxels.data() + from, ps.x * width);
      }
  }
  v.updateRange();
  return v;
}

}  // namespace renderers::scivis
