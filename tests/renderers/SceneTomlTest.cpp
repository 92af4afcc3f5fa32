#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "base/Error.h"
#include "renderers/BuiltinScenes.h"
#include "renderers/MeshImport.h"
#include "renderers/Scene.h"
#include "renderers/SceneToml.h"
#include "tests/DiagnosticsTestUtil.h"
#include "tests/renderers/RenderTestUtil.h"

namespace renderers {
namespace {

namespace fs = std::filesystem;

std::string writeFile(const std::string& name, const std::string& text) {
  const fs::path dir = fs::path(::testing::TempDir()) / "dfbwall-scene-tests";
  fs::create_directories(dir);
  const fs::path p = dir / name;
  std::ofstream(p) << text;
  return p.string();
}

// The problems loading `spec` gives, one headline each (DiagnosticsTestUtil.h).
std::string errorOf(const std::string& spec) {
  try {
    loadSceneDesc(spec);
  } catch (const base::Error& e) {
    return testutil::headlines(e.what());
  }
  return "(no error)";
}

const char* kHeader = R"(
[camera]
position = [0, 0, -5]
look_at = [0, 0, 0]

[materials.white]
type = "diffuse"
color = [0.8, 0.8, 0.8]
)";

TEST(SceneToml, MissingFileNamesTheFile) {
  EXPECT_EQ(errorOf("/nonexistent/scene.toml"), "/nonexistent/scene.toml: scene file not found");
}

TEST(SceneToml, UnknownMaterialGivesFileLineAndField) {
  const std::string path = writeFile("unknown-material.toml", std::string(kHeader) + R"(
[[meshes]]
name = "bunny"
vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
faces = [[0, 1, 2]]
material = "foo"
)");
  // kHeader is 8 lines with its leading newline, the [[meshes]] block starts on line 10.
  EXPECT_EQ(errorOf(path), path + ":14:12: mesh 'bunny'.material: material 'foo' is not defined");
}

TEST(SceneToml, BadFieldTypeGivesFileLineAndField) {
  const std::string path = writeFile("bad-type.toml", R"([camera]
position = [0, 0, -5]
look_at = [0, 0, 0]
fov = "wide"
)");
  EXPECT_EQ(errorOf(path), path + ":4:7: camera.fov: expected a number, got a string");
  const std::string vec = writeFile("bad-vector.toml", R"([camera]
position = [0, 0]
look_at = [0, 0, 0]
)");
  EXPECT_EQ(errorOf(vec),
            vec + ":2:12: camera.position: expected [x, y, z] (3 numbers), got 2 elements");
}

TEST(SceneToml, SyntaxErrorsMissingAndUnknownFields) {
  const std::string syntax = writeFile("syntax.toml", "[camera]\nposition = [0, 0, -5\n");
  EXPECT_EQ(errorOf(syntax).rfind(syntax + ":", 0), 0u) << errorOf(syntax);
  const std::string missing = writeFile("missing.toml", "[camera]\nposition = [0, 0, -5]\n");
  EXPECT_EQ(errorOf(missing), missing + ":1:1: camera.look_at: missing");
  const std::string unknown =
      writeFile("unknown-field.toml", std::string(kHeader) + "colour = 1\n");
  EXPECT_EQ(errorOf(unknown), unknown +
                                  ":9:1: material 'white': unknown field 'colour' (did you mean "
                                  "'color'?); known fields: type, color, emission, roughness, ior, "
                                  "opacity, specular, shininess");
  const std::string index = writeFile("bad-index.toml", std::string(kHeader) + R"(
[[meshes]]
name = "tri"
material = "white"
vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
faces = [[0, 1, 3]]
)");
  EXPECT_EQ(errorOf(index), index + ":14:17: mesh 'tri'.faces: vertex 3 does not exist");
}

TEST(SceneToml, UnknownBuiltinListsTheChoices) {
  EXPECT_EQ(errorOf("builtin:teapot"),
            "unknown built-in scene 'teapot' (choose cornell, spheres, wavelet, particles)");
}

TEST(SceneToml, CornellTomlEqualsTheBuiltin) {
  const SceneDesc file = readSceneToml(DFBWALL_SOURCE_DIR "/configs/scenes/cornell.toml");
  const SceneDesc builtin = cornellBox();
  ASSERT_EQ(file.instances.size(), builtin.instances.size());
  for (std::size_t i = 0; i < builtin.instances.size(); ++i) {
    const Shape& a = file.shapes[file.instances[i].shape];
    const Shape& b = builtin.shapes[builtin.instances[i].shape];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.mesh.positions, b.mesh.positions) << a.name;
    EXPECT_EQ(a.mesh.triangles, b.mesh.triangles) << a.name;
    const Material& ma = file.materials[file.instances[i].material];
    const Material& mb = builtin.materials[builtin.instances[i].material];
    EXPECT_EQ(ma.name, mb.name);
    EXPECT_EQ(ma.type, mb.type);
    EXPECT_EQ(ma.color, mb.color) << ma.name;
    EXPECT_EQ(ma.emission, mb.emission) << ma.name;
  }
  EXPECT_EQ(file.camera.position, builtin.camera.position);
  EXPECT_EQ(file.camera.lookAt, builtin.camera.lookAt);
  EXPECT_EQ(file.camera.fovY, builtin.camera.fovY);
}

