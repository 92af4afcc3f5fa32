// Scenes that must be refused when read or before they are loaded, each with an error naming
// the file, the line and the field: more memory than the rank may hold (the memory budget, set
// here with base::setMemoryLimit as dfbwall --memory-limit does), allocations that fail while
// loading, degenerate geometry and geometry float cannot hold, more volumes than scivis draws.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <new>

#include "base/Error.h"
#include "base/MemoryBudget.h"
#include "base/TomlDiagnostics.h"
#include "renderers/BuiltinScenes.h"
#include "renderers/RenderScene.h"
#include "renderers/TomlReader.h"
#include "renderers/scivis/bricks/BrickLoad.h"
#include "renderers/scivis/scene/SciVisScene.h"
#include "tests/DiagnosticsTestUtil.h"

namespace renderers::scivis {
namespace {

namespace fs = std::filesystem;

fs::path testDir() {
  const fs::path dir = fs::path(::testing::TempDir()) / "dfbwall-scene-refusals";
  fs::create_directories(dir);
  return dir;
}

std::string writeScene(const std::string& name, const std::string& text) {
  const fs::path p = testDir() / name;
  std::ofstream(p) << text;
  return p.string();
}

// A file of `bytes` bytes that takes no disk space (a sparse file of zeros).
std::string sparseFile(const std::string& name, std::uint64_t bytes) {
  const fs::path p = testDir() / name;
  std::ofstream(p).close();
  fs::resize_file(p, bytes);
  return p.string();
}

// The base::Error `step` throws for the scene at `path`, one headline a problem
// (DiagnosticsTestUtil.h), with the path replaced by "FILE", or "(no error)". A bare
// std::bad_alloc (or any other exception) fails the test.
template <class Step>
std::string errorOf(const std::string& path, Step step) {
  try {
    step();
  } catch (const base::Error& e) {
    std::string m = testutil::headlines(e.what());
    if (m.rfind(path, 0) == 0) m = "FILE" + m.substr(path.size());
    return m;
  }
  return "(no error)";
}

// The error reading the scene.
std::string errorOf(const std::string& path) {
  return errorOf(path, [&] { loadSceneDesc(path); });
}

// The error building the whole scene (what every rank of an image-parallel run loads).
std::string loadErrorOf(const std::string& path) {
  const SceneDesc d = loadSceneDesc(path);
  return errorOf(path, [&] { wholeScene(d); });
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

const std::string kCamera = R"([camera]
position = [0, 0, -5]
look_at = [0, 0, 0]
[materials.white]
type = "diffuse"
)";  // 5 lines

// A [[volumes]] table of a built-in wavelet field (4 lines); `dims` as "x, y, z".
std::string waveletVolume(const std::string& name, const std::string& dims) {
  return "[[volumes]]\nname = \"" + name + "\"\nsource = \"wavelet\"\ndims = [" + dims + "]\n";
}

// Sets a memory limit for one test and restores the machine's when it ends.
class Budget {
 public:
  explicit Budget(std::uint64_t bytes) { base::setMemoryLimit(bytes); }
  ~Budget() { base::setMemoryLimit(0); }
};

constexpr std::uint64_t kMiB = 1 << 20;

// ---- the memory budget ----------------------------------------------------------------------

TEST(SceneTomlBudget, AVolumeBeyondTheRankIsRefusedBeforeItsVoxelsNamingDimsAndBytes) {
  const Budget budget(64 * kMiB);
  const std::string path =
      writeScene("big-volume.toml", kCamera + waveletVolume("w", "512, 512, 512"));
  const auto start = std::chrono::steady_clock::now();
  const std::string e = loadErrorOf(path);
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
  // 512³ float voxels and their macrocells: 536870912 + 2097152 bytes.
  EXPECT_EQ(e.rfind("FILE:9:8: volume 'w'.dims: this rank holds 538968064 bytes of this "
                    "512x512x512 float32 volume (the whole scene",
                    0),
            0u)
      << e;
  EXPECT_TRUE(contains(e,
                       "needs 514 MiB (538968064 bytes), more than this rank may hold: 64 MiB "
                       "(67108864 bytes: --memory-limit)"))
      << e;
  // A quarter of it, as one brick of four, still does not fit; with more memory it does.
  const SceneDesc d = loadSceneDesc(path);
  try {
    checkOwnBricksMemory(d, 4, 1, 0, 4);
    ADD_FAILURE() << "a brick of 128 MiB fitted in 64 MiB";
  } catch (const base::Error& error) {
    EXPECT_TRUE(contains(error.what(), "volume 'w'.dims: this rank holds")) << error.what();
    EXPECT_TRUE(contains(error.what(), "(1 brick, ghost voxels")) << error.what();
  }
  base::setMemoryLimit(256 * kMiB);
  EXPECT_NO_THROW(checkOwnBricksMemory(d, 4, 1, 0, 4));
}

TEST(SceneTomlBudget, VolumesCountTogether) {
  const Budget budget(64 * kMiB);
  // Two volumes of 32 MiB (+ macrocells): each fits, both do not; the larger is named.
  const std::string path =
      writeScene("two-volumes.toml", kCamera + waveletVolume("a", "256, 256, 128") +
                                         waveletVolume("b", "256, 256, 129"));
  const std::string e = loadErrorOf(path);
  EXPECT_EQ(e.rfind("FILE:13:8: volume 'b'.dims: this rank holds", 0), 0u) << e;
  EXPECT_TRUE(contains(e, "more than this rank may hold: 64 MiB")) << e;
}

TEST(SceneTomlBudget, GeneratedAndFileParticlesAreRefusedBeforeTheyAreMade) {
  const Budget budget(64 * kMiB);
  const std::string generated = writeScene("many-particles.toml", kCamera + R"([[particles]]
name = "p"
material = "white"
generator = "clusters"
count = 100000000
)");
  EXPECT_EQ(errorOf(generated),
            "FILE:10:9: particles 'p'.count: loading it (100000000 particles) needs 1.49 GiB "
            "(1600000000 bytes), more than this rank may hold: 64 MiB (67108864 bytes: "
            "--memory-limit)");
  sparseFile("huge.xyz", 1ull << 30);
  const std::string file = writeScene("file-particles.toml", kCamera + R"([[particles]]
name = "f"
material = "white"
radius = 0.1
file = "huge.xyz"
)");
  EXPECT_EQ(errorOf(file).rfind(
                "FILE:10:8: particles 'f'.file: loading it (1073741824 bytes) needs 2 GiB "
                "(2147483648 bytes)",
                0),
            0u)
      << errorOf(file);
}

TEST(SceneTomlBudget, MeshFilesAndTheSceneFileItselfAreRefusedBeforeTheyAreRead) {
  const Budget budget(64 * kMiB);
  sparseFile("huge.obj", 1ull << 30);
  const std::string mesh = writeScene("big-mesh.toml", kCamera + R"([[meshes]]
name = "m"
material = "white"
file = "huge.obj"
)");
  EXPECT_EQ(
      errorOf(mesh).rfind("FILE:9:8: mesh 'm'.file: loading it (1073741824 bytes) needs 1 GiB", 0),
      0u)
      << errorOf(mesh);
  // 4 MiB of TOML: TOML++ may need 40 times that.
  const std::string big =
      writeScene("big-scene.toml", kCamera + "# " + std::string(4 * kMiB, 'x') + "\n[[spheres]]\n");
  // (The file as a whole: no line.)
  EXPECT_EQ(errorOf(big).rfind("FILE: the scene file (4194405 bytes; ", 0), 0u) << errorOf(big);
  EXPECT_TRUE(contains(errorOf(big), "more than this rank may hold: 64 MiB")) << errorOf(big);
}

TEST(SceneTomlBudget, TheBvhOfAMeshCountsWhenTheSceneIsBuilt) {
  // A strip of 20000 triangles: its file and vertices fit in 1.5 MiB, its BVH (about 96 bytes a
  // triangle) does not.
  {
    std::ofstream obj(testDir() / "strip.obj");
    for (int i = 0; i < 10001; ++i) obj << "v " << i << " 0 0\nv " << i << " 1 0\n";
    for (int i = 0; i < 10000; ++i) {
      const int a = 2 * i + 1;
      obj << "f " << a << " " << a + 2 << " " << a + 1 << "\nf " << a + 1 << " " << a + 2 << " "
          << a + 3 << "\n";
    }
  }
  const Budget budget(3 * kMiB / 2);
  const std::string path = writeScene("strip.toml", kCamera + R"([[meshes]]
name = "strip"
material = "white"
file = "strip.obj"
)");
  SceneDesc d = loadSceneDesc(path);
  ASSERT_EQ(d.shapes.at(0).mesh.triangles.size(), 20000u);
  try {
    buildRenderScene("pathtracer", std::move(d), false);
    ADD_FAILURE() << "the BVH fitted";
  } catch (const base::Error& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind("mesh 'strip' (", 0), 0u) << m;
    EXPECT_TRUE(contains(m,
                         "strip.obj): the scene's bounding volume hierarchy over its 20000 "
                         "primitives (about 96 bytes each, per placement)"))
        << m;
    EXPECT_TRUE(contains(m, "more than this rank may hold: 1.5 MiB")) << m;
  }
}

TEST(SceneTomlBudget, AFailedAllocationWhileLoadingNamesWhatWasLoading) {
  const std::string path = writeScene("alloc.toml", "[thing]\nsize = 1\n");
  base::TomlDiagnostics diagnostics(path);
  ASSERT_TRUE(diagnostics.readFile("scene file"));
  const toml::table root = *diagnostics.parse();
  TomlReader r(diagnostics);
  EXPECT_FALSE(r.entry([&] {
    r.loading(*root["thing"]["size"].node(), "thing.size", []() -> int { throw std::bad_alloc(); });
  }));
  try {
    diagnostics.throwIfAny();
    ADD_FAILURE() << "no error";
  } catch (const base::Error& e) {
    const std::string m = e.what();
    EXPECT_EQ(
        m.rfind(path + ":2:8: thing.size: out of memory while loading it; this rank may hold ", 0),
        0u)
        << m;
    EXPECT_FALSE(contains(m, "bad_alloc")) << m;
  }
}

// ---- degenerate geometry, and geometry float cannot hold --------------------------------------

struct Case {
  std::string name, text, expected;
};

void expectRefusals(const std::vector<Case>& cases) {
  for (const Case& c : cases) {
    const std::string e = errorOf(writeScene(c.name + ".toml", c.text));
    EXPECT_EQ(e.rfind("FILE" + c.expected, 0), 0u)
        << c.name << "\n got: " << e << "\n expected: FILE" << c.expected;
  }
}

const std::string kTriangle = R"(
[[meshes]]
name = "t"
material = "white"
vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
faces = [[0, 1, 2]]
)";  // lines 6-11 after kCamera

