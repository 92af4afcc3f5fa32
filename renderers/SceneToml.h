#pragma once
// Scene files in TOML (configs/scenes/cornell.toml shows every field). The problems of a file
// are collected and thrown as one base::Error (base/TomlDiagnostics.h), each naming the place
// and the field and echoing the line, e.g.
//   configs/x.toml:12:12: mesh 'bunny'.material: material 'foo' is not defined
//      12 | material = "foo"
//         |            ^~~~~
#include <string>

#include "renderers/SceneDesc.h"

namespace renderers {

// Mesh files named in the scene are read relative to the scene file's folder.
SceneDesc readSceneToml(const std::string& path);

}  // namespace renderers
