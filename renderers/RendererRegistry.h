#pragma once
// Renderers by name beyond the core's own (pathtracer, primary, pattern). A renderer kept in a
// folder of its own registers how it builds what it draws and how it is made, once, from the
// program's start (renderers/scivis/Registration.h), so the core never includes it;
// buildRenderScene and makeRenderer (RenderScene.h) look it up by name.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "renderers/RenderScene.h"

namespace renderers {

struct RendererFactory {
  // Builds what the renderer draws from scene.desc, the whole scene (not called for a
  // distributed scene, whose bricks load their own parts). Throws base::Error.
  std::function<void(RenderScene& scene)> build;
  // The renderer of a scene `build` made (the canvas size is checked before). Throws
  // base::Error.
  std::function<std::unique_ptr<Renderer>(const RenderScene& scene, const RenderSettings& settings)>
      make;
};

// Registers the renderer called `name`, replacing one registered under that name before.
// Thread-safe.
void registerRenderer(const std::string& name, RendererFactory factory);
// The renderer registered as `name`, or null. Thread-safe; the pointer stays valid.
const RendererFactory* findRenderer(const std::string& name);
// The registered names, in the order they were first registered.
std::vector<std::string> registeredRenderers();

}  // namespace renderers