TEST(SceneTomlGeometry, CamerasThatSeeNothing) {
  const std::string materials = "[materials.white]\ntype = \"diffuse\"\n" + kTriangle;
  expectRefusals({
      {"camera-same", "[camera]\nposition = [1, 2, 3]\nlook_at = [1, 2, 3]\n" + materials,
       ":3:11: camera.look_at: must differ from camera.position"},
      {"camera-up",
       "[camera]\nposition = [0, 0, -5]\nlook_at = [0, 0, 0]\nup = [0, 0, 2]\n" + materials,
       ":4:6: camera.up: must not be parallel to the view direction"},
      {"camera-up-zero",
       "[camera]\nposition = [0, 0, -5]\nlook_at = [0, 0, 0]\nup = [0, 0, 0]\n" + materials,
       ":4:6: camera.up: must be a non-zero direction"},
      {"camera-far", "[camera]\nposition = [1e30, 0, 0]\nlook_at = [-1e30, 0, 0]\n" + materials,
       ":3:11: camera.look_at: is too far from camera.position for float arithmetic"},
      {"camera-lens",
       "[camera]\nposition = [0, 0, -5]\nlook_at = [0, 0, 0]\nlens_radius = -1\n" + materials,
       ":4:15: camera.lens_radius: must not be negative"},
      {"camera-nan", "[camera]\nposition = [0, nan, -5]\nlook_at = [0, 0, 0]\n" + materials,
       ":2:16: camera.position: expected a finite number, got nan"},
  });
}

