// The scivis parts of scene files: the shipped example reads, and every mistake names its file,
// line and field.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "base/Error.h"
#include "renderers/BuiltinScenes.h"
#include "renderers/scivis/io/SciVisDesc.h"
#include "tests/DiagnosticsTestUtil.h"

namespace renderers::scivis {
namespace {

namespace fs = std::filesystem;

std::string writeScene(const std::string& name, const std::string& text) {
  const fs::path dir = fs::path(::testing::TempDir()) / "dfbwall-scivis-toml";
  fs::create_directories(dir);
  const fs::path p = dir / name;
  std::ofstream(p) << text;
  return p.string();
}

// The problems reading the scene, one headline each (DiagnosticsTestUtil.h).
std::string errorOf(const std::string& path) {
  try {
    loadSceneDesc(path);
  } catch (const base::Error& e) {
    return testutil::headlines(e.what());
  }
  return "(no error)";
}

const std::string kHeader = R"([camera]
position = [0, 0, -5]
look_at = [0, 0, 0]
[materials.white]
type = "diffuse"
[[volumes]]
name = "w"
source = "wavelet"
dims = [16, 16, 16]
transfer_function = { preset = "grayscale", range = [37.0, 277.0] }
)";  // 10 lines

TEST(SciVisToml, TheShippedWaveletSceneReads) {
  const SceneDesc d =
      loadSceneDesc(std::string(DFBWALL_SOURCE_DIR) + "/configs/scenes/wavelet.toml");
  ASSERT_EQ(sciVisDesc(d).volumes.size(), 1u);
  EXPECT_EQ(sciVisDesc(d).volumes[0].source.grid.dims, (Index3{96, 96, 96}));
  ASSERT_EQ(sciVisDesc(d).isosurfaces.size(), 2u);
  EXPECT_EQ(sciVisDesc(d).isosurfaces[1].value, 215.0f);
  EXPECT_EQ(d.materials[sciVisDesc(d).isosurfaces[1].material].name, "core");
  EXPECT_FLOAT_EQ(d.materials[sciVisDesc(d).isosurfaces[0].material].opacity, 0.3f);
  ASSERT_EQ(sciVisDesc(d).particles.size(), 1u);
  EXPECT_EQ(sciVisDesc(d).particles[0].centers.size(), 4u);
  EXPECT_EQ(sciVisDesc(d).particles[0].attribute.size(), 4u);
  ASSERT_EQ(sciVisDesc(d).lights.size(), 2u);
  EXPECT_EQ(sciVisDesc(d).lights[1].kind, LightDesc::Kind::Directional);
  EXPECT_EQ(sciVisDesc(d).settings.aoSamples, 1);
  EXPECT_EQ(d.instances.size(), 1u);
}

// scripts/bench paraview hands these to ParaView too (bench/paraview_wavelet.py maps the same
// fields): the 256^3 wavelet on [-1, 1]^3, one sample per voxel, VTK's stopping threshold.
TEST(SciVisToml, TheParaViewComparisonScenesRead) {
  for (const char* name : {"wavelet256-volume", "wavelet256-contours"}) {
    SCOPED_TRACE(name);
    const SceneDesc d =
        loadSceneDesc(std::string(DFBWALL_SOURCE_DIR) + "/configs/scenes/" + name + ".toml");
    ASSERT_EQ(sciVisDesc(d).volumes.size(), 1u);
    const VolumeDesc& v = sciVisDesc(d).volumes[0];
    EXPECT_EQ(v.source.grid.dims, (Index3{256, 256, 256}));
    EXPECT_FLOAT_EQ(v.source.grid.origin.x, -1.0f);
    EXPECT_FLOAT_EQ(v.source.grid.spacing.x, 2.0f / 255.0f);
    ASSERT_EQ(v.transfer.colors.size(), 3u);
    EXPECT_EQ(v.transfer.colors[1].first, 157.0f);
    EXPECT_EQ(sciVisDesc(d).settings.samplingRate, 1.0f);
    EXPECT_EQ(sciVisDesc(d).settings.minTransmittance, 1.0f / 128.0f);
    EXPECT_EQ(sciVisDesc(d).settings.aoSamples, 0);
    EXPECT_FALSE(sciVisDesc(d).settings.shadows);
    EXPECT_EQ(d.camera.fovY, 30.0f);
  }
  const SceneDesc c =
      loadSceneDesc(std::string(DFBWALL_SOURCE_DIR) + "/configs/scenes/wavelet256-contours.toml");
  EXPECT_FALSE(sciVisDesc(c).volumes[0].visible);
  ASSERT_EQ(sciVisDesc(c).isosurfaces.size(), 2u);
  EXPECT_EQ(sciVisDesc(c).isosurfaces[0].value, 160.0f);
  EXPECT_EQ(sciVisDesc(c).isosurfaces[1].value, 215.0f);
}

TEST(SciVisToml, MistakesNameFileLineAndField) {
  struct Case {
    std::string text, expected;
  };
  const Case cases[] = {
      {"[[isosurfaces]]\nvolume = \"nope\"\nvalue = 1\nmaterial = \"white\"\n",
       ":12:10: isosurface.volume: volume 'nope' is not defined"},
      {"[[isosurfaces]]\nvolume = \"w\"\nvalues = [1, 2]\nmaterials = [\"white\"]\n",
       ":14:13: isosurface.materials: must be an array with one material per value"},
      {"[[isosurfaces]]\nvolume = \"w\"\nvalue = nan\nmaterial = \"white\"\n",
       ":13:9: isosurface.values: expected a finite number, got nan"},
      {"[[particles]]\nmaterial = \"white\"\ncenters = [[0, 0, 0]]\n",
       ":11:1: particles 'particles'.radius: missing (or 'radii', or 'r' in the layout)"},
      {"[[particles]]\nmaterial = \"white\"\nradius = -1\ncenters = [[0, 0, 0]]\n",
       ":13:10: particles 'particles'.radius: must be positive"},
      {"[[particles]]\nmaterial = \"white\"\nradius = 1\ncentres = [[0, 0, 0]]\n",
       ":14:1: particles 'particles': unknown field 'centres' (did you mean 'centers'?)"},
      {"[[lights]]\ntype = \"spot\"\n",
       ":12:8: light.type: must be directional, point or ambient, not \"spot\""},
      {"[scivis]\nsampling_rate = 0\n", ":12:17: scivis.sampling_rate: must be in [0.01, 64]"},
      {"[scivis]\nshadows = 1\n", ":12:11: scivis.shadows: expected true or false, got an integer"},
  };
  int i = 0;
  for (const Case& c : cases) {
    const std::string path = writeScene("case" + std::to_string(i++) + ".toml", kHeader + c.text);
    const std::string e = errorOf(path);
    EXPECT_EQ(e.rfind(path + c.expected, 0), 0u) << "got: " << e << "\nexpected: " << c.expected;
  }
}

}  // namespace
}  // namespace renderers::scivis
