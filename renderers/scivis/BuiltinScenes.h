#pragma once
// The scivis renderer's built-in scenes, selectable as "builtin:NAME" once registered
// (Registration.h; renderers/BuiltinScenes.h has the core's).
//  - wavelet: VTK's wavelet field (resolution³ voxels over [-1, 1]³) as a faint cool-warm
//    volume with a glassy and an opaque isosurface.
//  - particles: `count` spheres clustered like a cosmology run's halos, coloured by density
//    (viridis).
#include <cstddef>

#include "renderers/SceneDesc.h"

namespace renderers::scivis {

SceneDesc waveletScene(int resolution = 160);
SceneDesc particleScene(std::size_t count = 1'000'000);

}  // namespace renderers::scivis
