#pragma once
// The scene as a renderer needs it, built once per rank: the path tracer's BVH for the surface
// renderers, or the scivis scene (volumes, isosurfaces, particles, meshes) for "scivis".
#include <memory>
#include <string>

#include "renderers/Renderer.h"
#include "renderers/Scene.h"

namespace renderers {

// renderers/scivis/scene/SciVisScene.h: made by the scivis renderer's registration
// (renderers/scivis/Registration.h), which the core does not include.
class SciVisScene;

struct RenderScene {
  std::shared_ptr<const SceneDesc> desc;
  std::shared_ptr<const Scene> surfaces;      // pathtracer, primary, pattern
  std::shared_ptr<const SciVisScene> scivis;  // scivis
};

// Builds what `renderer` draws from `desc` (the whole scene); with `distributed` only the
// description (the bricks load their own parts: scivis/bricks/BrickFrameDriver.h). Throws
// base::Error.
RenderScene buildRenderScene(const std::string& renderer, SceneDesc desc, bool distributed = false);

// Any renderer by name: "pathtracer", "primary", "pattern" or a registered one
// (RendererRegistry.h: "scivis"). `scene` must outlive it.
std::unique_ptr<Renderer> makeRenderer(const std::string& name, const RenderScene& scene,
                                       const RenderSettings& settings);

}  // namespace renderers