TEST(SceneTomlGeometry, MeshesAndSpheres) {
  auto sphere = [](const std::string& center, const std::string& radius) {
    return kCamera + "[[spheres]]\ncenter = " + center + "\nradius = " + radius +
           "\nmaterial = \"white\"\n";
  };
  std::ofstream(testDir() / "inf.obj") << "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n";
  std::ofstream(testDir() / "flat.obj") << "v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n";
  expectRefusals({
      {"mesh-flat", kCamera + R"([[meshes]]
name = "line"
material = "white"
vertices = [[0, 0, 0], [1, 1, 1], [2, 2, 2]]
faces = [[0, 1, 2]]
)",
       ":9:12: mesh 'line': no triangle has a non-zero area"},
      {"mesh-file-flat",
       kCamera + "[[meshes]]\nname = \"f\"\nmaterial = \"white\"\nfile = \"flat.obj\"\n",
       ":9:8: mesh 'f': no triangle has a non-zero area"},
      {"mesh-file-inf",
       kCamera + "[[meshes]]\nname = \"i\"\nmaterial = \"white\"\nfile = \"inf.obj\"\n",
       ":9:8: mesh 'i': vertex 1 has a non-finite position"},
      {"mesh-scale-zero", kCamera + kTriangle + "scale = [1, 0, 1]\n",
       ":12:9: mesh 't'.scale: makes a degenerate transform"},
      {"mesh-translate-inf", kCamera + R"([[meshes]]
name = "far"
material = "white"
vertices = [[3e38, 0, 0], [3e38, 1, 0], [3e38, 0, 1]]
faces = [[0, 1, 2]]
translate = [3e38, 0, 0]
)",
       ":11:13: mesh 'far': the transform moves its vertices beyond the float range"},
      {"instance-scale", kCamera + kTriangle + "[[instances]]\nmesh = \"t\"\nscale = 1e20\n",
       ":14:9: instance of 't'.scale: makes a degenerate transform"},
      {"sphere-tiny", sphere("[1e30, 0, 0]", "1"),
       ":8:10: sphere 'sphere'.radius: 1 is below float precision at its center"},
      {"sphere-huge", sphere("[3e38, 0, 0]", "1e38"),
       ":8:10: sphere 'sphere': center ± radius leaves the float range"},
  });
}

