#pragma once
// Reads a triangle mesh from any format Assimp knows (OBJ, PLY, OFF, STL, glTF, ...): every mesh
// of the file, node transforms applied, polygons triangulated, merged into one TriangleMesh.
// Throws base::Error naming the file and Assimp's reason.
#include <string>

#include "renderers/SceneDesc.h"

namespace renderers {

TriangleMesh importMesh(const std::string& path);

}  // namespace renderers
