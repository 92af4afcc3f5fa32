#include "renderers/scivis/Registration.h"

#include <memory>
#include <mutex>
#include <utility>

#include "base/Error.h"
#include "renderers/BuiltinScenes.h"
#include "renderers/RendererRegistry.h"
#include "renderers/SceneSections.h"
#include "renderers/scivis/BuiltinScenes.h"
#include "renderers/scivis/SciVisToml.h"
#include "renderers/scivis/bricks/BrickLoad.h"
#include "renderers/scivis/io/SciVisDesc.h"
#include "renderers/scivis/render/SciVisRenderer.h"
#include "renderers/scivis/scene/SciVisScene.h"

namespace renderers::scivis {

void registerSciVis() {
  static std::once_flag once;
  std::call_once(once, [] {
    RendererFactory scivis;
    scivis.build = [](RenderScene& scene) {
      scene.registered = std::make_shared<const SciVisScene>(scene.desc, wholeScene(*scene.desc));
    };
    scivis.make = [](const RenderScene& scene,
                     const RenderSettings& settings) -> std::unique_ptr<Renderer> {
      return std::make_unique<SciVisRenderer>(sciVisScene(scene), settings);
    };
    registerRenderer(kSciVisName, std::move(scivis));
    registerSceneSections({{"volumes", "isosurfaces", "particles", "lights", "scivis"},
                           "volumes or particles",
                           readSciVis});
    registerBuiltinScene("wavelet", [] { return waveletScene(); });
    registerBuiltinScene("particles", [] { return particleScene(); });
  });
}

const SciVisScene* findSciVisScene(const RenderScene& scene) {
  return dynamic_cast<const SciVisScene*>(scene.registered.get());
}

const SciVisScene& sciVisScene(const RenderScene& scene) {
  const SciVisScene* s = findSciVisScene(scene);
  if (!s) throw base::Error("renderer scivis: the scene was not built for it");
  return *s;
}

}  // namespace renderers::scivis