TEST(SceneTomlGeometry, ParticlesFromFiles) {
  auto records = [](const std::string& name, std::vector<float> values) {
    std::ofstream(testDir() / name, std::ios::binary)
        .write(reinterpret_cast<const char*>(values.data()),
               static_cast<std::streamsize>(values.size() * sizeof(float)));
  };
  const float inf = INFINITY, nan = NAN;
  records("zero-radius.xyzr", {0, 0, 0, 0.1f, 1, 1, 1, 0});
  records("inf-radius.xyzr", {0, 0, 0, inf});
  records("nan-attribute.xyza", {0, 0, 0, 1, 1, 1, 1, nan});
  records("far.xyz", {1e30f, 0, 0});
  auto scene = [&](const std::string& file, const std::string& layout, const std::string& extra) {
    return kCamera + "[[particles]]\nname = \"p\"\nmaterial = \"white\"\nfile = \"" + file +
           "\"\nlayout = \"" + layout + "\"\n" + extra;
  };
  expectRefusals({
      {"particles-zero", scene("zero-radius.xyzr", "xyzr", ""),
       ":9:8: particles 'p': every radius must be positive and finite, not 0"},
      {"particles-inf", scene("inf-radius.xyzr", "xyzr", ""),
       ":9:8: particles 'p': every radius must be positive and finite, not inf"},
      {"particles-nan", scene("nan-attribute.xyza", "xyza", "radius = 0.1\n"),
       ":11:10: particles 'p': the attribute of particle 1 is not finite"},
      {"particles-tiny", scene("far.xyz", "xyz", "radius = 0.5\n"),
       ":11:10: particles 'p': the radius of particle 0, 0.5, is below float precision"},
      {"particles-size", kCamera + R"([[particles]]
name = "g"
material = "white"
generator = "clusters"
count = 1000
center = [3e38, 0, 0]
size = 3e38
)",
       ":6:1: particles 'g': particle "},
  });
}

