#include <netcdf.h>

#include <cmath>
#include <mutex>
#include <string>
#include <vector>

#include "base/Error.h"
#include "renderers/scivis/io/formats/LibraryFormats.h"

namespace renderers::scivis {

std::mutex& hdf5LibraryLock();  // Hdf5File.cpp: NetCDF-4 files go through HDF5 too

namespace {

class NcFile {
 public:
  explicit NcFile(const std::string& path) : path_(path) {
    const int rc = nc_open(path.c_str(), NC_NOWRITE, &id_);
    if (rc != NC_NOERR)
      throw base::Error(path + ": cannot open as a NetCDF file (" + nc_strerror(rc) + ")");
  }
  ~NcFile() { nc_close(id_); }
  NcFile(const NcFile&) = delete;
  NcFile& operator=(const NcFile&) = delete;
  int id() const { return id_; }
  void check(int rc, const std::string& what) const {
    if (rc != NC_NOERR) throw base::Error(path_ + ": " + what + ": " + nc_strerror(rc));
  }

 private:
  std::string path_;
  int id_ = -1;
};

std::vector<std::string> volumeVariables(const NcFile& f) {
  int count = 0;
  f.check(nc_inq_nvars(f.id(), &count), "listing variables");
  std::vector<std::string> names;
  for (int v = 0; v < count; ++v) {
    char name[NC_MAX_NAME + 1] = {};
    int dims = 0;
    if (nc_inq_varname(f.id(), v, name) == NC_NOERR &&
        nc_inq_varndims(f.id(), v, &dims) == NC_NOERR && (dims == 3 || dims == 4))
      names.push_back(name);
  }
  return names;
}

FileType fileTypeOf(nc_type t, const std::string& what) {
  switch (t) {
    case NC_BYTE:
      return FileType::Int8;
    case NC_UBYTE:
      return FileType::UInt8;
    case NC_SHORT:
      return FileType::Int16;
    case NC_USHORT:
      return FileType::UInt16;
    case NC_INT:
      return FileType::Int32;
    case NC_UINT:
      return FileType::UInt32;
    case NC_FLOAT:
      return FileType::Float32;
    case NC_DOUBLE:
      return FileType::Float64;
    default:
      break;
  }
  throw base::Error(what +
                    ": the variable's type is not one dfbwall reads (byte, ubyte, short, ushort, "
                    "int, uint, float, double)");
}

std::vector<double> attribute(int file, int var, const char* name) {
  nc_type type;
  std::size_t length = 0;
  if (nc_inq_att(file, var, name, &type, &length) != NC_NOERR) return {};
  if (type == NC_CHAR || type == NC_STRING || length == 0 || length > 16) return {};
  std::vector<double> v(length);
  if (nc_get_att_double(file, var, name, v.data()) != NC_NOERR) return {};
  return v;
}

// Spacing and origin of an axis from its coordinate variable (1-D, named as the dimension):
// evenly spread from the lowest to the highest value. Uneven axes (ocean depths) are drawn
// evenly; a descending axis (latitudes from north to south) is drawn mirrored.
void axisGeometry(int file, int dim, std::size_t length, float& spacing, float& origin) {
  char name[NC_MAX_NAME + 1] = {};
  int var = -1, rank = 0;
  if (nc_inq_dimname(file, dim, name) != NC_NOERR || nc_inq_varid(file, name, &var) != NC_NOERR ||
      nc_inq_varndims(file, var, &rank) != NC_NOERR || rank != 1)
    return;
  double first = 0, last = 0;
  const std::size_t a = 0, b = length - 1;
  if (nc_get_var1_double(file, var, &a, &first) != NC_NOERR ||
      nc_get_var1_double(file, var, &b, &last) != NC_NOERR)
    return;
  const double step = std::fabs(last - first) / static_cast<double>(length - 1);
  if (!(step > 0) || !std::isfinite(step)) return;
  spacing = static_cast<float>(step);
  origin = static_cast<float>(std::min(first, last));
}

}  // namespace

void resolveNetCdf(VolumeSource& source) {
  std::lock_guard<std::mutex> lock(hdf5LibraryLock());
  VolumeFileParams& f = source.file;
  const NcFile file(f.path);
  const std::vector<std::string> names = volumeVariables(file);
  if (f.variable.empty()) {
    if (names.size() != 1)
      throw base::Error(f.path + ": the file has " + std::to_string(names.size()) +
                        " 3-D/4-D variables; say which with 'variable' (" + listedNames(names) +
                        ")");
    f.variable = names[0];
  }
  int var = -1;
  if (nc_inq_varid(file.id(), f.variable.c_str(), &var) != NC_NOERR)
    throw base::Error(f.path + ": no variable '" + f.variable +
                      "' (the 3-D/4-D variables: " + listedNames(names) + ")");
  const std::string what = f.path + ": variable '" + f.variable + "'";
  int rank = 0, dimIds[NC_MAX_VAR_DIMS] = {};
  nc_type type;
  file.check(nc_inq_var(file.id(), var, nullptr, &type, &rank, dimIds, nullptr), what);
  checkArrayRank(rank, what);
  std::size_t len[4] = {};
  for (int a = 0; a < rank; ++a) file.check(nc_inq_dimlen(file.id(), dimIds[a], &len[a]), what);
  const std::uint64_t extents[4] = {len[0], len[1], len[2], len[3]};
  source.grid.dims = arrayGridDims(extents, rank, f.time, what);
  const int t = rank - 3;
  const FileType stored = fileTypeOf(type, what);
  f.missing = attribute(file.id(), var, "_FillValue");
  for (double m : attribute(file.id(), var, "missing_value")) f.missing.push_back(m);
  const std::vector<double> scale = attribute(file.id(), var, "scale_factor"),
                            offset = attribute(file.id(), var, "add_offset");
  f.slope = scale.size() == 1 ? static_cast<float>(scale[0]) : 1.0f;
  f.intercept = offset.size() == 1 ? static_cast<float>(offset[0]) : 0.0f;
  source.grid.spacing = Vec3{1.0f};
  source.grid.origin = Vec3{0.0f};
  axisGeometry(file.id(), dimIds[t + 2], len[t + 2], source.grid.spacing.x, source.grid.origin.x);
  axisGeometry(file.id(), dimIds[t + 1], len[t + 1], source.grid.spacing.y, source.grid.origin.y);
  axisGeometry(file.id(), dimIds[t], len[t], source.grid.spacing.z, source.grid.origin.z);
  f.hasGeometry = true;
  source.type = heldTypeOf(stored, !f.missing.empty(), f.slope != 1.0f || f.intercept != 0.0f);
}

Volume loadNetCdfBox(const VolumeSource& source, const VoxelBox& box) {
  std::lock_guard<std::mutex> lock(hdf5LibraryLock());
  const VolumeFileParams& f = source.file;
  const NcFile file(f.path);
  int var = -1, rank = 0;
  if (nc_inq_varid(file.id(), f.variable.c_str(), &var) != NC_NOERR)
    throw base::Error(f.path + ": no variable '" + f.variable + "'");
  file.check(nc_inq_varndims(file.id(), var, &rank), "variable '" + f.variable + "'");
  const int t = rank - 3;
  const Index3 s = box.size();
  std::size_t start[4] = {static_cast<std::size_t>(f.time)}, count[4] = {1};
  start[t] = static_cast<std::size_t>(box.lo.z), start[t + 1] = static_cast<std::size_t>(box.lo.y),
  start[t + 2] = static_cast<std::size_t>(box.lo.x);
  count[t] = static_cast<std::size_t>(s.z), count[t + 1] = static_cast<std::size_t>(s.y),
  count[t + 2] = static_cast<std::size_t>(s.x);
  Volume v;
  v.grid = source.grid;
  v.box = box;
  v.type = source.type;
  v.voxels = allocateVoxelBytes(box, v.type);
  void* to = v.voxels.data();
  const int rc =
      v.type == VoxelType::UInt8
          ? nc_get_vara_uchar(file.id(), var, start, count, static_cast<unsigned char*>(to))
      : v.type == VoxelType::UInt16
          ? nc_get_vara_ushort(file.id(), var, start, count, static_cast<unsigned short*>(to))
          : nc_get_vara_float(file.id(), var, start, count, static_cast<float*>(to));
  // NC_ERANGE: some value did not fit a float (a double beyond 3.4e38): it is stored clipped.
  if (rc != NC_NOERR && rc != NC_ERANGE)
    file.check(rc, "variable '" + f.variable + "': reading the brick's voxels");
  markMissing(v, f.missing, f.slope, f.intercept);
  return v;
}

}  // namespace renderers::scivis
