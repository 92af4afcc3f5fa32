// The core holds the scivis renderer's parts of a scene and what it builds without knowing their
// types: a description's "scivis" extension is copied deeply and counted in its input files and
// bytes; the renderer's scene and built-in scenes come through the registries, and the core's
// errors name the renderer from them.
#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "base/Error.h"
#include "renderers/BuiltinScenes.h"
#include "renderers/RenderScene.h"
#include "renderers/scivis/BuiltinScenes.h"
#include "renderers/scivis/Registration.h"
#include "renderers/scivis/io/SciVisDesc.h"
#include "renderers/scivis/scene/SciVisScene.h"

namespace renderers::scivis {
namespace {

TEST(SceneExtension, ACopiedDescriptionHoldsItsOwnScivisParts) {
  SceneDesc a;
  sciVisDesc(a).volumes.push_back({});
  sciVisDesc(a).volumes[0].name = "a";
  SceneDesc b = a;
  sciVisDesc(b).volumes[0].name = "b";
  EXPECT_EQ(sciVisDesc(std::as_const(a)).volumes[0].name, "a");
  EXPECT_EQ(sciVisDesc(std::as_const(b)).volumes[0].name, "b");
  b = a;
  EXPECT_EQ(sciVisDesc(std::as_const(b)).volumes[0].name, "a");
}

TEST(SceneExtension, ItsFilesAndBytesCountInTheDescription) {
  SceneDesc d;
  Shape mesh;
  mesh.file = "m.obj";
  d.shapes.push_back(mesh);
  ParticlesDesc p;
  p.file = "p.raw";
  p.centers = {Vec3{0.0f}, Vec3{1.0f}};
  p.radii = {0.5f};
  sciVisDesc(d).particles.push_back(p);
  VolumeDesc v;
  v.source.kind = VolumeSource::Kind::RawFile;
  v.source.raw.path = "v.raw";
  sciVisDesc(d).volumes.push_back(v);
  EXPECT_EQ(d.inputFiles(), (std::vector<std::string>{"m.obj", "p.raw", "v.raw"}));
  EXPECT_EQ(d.bytes(), mesh.bytes() + p.bytes());
  EXPECT_EQ(d.extensions.drawnBy(), std::vector<std::string>{"scivis"});
}

TEST(SceneExtension, ADescriptionWithoutScivisPartsReadsAsEmpty) {
  const SceneDesc d = cornellBox();
  EXPECT_EQ(d.extensions.find(kSciVisName), nullptr);
  EXPECT_TRUE(sciVisDesc(d).empty());
  EXPECT_TRUE(d.extensions.drawnBy().empty());
}

TEST(RendererScene, TheScivisSceneComesBackOnlyFromAScivisBuild) {
  const RenderScene scivis = buildRenderScene("scivis", waveletScene(16));
  EXPECT_NE(findSciVisScene(scivis), nullptr);
  EXPECT_EQ(sciVisScene(scivis).sciVis().volumes.size(), 1u);
  const RenderScene cornell = buildRenderScene("pathtracer", cornellBox());
  EXPECT_EQ(findSciVisScene(cornell), nullptr);
  EXPECT_THROW(sciVisScene(cornell), base::Error);
}

TEST(RendererScene, TheCoreNamesTheRendererOfAScenesPartsFromTheRegistries) {
  try {
    buildRenderScene("pathtracer", waveletScene(16));
    FAIL() << "a volume scene was built for the path tracer";
  } catch (const base::Error& e) {
    EXPECT_NE(std::string(e.what()).find("drawn by --renderer scivis"), std::string::npos)
        << e.what();
  }
  const RenderScene scivis = buildRenderScene("scivis", waveletScene(16));
  RenderSettings settings;
  settings.width = settings.height = 8;
  try {
    makeRenderer("primary", scivis, settings);
    FAIL() << "a primary renderer was made of a scivis scene";
  } catch (const base::Error& e) {
    EXPECT_NE(std::string(e.what()).find("the scene was built for scivis"), std::string::npos)
        << e.what();
  }
}

TEST(BuiltinScenes, TheScivisScenesAreRegisteredAfterTheCores) {
  EXPECT_EQ(builtinSceneNames(),
            (std::vector<std::string>{"cornell", "spheres", "wavelet", "particles"}));
  EXPECT_EQ(sciVisDesc(loadSceneDesc("builtin:wavelet")).volumes.size(), 1u);
  try {
    loadSceneDesc("builtin:nothing");
    FAIL() << "an unknown built-in scene was loaded";
  } catch (const base::Error& e) {
    EXPECT_NE(std::string(e.what()).find("cornell, spheres, wavelet, particles"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace renderers::scivis
