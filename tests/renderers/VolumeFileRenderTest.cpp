// Volume files rendered: HDF5 and NetCDF volumes render exactly as the same field from a raw
// file, and NaN voxels (missing values) render as empty space.
#include <gtest/gtest.h>

#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>

#include "base/Error.h"
#include "renderers/RenderScene.h"
#include "renderers/scivis/BuiltinScenes.h"
#include "renderers/scivis/io/SciVisDesc.h"
#include "renderers/scivis/io/VolumeLoad.h"
#include "renderers/scivis/io/formats/VolumeFile.h"
#include "renderers/scivis/scene/VolumeField.h"
#include "tests/renderers/RenderTestUtil.h"
#include "tests/renderers/VolumeFileTestUtil.h"

namespace renderers::scivis {
namespace {

using namespace volfiletest;

// `d` drawn by scivis (48x36, one sample a pixel), its first volume coloured viridis over [lo, hi]
// with opacity `opacity[0]` at lo and `opacity[1]` at hi, every isosurface at `isoValue`.
std::vector<float> renderField(SceneDesc d, float lo, float hi, const float (&opacity)[2],
                               float isoValue, std::uint64_t seed) {
  sciVisDesc(d).volumes[0].transfer = transferFunctionPreset("viridis", lo, hi);
  sciVisDesc(d).volumes[0].transfer.opacities = {{lo, opacity[0]}, {hi, opacity[1]}};
  for (IsosurfaceDesc& iso : sciVisDesc(d).isosurfaces) iso.value = isoValue;
  const RenderScene scene = buildRenderScene("scivis", d);
  RenderSettings settings;
  settings.width = 48, settings.height = 36, settings.seed = seed;
  return test::renderImage(*makeRenderer("scivis", scene, settings), 48, 36, 16, 2, 1);
}

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
    sciVisDesc(d).volumes[0].source = source;
    return renderField(d, -20, 99, {0.1f, 0.8f}, 30, 3);
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
    sciVisDesc(scene).settings.aoSamples = 0;
    sciVisDesc(scene).settings.shadows = false;
    VolumeSource& s = sciVisDesc(scene).volumes[0].source;
    s = VolumeSource{};
    s.kind = VolumeSource::Kind::RawFile;
    s.raw.path = (folder() / file).string();
    s.type = VoxelType::Float32;
    s.grid.dims = d;
    s.grid.spacing = Vec3{0.08f};
    s.grid.origin = {x0, -0.6f, -0.52f};
    return renderField(scene, -40, 90, {0.05f, 0.3f}, 40, 5);
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

}  // namespace
}  // namespace renderers::scivis
