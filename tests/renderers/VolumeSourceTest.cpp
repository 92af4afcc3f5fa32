// Volumes and their sources: the wavelet against VTK's own values, bricks against the whole
// field bit for bit, raw files read box by box and nothing more.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "base/Error.h"
#include "renderers/scivis/io/VolumeLoad.h"
#include "renderers/scivis/scene/VolumeField.h"

namespace renderers::scivis {
namespace {

namespace fs = std::filesystem;

VolumeSource procedural(VolumeSource::Kind kind, Index3 dims) {
  VolumeSource s;
  s.kind = kind;
  s.grid.dims = dims;
  return s;
}

std::string errorOf(const VolumeSource& s, const VoxelBox& box) {
  try {
    loadVolume(s, box);
  } catch (const base::Error& e) {
    return e.what();
  }
  return "(no error)";
}

// Every voxel of `part` equals the same voxel of `whole`, bit for bit.
void expectSameVoxels(const Volume& whole, const Volume& part) {
  ASSERT_TRUE(whole.box.contains(part.box));
  ASSERT_EQ(whole.type, part.type);
  std::size_t checked = 0;
  for (int k = part.box.lo.z; k < part.box.hi.z; ++k)
    for (int j = part.box.lo.y; j < part.box.hi.y; ++j)
      for (int i = part.box.lo.x; i < part.box.hi.x; ++i, ++checked)
        ASSERT_EQ(std::bit_cast<std::uint32_t>(whole.at(i, j, k)),
                  std::bit_cast<std::uint32_t>(part.at(i, j, k)))
            << "voxel " << i << ", " << j << ", " << k;
  EXPECT_EQ(checked, part.box.voxelCount());
}

TEST(Volume, SizesAndBoxes) {
  EXPECT_EQ(voxelBytes(VoxelType::Float32), 4u);
  EXPECT_EQ(voxelBytes(VoxelType::UInt16), 2u);
  EXPECT_EQ(voxelBytes(VoxelType::UInt8), 1u);
  EXPECT_STREQ(voxelTypeName(VoxelType::UInt16), "uint16");
  // 64-bit counts: 2048³ does not fit 32 bits.
  const VoxelBox big{{0, 0, 0}, {2048, 2048, 2048}};
  EXPECT_EQ(big.voxelCount(), std::size_t{1} << 33);
  EXPECT_EQ((VoxelBox{{1, 1, 1}, {1, 5, 5}}.voxelCount()), 0u);
  EXPECT_TRUE(big.contains({{10, 0, 2047}, {2048, 1, 2048}}));
  EXPECT_FALSE(big.contains({{10, 0, 2047}, {2049, 1, 2048}}));
  EXPECT_FALSE(big.contains({{-1, 0, 0}, {1, 1, 1}}));

  GridGeometry g;
  g.dims = {10, 20, 30};
  g.origin = {1, 2, 3};
  g.spacing = {0.5f, 1, 2};
  Vec3 lo, hi;
  g.bounds({{2, 0, 1}, {4, 20, 30}}, lo, hi);
  EXPECT_EQ(lo, (Vec3{2, 2, 5}));
  EXPECT_EQ(hi, (Vec3{2.5f, 21, 61}));
}

TEST(Volume, AtReadsEachTypeAndUpdateRangeSpansThem) {
  Volume v;
  v.box = {{5, 6, 7}, {7, 7, 8}};  // two voxels
  v.type = VoxelType::UInt16;
  const std::uint16_t u16[2] = {700, 65535};
  v.voxels.resize(4);
  std::memcpy(v.voxels.data(), u16, 4);
  EXPECT_EQ(v.at(5, 6, 7), 700.0f);
  EXPECT_EQ(v.at(6, 6, 7), 65535.0f);
  v.updateRange();
  EXPECT_EQ(v.valueMin, 700.0f);
  EXPECT_EQ(v.valueMax, 65535.0f);

  v.type = VoxelType::Float32;
  const float f[2] = {NAN, -3.5f};  // a NaN voxel does not poison the range
  v.voxels.resize(8);
  std::memcpy(v.voxels.data(), f, 8);
  v.updateRange();
  EXPECT_EQ(v.valueMin, -3.5f);
  EXPECT_EQ(v.valueMax, -3.5f);
}

// Slices whose bytes are a multiple of 1 KiB get a cache line after each, in the buffer they
// came in (its capacity holds the padding); every voxel keeps its value, the range stays, and
// a field samples the spread voxels to the same bits as the dense ones.
TEST(Volume, SpreadSlicesMoveNoValueAndPadOnlyWhereSlicesAlias) {
  const VolumeSource wavelet = procedural(VolumeSource::Kind::Wavelet, {64, 32, 9});
  const VoxelBox box{{0, 0, 0}, {64, 32, 9}};  // 64 x 32 floats: 8 KiB slices
  EXPECT_EQ(slicePaddingFor(box, VoxelType::Float32), 16u);
  EXPECT_EQ(slicePaddingFor(box, VoxelType::UInt16), 32u);
  EXPECT_EQ(slicePaddingFor(box, VoxelType::UInt8), 64u);
  EXPECT_EQ(slicePaddingFor({{0, 0, 0}, {60, 32, 9}}, VoxelType::Float32), 0u);  // 7.5 KiB
  EXPECT_EQ(slicePaddingFor({{0, 0, 0}, {0, 32, 9}}, VoxelType::Float32), 0u);

  const Volume dense = loadVolume(wavelet, box);
  ASSERT_EQ(dense.slicePadding, 0u);
  Volume spread = dense;
  spread.voxels = allocateVoxelBytes(box, spread.type);
  std::memcpy(spread.voxels.data(), dense.voxels.data(), dense.voxels.size());
  const std::byte* buffer = spread.voxels.data();
  spread.spreadSlices();
  EXPECT_EQ(spread.voxels.data(), buffer) << "moved out of its buffer";
  EXPECT_EQ(spread.slicePadding, 16u);
  EXPECT_EQ(spread.sliceStride(), 64u * 32u + 16u);
  EXPECT_EQ(spread.bytes(), dense.bytes() + 9 * 64);
  expectSameVoxels(dense, spread);
  for (std::size_t z = 0; z < 9; ++z)
    for (std::size_t b = 0; b < 64; ++b)
      EXPECT_EQ(spread.voxels[(z * spread.sliceStride() + 64 * 32) * 4 + b], std::byte{0});
  spread.updateRange();
  EXPECT_EQ(spread.valueMin, dense.valueMin);
  EXPECT_EQ(spread.valueMax, dense.valueMax);
  const std::vector<std::byte> once = spread.voxels;
  spread.spreadSlices();  // already spread: nothing moves
  EXPECT_EQ(spread.voxels, once);

  const VolumeField a(dense), b(spread);
  EXPECT_EQ(b.layout().strideZ, spread.sliceStride());
  int sampled = 0;
  for (float z = -0.5f; z < 9.5f; z += 0.37f)
    for (float y = -0.5f; y < 32.5f; y += 1.13f)
      for (float x = -0.5f; x < 64.5f; x += 1.71f) {
        const Vec3 p = dense.grid.worldOf(x, y, z);
        float va = 0, vb = 0;
        const bool ina = a.sample(p, va), inb = b.sample(p, vb);
        ASSERT_EQ(ina, inb);
        if (!ina) continue;
        ASSERT_EQ(std::bit_cast<std::uint32_t>(va), std::bit_cast<std::uint32_t>(vb));
        ++sampled;
      }
  EXPECT_GT(sampled, 10000);
  for (int m = 0; m < a.macroCount(); ++m) {
    EXPECT_EQ(a.macroMin(m), b.macroMin(m));
    EXPECT_EQ(a.macroMax(m), b.macroMax(m));
  }

  // Slices that do not alias are left dense.
  Volume odd = loadVolume(wavelet, {{2, 0, 0}, {62, 32, 9}});
  const std::vector<std::byte> before = odd.voxels;
  odd.spreadSlices();
  EXPECT_EQ(odd.slicePadding, 0u);
  EXPECT_EQ(odd.voxels, before);
}

// Each macrocell's range is the least and greatest of the voxels its cells interpolate (its far
// face included, NaN left out), for a box that starts off the macrocell grid, in every type.
TEST(VolumeField, MacrocellRangesSpanTheirVoxels) {
  const VolumeSource wavelet = procedural(VolumeSource::Kind::Wavelet, {48, 40, 36});
  const VoxelBox box{{3, 5, 2}, {45, 40, 29}};
  for (VoxelType type : {VoxelType::Float32, VoxelType::UInt8, VoxelType::UInt16}) {
    Volume v = loadVolume(wavelet, box);
    if (type != VoxelType::Float32) {  // the same values, rounded, in the integer type
      Volume u = v;
      u.type = type;
      u.voxels.assign(box.voxelCount() * voxelBytes(type), std::byte{0});
      for (std::size_t n = 0; n < box.voxelCount(); ++n) {
        float f;
        std::memcpy(&f, v.voxels.data() + 4 * n, 4);
        const auto w =
            static_cast<std::uint16_t>(std::lround(f) & (type == VoxelType::UInt8 ? 0xff : 0xffff));
        std::memcpy(u.voxels.data() + n * voxelBytes(type), &w, voxelBytes(type));
      }
      v = u;
    } else {
      const float nan = NAN;  // missing values in two places
      std::memcpy(v.voxels.data() + 4 * 7, &nan, 4);
      std::memcpy(v.voxels.data() + 4 * (box.voxelCount() / 2), &nan, 4);
    }
    const VolumeField field(v);
    ASSERT_GT(field.macroCount(), 20);
    for (int m = 0; m < field.macroCount(); ++m) {
      const Index3 c0 = field.macroOrigin(m);
      float lo = INFINITY, hi = -INFINITY;
      for (int k = std::max(c0.z, box.lo.z); k <= std::min(c0.z + 8, box.hi.z - 1); ++k)
        for (int j = std::max(c0.y, box.lo.y); j <= std::min(c0.y + 8, box.hi.y - 1); ++j)
          for (int i = std::max(c0.x, box.lo.x); i <= std::min(c0.x + 8, box.hi.x - 1); ++i) {
            const float value = v.at(i, j, k);
            if (value < lo) lo = value;
            if (value > hi) hi = value;
          }
      ASSERT_EQ(field.macroMin(m), lo) << voxelTypeName(type) << " macrocell " << m;
      ASSERT_EQ(field.macroMax(m), hi) << voxelTypeName(type) << " macrocell " << m;
    }
  }
}

// Reference values from VTK 9.1 (Debian's python3-vtk9):
//   s = vtk.vtkRTAnalyticSource(); s.Update()
//   s.GetOutput().GetScalarComponentAsDouble(i - 10, j - 10, k - 10, 0)
// (its whole extent is [-10, 10]³; our voxel i is VTK's index i - 10).
TEST(Wavelet, EqualsVtkRTAnalyticSourceAt21Cubed) {
  const VolumeSource s = procedural(VolumeSource::Kind::Wavelet, {21, 21, 21});
  const Volume v = loadVolume(s, s.grid.wholeBox());
  struct Reference {
    int i, j, k;
    std::uint32_t bits;  // the float VTK stores
  };
  const Reference vtk[] = {{0, 0, 0, 0x42730dca},    {10, 10, 10, 0x43820000},
                           {20, 20, 20, 0x42647477}, {3, 7, 11, 0x43328bbc},
                           {20, 0, 5, 0x42c85a61},   {13, 2, 19, 0x42d72e4b},
                           {10, 4, 16, 0x433d8b7c}};
  for (const Reference& r : vtk) {
    EXPECT_EQ(std::bit_cast<std::uint32_t>(v.at(r.i, r.j, r.k)), r.bits)
        << r.i << ", " << r.j << ", " << r.k << ": " << v.at(r.i, r.j, r.k) << " vs "
        << std::bit_cast<float>(r.bits);
    EXPECT_EQ(proceduralValue(s, r.i, r.j, r.k), std::bit_cast<float>(r.bits));
  }
  EXPECT_EQ(v.at(10, 10, 10), 260.0f);  // 255 + 0 + 0 + 5 cos(0)
  // VTK's GetScalarRange() of the same field.
  EXPECT_EQ(v.valueMin, 37.35310363769531f);
  EXPECT_EQ(v.valueMax, 276.8288269042969f);
  const auto range = knownValueRange(s);
  ASSERT_TRUE(range);
  EXPECT_EQ(range->first, v.valueMin);
  EXPECT_EQ(range->second, v.valueMax);
}

TEST(Wavelet, EveryResolutionSamplesTheSameExtent) {
  // 41³ has VTK's 21 points at its even indices: the same positions, the same values.
  const VolumeSource coarse = procedural(VolumeSource::Kind::Wavelet, {21, 21, 21});
  const VolumeSource fine = procedural(VolumeSource::Kind::Wavelet, {41, 41, 41});
  for (int n : {0, 3, 10, 17, 20})
    EXPECT_EQ(proceduralValue(fine, 2 * n, 2 * (20 - n), 2 * (n / 2)),
              proceduralValue(coarse, n, 20 - n, n / 2));
  // The known range at 512³ comes from 129³ samples, within 0.1% of the 256³ field's range.
  const auto range = knownValueRange(procedural(VolumeSource::Kind::Wavelet, {512, 512, 512}));
  ASSERT_TRUE(range);
  const Volume v = loadVolume(procedural(VolumeSource::Kind::Wavelet, {256, 256, 256}),
                              {{0, 0, 0}, {256, 256, 256}});
  EXPECT_NEAR(range->first, v.valueMin, 0.001f * (v.valueMax - v.valueMin));
  EXPECT_NEAR(range->second, v.valueMax, 0.001f * (v.valueMax - v.valueMin));
}

TEST(Procedural, AnySubBoxEqualsTheWholeFieldBitForBit) {
  for (auto kind : {VolumeSource::Kind::Wavelet, VolumeSource::Kind::MarschnerLobb}) {
    const VolumeSource s = procedural(kind, {37, 29, 23});
    const Volume whole = loadVolume(s, s.grid.wholeBox());
    const VoxelBox boxes[] = {{{0, 0, 0}, {1, 1, 1}},
                              {{36, 28, 22}, {37, 29, 23}},
                              {{5, 3, 2}, {17, 29, 9}},
                              {{0, 11, 0}, {37, 12, 23}},
                              {{20, 0, 10}, {37, 29, 11}}};
    for (const VoxelBox& b : boxes) {
      const Volume part = loadVolume(s, b);
      EXPECT_EQ(part.box, b);
      EXPECT_EQ(part.bytes(), b.voxelCount() * 4);
      expectSameVoxels(whole, part);
      EXPECT_EQ(std::bit_cast<std::uint32_t>(part.at(b.lo.x, b.lo.y, b.lo.z)),
                std::bit_cast<std::uint32_t>(proceduralValue(s, b.lo.x, b.lo.y, b.lo.z)));
    }
  }
}

TEST(MarschnerLobb, MatchesTheFormulaOnMinusOneToOne) {
  const VolumeSource s = procedural(VolumeSource::Kind::MarschnerLobb, {41, 41, 41});
  auto rho = [](double x, double y, double z) {
    const double pi = 3.14159265358979323846, fM = 6, a = 0.25;
    const double r = std::sqrt(x * x + y * y);
    return (1 - std::sin(pi * z / 2) + a * (1 + std::cos(2 * pi * fM * std::cos(pi * r / 2)))) /
           (2 * (1 + a));
  };
  EXPECT_NEAR(proceduralValue(s, 0, 0, 0), rho(-1, -1, -1), 1e-6);
  EXPECT_NEAR(proceduralValue(s, 20, 20, 40), rho(0, 0, 1), 1e-6);
  EXPECT_NEAR(proceduralValue(s, 7, 33, 12), rho(-0.65, 0.65, -0.4), 1e-6);
  // At the centre: (1 - 0 + 0.25 (1 + cos(12 pi))) / 2.5 = 1.5 / 2.5.
  EXPECT_NEAR(proceduralValue(s, 20, 20, 20), 0.6, 1e-6);
  EXPECT_EQ(knownValueRange(s), (std::pair{0.0f, 1.0f}));
}

TEST(Procedural, BadBoxesAreErrors) {
  const VolumeSource s = procedural(VolumeSource::Kind::Wavelet, {8, 8, 8});
  EXPECT_EQ(errorOf(s, {{0, 0, 0}, {9, 8, 8}}),
            "volume box [0, 0, 0] to [9, 8, 8) is empty or outside the grid 8x8x8");
  EXPECT_EQ(errorOf(s, {{3, 3, 3}, {3, 8, 8}}),
            "volume box [3, 3, 3] to [3, 8, 8) is empty or outside the grid 8x8x8");
  EXPECT_EQ(errorOf(procedural(VolumeSource::Kind::Wavelet, {1, 8, 8}), {{0, 0, 0}, {1, 1, 1}}),
            "volume grid 1x8x8 needs at least 2 voxels per axis");
}

// ---- raw files ---------------------------------------------------------------------------------

fs::path tempDir() {
  const fs::path dir = fs::path(::testing::TempDir()) / "dfbwall-volume-tests";
  fs::create_directories(dir);
  return dir;
}

// A raw file of `dims` voxels of `type` whose voxel n holds a value made from n, in the given
// byte order, after `header` bytes of 0xAB.
VolumeSource writeRaw(const std::string& name, Index3 dims, VoxelType type, bool bigEndian,
                      std::uint64_t header) {
  VolumeSource s;
  s.kind = VolumeSource::Kind::RawFile;
  s.grid.dims = dims;
  s.type = type;
  s.raw = {(tempDir() / name).string(), bigEndian, header};
  std::ofstream out(s.raw.path, std::ios::binary);
  for (std::uint64_t h = 0; h < header; ++h) out.put(static_cast<char>(0xAB));
  const std::size_t count = s.grid.wholeBox().voxelCount(), width = voxelBytes(type);
  for (std::size_t n = 0; n < count; ++n) {
    unsigned char bytes[4];
    if (type == VoxelType::Float32) {
      const float f = static_cast<float>(n) * 0.37f - 100.0f;
      std::memcpy(bytes, &f, 4);
    } else {
      const std::uint32_t u =
          static_cast<std::uint32_t>(n * 7919u) & (type == VoxelType::UInt8 ? 0xFFu : 0xFFFFu);
      std::memcpy(bytes, &u, 4);
    }
    // bytes holds the little-endian encoding (x86); a big-endian file stores them reversed.
    if (bigEndian)
      for (std::size_t i = 0; i < width / 2; ++i) std::swap(bytes[i], bytes[width - 1 - i]);
    out.write(reinterpret_cast<const char*>(bytes), static_cast<std::streamsize>(width));
  }
  return s;
}

TEST(RawVolume, SubBoxesEqualTheWholeReadForEveryTypeAndByteOrderAndReadOnlyTheBox) {
  static_assert(std::endian::native == std::endian::little, "the fixture writes little-endian");
  const Index3 dims{13, 11, 7};
  for (VoxelType type : {VoxelType::Float32, VoxelType::UInt8, VoxelType::UInt16}) {
    for (bool big : {false, true}) {
      const std::string name = std::string(voxelTypeName(type)) + (big ? "-be" : "-le") + ".raw";
      const VolumeSource s = writeRaw(name, dims, type, big, big ? 17 : 0);
      const Volume whole = loadVolume(s, s.grid.wholeBox());
      ASSERT_EQ(whole.bytes(), s.grid.wholeBox().voxelCount() * voxelBytes(type));
      // The whole read decodes what was written.
      const float expected = type == VoxelType::Float32 ? 123 * 0.37f - 100.0f
                             : type == VoxelType::UInt8
                                 ? static_cast<float>((123u * 7919u) & 0xFF)
                                 : static_cast<float>((123u * 7919u) & 0xFFFF);
      EXPECT_EQ(whole.at(123 % 13, (123 / 13) % 11, 123 / 143), expected) << name;
      const VoxelBox boxes[] = {{{2, 3, 1}, {9, 10, 6}},   // rows
                                {{0, 4, 2}, {13, 8, 5}},   // whole rows: a read per slab
                                {{0, 0, 3}, {13, 11, 7}},  // whole slabs: one read
                                {{12, 10, 6}, {13, 11, 7}}};
      for (const VoxelBox& b : boxes) {
        const std::uint64_t before = volumeFileBytesRead();
        const Volume part = loadVolume(s, b);
        EXPECT_EQ(volumeFileBytesRead() - before, b.voxelCount() * voxelBytes(type)) << name;
        expectSameVoxels(whole, part);
      }
    }
  }
}

TEST(RawVolume, ABrickOfAHugeSparseFileReadsOnlyItsVoxels) {
  // 4096 x 4096 x 1024 uint16: a 32 GiB file, sparse, so it costs no disk. Reading a brick must
  // touch only the brick's rows: 16 x 16 rows of 32 bytes.
  VolumeSource s;
  s.kind = VolumeSource::Kind::RawFile;
  s.grid.dims = {4096, 4096, 1024};
  s.type = VoxelType::UInt16;
  s.raw = {(tempDir() / "sparse.raw").string(), true, 64};
  {
    const int fd = ::open(s.raw.path.c_str(), O_CREAT | O_TRUNC | O_WRONLY, 0644);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::ftruncate(fd, static_cast<off_t>(expectedRawFileBytes(s))), 0);
    // One big-endian voxel inside the brick: (1000, 2000, 500) = 0x1234.
    const std::uint64_t at = 64 + ((500ull * 4096 + 2000) * 4096 + 1000) * 2;
    const unsigned char bytes[2] = {0x12, 0x34};
    ASSERT_EQ(::pwrite(fd, bytes, 2, static_cast<off_t>(at)), 2);
    ::close(fd);
  }
  const VoxelBox brick{{992, 1995, 490}, {1008, 2011, 506}};
  const std::uint64_t before = volumeFileBytesRead();
  const Volume v = loadVolume(s, brick);
  EXPECT_EQ(volumeFileBytesRead() - before, 16u * 16u * 16u * 2u);
  EXPECT_EQ(v.at(1000, 2000, 500), 4660.0f);
  EXPECT_EQ(v.at(1001, 2000, 500), 0.0f);
  EXPECT_EQ(v.valueMax, 4660.0f);
  fs::remove(s.raw.path);
}

TEST(RawVolume, MissingOrWrongSizedFilesNameTheFileAndTheExpectedSize) {
  VolumeSource s = writeRaw("short.raw", {4, 4, 4}, VoxelType::UInt16, false, 0);
  s.raw.headerBytes = 10;  // the file lacks those 10 bytes
  const std::string path = s.raw.path;
  EXPECT_EQ(errorOf(s, {{0, 0, 0}, {1, 1, 1}}),
            path +
                ": raw volume file is 128 bytes, expected 138 bytes (4x4x4 uint16 voxels of 2 "
                "bytes + 10 header bytes)");
  s.raw.path = (tempDir() / "no-such.raw").string();
  EXPECT_EQ(errorOf(s, {{0, 0, 0}, {1, 1, 1}}),
            s.raw.path +
                ": cannot open the raw volume file (No such file or directory); expected "
                "138 bytes (4x4x4 uint16 voxels of 2 bytes + 10 header bytes)");
  EXPECT_THROW(checkRawFile(s), base::Error);
}

}  // namespace
}  // namespace renderers::scivis
