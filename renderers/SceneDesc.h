#pragma once
// A scene as plain data: what SceneToml reads, BuiltinScenes make and Scene builds a BVH from;
// a registered renderer's parts of it (SceneExtension.h) ride along under the renderer's name.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "renderers/Camera.h"
#include "renderers/Material.h"
#include "renderers/Math.h"
#include "renderers/SceneExtension.h"

namespace renderers {

// What Embree's acceleration structure and its copy of a primitive (a triangle or a sphere)
// take, about, for the memory budget: BVH4 nodes and leaves, the vertex and index buffers.
constexpr std::uint64_t kBvhBytesPerPrimitive = 96;

struct TriangleMesh {
  std::vector<Vec3> positions;
  std::vector<std::array<std::uint32_t, 3>> triangles;  // counter-clockwise seen from the front
};

struct SphereSet {
  std::vector<Vec3> centers;
  std::vector<float> radii;
};

// Geometry in object space: a triangle mesh or a set of spheres (exactly one is non-empty).
struct Shape {
  std::string name;
  std::string file;  // the mesh file it was read from; empty when given inline
  TriangleMesh mesh;
  SphereSet spheres;
  // Optional material per primitive (indices into SceneDesc::materials); when empty the
  // instance's material applies to every primitive.
  std::vector<std::uint32_t> primitiveMaterials;
  bool isSpheres() const { return !spheres.centers.empty(); }
  std::uint64_t bytes() const {
    return mesh.positions.size() * sizeof(Vec3) +
           mesh.triangles.size() * sizeof(mesh.triangles[0]) +
           spheres.centers.size() * sizeof(Vec3) + spheres.radii.size() * sizeof(float) +
           primitiveMaterials.size() * sizeof(std::uint32_t);
  }
  std::size_t primitiveCount() const {
    return isSpheres() ? spheres.centers.size() : mesh.triangles.size();
  }
};

struct Instance {
  std::uint32_t shape = 0;
  Affine transform;
  std::uint32_t material = 0;
};

struct Environment {
  enum class Kind { Constant, Gradient };
  Kind kind = Kind::Constant;
  Vec3 color{};          // constant
  Vec3 bottom{}, top{};  // gradient over the world y direction, bottom (y=-1) to top (y=1)
  Vec3 radiance(Vec3 dir) const {
    if (kind == Kind::Constant) return color;
    const float t = 0.5f * (dir.y + 1.0f);
    return bottom * (1.0f - t) + top * t;
  }
};

struct SceneDesc {
  std::vector<Material> materials;
  std::vector<Shape> shapes;
  std::vector<Instance> instances;
  CameraDesc camera;
  Environment environment;

  // What registered renderers draw beyond the meshes and spheres above, by renderer name.
  SceneExtensions extensions;

  // Index of the material called `name`, or -1.
  int findMaterial(const std::string& name) const;
  // Every file the description refers to besides the scene file itself (meshes, then the
  // extensions' files): a cluster checks that every host reads the same bytes from them.
  std::vector<std::string> inputFiles() const;
  // The bytes its shapes and extensions hold (what the memory budget counts as read so far).
  std::uint64_t bytes() const;
};

}  // namespace renderers
