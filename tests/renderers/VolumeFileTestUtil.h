#pragma once
// Volume files written by the tests from a known field: NRRD, MetaImage and NIfTI bytes, HDF5
// and NetCDF files through their own libraries, and checks that a source reads the field.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <netcdf.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "renderers/scivis/io/VolumeLoad.h"
#include "renderers/scivis/io/formats/VolumeFile.h"

namespace renderers::scivis::volfiletest {

namespace fs = std::filesystem;

inline constexpr Index3 kDims{13, 9, 7};

// The known field: distinct small integers (exact in every type, also int8), some negative.
inline double field(int i, int j, int k) { return (i * 7 + j * 3 + k * 5) % 120 - 20; }
inline double unsignedField(int i, int j, int k) { return field(i, j, k) + 20; }

inline fs::path folder() {
  static const fs::path p = [] {
    const fs::path f =
        fs::temp_directory_path() / ("dfbwall-volfiles-" + std::to_string(::getpid()));
    fs::create_directories(f);
    return f;
  }();
  return p;
}

inline void writeFile(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

template <class T>
inline std::string voxelBytesOf(bool bigEndian, bool isUnsigned, Index3 d = kDims) {
  std::string out;
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i) {
        const T v = static_cast<T>(isUnsigned ? unsignedField(i, j, k) : field(i, j, k));
        char b[sizeof(T)];
        std::memcpy(b, &v, sizeof v);
        if (bigEndian) std::reverse(b, b + sizeof b);
        out.append(b, sizeof b);
      }
  return out;
}

// windowBits 15 + 16: gzip; 15: zlib.
inline std::string deflated(const std::string& in, int windowBits) {
  z_stream z{};
  deflateInit2(&z, 6, Z_DEFLATED, windowBits, 8, Z_DEFAULT_STRATEGY);
  std::string out(deflateBound(&z, in.size()) + 64, '\0');
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(in.data()));
  z.avail_in = static_cast<uInt>(in.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(out.size());
  EXPECT_EQ(deflate(&z, Z_FINISH), Z_STREAM_END);
  out.resize(z.total_out);
  deflateEnd(&z);
  return out;
}
inline std::string gzipped(const std::string& in) { return deflated(in, 15 + 16); }

inline std::string niftiHeader(Index3 d, int datatype, int bitpix, float slope = 1,
                               float inter = 0) {
  std::string h(352, '\0');
  auto put = [&](std::size_t at, auto v) { std::memcpy(h.data() + at, &v, sizeof v); };
  put(0, std::int32_t{348});
  const std::int16_t dim[8] = {3,
                               static_cast<std::int16_t>(d.x),
                               static_cast<std::int16_t>(d.y),
                               static_cast<std::int16_t>(d.z),
                               1,
                               1,
                               1,
                               1};
  std::memcpy(h.data() + 40, dim, sizeof dim);
  put(70, static_cast<std::int16_t>(datatype));
  put(72, static_cast<std::int16_t>(bitpix));
  const float pixdim[8] = {1, 0.5f, 0.25f, 2, 1, 1, 1, 1};
  std::memcpy(h.data() + 76, pixdim, sizeof pixdim);
  put(108, 352.0f);
  put(112, slope);
  put(116, inter);
  put(254, std::int16_t{1});  // sform
  put(280 + 12, -3.0f), put(296 + 12, 4.0f), put(312 + 12, 5.5f);
  std::memcpy(h.data() + 344, "n+1", 4);
  return h;
}

inline VolumeSource fileSource(const fs::path& path) {
  VolumeSource s;
  s.kind = VolumeSource::Kind::File;
  s.file.path = path.string();
  s.file.format = *volumeFormatOfPath(path.string());
  resolveVolumeFile(s);
  return s;
}

// The whole read holds the field (as `expected` gives it), and bricks equal its boxes bit for bit.
inline void expectField(const VolumeSource& s, double (*expected)(int, int, int), VoxelType held) {
  ASSERT_EQ(s.grid.dims, kDims);
  EXPECT_EQ(s.type, held);
  const Volume whole = loadVolume(s, s.grid.wholeBox());
  ASSERT_EQ(whole.type, held);
  for (int k = 0; k < kDims.z; ++k)
    for (int j = 0; j < kDims.y; ++j)
      for (int i = 0; i < kDims.x; ++i)
        ASSERT_EQ(whole.at(i, j, k), static_cast<float>(expected(i, j, k)))
            << s.file.path << " voxel " << i << ", " << j << ", " << k;
  for (const VoxelBox box : {VoxelBox{{0, 0, 0}, {13, 9, 7}}, VoxelBox{{3, 2, 1}, {9, 8, 5}},
                             VoxelBox{{0, 4, 2}, {13, 9, 4}}, VoxelBox{{5, 0, 6}, {7, 2, 7}}}) {
    const Volume part = loadVolume(s, box);
    ASSERT_EQ(part.type, held);
    for (int k = box.lo.z; k < box.hi.z; ++k)
      for (int j = box.lo.y; j < box.hi.y; ++j)
        for (int i = box.lo.x; i < box.hi.x; ++i)
          ASSERT_EQ(std::bit_cast<std::uint32_t>(part.at(i, j, k)),
                    std::bit_cast<std::uint32_t>(whole.at(i, j, k)));
  }
}

// ---- HDF5 and NetCDF, written here with their own libraries -------------------------------

template <class T>
inline std::vector<T> values(bool isUnsigned, int steps = 1) {
  std::vector<T> v;
  for (int t = 0; t < steps; ++t)
    for (int k = 0; k < kDims.z; ++k)
      for (int j = 0; j < kDims.y; ++j)
        for (int i = 0; i < kDims.x; ++i)
          v.push_back(
              static_cast<T>((isUnsigned ? unsignedField(i, j, k) : field(i, j, k)) + 100 * t));
  return v;
}

inline void writeHdf5(const fs::path& path) {
  const hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  const hsize_t d3[3] = {7, 9, 13}, d4[4] = {2, 7, 9, 13}, chunk[4] = {1, 4, 4, 4};
  // Contiguous float32, 3-D.
  hid_t space = H5Screate_simple(3, d3, nullptr);
  hid_t d = H5Dcreate2(f, "/f32", H5T_IEEE_F32LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  H5Dwrite(d, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, values<float>(false).data());
  H5Dclose(d);
  H5Sclose(space);
  // Chunked, compressed big-endian int16, 4-D (two time steps), in a group.
  H5Gclose(H5Gcreate2(f, "/sim", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  space = H5Screate_simple(4, d4, nullptr);
  hid_t plist = H5Pcreate(H5P_DATASET_CREATE);
  H5Pset_chunk(plist, 4, chunk);
  H5Pset_deflate(plist, 4);
  d = H5Dcreate2(f, "/sim/i16", H5T_STD_I16BE, space, H5P_DEFAULT, plist, H5P_DEFAULT);
  H5Dwrite(d, H5T_NATIVE_SHORT, H5S_ALL, H5S_ALL, H5P_DEFAULT,
           values<std::int16_t>(false, 2).data());
  H5Dclose(d);
  H5Pclose(plist);
  H5Sclose(space);
  // uint8, 3-D.
  space = H5Screate_simple(3, d3, nullptr);
  d = H5Dcreate2(f, "/u8", H5T_STD_U8LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  H5Dwrite(d, H5T_NATIVE_UCHAR, H5S_ALL, H5S_ALL, H5P_DEFAULT, values<std::uint8_t>(true).data());
  H5Dclose(d);
  H5Sclose(space);
  H5Fclose(f);
}

// A NetCDF file: classic (contiguous) or NetCDF-4 (chunked).
inline void writeNetCdf(const fs::path& path, bool netcdf4) {
  int nc, dz, dy, dx, dt, var;
  ASSERT_EQ(nc_create(path.c_str(), netcdf4 ? NC_NETCDF4 : NC_CLOBBER, &nc), NC_NOERR);
  nc_def_dim(nc, "time", 2, &dt);
  nc_def_dim(nc, "depth", 7, &dz);
  nc_def_dim(nc, "lat", 9, &dy);
  nc_def_dim(nc, "lon", 13, &dx);
  int lon;
  nc_def_var(nc, "lon", NC_DOUBLE, 1, &dx, &lon);
  const int d3[3] = {dz, dy, dx}, d4[4] = {dt, dz, dy, dx};
  nc_def_var(nc, "temp", NC_FLOAT, 3, d3, &var);
  const float fill = -1e10f;
  nc_put_att_float(nc, var, "_FillValue", NC_FLOAT, 1, &fill);
  int series;
  nc_def_var(nc, "series", netcdf4 ? NC_USHORT : NC_SHORT, 4, d4, &series);
  int wide;
  nc_def_var(nc, "wide", NC_DOUBLE, 3, d3, &wide);
  if (netcdf4) {
    const std::size_t chunks[3] = {3, 4, 5};
    nc_def_var_chunking(nc, var, NC_CHUNKED, chunks);
    nc_def_var_deflate(nc, wide, 0, 1, 3);
  }
  nc_enddef(nc);
  std::vector<double> lons;
  for (int i = 0; i < 13; ++i) lons.push_back(10 + 2.5 * i);
  nc_put_var_double(nc, lon, lons.data());
  std::vector<float> t = values<float>(false);
  t[5] = fill;             // voxel (5, 0, 0): "land"
  t[t.size() - 1] = fill;  // the last voxel
  nc_put_var_float(nc, var, t.data());
  if (netcdf4)
    nc_put_var_ushort(nc, series, values<unsigned short>(true, 2).data());
  else
    nc_put_var_short(nc, series, values<short>(false, 2).data());
  nc_put_var_double(nc, wide, values<double>(false).data());
  nc_close(nc);
}

inline VolumeSource libSource(const fs::path& path, const std::string& name, int time = 0) {
  VolumeSource s;
  s.kind = VolumeSource::Kind::File;
  s.file.path = path.string();
  s.file.format = *volumeFormatOfPath(path.string());
  (s.file.format == VolumeFormat::Hdf5 ? s.file.dataset : s.file.variable) = name;
  s.file.time = time;
  resolveVolumeFile(s);
  return s;
}

}  // namespace renderers::scivis::volfiletest
