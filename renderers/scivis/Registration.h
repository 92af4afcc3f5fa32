#pragma once
// The scivis renderer's place in the core, which does not include it: the renderer "scivis"
// (RendererRegistry.h; its scene built whole, as one brick), the scene file's scivis parts
// (SceneSections.h: volumes, isosurfaces, particles, lights and [scivis], SciVisToml.h, read
// into SceneDesc::extensions: io/SciVisDesc.h) and the built-in scenes wavelet and particles
// (BuiltinScenes.h).
// A program calls registerSciVis() once at its start, before it reads a scene (dfbwall's main,
// the benchmarks, the tests); calling it again does nothing.
#include "renderers/RenderScene.h"

namespace renderers::scivis {

class SciVisScene;

void registerSciVis();

// The scivis scene buildRenderScene made for the renderer "scivis", or null when `scene` was
// built for another renderer or distributed.
const SciVisScene* findSciVisScene(const RenderScene& scene);
// findSciVisScene(), or base::Error when there is none.
const SciVisScene& sciVisScene(const RenderScene& scene);

}  // namespace renderers::scivis
