// Volume files (NRRD, NIfTI, MetaImage, HDF5, NetCDF) written here from a known field: every
// format and type reads back the field's values, any brick equals the same box of the whole
// read, raw data is read over the brick only, missing values become NaN and stay out of the
// range.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>

#include "base/Error.h"
#include "renderers/BuiltinScenes.h"
#include "renderers/RenderScene.h"
#include "renderers/scivis/io/VolumeLoad.h"
#include "renderers/scivis/io/formats/ArrayHeader.h"
#include "renderers/scivis/io/formats/VolumeFile.h"
#include "renderers/scivis/scene/VolumeField.h"
#include "tests/renderers/RenderTestUtil.h"
#include "tests/renderers/VolumeFileTestUtil.h"

namespace renderers::scivis {
namespace {

using namespace volfiletest;

TEST(VolumeFile, FormatsFromTheName) {
  EXPECT_EQ(volumeFormatOfPath("a/b.NII.gz"), VolumeFormat::Nifti);
  EXPECT_EQ(volumeFormatOfPath("x.nhdr"), VolumeFormat::Nrrd);
  EXPECT_EQ(volumeFormatOfPath("x.mha"), VolumeFormat::MetaImage);
  EXPECT_EQ(volumeFormatOfPath("x.cdf"), VolumeFormat::NetCdf);
  EXPECT_EQ(volumeFormatOfPath("x.hdf5"), VolumeFormat::Hdf5);
  EXPECT_EQ(volumeFormatOfPath("x.raw"), std::nullopt);
  EXPECT_EQ(volumeFormatNamed("metaimage"), VolumeFormat::MetaImage);
  EXPECT_EQ(volumeFormatOfPath("t1.hdr.gz"), VolumeFormat::Nifti);
  EXPECT_EQ(volumeFormatOfPath("run/p.PVTI"), VolumeFormat::Vtk);
  EXPECT_EQ(volumeFormatOfPath("x.vti"), VolumeFormat::Vtk);
  EXPECT_EQ(volumeFormatNamed("vtk"), VolumeFormat::Vtk);
  EXPECT_EQ(niftiImagePath("a/T1.HDR.gz"), "a/T1.IMG.gz");
  EXPECT_EQ(niftiImagePath("t1.nii"), "");
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

// Compressed files read layer after layer (as a brick's shell is, each layer starting at the
// previous one's last plane) resume the stream rather than inflate from the start each time,
// and give the whole read's voxels; so do reads going backwards.
TEST(VolumeFile, CompressedLayersInAnyOrderEqualTheWholeRead) {
  writeFile(folder() / "layers.nii.gz",
            gzipped(niftiHeader(kDims, 4, 16) + voxelBytesOf<std::int16_t>(false, false)));
  const VolumeSource s = fileSource(folder() / "layers.nii.gz");
  const Volume whole = loadVolume(s, s.grid.wholeBox());
  for (const int z0 : {0, 2, 4, 5, 2, 0, 3, 4}) {
    const VoxelBox layer{{1, 2, z0}, {12, 9, std::min(z0 + 3, kDims.z)}};
    const Volume part = loadVolume(s, layer);
    for (int k = layer.lo.z; k < layer.hi.z; ++k)
      for (int j = layer.lo.y; j < layer.hi.y; ++j)
        for (int i = layer.lo.x; i < layer.hi.x; ++i)
          ASSERT_EQ(part.at(i, j, k), whole.at(i, j, k)) << "layer from z " << z0;
  }
}

// Streams whose decoder cannot be copied (NRRD ascii here; bzip2 and hex alike) read layer after
// layer, each starting at the previous one's last plane, replay that plane rather than decode
// the file again from its start: about one pass over the file in all, and the whole read's
// voxels.
TEST(VolumeFile, TextLayersReplayTheirOverlapInsteadOfDecodingAgain) {
  const Index3 d{64, 64, 64};
  std::string text = "NRRD0004\ntype: short\ndimension: 3\nsizes: 64 64 64\nencoding: ascii\n\n";
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i)
        text += std::to_string((i * 7 + j * 3 + k * 5) % 2000 - 1000) + " ";
  writeFile(folder() / "layers.nrrd", text);
  writeFile(folder() / "layers-copy.nrrd", text);  // read whole: its stream is not the layers'
  const VolumeSource copy = fileSource(folder() / "layers-copy.nrrd");
  const Volume whole = loadVolume(copy, copy.grid.wholeBox());
  const VolumeSource s = fileSource(folder() / "layers.nrrd");
  const std::uint64_t before = volumeFileBytesRead();
  for (int z0 = 0; z0 + 1 < d.z; z0 += 8) {
    const VoxelBox layer{{3, 0, z0}, {60, 64, std::min(z0 + 9, d.z)}};
    const Volume part = loadVolume(s, layer);
    for (int k = layer.lo.z; k < layer.hi.z; ++k)
      for (int j = layer.lo.y; j < layer.hi.y; ++j)
        for (int i = layer.lo.x; i < layer.hi.x; ++i)
          ASSERT_EQ(part.at(i, j, k), whole.at(i, j, k)) << "layer from z " << z0;
  }
  const double passes = static_cast<double>(volumeFileBytesRead() - before) / text.size();
  EXPECT_LT(passes, 1.3) << "the layers read the file " << passes << " times over";
  std::printf("8 overlapping layers of a %zu-byte ascii NRRD: %.2f passes over the file\n",
              text.size(), passes);
}

TEST(VolumeFile, RawDataIsReadOverTheBrickOnly) {
  writeFile(folder() / "brick.nhdr",
            "NRRD0004\ntype: uint16\nendian: little\ndimension: 3\n"
            "sizes: 13 9 7\ndata file: brick.raw\n");
  writeFile(folder() / "brick.raw", voxelBytesOf<std::uint16_t>(false, true));
  writeFile(folder() / "brick.nii", niftiHeader(kDims, 16, 32) + voxelBytesOf<float>(false, false));
  for (const char* name : {"brick.nhdr", "brick.nii"}) {
    const VolumeSource s = fileSource(folder() / name);
    const VoxelBox box{{2, 3, 1}, {10, 7, 6}};
    const std::uint64_t before = volumeFileBytesRead();
    const Volume v = loadVolume(s, box);
    const std::size_t width = voxelBytes(s.type);
    EXPECT_EQ(volumeFileBytesRead() - before, box.voxelCount() * width) << name;
    EXPECT_EQ(v.bytes(), box.voxelCount() * width) << name;
  }
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
  } catch (const base::Error& e) {
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
}  // namespace
}  // namespace renderers::scivis
