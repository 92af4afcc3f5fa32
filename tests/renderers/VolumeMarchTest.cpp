// The one-volume march (VolumeMarch.h): its kernels (SSE, one ray 4 samples at a time; AVX2,
// packets of 8 rays; AVX-512, packets of 16) give the same image bit for bit, and that image is the
// generic loop's. Every kernel the machine runs is compared; SSE runs everywhere.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "renderers/RenderScene.h"
#include "renderers/scivis/BuiltinScenes.h"
#include "renderers/scivis/Registration.h"
#include "renderers/scivis/io/VolumeLoad.h"
#include "renderers/scivis/render/MarchOnly.h"
#include "renderers/scivis/render/SciVisRenderer.h"
#include "renderers/scivis/render/VolumeMarch.h"
#include "tests/renderers/RenderTestUtil.h"

namespace renderers::scivis {
namespace {

// The wavelet as a haze without isosurfaces: nothing below 150 (empty macrocells to jump), an
// opacity ramp above, `peak` at the top (a high peak ends rays early).
SceneDesc haze(float peak, int resolution = 40) {
  SceneDesc d = waveletScene(resolution);
  sciVisDesc(d).isosurfaces.clear();
  sciVisDesc(d).volumes[0].transfer.opacities = {{37.0f, 0.0f}, {150.0f, 0.0f}, {277.0f, peak}};
  sciVisDesc(d).settings.aoSamples = 0;
  return d;
}

std::vector<MarchKernel> kernels() {
  std::vector<MarchKernel> out = {MarchKernel::Sse};
  if (marchKernelAvailable(MarchKernel::Avx2)) out.push_back(MarchKernel::Avx2);
  if (marchKernelAvailable(MarchKernel::Avx512)) out.push_back(MarchKernel::Avx512);
  return out;
}

RenderSettings settings(int w, int h) {
  RenderSettings s;
  s.width = w, s.height = h, s.seed = 11;
  return s;
}

constexpr int kW = 53, kH = 41;  // not a multiple of the packet width

std::vector<float> image(const SciVisScene& scene, MarchKernel kernel, std::uint64_t* samples) {
  const SciVisRenderer r(scene, settings(kW, kH), SciVisOptions{true, kernel});
  // Two samples per pixel: a packet must not change the order a pixel's samples add up in.
  auto out = test::renderImage(r, kW, kH, 16, 2, 2);
  if (samples) *samples = r.volumeSamples();
  return out;
}

bool sameBits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

TEST(VolumeMarch, EveryKernelGivesTheSseImage) {
  for (float peak : {0.08f, 0.9f}) {
    const RenderScene scene = buildRenderScene("scivis", haze(peak));
    std::uint64_t samples = 0;
    const auto sse = image(sciVisScene(scene), MarchKernel::Sse, &samples);
    EXPECT_GT(samples, 10000u);
    // The haze shows: pixels differ from one another (the background is a gradient, so compare
    // a pixel through the volume's centre with one beside it, off the volume).
    const std::size_t centre = 4 * (static_cast<std::size_t>(kH / 2) * kW + kW / 2);
    const std::size_t corner = 4 * (static_cast<std::size_t>(kH / 2) * kW + 0);
    EXPECT_NE(sse[centre], sse[corner]) << "peak " << peak;
    for (MarchKernel k : kernels()) {
      const auto other = image(sciVisScene(scene), k, nullptr);
      EXPECT_TRUE(sameBits(sse, other)) << marchKernelName(k) << ", peak " << peak;
    }
  }
}

// With a second, invisible volume the renderer takes its generic loop; the march must composite
// exactly what that loop composites.
TEST(VolumeMarch, MarchesAsTheGenericLoop) {
  SceneDesc one = haze(0.5f), two = haze(0.5f);
  sciVisDesc(two).volumes.push_back(sciVisDesc(two).volumes[0]);
  sciVisDesc(two).volumes[1].name = "twin";
  sciVisDesc(two).volumes[1].visible = false;
  const RenderScene a = buildRenderScene("scivis", one), b = buildRenderScene("scivis", two);
  const auto generic = image(sciVisScene(b), MarchKernel::Sse, nullptr);
  for (MarchKernel k : kernels())
    EXPECT_TRUE(sameBits(generic, image(sciVisScene(a), k, nullptr))) << marchKernelName(k);
}

// Rays cut into pieces (as bricks cut them), integrated as a batch (packets where the kernel
// takes them): each piece gets the fragment the SSE march gives it alone.
TEST(VolumeMarch, CutRaysGiveTheSseFragments) {
  const RenderScene scene = buildRenderScene("scivis", haze(0.5f));
  const SceneDesc& desc = *scene.desc;
  Camera camera(desc.camera, 64, 64);
  const SciVisRenderer sse(sciVisScene(scene), settings(64, 64),
                           SciVisOptions{true, MarchKernel::Sse});
  std::vector<SciVisRenderer::RayPiece> pieces;
  for (const test::PixelRay& r :
       test::pixelRaysThrough(camera, 64, 64, 1, 3, 2, 5, Box3{Vec3{-1.0f}, Vec3{1.0f}})) {
    const Sampler sampler(4, r.x, r.y, 0, 0);
    for (float cut : {0.0f, 0.3f, 0.71f}) {
      const float tc = r.t0 + cut * (r.t1 - r.t0);
      pieces.push_back({r.origin, r.dir, r.t0, tc, sampler});
      pieces.push_back({r.origin, r.dir, tc, r.t1, sampler});
    }
  }
  ASSERT_GT(pieces.size(), 600u);
  for (MarchKernel k : kernels()) {
    const SciVisRenderer other(sciVisScene(scene), settings(64, 64), SciVisOptions{true, k});
    std::vector<Fragment> got(pieces.size());
    other.integrate(pieces.data(), pieces.size(), got.data());
    int seen = 0;
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      const SciVisRenderer::RayPiece& r = pieces[i];
      const Fragment want = sse.integrate(r.origin, r.dir, r.t0, r.t1, r.sampler);
      EXPECT_EQ(std::memcmp(want.rgba, got[i].rgba, sizeof want.rgba), 0)
          << marchKernelName(k) << " piece " << i;
      EXPECT_EQ(std::memcmp(&want.depth, &got[i].depth, sizeof want.depth), 0);
      seen += want.rgba[3] > 0.01f;
    }
    EXPECT_GT(seen, 300) << "pieces that show the haze";
  }
}

// marchOnly16 takes the pieces marchRayOf takes one at a time, their MarchRays bit for bit:
// pieces through the data, beside it (a box larger than the data's), cut, empty and reversed.
TEST(VolumeMarch, SixteenPiecesSetUpAsOneAtATime) {
  if (!marchKernelAvailable(MarchKernel::Avx512)) GTEST_SKIP() << "no AVX-512 here";
  const RenderScene scene = buildRenderScene("scivis", haze(0.5f));
  const Box3& data = sciVisScene(scene).volumes()[0].field->dataBounds();
  const float step = sciVisScene(scene).volumeStep(), minT = 1.0f / 128.0f;
  Camera camera(scene.desc->camera, 48, 48);
  std::vector<SciVisRenderer::RayPiece> pieces;
  for (const test::PixelRay& r :
       test::pixelRaysThrough(camera, 48, 48, 0, 1, 0, 1, Box3{Vec3{-1.6f}, Vec3{1.6f}})) {
    const Sampler sampler(4, r.x, r.y, 0, 0);
    const float tc = r.t0 + 0.37f * (r.t1 - r.t0);
    pieces.push_back({r.origin, r.dir, r.t0, r.t1, sampler});
    pieces.push_back({r.origin, r.dir, r.t0, tc, sampler});
    pieces.push_back({r.origin, r.dir, tc, r.t1, sampler});
    pieces.push_back({r.origin, r.dir, tc, tc, sampler});      // empty
    pieces.push_back({r.origin, r.dir, r.t1, r.t0, sampler});  // reversed
  }
  pieces.resize(pieces.size() / 16 * 16);
  ASSERT_GT(pieces.size(), 5000u);
  int taken = 0, missed = 0;
  for (std::size_t base = 0; base < pieces.size(); base += 16) {
    MarchRay got[16] = {};
    const unsigned mask = marchOnly16(pieces.data() + base, data, step, minT, got);
    int n = 0;
    for (int l = 0; l < 16; ++l) {
      const SciVisRenderer::RayPiece& r = pieces[base + static_cast<std::size_t>(l)];
      MarchRay want;
      const bool takes = marchRayOf(r, reciprocal(r.dir), data, step, minT, want);
      ASSERT_EQ(takes, ((mask >> l) & 1u) != 0) << "piece " << base + static_cast<std::size_t>(l);
      if (!takes) {
        ++missed;
        continue;
      }
      EXPECT_EQ(std::memcmp(&want, &got[n++], sizeof want), 0)
          << "piece " << base + static_cast<std::size_t>(l);
      ++taken;
    }
  }
  EXPECT_GT(taken, 1000);
  EXPECT_GT(missed, 1000);
}

// The haze's wavelet stored as integers in a raw file (uint8: value - 30, uint16: value x 200,
// rounded), its transfer function moved along: packets widen the voxels in their lanes, the
// SSE march one ray at a time; both must give the same image.
SceneDesc integerHaze(VoxelType type, float peak, int resolution = 40) {
  SceneDesc d = haze(peak, resolution);
  VolumeSource& s = sciVisDesc(d).volumes[0].source;
  const VolumeSource wavelet = s;
  const Index3 n = wavelet.grid.dims;
  const float offset = type == VoxelType::UInt8 ? -30.0f : 0.0f;
  const float scale = type == VoxelType::UInt8 ? 1.0f : 200.0f;
  const std::filesystem::path path = std::filesystem::path(::testing::TempDir()) /
                                     (std::string("dfbwall-march-") + voxelTypeName(type) + "-" +
                                      std::to_string(resolution) + ".raw");
  std::ofstream out(path, std::ios::binary);
  for (int k = 0; k < n.z; ++k)
    for (int j = 0; j < n.y; ++j)
      for (int i = 0; i < n.x; ++i) {
        const float v = (proceduralValue(wavelet, i, j, k) + offset) * scale;
        const long u =
            std::lround(std::clamp(v, 0.0f, type == VoxelType::UInt8 ? 255.0f : 65535.0f));
        if (type == VoxelType::UInt8) {
          out.put(static_cast<char>(u));
        } else {
          const std::uint16_t w = static_cast<std::uint16_t>(u);
          out.write(reinterpret_cast<const char*>(&w), 2);  // little-endian (x86)
        }
      }
  out.close();
  s.kind = VolumeSource::Kind::RawFile;
  s.type = type;
  s.raw = {path.string(), false, 0};
  TransferFunction& t = sciVisDesc(d).volumes[0].transfer;
  for (auto& c : t.colors) c.first = (c.first + offset) * scale;
  for (auto& o : t.opacities) o.first = (o.first + offset) * scale;
  t.valueMin = (t.valueMin + offset) * scale, t.valueMax = (t.valueMax + offset) * scale;
  return d;
}

TEST(VolumeMarch, IntegerVoxelsGiveTheSseImageInEveryKernel) {
  for (VoxelType type : {VoxelType::UInt8, VoxelType::UInt16}) {
    const RenderScene scene = buildRenderScene("scivis", integerHaze(type, 0.5f));
    ASSERT_EQ(sciVisScene(scene).volumes()[0].field->volume().type, type);
    std::uint64_t samples = 0;
    const auto sse = image(sciVisScene(scene), MarchKernel::Sse, &samples);
    EXPECT_GT(samples, 10000u) << voxelTypeName(type);
    const std::size_t centre = 4 * (static_cast<std::size_t>(kH / 2) * kW + kW / 2);
    const std::size_t corner = 4 * (static_cast<std::size_t>(kH / 2) * kW + 0);
    EXPECT_NE(sse[centre], sse[corner]) << voxelTypeName(type);
    for (MarchKernel k : kernels()) {
      EXPECT_TRUE(sameBits(sse, image(sciVisScene(scene), k, nullptr)))
          << marchKernelName(k) << ", " << voxelTypeName(type);
      if (k == MarchKernel::Avx512) {
        EXPECT_TRUE(marchesPackets(sciVisScene(scene).volumes()[0], k)) << voxelTypeName(type);
      }
    }
  }
}

// 64² slices (16, 8 and 4 KiB as float, uint16, uint8) are laid a cache line apart in the
// scene (Volume::spreadSlices): every kernel and the generic loop read them so.
TEST(VolumeMarch, SpreadSlicesGiveTheGenericLoopsImageInEveryKernel) {
  for (VoxelType type : {VoxelType::Float32, VoxelType::UInt16, VoxelType::UInt8}) {
    const SceneDesc one = type == VoxelType::Float32 ? haze(0.5f, 64) : integerHaze(type, 0.5f, 64);
    SceneDesc two = one;
    sciVisDesc(two).volumes.push_back(sciVisDesc(two).volumes[0]);
    sciVisDesc(two).volumes[1].name = "twin";
    sciVisDesc(two).volumes[1].visible = false;
    const RenderScene a = buildRenderScene("scivis", one), b = buildRenderScene("scivis", two);
    const Volume& spread = sciVisScene(a).content().volumes[0];
    ASSERT_EQ(spread.type, type);
    ASSERT_EQ(spread.slicePadding * voxelBytes(type), 64u) << voxelTypeName(type);
    std::uint64_t samples = 0;
    const auto generic = image(sciVisScene(b), MarchKernel::Sse, &samples);
    EXPECT_GT(samples, 10000u) << voxelTypeName(type);
    for (MarchKernel k : kernels())
      EXPECT_TRUE(sameBits(generic, image(sciVisScene(a), k, nullptr)))
          << marchKernelName(k) << ", " << voxelTypeName(type);
  }
}

// The haze's wavelet as float voxels in a raw file with what the transfer function's lookup
// must clamp: a slab of NaN voxels (missing values), a slab below the function's range (-50)
// and the wavelet's top above it (range 0 .. 200, the wavelet reaches 277), every value seen.
SceneDesc clampedHaze() {
  SceneDesc d = haze(0.5f);
  VolumeSource& s = sciVisDesc(d).volumes[0].source;
  const VolumeSource wavelet = s;
  const Index3 n = wavelet.grid.dims;
  const std::filesystem::path path =
      std::filesystem::path(::testing::TempDir()) / "dfbwall-march-clamped.raw";
  std::ofstream out(path, std::ios::binary);
  for (int k = 0; k < n.z; ++k)
    for (int j = 0; j < n.y; ++j)
      for (int i = 0; i < n.x; ++i) {
        float v = proceduralValue(wavelet, i, j, k);
        if (i >= 10 && i < 14) v = std::numeric_limits<float>::quiet_NaN();
        if (i >= 20 && i < 24) v = -50.0f;
        out.write(reinterpret_cast<const char*>(&v), sizeof v);  // little-endian (x86)
      }
  out.close();
  s.kind = VolumeSource::Kind::RawFile;
  s.type = VoxelType::Float32;
  s.raw = {path.string(), false, 0};
  TransferFunction& t = sciVisDesc(d).volumes[0].transfer;
  t.valueMin = 0.0f, t.valueMax = 200.0f;
  t.opacities = {{0.0f, 0.3f}, {200.0f, 0.05f}};
  return d;
}

// The lookup's clamps (below the range, above it, NaN) in every kernel: the SSE image, which is
// the generic loop's, bit for bit, and no NaN in it.
TEST(VolumeMarch, ClampsAndMissingValuesGiveTheSseImageInEveryKernel) {
  SceneDesc twin = clampedHaze();
  sciVisDesc(twin).volumes.push_back(sciVisDesc(twin).volumes[0]);
  sciVisDesc(twin).volumes[1].name = "twin";
  sciVisDesc(twin).volumes[1].visible = false;
  const RenderScene scene = buildRenderScene("scivis", clampedHaze());
  const RenderScene generic = buildRenderScene("scivis", twin);
  std::uint64_t samples = 0;
  const auto sse = image(sciVisScene(scene), MarchKernel::Sse, &samples);
  EXPECT_GT(samples, 10000u);
  for (std::size_t i = 0; i < sse.size(); ++i) ASSERT_FALSE(std::isnan(sse[i])) << "value " << i;
  EXPECT_TRUE(sameBits(sse, image(sciVisScene(generic), MarchKernel::Sse, nullptr)));
  for (MarchKernel k : kernels())
    EXPECT_TRUE(sameBits(sse, image(sciVisScene(scene), k, nullptr))) << marchKernelName(k);
}

TEST(VolumeMarch, KernelNames) {
  EXPECT_EQ(resolveMarchKernel(MarchKernel::Sse), MarchKernel::Sse);
  const MarchKernel best = resolveMarchKernel(MarchKernel::Auto);
  EXPECT_TRUE(marchKernelAvailable(best));
  EXPECT_NE(best, MarchKernel::Auto);
}

}  // namespace
}  // namespace renderers::scivis
