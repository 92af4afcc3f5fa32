#include "renderers/Renderer.h"

#include <pmmintrin.h>
#include <xmmintrin.h>

#include <cmath>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include "base/Error.h"
#include "base/MemoryBudget.h"
#include "renderers/PathTracer.h"
#include "renderers/PatternRenderer.h"
#include "renderers/PrimaryRenderer.h"
#include "renderers/RenderScene.h"
#include "renderers/RendererRegistry.h"

namespace renderers {
namespace {

// "a, b or c".
std::string listed(const std::vector<std::string>& names) {
  std::string text;
  for (std::size_t i = 0; i < names.size(); ++i)
    text += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
  return text;
}

// "pathtracer, primary, pattern or ...": the core's renderers and the registered ones.
std::string rendererChoices() {
  std::vector<std::string> names{"pathtracer", "primary", "pattern"};
  for (std::string& name : registeredRenderers()) names.push_back(std::move(name));
  return listed(names);
}

}  // namespace

std::unique_ptr<Renderer> makeRenderer(const std::string& name, const Scene& scene,
                                       const RenderSettings& settings) {
  if (settings.width <= 0 || settings.height <= 0)
    throw base::Error("renderer: canvas size must be positive");
  if (name == "pathtracer") return std::make_unique<PathTracer>(scene, settings);
  if (name == "primary") return std::make_unique<PrimaryRenderer>(scene, settings);
  if (name == "pattern") return std::make_unique<PatternRenderer>(settings);
  if (findRenderer(name))
    throw base::Error("the " + name + " renderer draws a " + name +
                      " scene: build it with buildRenderScene");
  throw base::Error("unknown renderer '" + name + "' (choose " + rendererChoices() + ")");
}

namespace {

RenderScene buildScene(const std::string& renderer, SceneDesc desc, bool distributed) {
  RenderScene out;
  out.desc = std::make_shared<const SceneDesc>(std::move(desc));
  out.renderer = renderer;
  if (distributed) return out;
  if (const RendererFactory* registered = findRenderer(renderer)) {
    registered->build(out);
  } else if (renderer != "pattern") {
    if (out.desc->instances.empty()) {
      const std::vector<std::string> others = out.desc->extensions.drawnBy();
      throw base::Error(
          "renderer " + renderer + " draws meshes and spheres, and the scene has none" +
          (others.empty() ? std::string()
                          : " (what it has is drawn by --renderer " + listed(others) + ")"));
    }
    out.surfaces = std::make_shared<const Scene>(*out.desc);
  }
  return out;
}

}  // namespace

RenderScene buildRenderScene(const std::string& renderer, SceneDesc desc, bool distributed) {
  try {
    return buildScene(renderer, std::move(desc), distributed);
  } catch (const std::bad_alloc&) {
    throw base::Error(
        "building the scene for the " + renderer +
        " renderer (its volumes and bounding volume hierarchies): out of memory; this "
        "rank may hold " +
        base::memoryLimitText());
  }
}

std::unique_ptr<Renderer> makeRenderer(const std::string& name, const RenderScene& scene,
                                       const RenderSettings& settings) {
  if (const RendererFactory* registered = findRenderer(name)) {
    if (settings.width <= 0 || settings.height <= 0)
      throw base::Error("renderer: canvas size must be positive");
    return registered->make(scene, settings);
  }
  if (name == "pattern") return std::make_unique<PatternRenderer>(settings);
  if (!scene.surfaces)
    throw base::Error("renderer " + name + ": the scene was built for " + scene.renderer);
  return makeRenderer(name, *scene.surfaces, settings);
}

void prepareTile(const dfb::Region& region, std::uint32_t accumulationId, std::uint32_t firstSample,
                 std::uint32_t samples, dfb::Tile& out) {
  // Not Tile::reset: this must not need more of dfb than its headers.
  out.region = region;
  out.generation = 0;
  out.children = 0;
  out.accumulationId = accumulationId;
  out.sequence = firstSample;
  out.weight = samples;
  out.color.assign(4 * static_cast<std::size_t>(region.pixelCount()), 0.0f);
  out.depth.clear();
  out.normal.clear();
  out.albedo.clear();
}

void enableFlushToZero() {
  _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
  _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
}

}  // namespace renderers
