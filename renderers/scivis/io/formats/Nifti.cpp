// NIfTI-1 headers (https://nifti.nimh.nih.gov/nifti-1, nifti1.h): a 348-byte binary header,
// little or big endian (sizeof_hdr = 348 tells which), voxels from vox_offset. The grid is
// axis-aligned here: spacing from pixdim, origin from the sform's or qform's offsets; rotations
// and flips of those transforms are not applied.
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

}  // namespace

ArrayHeader parseNiftiHeader(std::string_view bytes, const std::string& path, bool compressed,
                             int time) {
  const base::SourceLocation file{path};  // a binary header: no lines
  if (bytes.size() < kNiftiHeaderBytes)
    throw base::Error(
        file, std::to_string(bytes.size()) + " bytes, too short for a NIfTI-1 header (348 bytes)");
  std::int32_t sizeofHdr;
  std::memcpy(&sizeofHdr, bytes.data(), 4);
  const bool swap = sizeofHdr != 348;
  const Reader r(bytes, swap);
  if (r.get<std::int32_t>(0) != 348)
    throw base::Error(file,
                      "NIfTI field 'sizeof_hdr' is not 348 in either byte order: not a "
                      "NIfTI-1 file (NIfTI-2 is not read)");
  if (std::memcmp(bytes.data() + 344, "n+1", 4) != 0)
    throw base::Error(file,
                      "NIfTI field 'magic' is not \"n+1\" (a single-file .nii; .hdr/.img "
                      "pairs are not read)");
  const int rank = r.get<std::int16_t>(40);
  if (rank < 3 || rank > 7)
    throw base::Error(file, "NIfTI field 'dim[0]' is " + std::to_string(rank) +
                                ", dfbwall reads 3-D volumes (and one time step of 4-D ones)");
  ArrayHeader h;
  int d[7];
  for (int a = 0; a < 7; ++a) d[a] = a < rank ? r.get<std::int16_t>(42 + 2 * a) : 1;
  for (int a = 4; a < 7; ++a)
    if (d[a] != 1)
      throw base::Error(file, "NIfTI field 'dim[" + std::to_string(a + 1) + "]' is " +
                                  std::to_string(d[a]) +
                                  ": only 3-D scalar volumes and time series are read");
  if (d[3] < 1)
    throw base::Error(file, "NIfTI field 'dim[4]' is " + std::to_string(d[3]) + ", must be >= 1");
  if (time < 0 || time >= d[3])
    throw base::Error(file, "time " + std::to_string(time) + " is past the file's " +
                                std::to_string(d[3]) + " time steps (NIfTI field 'dim[4]')");
  h.dims = {d[0], d[1], d[2]};
  if (const std::string problem = fileDimsProblem(h.dims); !problem.empty())
    throw base::Error(file, "NIfTI field 'dim': " + problem);
  h.data.type = niftiType(r.get<std::int16_t>(70), file);
  h.data.bigEndian = swap != (std::endian::native == std::endian::big);
  for (int a = 0; a < 3; ++a) {
    const float p = std::fabs(r.get<float>(80 + 4 * a));
    (a == 0   ? h.spacing.x
     : a == 1 ? h.spacing.y
              : h.spacing.z) = std::isfinite(p) && p > 0 ? p : 1.0f;
  }
  const float voxOffset = r.get<float>(108);
  if (!(voxOffset >= 348 && voxOffset < 1e9f))
    throw base::Error(file, "NIfTI field 'vox_offset' is " + std::to_string(voxOffset) +
                                ", must be at least 348");
  float slope = r.get<float>(112), intercept = r.get<float>(116);
  if (!std::isfinite(slope) || slope == 0) slope = 1, intercept = 0;  // 0: no scaling (nifti1.h)
  if (!std::isfinite(intercept)) intercept = 0;
  h.data.slope = slope, h.data.intercept = intercept;
  // The world position of voxel 0: the sform's offsets when it is set, else the qform's.
  const int qform = r.get<std::int16_t>(252), sform = r.get<std::int16_t>(254);
  Vec3 o{};
  if (sform > 0)
    o = {r.get<float>(280 + 12), r.get<float>(296 + 12), r.get<float>(312 + 12)};
  else if (qform > 0)
    o = {r.get<float>(268), r.get<float>(272), r.get<float>(276)};
  if (std::isfinite(o.x) && std::isfinite(o.y) && std::isfinite(o.z)) h.origin = o;
  const std::uint64_t volumeBytes =
      static_cast<std::uint64_t>(h.dims.x) * h.dims.y * h.dims.z * fileTypeBytes(h.data.type);
  const auto start =
      static_cast<std::uint64_t>(voxOffset) + static_cast<std::uint64_t>(time) * volumeBytes;
  h.data.path = path;
  h.data.compressed = compressed;
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
