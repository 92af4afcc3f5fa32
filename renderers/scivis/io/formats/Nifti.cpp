// NIfTI-1 and NIfTI-2 headers (https://nifti.nimh.nih.gov/nifti-1, nifti1.h, nifti2.h): a 348-
// (NIfTI-1: 16-bit dims, float offsets) or 540-byte (NIfTI-2: 64-bit dims, double fields)
// binary header, little or big endian (sizeof_hdr tells which), voxels from vox_offset of the
// same file (.nii, magic "n+1"/"n+2") or of the .img beside a .hdr (magic "ni1"/"ni2"). The grid
// is axis-aligned here: spacing from pixdim, origin from the sform's or qform's offsets;
// rotations and flips of those transforms are not applied.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "base/Error.h"
#include "renderers/scivis/io/formats/ArrayHeader.h"

namespace renderers::scivis {
namespace {

class Reader {
 public:
  Reader(std::string_view bytes, bool swap) : bytes_(bytes), swap_(swap) {}
  template <class T>
  T get(std::size_t offset) const {
    unsigned char b[sizeof(T)];
    std::memcpy(b, bytes_.data() + offset, sizeof b);
    if (swap_)
      for (std::size_t i = 0; i < sizeof b / 2; ++i) std::swap(b[i], b[sizeof b - 1 - i]);
    T v;
    std::memcpy(&v, b, sizeof v);
    return v;
  }

