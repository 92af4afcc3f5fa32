#pragma once
// The scivis renderer's place in the core, which does not include it: the renderer "scivis"
// (RendererRegistry.h; its scene built whole, as one brick) and the scene file's scivis parts
// (SceneSections.h: volumes, isosurfaces, particles, lights and [scivis], SciVisToml.h).
// A program calls registerSciVis() once at its start, before it reads a scene (dfbwall's main,
// the benchmarks, the tests); calling it again does nothing.
namespace renderers {

void registerSciVis();

}  // namespace renderers
