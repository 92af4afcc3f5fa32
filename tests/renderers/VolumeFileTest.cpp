// Volume files (NRRD, NIfTI, MetaImage, HDF5, NetCDF) written here from a known field: every
// format and type reads back the field's values, any brick equals the same box of the whole
// read, raw data is read over the brick only, missing values become NaN and stay out of the
// range, HDF5 and NetCDF volumes render exactly as the same field from a raw file, and hostile
// files each give one error naming the file, fast.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <netcdf.h>
#include <zlib.h>

#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include "renderers/BuiltinScenes.h"
#include "renderers/Error.h"
#include "renderers/RenderScene.h"
#include "renderers/scivis/VolumeField.h"
#include "renderers/scivis/VolumeSource.h"
#include "renderers/scivis/formats/ArrayHeader.h"
#include "renderers/scivis/formats/VolumeFile.h"
#include "tests/renderers/RenderTestUtil.h"

namespace renderers {
namespace {

namespace fs = std::filesystem;

constexpr Index3 kDims{13, 9, 7};

// The known field: distinct small integers (exact in every type, also int8), some negative.
double field(int i, int j, int k) { return (i * 7 + j * 3 + k * 5) % 120 - 20; }
double unsignedField(int i, int j, int k) { return field(i, j, k) + 20; }

fs::path folder() {
  static const fs::path p = [] {
    const fs::path f =
        fs::temp_directory_path() / ("dfbwall-volfiles-" + std::to_string(::getpid()));
    fs::create_directories(f);
    return f;
  }();
  return p;
}

void writeFile(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

template <class T>
std::string voxelBytesOf(bool bigEndian, bool isUnsigned, Index3 d = kDims) {
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
std::string deflated(const std::string& in, int windowBits) {
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
std::string gzipped(const std::string& in) { return deflated(in, 15 + 16); }

std::string niftiHeader(Index3 d, int datatype, int bitpix, float slope = 1, float inter = 0) {
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

VolumeSource fileSource(const fs::path& path) {
  VolumeSource s;
  s.kind = VolumeSource::Kind::File;
  s.file.path = path.string();
  s.file.format = *volumeFormatOfPath(path.string());
  resolveVolumeFile(s);
  return s;
}

// The whole read holds the field (as `expected` gives it), and bricks equal its boxes bit for bit.
void expectField(const VolumeSource& s, double (*expected)(int, int, int), VoxelType held) {
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

TEST(VolumeFile, FormatsFromTheName) {
  EXPECT_EQ(volumeFormatOfPath("a/b.NII.gz"), VolumeFormat::Nifti);
  EXPECT_EQ(volumeFormatOfPath("x.nhdr"), VolumeFormat::Nrrd);
  EXPECT_EQ(volumeFormatOfPath("x.mha"), VolumeFormat::MetaImage);
  EXPECT_EQ(volumeFormatOfPath("x.cdf"), VolumeFormat::NetCdf);
  EXPECT_EQ(volumeFormatOfPath("x.hdf5"), VolumeFormat::Hdf5);
  EXPECT_EQ(volumeFormatOfPath("x.raw"), std::nullopt);
  EXPECT_EQ(volumeFormatNamed("metaimage"), VolumeFormat::MetaImage);
}

TEST(VolumeFile, NrrdEveryEncodingAndTypeReadsTheFieldAndBricksEqualTheWhole) {
  const std::string head =
      "NRRD0004\n# a comment\ndimension: 3\nsizes: 13 9 7\nspacings: 0.5 1 2\n"
      "space origin: (1,2,3)\nk:=v\n";
  writeFile(folder() / "u8.nrrd",
            head + "type: uchar\nencoding: raw\n\n" + voxelBytesOf<std::uint8_t>(false, true));
  writeFile(folder() / "i16.nrrd", head + "type: short\nendian: big\nencoding: gzip\n\n" +
                                       gzipped(voxelBytesOf<std::int16_t>(true, false)));
  writeFile(folder() / "f64.raw", std::string(5, 'x') + voxelBytesOf<double>(false, false));
  writeFile(folder() / "f64.nhdr", head +
                                       "type: double\nendian: little\nbyte skip: 5\n"
                                       "data file: f64.raw\n");
  writeFile(folder() / "i8.nrrd", head + "type: int8\nencoding: gz\n\n" +
                                      gzipped(voxelBytesOf<std::int8_t>(false, false)));
  const VolumeSource u8 = fileSource(folder() / "u8.nrrd");
  expectField(u8, unsignedField, VoxelType::UInt8);
  EXPECT_EQ(u8.grid.spacing, (Vec3{0.5f, 1, 2}));
  EXPECT_EQ(u8.grid.origin, (Vec3{1, 2, 3}));
  expectField(fileSource(folder() / "i16.nrrd"), field, VoxelType::Float32);
  expectField(fileSource(folder() / "f64.nhdr"), field, VoxelType::Float32);
  expectField(fileSource(folder() / "i8.nrrd"), field, VoxelType::Float32);
}

TEST(VolumeFile, MetaImageLocalDetachedAndCompressed) {
  const std::string head =
      "ObjectType = Image\nNDims = 3\nDimSize = 13 9 7\n"
      "ElementSpacing = 1 2 3\nOffset = -1 0 1\n";
  writeFile(folder() / "u16.mha", head +
                                      "ElementType = MET_USHORT\nBinaryDataByteOrderMSB = True\n"
                                      "ElementDataFile = LOCAL\n" +
                                      voxelBytesOf<std::uint16_t>(true, true));
  writeFile(folder() / "f32.raw", voxelBytesOf<float>(false, false));
  writeFile(folder() / "f32.mhd", head + "ElementType = MET_FLOAT\nElementDataFile = f32.raw\n");
  writeFile(folder() / "i32.mha", head +
                                      "ElementType = MET_INT\nCompressedData = True\n"
                                      "ElementDataFile = LOCAL\n" +
                                      deflated(voxelBytesOf<std::int32_t>(false, false), 15));
  const VolumeSource u16 = fileSource(folder() / "u16.mha");
  expectField(u16, unsignedField, VoxelType::UInt16);
  EXPECT_EQ(u16.grid.spacing, (Vec3{1, 2, 3}));
  EXPECT_EQ(u16.grid.origin, (Vec3{-1, 0, 1}));
  expectField(fileSource(folder() / "f32.mhd"), field, VoxelType::Float32);
  expectField(fileSource(folder() / "i32.mha"), field, VoxelType::Float32);
}

TEST(VolumeFile, NiftiPlainGzippedAndScaled) {
  writeFile(folder() / "u8.nii",
            niftiHeader(kDims, 2, 8) + voxelBytesOf<std::uint8_t>(false, true));
  writeFile(folder() / "i16.nii.gz",
            gzipped(niftiHeader(kDims, 4, 16) + voxelBytesOf<std::int16_t>(false, false)));
  // scl_slope 2, scl_inter 20 on uint8 (x + 20) / 2 - 10 ... : stored (field + 20), value 2 s - 20.
  writeFile(folder() / "scaled.nii",
            niftiHeader(kDims, 2, 8, 2, -20) + voxelBytesOf<std::uint8_t>(false, true));
  const VolumeSource u8 = fileSource(folder() / "u8.nii");
  expectField(u8, unsignedField, VoxelType::UInt8);
  EXPECT_EQ(u8.grid.spacing, (Vec3{0.5f, 0.25f, 2}));
  EXPECT_EQ(u8.grid.origin, (Vec3{-3, 4, 5.5f}));
  expectField(fileSource(folder() / "i16.nii.gz"), field, VoxelType::Float32);
  expectField(
      fileSource(folder() / "scaled.nii"),
      [](int i, int j, int k) { return 2 * field(i, j, k) + 20; }, VoxelType::Float32);
}

TEST(VolumeFile, RawDataIsReadOverTheBrickOnly) {
  const VolumeSource s = fileSource(folder() / "u16.mha");
  const VoxelBox box{{2, 3, 1}, {10, 7, 6}};
  const std::uint64_t before = volumeFileBytesRead();
  const Volume v = loadVolume(s, box);
  EXPECT_EQ(volumeFileBytesRead() - before, box.voxelCount() * 2);
  EXPECT_EQ(v.bytes(), box.voxelCount() * 2);
}

// ---- HDF5 and NetCDF, written here with their own libraries -------------------------------

template <class T>
std::vector<T> values(bool isUnsigned, int steps = 1) {
  std::vector<T> v;
  for (int t = 0; t < steps; ++t)
    for (int k = 0; k < kDims.z; ++k)
      for (int j = 0; j < kDims.y; ++j)
        for (int i = 0; i < kDims.x; ++i)
          v.push_back(
              static_cast<T>((isUnsigned ? unsignedField(i, j, k) : field(i, j, k)) + 100 * t));
  return v;
}

void writeHdf5(const fs::path& path) {
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
void writeNetCdf(const fs::path& path, bool netcdf4) {
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

VolumeSource libSource(const fs::path& path, const std::string& name, int time = 0) {
  VolumeSource s;
  s.kind = VolumeSource::Kind::File;
  s.file.path = path.string();
  s.file.format = *volumeFormatOfPath(path.string());
  (s.file.format == VolumeFormat::Hdf5 ? s.file.dataset : s.file.variable) = name;
  s.file.time = time;
  resolveVolumeFile(s);
  return s;
}

TEST(VolumeFile, Hdf5ContiguousChunkedAndFourDimensional) {
  writeHdf5(folder() / "v.h5");
  expectField(libSource(folder() / "v.h5", "/f32"), field, VoxelType::Float32);
  expectField(libSource(folder() / "v.h5", "/u8"), unsignedField, VoxelType::UInt8);
  expectField(libSource(folder() / "v.h5", "/sim/i16"), field, VoxelType::Float32);
  expectField(
      libSource(folder() / "v.h5", "/sim/i16", 1),
      [](int i, int j, int k) { return field(i, j, k) + 100; }, VoxelType::Float32);
  try {
    libSource(folder() / "v.h5", "/nope");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("v.h5: no dataset '/nope' (the 3-D/4-D datasets: /f32, "
                                         "/sim/i16, /u8)"),
              std::string::npos)
        << e.what();
  }
}

TEST(VolumeFile, NetCdfClassicAndNetCdf4MissingValuesAreNanAndOutOfTheRange) {
  for (const bool netcdf4 : {false, true}) {
    const fs::path path = folder() / (netcdf4 ? "v4.nc" : "v3.nc");
    writeNetCdf(path, netcdf4);
    const VolumeSource temp = libSource(path, "temp");
    EXPECT_EQ(temp.grid.spacing.x, 2.5f);
    EXPECT_EQ(temp.grid.origin.x, 10.0f);
    const Volume v = loadVolume(temp, temp.grid.wholeBox());
    EXPECT_TRUE(std::isnan(v.at(5, 0, 0)));
    EXPECT_TRUE(std::isnan(v.at(12, 8, 6)));
    EXPECT_EQ(v.at(4, 0, 0), static_cast<float>(field(4, 0, 0)));
    EXPECT_EQ(v.valueMin, -20.0f);
    EXPECT_EQ(v.valueMax, 99.0f);
    // A brick equals the whole read's box (NaN included).
    const VoxelBox box{{3, 0, 0}, {8, 5, 4}};
    const Volume part = loadVolume(temp, box);
    for (int k = box.lo.z; k < box.hi.z; ++k)
      for (int j = box.lo.y; j < box.hi.y; ++j)
        for (int i = box.lo.x; i < box.hi.x; ++i)
          ASSERT_EQ(std::bit_cast<std::uint32_t>(part.at(i, j, k)),
                    std::bit_cast<std::uint32_t>(v.at(i, j, k)));
    // NaN samples are "no data": not sampled, not in the macrocell ranges.
    const VolumeField f(v);
    float value = 0;
    EXPECT_FALSE(f.sample(temp.grid.worldOf(5.0f, 0.0f, 0.0f), value));
    EXPECT_TRUE(f.sample(temp.grid.worldOf(2.5f, 3.5f, 1.5f), value));
    EXPECT_EQ(f.macroMin(0), -20.0f);
    expectField(libSource(path, "wide"), field, VoxelType::Float32);
    if (netcdf4)
      expectField(
          libSource(path, "series", 1),
          [](int i, int j, int k) { return unsignedField(i, j, k) + 100; }, VoxelType::UInt16);
    else
      expectField(
          libSource(path, "series", 1), [](int i, int j, int k) { return field(i, j, k) + 100; },
          VoxelType::Float32);
  }
}

// The same field from HDF5, NetCDF-3, NetCDF-4 and a raw file renders the same bytes (the
// volume rendered with a transfer function and an isosurface, shaded).
TEST(VolumeFile, Hdf5AndNetCdfRenderAsTheSameFieldFromARawFile) {
  writeHdf5(folder() / "r.h5");
  writeNetCdf(folder() / "r3.nc", false);
  writeNetCdf(folder() / "r4.nc", true);
  writeFile(folder() / "r.raw", voxelBytesOf<float>(false, false));
  VolumeSource raw;
  raw.kind = VolumeSource::Kind::RawFile;
  raw.raw.path = (folder() / "r.raw").string();
  raw.type = VoxelType::Float32;
  raw.grid.dims = kDims;
  auto render = [&](VolumeSource source) {
    SceneDesc d = waveletScene(21);
    source.grid.spacing = Vec3{0.15f};
    source.grid.origin = {-0.9f, -0.6f, -0.45f};
    d.volumes[0].source = source;
    d.volumes[0].transfer = transferFunctionPreset("viridis", -20, 99);
    d.volumes[0].transfer.opacities = {{-20, 0.1f}, {99, 0.8f}};
    for (IsosurfaceDesc& iso : d.isosurfaces) iso.value = 30;
    const RenderScene scene = buildRenderScene("scivis", d);
    RenderSettings settings;
    settings.width = 48, settings.height = 36, settings.seed = 3;
    return test::renderImage(*makeRenderer("scivis", scene, settings), 48, 36, 16, 2, 1);
  };
  const std::vector<float> expected = render(raw);
  int lit = 0;
  for (std::size_t i = 0; i < expected.size(); i += 4) lit += expected[i] + expected[i + 1] > 0.05f;
  EXPECT_GT(lit, 200) << "the field should cover much of the image";
  for (const auto& [file, name] :
       {std::pair{"r.h5", "/f32"}, {"r.h5", "/sim/i16"}, {"r3.nc", "wide"}, {"r4.nc", "wide"}}) {
    const std::vector<float> image = render(libSource(folder() / file, name));
    ASSERT_EQ(image.size(), expected.size());
    EXPECT_EQ(0, std::memcmp(image.data(), expected.data(), image.size() * 4))
        << file << " " << name;
  }
}

// Missing values render as empty space: a field whose voxels x < 6 are NaN renders as the same
// field cut to x >= 6 (the samples whose cells touch a NaN are not drawn, no isosurface is
// crossed into or out of them, gradients there are one-sided as at the data's edge).
TEST(VolumeFile, NanVoxelsRenderAsTheFieldWithoutThem) {
  const Index3 dims{24, 16, 14};
  auto value = [](int i, int j, int k) {
    return static_cast<float>(std::sin(0.4 * i) * 40 + j * 3 + k * 2);
  };
  std::string withNan, cut;
  for (int k = 0; k < dims.z; ++k)
    for (int j = 0; j < dims.y; ++j)
      for (int i = 0; i < dims.x; ++i) {
        const float v = i < 6 ? std::numeric_limits<float>::quiet_NaN() : value(i, j, k);
        withNan.append(reinterpret_cast<const char*>(&v), 4);
        if (i >= 6) cut.append(reinterpret_cast<const char*>(&v), 4);
      }
  writeFile(folder() / "nan.raw", withNan);
  writeFile(folder() / "cut.raw", cut);
  auto render = [&](const std::string& file, Index3 d, float x0) {
    SceneDesc scene = waveletScene(21);
    scene.scivis.aoSamples = 0;
    scene.scivis.shadows = false;
    VolumeSource& s = scene.volumes[0].source;
    s = VolumeSource{};
    s.kind = VolumeSource::Kind::RawFile;
    s.raw.path = (folder() / file).string();
    s.type = VoxelType::Float32;
    s.grid.dims = d;
    s.grid.spacing = Vec3{0.08f};
    s.grid.origin = {x0, -0.6f, -0.52f};
    scene.volumes[0].transfer = transferFunctionPreset("viridis", -40, 90);
    scene.volumes[0].transfer.opacities = {{-40, 0.05f}, {90, 0.3f}};
    for (IsosurfaceDesc& iso : scene.isosurfaces) iso.value = 40;
    const RenderScene built = buildRenderScene("scivis", scene);
    RenderSettings settings;
    settings.width = 48, settings.height = 36, settings.seed = 5;
    return test::renderImage(*makeRenderer("scivis", built, settings), 48, 36, 16, 2, 1);
  };
  const std::vector<float> a = render("nan.raw", dims, -0.92f);
  const std::vector<float> b = render("cut.raw", {dims.x - 6, dims.y, dims.z}, -0.92f + 6 * 0.08f);
  ASSERT_EQ(a.size(), b.size());
  float worst = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_FALSE(std::isnan(a[i])) << "pixel value " << i;
    worst = std::max(worst, std::abs(a[i] - b[i]));
  }
  EXPECT_LE(worst, 1e-5f);
  int lit = 0;
  for (std::size_t i = 0; i < a.size(); i += 4) lit += a[i] + a[i + 1] + a[i + 2] > 0.3f;
  EXPECT_GT(lit, 300) << "the field should cover much of the image";
  std::printf("NaN field vs the cut field: largest difference %.3g, %d lit pixels\n", worst, lit);
}

// ---- hostile files: one error naming the file, fast, no crash ------------------------------

std::string errorOf(const fs::path& path, bool loadToo = true) {
  const auto start = std::chrono::steady_clock::now();
  std::string message = "(no error)";
  try {
    const VolumeSource s = fileSource(path);
    if (loadToo) loadVolume(s, {{0, 0, 0}, s.grid.dims});
  } catch (const Error& e) {
    message = e.what();
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(seconds, 2.0) << path;
  return message;
}

void expectError(const std::string& name, const std::string& bytes, const std::string& says) {
  writeFile(folder() / name, bytes);
  const std::string message = errorOf(folder() / name);
  EXPECT_NE(message.find(says), std::string::npos) << name << ": " << message;
  if (says != "(no error)") {
    EXPECT_NE(message.find(name), std::string::npos) << "the error names the file: " << message;
  }
}

TEST(VolumeFile, HostileFilesGiveOneErrorNamingTheFile) {
  const std::string nrrd = "NRRD0004\ndimension: 3\n";
  const std::string u8 = voxelBytesOf<std::uint8_t>(false, true);
  expectError("short.nrrd", nrrd + "type: uchar\nsizes: 13 9 7\n\n" + u8.substr(0, 100),
              "shorter than the 868 the header calls for");
  expectError("huge.nrrd", nrrd + "type: uchar\nsizes: 13 9 70000\n\n" + u8, "more than the cap");
  expectError("total.nrrd", nrrd + "type: uchar\nsizes: 16000 16000 16000\n\n",
              "voxels, more than");
  expectError("type.nrrd", nrrd + "type: block\nsizes: 13 9 7\n\n", "type 'block'");
  expectError("enc.nrrd", nrrd + "type: uchar\nencoding: bzip2\nsizes: 13 9 7\n\n", "bzip2");
  expectError("dim.nrrd", "NRRD0004\ndimension: 4\n", "dimension 4");
  expectError("junk.nrrd", nrrd + "sizes: 13 9 x7\n", "'x7' is not a number");
  expectError("line.nrrd", nrrd + "type: uchar\nsizes 13 9 7\n", "line.nrrd:4");
  expectError("endian.nrrd", nrrd + "type: short\nsizes: 13 9 7\n\n", "misses field 'endian'");
  expectError("nomagic.nrrd", "PK\3\4", "not an NRRD file");
  expectError("endsearly.nrrd",
              nrrd + "type: uchar\nencoding: gzip\nsizes: 13 9 7\n\n" + gzipped(u8.substr(0, 500)),
              "ends after 500 bytes");
  expectError("corrupt.nrrd",
              nrrd + "type: uchar\nencoding: gzip\nsizes: 13 9 7\n\n" + std::string(300, 'z'),
              "corrupt");
  // A gzip bomb: 32 MiB of zeros behind a header asking for 819 bytes: reading stops there.
  expectError("bomb.nrrd",
              nrrd + "type: uchar\nencoding: gzip\nsizes: 13 9 7\n\n" +
                  gzipped(std::string(32u << 20, '\0')),
              "(no error)");
  expectError("bomb2.nrrd",
              nrrd + "type: uchar\nencoding: gzip\nsizes: 1000 1000 40\n\n" +
                  gzipped(std::string(16u << 20, '\0')),
              "ends after 16777216 bytes");
  const std::string nifti = niftiHeader(kDims, 2, 8);
  expectError("trunc.nii", nifti.substr(0, 200), "too short for a NIfTI-1 header");
  expectError("short.nii", nifti + u8.substr(0, 10), "shorter than");
  std::string lying = nifti;
  lying[70] = 77;  // datatype 77: no such type
  expectError("type.nii", lying + u8, "'datatype' 77");
  std::string big = nifti;
  const std::int16_t huge = 30000;
  for (int a = 0; a < 3; ++a) std::memcpy(big.data() + 42 + 2 * a, &huge, 2);
  expectError("huge.nii", big, "must be between 2 and 16384");
  std::string magic = nifti;
  magic[345] = 'i';
  expectError("magic.nii", magic + u8, "'magic'");
  expectError("notgz.nii.gz", gzipped(nifti + u8).substr(0, 300), "ends after");
  expectError("nometa.mha", "ObjectType = Image\nNDims = 3\nDimSize = 13 9 7\n", "ElementDataFile");
  expectError("metatype.mha",
              "NDims = 3\nDimSize = 13 9 7\nElementType = MET_STRING\nElementDataFile = LOCAL\n",
              "MET_STRING");
  expectError("nofile.mhd",
              "NDims = 3\nDimSize = 13 9 7\nElementType = MET_UCHAR\nElementDataFile = gone.raw\n",
              "nofile.mhd: its data file");
  expectError("garbage.h5", "not an hdf5 file at all", "cannot open as an HDF5 file");
  expectError("garbage.nc", "CDF\1 lies", "has 0 3-D/4-D variables");
  // Wrong types: a NetCDF text variable; an HDF5 file with only a 2-D dataset.
  {
    const fs::path p = folder() / "text.nc";
    int nc, d[3], v;
    nc_create(p.c_str(), NC_CLOBBER, &nc);
    nc_def_dim(nc, "z", 2, &d[0]), nc_def_dim(nc, "y", 2, &d[1]), nc_def_dim(nc, "x", 2, &d[2]);
    nc_def_var(nc, "words", NC_CHAR, 3, d, &v);
    nc_close(nc);
    const std::string m = errorOf(p);
    EXPECT_NE(m.find("text.nc: variable 'words': the variable's type is not one"),
              std::string::npos)
        << m;
  }
  {
    const fs::path p = folder() / "flat.h5";
    const hid_t f = H5Fcreate(p.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    const hsize_t d2[2] = {4, 4};
    const hid_t space = H5Screate_simple(2, d2, nullptr);
    H5Dclose(H5Dcreate2(f, "/image", H5T_IEEE_F32LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    H5Sclose(space);
    H5Fclose(f);
    const std::string m = errorOf(p);
    EXPECT_NE(m.find("flat.h5: the file has 0 3-D/4-D datasets"), std::string::npos) << m;
  }
}

}  // namespace
}  // namespace renderers