 private:
  std::string_view bytes_;
  bool swap_;
};

// Where the fields both versions share lie, and in which width.
struct Layout {
  int version;
  std::size_t headerBytes, dim, datatype, pixdim, voxOffset, slope, intercept, qform, sform,
      qoffset, srow, magic;
  bool wide;  // NIfTI-2: int64 dims and offsets, double floats
};
constexpr Layout kNifti1{1, 348, 40, 70, 76, 108, 112, 116, 252, 254, 268, 280, 344, false};
constexpr Layout kNifti2{2, 540, 16, 12, 104, 168, 176, 184, 344, 348, 376, 400, 4, true};

FileType niftiType(int code, const base::SourceLocation& file) {
  switch (code) {
    case 2:
      return FileType::UInt8;
    case 4:
      return FileType::Int16;
    case 8:
      return FileType::Int32;
    case 16:
      return FileType::Float32;
    case 64:
      return FileType::Float64;
    case 256:
      return FileType::Int8;
    case 512:
      return FileType::UInt16;
    case 768:
      return FileType::UInt32;
    default:
      break;
  }
  throw base::Error(
      file, "NIfTI field 'datatype' " + std::to_string(code) +
                " is not a scalar type dfbwall reads (uint8 2, int16 4, int32 8, float32 16, "
                "float64 64, int8 256, uint16 512, uint32 768)");
}

bool endsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

}  // namespace

std::string niftiImagePath(const std::string& headerPath) {
  std::string lower = headerPath;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  const bool gz = endsWith(lower, ".gz");
  const std::size_t stem = headerPath.size() - (gz ? 3 : 0);
  if (stem < 4 || lower.compare(stem - 4, 4, ".hdr") != 0) return {};
  const bool upper = headerPath[stem - 3] == 'H';
  return headerPath.substr(0, stem - 3) + (upper ? "IMG" : "img") + headerPath.substr(stem);
}

ArrayHeader parseNiftiHeader(std::string_view bytes, const std::string& path, bool compressed,
                             int time) {
  const base::SourceLocation file{path};  // a binary header: no lines
  std::int32_t sizeofHdr = 0;
  std::memcpy(&sizeofHdr, bytes.data(), std::min<std::size_t>(4, bytes.size()));
  const bool swap = sizeofHdr != 348 && sizeofHdr != 540;
  const std::int32_t size = bytes.size() >= 4 ? Reader(bytes, swap).get<std::int32_t>(0) : 0;
  // Too short for either version: named by the version sizeof_hdr claims (NIfTI-1 otherwise).
  if (bytes.size() < (size == 540 ? 540u : 348u))
    throw base::Error(file, std::to_string(bytes.size()) + " bytes, too short for a NIfTI-" +
                                (size == 540 ? "2 header (540 bytes)" : "1 header (348 bytes)"));
  if (size != 348 && size != 540)
    throw base::Error(file,
                      "NIfTI field 'sizeof_hdr' is not 348 (NIfTI-1) or 540 (NIfTI-2) in either "
                      "byte order: not a NIfTI file");
  const Layout& L = size == 348 ? kNifti1 : kNifti2;
  const std::string version = "NIfTI-" + std::to_string(L.version);
  const Reader r(bytes, swap);
  // "n+1"/"n+2": voxels in this file; "ni1"/"ni2": in the .img beside this .hdr.
  const char digit = static_cast<char>('0' + L.version);
  const std::string_view magic(bytes.data() + L.magic, 4);
  const bool single = magic == std::string_view(std::string{'n', '+', digit, '\0'});
  const bool pair = magic == std::string_view(std::string{'n', 'i', digit, '\0'});
  const std::string imagePath = niftiImagePath(path);
  if (!single && !pair)
    throw base::Error(file, "NIfTI field 'magic' is not \"n+" + std::string(1, digit) +
                                "\" (a single .nii file) or \"ni" + std::string(1, digit) +
                                "\" (a .hdr/.img pair)");
  if (pair && imagePath.empty())
    throw base::Error(file,
                      "NIfTI field 'magic' says the voxels are in a separate .img file, "
                      "but this file is not named .hdr");
  const auto integer = [&](std::size_t at) -> std::int64_t {
    return L.wide ? r.get<std::int64_t>(at) : r.get<std::int16_t>(at);
  };
  const auto real = [&](std::size_t at) -> double {
    return L.wide ? r.get<double>(at) : static_cast<double>(r.get<float>(at));
  };
  const std::size_t wide = L.wide ? 8 : 2, realWidth = L.wide ? 8 : 4;
  const std::int64_t rank = integer(L.dim);
  if (rank < 3 || rank > 7)
    throw base::Error(file, version + " field 'dim[0]' is " + std::to_string(rank) +
                                ", dfbwall reads 3-D volumes (and one time step of 4-D ones)");
  ArrayHeader h;
  std::int64_t d[7];
  for (int a = 0; a < 7; ++a) d[a] = a < rank ? integer(L.dim + wide * (a + 1)) : 1;
  for (int a = 4; a < 7; ++a)
    if (d[a] != 1)
      throw base::Error(file, version + " field 'dim[" + std::to_string(a + 1) + "]' is " +
                                  std::to_string(d[a]) +
                                  ": only 3-D scalar volumes and time series are read");
  if (d[3] < 1)
    throw base::Error(file,
                      version + " field 'dim[4]' is " + std::to_string(d[3]) + ", must be >= 1");
  if (time < 0 || time >= d[3])
    throw base::Error(file, "time " + std::to_string(time) + " is past the file's " +
                                std::to_string(d[3]) + " time steps (" + version +
                                " field 'dim[4]')");
  for (int a = 0; a < 3; ++a)
    if (d[a] < 2 || d[a] > kMaxFileDims)
      throw base::Error(file, version + " field 'dim': " + std::to_string(d[a]) +
                                  " voxels along axis " + std::to_string(a) +
                                  ", must be between 2 and " + std::to_string(kMaxFileDims));
  h.dims = {static_cast<int>(d[0]), static_cast<int>(d[1]), static_cast<int>(d[2])};
  if (const std::string problem = fileDimsProblem(h.dims); !problem.empty())
    throw base::Error(file, version + " field 'dim': " + problem);
  h.data.type = niftiType(r.get<std::int16_t>(L.datatype), file);
  h.data.bigEndian = swap != (std::endian::native == std::endian::big);
  for (int a = 0; a < 3; ++a) {
    const auto p = static_cast<float>(std::fabs(real(L.pixdim + realWidth * (a + 1))));
    (a == 0   ? h.spacing.x
     : a == 1 ? h.spacing.y
              : h.spacing.z) = std::isfinite(p) && p > 0 ? p : 1.0f;
  }
  // Where the voxels start: NIfTI-1 stores it as a float, NIfTI-2 as an int64.
  const double voxOffset = L.wide ? static_cast<double>(r.get<std::int64_t>(L.voxOffset))
                                  : static_cast<double>(r.get<float>(L.voxOffset));
  const double lowest = single ? static_cast<double>(L.headerBytes) : 0.0;
  if (!(voxOffset >= lowest && voxOffset < 1e15))
    throw base::Error(file, version + " field 'vox_offset' is " + std::to_string(voxOffset) +
                                ", must be at least " + std::to_string(static_cast<int>(lowest)));
  auto slope = static_cast<float>(real(L.slope)), intercept = static_cast<float>(real(L.intercept));
  if (!std::isfinite(slope) || slope == 0) slope = 1, intercept = 0;  // 0: no scaling (nifti1.h)
  if (!std::isfinite(intercept)) intercept = 0;
  h.data.slope = slope, h.data.intercept = intercept;
  // The world position of voxel 0: the sform's offsets when it is set, else the qform's.
  const std::int64_t qform = L.wide ? r.get<std::int32_t>(L.qform) : r.get<std::int16_t>(L.qform);
  const std::int64_t sform = L.wide ? r.get<std::int32_t>(L.sform) : r.get<std::int16_t>(L.sform);
  double o[3] = {0, 0, 0};
  bool placed = false;
  if (sform > 0) {
    for (int a = 0; a < 3; ++a) o[a] = real(L.srow + realWidth * (4 * a + 3));
    placed = true;
  } else if (qform > 0) {
    for (int a = 0; a < 3; ++a) o[a] = real(L.qoffset + realWidth * a);
    placed = true;
  }
  const Vec3 origin{static_cast<float>(o[0]), static_cast<float>(o[1]), static_cast<float>(o[2])};
  if (placed && std::isfinite(origin.x) && std::isfinite(origin.y) && std::isfinite(origin.z))
    h.origin = origin;
  const std::uint64_t volumeBytes =
      static_cast<std::uint64_t>(h.dims.x) * static_cast<std::uint64_t>(h.dims.y) *
      static_cast<std::uint64_t>(h.dims.z) * fileTypeBytes(h.data.type);
  const auto start =
      static_cast<std::uint64_t>(voxOffset) + static_cast<std::uint64_t>(time) * volumeBytes;
  if (pair) {
    h.data.path = imagePath;
    compressed = endsWith(imagePath, ".gz") || endsWith(imagePath, ".GZ");
  } else {
    h.data.path = path;
  }
  h.data.encoding = compressed ? Encoding::Zlib : Encoding::Raw;
  if (compressed)
    h.data.streamSkip = start;
  else
    h.data.fileOffset = start;
  return h;
}

std::string fileDimsProblem(Index3 dims) {
  std::uint64_t total = 1;
  for (int a = 0; a < 3; ++a) {
    if (dims[a] < 2 || dims[a] > kMaxFileDims)
      return std::to_string(dims[a]) + " voxels along axis " + std::to_string(a) +
             ", must be between 2 and " + std::to_string(kMaxFileDims);
    total *= static_cast<std::uint64_t>(dims[a]);
  }
  if (total > kMaxFileVoxels)
    return std::to_string(total) + " voxels, more than the cap of " +
           std::to_string(kMaxFileVoxels);
  return {};
}

}  // namespace renderers::scivis
