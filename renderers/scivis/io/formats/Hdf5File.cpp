#include <hdf5.h>

#include <mutex>
#include <string>
#include <vector>

#include "base/Error.h"
#include "renderers/scivis/io/formats/LibraryFormats.h"

namespace renderers::scivis {

std::mutex& hdf5LibraryLock() {
  static std::mutex lock;
  return lock;
}

namespace {

// Closes an HDF5 handle when it goes out of scope.
class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~Handle() {
    if (id_ >= 0) close_(id_);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

hid_t openFile(const std::string& path) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are ours to report
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (f < 0) throw base::Error(path + ": cannot open as an HDF5 file (missing or not HDF5)");
  return f;
}

// The paths of the file's 3-D and 4-D datasets.
std::vector<std::string> volumeDatasets(hid_t file) {
  std::vector<std::string> names;
  H5Ovisit2(
      file, H5_INDEX_NAME, H5_ITER_NATIVE,
      [](hid_t root, const char* name, const H5O_info_t* info, void* data) -> herr_t {
        if (info->type != H5O_TYPE_DATASET) return 0;
        const hid_t d = H5Dopen2(root, name, H5P_DEFAULT);
        if (d < 0) return 0;
        const hid_t space = H5Dget_space(d);
        const int rank = H5Sget_simple_extent_ndims(space);
        H5Sclose(space);
        H5Dclose(d);
        if (rank == 3 || rank == 4)
          static_cast<std::vector<std::string>*>(data)->push_back(std::string("/") + name);
        return 0;
      },
      &names, H5O_INFO_BASIC);
  return names;
}

FileType fileTypeOf(hid_t type, const std::string& what) {
  const H5T_class_t c = H5Tget_class(type);
  const std::size_t size = H5Tget_size(type);
  if (c == H5T_INTEGER) {
    const bool sign = H5Tget_sign(type) == H5T_SGN_2;
    if (size == 1) return sign ? FileType::Int8 : FileType::UInt8;
    if (size == 2) return sign ? FileType::Int16 : FileType::UInt16;
    if (size == 4) return sign ? FileType::Int32 : FileType::UInt32;
  } else if (c == H5T_FLOAT) {
    if (size == 4) return FileType::Float32;
    if (size == 8) return FileType::Float64;
  }
  throw base::Error(what +
                    ": the data type is not one dfbwall reads (8 to 32-bit integers, float32, "
                    "float64)");
}

// A numeric attribute's values (empty when absent).
std::vector<double> attribute(hid_t object, const char* name) {
  if (H5Aexists(object, name) <= 0) return {};
  const Handle a(H5Aopen(object, name, H5P_DEFAULT), H5Aclose);
  if (!a.ok()) return {};
  const Handle space(H5Aget_space(a.get()), H5Sclose);
  const hssize_t n = H5Sget_simple_extent_npoints(space.get());
  const Handle type(H5Aget_type(a.get()), H5Tclose);
  const H5T_class_t c = H5Tget_class(type.get());
  if (n <= 0 || n > 16 || (c != H5T_INTEGER && c != H5T_FLOAT)) return {};
  std::vector<double> v(static_cast<std::size_t>(n));
  if (H5Aread(a.get(), H5T_NATIVE_DOUBLE, v.data()) < 0) return {};
  return v;
}

}  // namespace

void resolveHdf5(VolumeSource& source) {
  std::lock_guard<std::mutex> lock(hdf5LibraryLock());
  VolumeFileParams& f = source.file;
  const Handle file(openFile(f.path), H5Fclose);
  const std::vector<std::string> names = volumeDatasets(file.get());
  if (f.dataset.empty()) {
    if (names.size() != 1)
      throw base::Error(f.path + ": the file has " + std::to_string(names.size()) +
                        " 3-D/4-D datasets; say which with 'dataset' (" + listedNames(names) + ")");
    f.dataset = names[0];
  }
  const Handle d(H5Lexists(file.get(), f.dataset.c_str(), H5P_DEFAULT) > 0
                     ? H5Dopen2(file.get(), f.dataset.c_str(), H5P_DEFAULT)
                     : -1,
                 H5Dclose);
  if (!d.ok())
    throw base::Error(f.path + ": no dataset '" + f.dataset +
                      "' (the 3-D/4-D datasets: " + listedNames(names) + ")");
  const std::string what = f.path + ": dataset '" + f.dataset + "'";
  const Handle space(H5Dget_space(d.get()), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  checkArrayRank(rank, what);
  hsize_t dims[4] = {};
  H5Sget_simple_extent_dims(space.get(), dims, nullptr);
  const std::uint64_t len[4] = {dims[0], dims[1], dims[2], dims[3]};
  source.grid.dims = arrayGridDims(len, rank, f.time, what);
  const Handle type(H5Dget_type(d.get()), H5Tclose);
  const FileType stored = fileTypeOf(type.get(), what);
  f.missing = attribute(d.get(), "_FillValue");
  for (double m : attribute(d.get(), "missing_value")) f.missing.push_back(m);
  f.hasGeometry = false;
  source.type = heldTypeOf(stored, !f.missing.empty(), false);
}

Volume loadHdf5Box(const VolumeSource& source, const VoxelBox& box) {
  std::lock_guard<std::mutex> lock(hdf5LibraryLock());
  const VolumeFileParams& f = source.file;
  const Handle file(openFile(f.path), H5Fclose);
  const Handle d(H5Dopen2(file.get(), f.dataset.c_str(), H5P_DEFAULT), H5Dclose);
  if (!d.ok()) throw base::Error(f.path + ": no dataset '" + f.dataset + "'");
  const Handle space(H5Dget_space(d.get()), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  const int t = rank - 3;
  const Index3 s = box.size();
  hsize_t start[4] = {static_cast<hsize_t>(f.time)}, count[4] = {1};
  start[t] = static_cast<hsize_t>(box.lo.z), start[t + 1] = static_cast<hsize_t>(box.lo.y),
  start[t + 2] = static_cast<hsize_t>(box.lo.x);
  count[t] = static_cast<hsize_t>(s.z), count[t + 1] = static_cast<hsize_t>(s.y),
  count[t + 2] = static_cast<hsize_t>(s.x);
  if (H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start, nullptr, count, nullptr) < 0)
    throw base::Error(f.path + ": dataset '" + f.dataset + "': cannot select the brick's voxels");
  const Handle memory(H5Screate_simple(rank, count, nullptr), H5Sclose);
  Volume v;
  v.grid = source.grid;
  v.box = box;
  v.type = source.type;
  v.voxels = allocateVoxelBytes(box, v.type);
  const hid_t memType = v.type == VoxelType::UInt8    ? H5T_NATIVE_UCHAR
                        : v.type == VoxelType::UInt16 ? H5T_NATIVE_USHORT
                                                      : H5T_NATIVE_FLOAT;
  if (H5Dread(d.get(), memType, memory.get(), space.get(), H5P_DEFAULT, v.voxels.data()) < 0)
    throw base::Error(f.path + ": dataset '" + f.dataset +
                      "': reading the brick's voxels failed "
                      "(truncated or corrupt file?)");
  markMissing(v, f.missing, 1.0f, 0.0f);
  return v;
}

}  // namespace renderers::scivis
