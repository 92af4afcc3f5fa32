#include "renderers/scivis/io/formats/VolumeFile.h"

#include <fcntl.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <limits>
#include <vector>

#include "base/Error.h"
#include "renderers/scivis/io/formats/ArrayHeader.h"
#include "renderers/scivis/io/formats/LibraryFormats.h"
#include "renderers/scivis/io/formats/VtkImage.h"

namespace renderers::scivis {
namespace {

bool endsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

std::string lowerCase(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// The file's first `bytes` bytes (fewer if it is shorter); inflated when `gzip`.
std::string headBytes(const std::string& path, std::size_t bytes, bool gzip) {
  std::string out(bytes, '\0');
  if (gzip) {
    gzFile f = gzopen(path.c_str(), "rb");
    if (!f) throw base::Error(path + ": cannot open (" + std::strerror(errno) + ")");
    const int n = gzread(f, out.data(), static_cast<unsigned>(bytes));
    int code = 0;
    const std::string message = n < 0 ? gzerror(f, &code) : "";
    gzclose(f);
    if (n < 0) throw base::Error(path + ": not a readable gzip file (" + message + ")");
    out.resize(static_cast<std::size_t>(n));
    return out;
  }
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0) throw base::Error(path + ": cannot open (" + std::strerror(errno) + ")");
  std::size_t done = 0;
  while (done < bytes) {
    const ssize_t n = ::read(fd, out.data() + done, bytes - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    done += static_cast<std::size_t>(n);
  }
  ::close(fd);
  out.resize(done);
  return out;
}

}  // namespace

std::optional<VolumeFormat> volumeFormatOfPath(const std::string& path) {
  const std::string p = lowerCase(path);
  for (const char* e : {".nrrd", ".nhdr"})
    if (endsWith(p, e)) return VolumeFormat::Nrrd;
  for (const char* e : {".nii", ".nii.gz", ".hdr", ".hdr.gz"})
    if (endsWith(p, e)) return VolumeFormat::Nifti;
  for (const char* e : {".mhd", ".mha"})
    if (endsWith(p, e)) return VolumeFormat::MetaImage;
  for (const char* e : {".vti", ".pvti"})
    if (endsWith(p, e)) return VolumeFormat::Vtk;
  for (const char* e : {".h5", ".hdf5", ".he5", ".hdf"})
    if (endsWith(p, e)) return VolumeFormat::Hdf5;
  for (const char* e : {".nc", ".cdf", ".nc4", ".netcdf"})
    if (endsWith(p, e)) return VolumeFormat::NetCdf;
  return std::nullopt;
}

std::optional<VolumeFormat> volumeFormatNamed(const std::string& name) {
  for (VolumeFormat f : {VolumeFormat::Nrrd, VolumeFormat::Nifti, VolumeFormat::MetaImage,
                         VolumeFormat::Hdf5, VolumeFormat::NetCdf, VolumeFormat::Vtk})
    if (name == volumeFormatName(f)) return f;
  return std::nullopt;
}

const char* volumeFormatName(VolumeFormat format) {
  switch (format) {
    case VolumeFormat::Nrrd:
      return "nrrd";
    case VolumeFormat::Nifti:
      return "nifti";
    case VolumeFormat::MetaImage:
      return "metaimage";
    case VolumeFormat::Hdf5:
      return "hdf5";
    case VolumeFormat::NetCdf:
      return "netcdf";
    case VolumeFormat::Vtk:
      return "vtk";
  }
  return "unknown";
}

void resolveVolumeFile(VolumeSource& source) {
  VolumeFileParams& f = source.file;
  source.kind = VolumeSource::Kind::File;
  if (f.format == VolumeFormat::Hdf5) return resolveHdf5(source);
  if (f.format == VolumeFormat::NetCdf) return resolveNetCdf(source);
  if (f.format == VolumeFormat::Vtk) return resolveVtkImage(source);
  ArrayHeader h;
  switch (f.format) {
    case VolumeFormat::Nrrd:
      h = parseNrrdHeader(headBytes(f.path, kMaxTextHeader, false), f.path);
      break;
    case VolumeFormat::MetaImage:
      h = parseMetaImageHeader(headBytes(f.path, kMaxTextHeader, false), f.path);
      break;
    case VolumeFormat::Nifti: {
      const bool gz = endsWith(lowerCase(f.path), ".gz");
      h = parseNiftiHeader(headBytes(f.path, kNiftiHeaderBytes, gz), f.path, gz, f.time);
      break;
    }
    default:
      break;
  }
  if (f.time != 0 && f.format != VolumeFormat::Nifti)
    throw base::Error(f.path + ": 'time' is for 4-D NIfTI, HDF5 and NetCDF data; this " +
                      volumeFormatName(f.format) + " file is 3-D");
  try {
    checkStoredArray(h.data, h.dims);
  } catch (const base::Error& e) {
    if (h.data.path == f.path) throw;
    throw base::Error(f.path + ": its data file " + e.what());
  }
  f.stored = h.data;
  f.hasGeometry = true;
  source.grid.dims = h.dims;
  source.grid.spacing = h.spacing;
  source.grid.origin = h.origin;
  source.type = heldVoxelType(h.data);
}

Volume loadVolumeFile(const VolumeSource& source, const VoxelBox& box) {
  switch (source.file.format) {
    case VolumeFormat::Hdf5:
      return loadHdf5Box(source, box);
    case VolumeFormat::NetCdf:
      return loadNetCdfBox(source, box);
    case VolumeFormat::Vtk:
      return loadVtkImageBox(source, box);
    default:
      return readStoredBox(source.file.stored, source.grid, box);
  }
}

void markMissing(Volume& v, const std::vector<double>& missing, float slope, float intercept) {
  if (v.type == VoxelType::Float32 && (!missing.empty() || slope != 1.0f || intercept != 0.0f)) {
    std::vector<float> marks;
    for (double m : missing) marks.push_back(static_cast<float>(m));
    const std::size_t n = v.box.voxelCount();
    for (std::size_t i = 0; i < n; ++i) {
      float x;
      std::memcpy(&x, v.voxels.data() + 4 * i, 4);
      if (std::find(marks.begin(), marks.end(), x) != marks.end())
        x = std::numeric_limits<float>::quiet_NaN();
      else
        x = x * slope + intercept;
      std::memcpy(v.voxels.data() + 4 * i, &x, 4);
    }
  }
  v.updateRange();
}

std::string listedNames(const std::vector<std::string>& names) {
  if (names.empty()) return "none";
  std::string s;
  for (const std::string& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

void checkArrayRank(int rank, const std::string& what) {
  if (rank != 3 && rank != 4)
    throw base::Error(what + " has " + std::to_string(rank) +
                      " dimensions; 3 (z, y, x) or 4 (t, z, y, x) are read");
}

Index3 arrayGridDims(const std::uint64_t* len, int rank, int time, const std::string& what) {
  const int t = rank - 3;
  if (rank == 4 && (time < 0 || static_cast<std::uint64_t>(time) >= len[0]))
    throw base::Error(what + ": time " + std::to_string(time) + " is past its " +
                      std::to_string(len[0]) + " time steps");
  if (rank == 3 && time != 0)
    throw base::Error(what + " is 3-D: it has no time " + std::to_string(time));
  for (int a = 0; a < 3; ++a)
    if (len[t + a] > static_cast<std::uint64_t>(kMaxFileDims))
      throw base::Error(what + ": " + std::to_string(len[t + a]) +
                        " voxels along an axis, more than the cap of " +
                        std::to_string(kMaxFileDims));
  const Index3 dims{static_cast<int>(len[t + 2]), static_cast<int>(len[t + 1]),
                    static_cast<int>(len[t])};
  if (const std::string problem = fileDimsProblem(dims); !problem.empty())
    throw base::Error(what + ": " + problem);
  return dims;
}

VoxelType heldTypeOf(FileType type, bool anyMissing, bool scaled) {
  if (anyMissing || scaled) return VoxelType::Float32;
  StoredArray a;
  a.type = type;
  return heldVoxelType(a);
}

}  // namespace renderers::scivis