TEST(SceneTomlGeometry, VolumesFloatCannotPlace) {
  const std::string w = kCamera + "[[volumes]]\nname = \"w\"\nsource = \"wavelet\"\n";  // to 8
  expectRefusals({
      {"volume-precision", w + "origin = [1e30, 0, 0]\nspacing = 1e-30\n",
       ":10:11: volume 'w'.spacing: along x, 1e-30, is below float precision at the grid's "
       "coordinates"},
      {"volume-origin", w + "origin = [1e30, 0, 0]\n",
       ":9:10: volume 'w'.spacing: along x, 0.1, is below float precision"},
      {"volume-overflow", w + "dims = [4096, 2, 2]\nspacing = 1e35\n",
       ":10:11: volume 'w'.spacing: along x: the grid's far corner, origin + spacing (dims - 1) "
       "= "},
      {"volume-denormal", w + "spacing = 1e-40\n",
       ":9:11: volume 'w'.spacing: along x, 9.99995e-41, must be a positive normal float"},
      {"volume-steps", w + "dims = [64, 64, 64]\nspacing = 1e-5\n[scivis]\nsampling_rate = 64\n",
       ":10:11: volume 'w'.spacing: the volumes are sampled every 1.5625e-07 world units"},
  });
  // Every volume reader calls the same check (GridGeometry::problem).
  GridGeometry g;
  g.dims = {4, 4, 4};
  g.spacing = Vec3{1e-39f};
  EXPECT_TRUE(contains(g.problem(), "must be a positive normal float")) << g.problem();
}

TEST(SceneTomlGeometry, LightsBeyondTheFloatRange) {
  expectRefusals({
      {"light-overflow", kCamera + kTriangle + R"([[lights]]
type = "ambient"
color = [3e38, 1, 1]
intensity = 10
)",
       ":15:13: light: color x intensity is beyond the float range"},
  });
}

// ---- scivis limits ----------------------------------------------------------------------------

TEST(SceneTomlSciVisLimits, ANinthVolumeIsRefusedWhereItIsDeclared) {
  std::string text = kCamera;
  for (int i = 0; i < 9; ++i)
    text += "[[volumes]]\nname = \"v" + std::to_string(i) + "\"\nsource = \"marschner-lobb\"\n";
  // Volume 9 starts on line 6 + 8 * 3.
  EXPECT_EQ(
      errorOf(writeScene("nine.toml", text)),
      "FILE:30:1: volumes: the scivis renderer draws at most 8 volumes, and this is volume 9");
  // Eight are fine; a description with nine made elsewhere is refused when the scene is built.
  SceneDesc d = loadSceneDesc(writeScene("eight.toml", text.substr(0, text.rfind("[[volumes]]"))));
  ASSERT_EQ(sciVisDesc(d).volumes.size(), SciVisScene::kMaxVolumes);
  sciVisDesc(d).volumes.push_back(sciVisDesc(d).volumes.back());
  const auto desc = std::make_shared<const SceneDesc>(d);
  try {
    SciVisScene scene(desc, BrickContent{});
    ADD_FAILURE() << "nine volumes accepted";
  } catch (const base::Error& e) {
    EXPECT_STREQ(e.what(), "the scene has 9 volumes; the scivis renderer draws at most 8");
  }
}

}  // namespace
}  // namespace renderers::scivis
