#include "renderers/MeshImport.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <assimp/Importer.hpp>

#include <string>

#include "base/Error.h"
#include "base/MemoryBudget.h"

namespace renderers {

TriangleMesh importMesh(const std::string& path) {
  Assimp::Importer importer;
  // Points and lines are of no use to a ray tracer; dropping them keeps every face a triangle.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* scene =
      importer.ReadFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                  aiProcess_PreTransformVertices | aiProcess_SortByPType);
  if (!scene || !scene->mRootNode) {
    // Assimp catches what its readers throw and keeps only the text: a failed allocation
    // would reach the user as a bare "std::bad_alloc".
    const std::string why = importer.GetErrorString();
    if (why.find("bad_alloc") != std::string::npos)
      throw base::Error(path + ": out of memory while importing it; this rank may hold " +
                        base::memoryLimitText());
    throw base::Error(path + ": " + why);
  }
  TriangleMesh out;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    const auto base = static_cast<std::uint32_t>(out.positions.size());
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      out.positions.push_back({p.x, p.y, p.z});
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;
      out.triangles.push_back(
          {base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]});
    }
  }
  if (out.triangles.empty()) throw base::Error(path + ": no triangles in the file");
  return out;
}

}  // namespace renderers
