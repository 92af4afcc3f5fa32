#pragma once
// The scene as a renderer needs it, built once per rank: the path tracer's BVH for the core's
// surface renderers, or what a registered renderer builds for itself (RendererRegistry.h).
#include <memory>
#include <string>

#include "renderers/Renderer.h"
#include "renderers/RendererScene.h"
#include "renderers/Scene.h"

namespace renderers {

struct RenderScene {
  std::shared_ptr<const SceneDesc> desc;
  std::string renderer;                             // the renderer it was built for
  std::shared_ptr<const Scene> surfaces;            // pathtracer, primary, pattern
  std::shared_ptr<const RendererScene> registered;  // a registered renderer's own
};

// Builds what `renderer` draws from `desc` (the whole scene); with `distributed` only the
// description (a renderer driving bricks loads its own parts). Throws base::Error.
RenderScene buildRenderScene(const std::string& renderer, SceneDesc desc, bool distributed = false);

// Any renderer by name: "pathtracer", "primary", "pattern" or a registered one
// (RendererRegistry.h). `scene` must outlive it.
std::unique_ptr<Renderer> makeRenderer(const std::string& name, const RenderScene& scene,
                                       const RenderSettings& settings);

}  // namespace renderers
