#pragma once
// Scene files in TOML (configs/scenes/cornell.toml shows every field). Every problem is a
// base::Error reading "FILE:LINE: what is wrong", naming the field, e.g.
//   configs/x.toml:12: material 'foo' of mesh 'bunny' is not defined
#include <string>

#include "renderers/SceneDesc.h"

namespace renderers {

// Mesh files named in the scene are read relative to the scene file's folder.
SceneDesc readSceneToml(const std::string& path);

}  // namespace renderers
