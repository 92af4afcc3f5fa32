#include "renderers/scivis/Registration.h"

#include <memory>
#include <mutex>
#include <utility>

#include "base/Error.h"
#include "renderers/RendererRegistry.h"
#include "renderers/SceneSections.h"
#include "renderers/scivis/SciVisToml.h"
#include "renderers/scivis/bricks/Bricks.h"
#include "renderers/scivis/render/SciVisRenderer.h"
#include "renderers/scivis/scene/SciVisScene.h"

namespace renderers {

void registerSciVis() {
  static std::once_flag once;
  std::call_once(once, [] {
    RendererFactory scivis;
    scivis.build = [](RenderScene& scene) {
      scene.scivis = std::make_shared<const SciVisScene>(scene.desc, wholeScene(*scene.desc));
    };
    scivis.make = [](const RenderScene& scene,
                     const RenderSettings& settings) -> std::unique_ptr<Renderer> {
      if (!scene.scivis) throw base::Error("renderer scivis: the scene was not built for it");
      return std::make_unique<SciVisRenderer>(*scene.scivis, settings);
    };
    registerRenderer("scivis", std::move(scivis));
    registerSceneSections(
        {{"volumes", "isosurfaces", "particles", "lights", "scivis"}, readSciVis});
  });
}

}  // namespace renderers
