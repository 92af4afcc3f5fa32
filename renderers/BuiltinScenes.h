#pragma once
// Scenes compiled in, selectable as "builtin:NAME".
//  - cornell: the measured Cornell box (graphics.cornell.edu/online/box/data.html), the same
//    geometry, reflectances, light and camera as pbrt-v4's and Mitsuba's cornell-box scenes.
//  - spheres: a few thousand spheres of mixed materials on a floor under an area light and a
//    sky gradient; glass and metal crowd one side, so tile costs differ a lot (load balancing).
#include <cstddef>
#include <string>
#include <vector>

#include "renderers/SceneDesc.h"

namespace renderers {

SceneDesc cornellBox();
SceneDesc manySpheres(int countX = 60, int countZ = 50);
// For the scivis renderer: VTK's wavelet field (resolution³ voxels over [-1, 1]³) as a faint
// cool-warm volume with a glassy and an opaque isosurface.
SceneDesc waveletScene(int resolution = 160);
// For the scivis renderer: `count` spheres clustered like a cosmology run's halos, coloured by
// density (viridis).
SceneDesc particleScene(std::size_t count = 1'000'000);

std::vector<std::string> builtinSceneNames();
// "builtin:NAME" → that scene; anything else is a TOML file path (SceneToml.h).
// Throws base::Error, listing the built-in names for an unknown one.
SceneDesc loadSceneDesc(const std::string& spec);

}  // namespace renderers