TEST(SceneToml, MeshFilesThroughAssimpWithInstancesAndTransforms) {
  // A unit square as OBJ (two triangles) and a tetrahedron as OFF, read relative to the scene.
  writeFile("square.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
  writeFile("tetra.off",
            "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  const std::string path = writeFile("with-files.toml", std::string(kHeader) + R"(
[materials.glow]
type = "emissive"
emission = [1, 1, 1]

[[meshes]]
name = "square"
file = "square.obj"
material = "glow"
scale = 2
translate = [10, 0, 0]

[[meshes]]
name = "tetra"
file = "tetra.off"
material = "white"

[[instances]]
mesh = "square"
material = "white"
rotate = [0, 1, 0, 90]

[[spheres]]
name = "ball"
center = [0, 3, 0]
radius = 0.5
material = "white"
)");
  const SceneDesc d = readSceneToml(path);
  ASSERT_EQ(d.shapes.size(), 3u);
  EXPECT_EQ(d.shapes[0].mesh.triangles.size(), 2u);
  EXPECT_EQ(d.shapes[1].mesh.triangles.size(), 4u);
  ASSERT_EQ(d.instances.size(), 4u);
  const Scene scene(d);
  EXPECT_EQ(scene.lightCount(), 2);  // the first square glows, its instance does not
  Hit hit;
  ASSERT_TRUE(scene.intersect({11, 1, -5}, {0, 0, 1}, 0, 1e9f, hit));  // scaled and moved
  EXPECT_EQ(hit.material->name, "glow");
  EXPECT_NEAR(hit.t, 5.0f, 1e-4f);
  ASSERT_TRUE(scene.intersect({-5, 0.5f, 0.5f}, {1, 0, 0}, 0, 1e9f, hit));  // the rotated copy
  EXPECT_EQ(hit.material->name, "white");
  EXPECT_NEAR(std::abs(hit.normal.x), 1.0f, 1e-5f);
  ASSERT_TRUE(scene.intersect({0, 3, -5}, {0, 0, 1}, 0, 1e9f, hit));
  EXPECT_NEAR(hit.t, 4.5f, 1e-4f);

  const std::string broken = writeFile("broken-file.toml", std::string(kHeader) + R"(
[[meshes]]
name = "nothing"
file = "does-not-exist.obj"
material = "white"
)");
  const std::string e = errorOf(broken);
  EXPECT_EQ(e.rfind(broken + ":12:8: mesh 'nothing'.file: ", 0), 0u) << e;
}

TEST(SceneToml, StanfordBunnyFromCgal) {
  const std::string bunny = test::cgalBunny();
  ASSERT_FALSE(bunny.empty()) << "libcgal-demo is not installed (scripts/setup installs it)";
  const TriangleMesh m = importMesh(bunny);
  EXPECT_GT(m.triangles.size(), 50000u);
}

}  // namespace
}  // namespace renderers
