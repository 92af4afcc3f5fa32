#pragma once
// Scenes compiled in, selectable as "builtin:NAME".
//  - cornell: the measured Cornell box (graphics.cornell.edu/online/box/data.html), the same
//    geometry, reflectances, light and camera as pbrt-v4's and Mitsuba's cornell-box scenes.
//  - spheres: a few thousand spheres of mixed materials on a floor under an area light and a
//    sky gradient; glass and metal crowd one side, so tile costs differ a lot (load balancing).
// A renderer kept in a folder of its own registers its own from the program's start (the
// scivis renderer: renderers/scivis/BuiltinScenes.h).
#include <functional>
#include <string>
#include <vector>

#include "renderers/SceneDesc.h"

namespace renderers {

SceneDesc cornellBox();
SceneDesc manySpheres(int countX = 60, int countZ = 50);

// Registers the built-in scene `name`, replacing one registered under that name before.
// Thread-safe.
void registerBuiltinScene(const std::string& name, std::function<SceneDesc()> make);
// The core's names, then the registered ones in the order they were first registered.
std::vector<std::string> builtinSceneNames();
// "builtin:NAME" → that scene; anything else is a TOML file path (SceneToml.h).
// Throws base::Error, listing the built-in names for an unknown one.
SceneDesc loadSceneDesc(const std::string& spec);

}  // namespace renderers
