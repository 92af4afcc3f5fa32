// Writes a scene's triangle meshes, instance transforms applied, as Wavefront OBJ + MTL, so
// Embree's tutorial path tracer can render the same geometry (figure 6 of scripts/bench).
// Diffuse albedo goes to Kd; emission has no OBJ field Embree's tutorial reads, so lights are
// given on its command line instead (scripts/bench does that). Spheres are skipped.
//   scene_to_obj SCENE OUT.obj   (prints the camera as Embree options on stdout)
#include <cstdio>
#include <stdexcept>
#include <string>

#include "renderers/BuiltinScenes.h"
#include "renderers/scivis/Registration.h"

int main(int argc, char** argv) {
  renderers::scivis::registerSciVis();  // scenes may have volumes, isosurfaces and particles
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s SCENE OUT.obj\n", argv[0]);
    return 2;
  }
  try {
    const renderers::SceneDesc scene = renderers::loadSceneDesc(argv[1]);
    const std::string obj = argv[2], mtl = obj.substr(0, obj.size() - 4) + ".mtl";
    FILE* m = std::fopen(mtl.c_str(), "w");
    FILE* o = std::fopen(obj.c_str(), "w");
    if (!m || !o) throw std::runtime_error("cannot write " + obj);
    for (const renderers::Material& material : scene.materials)
      std::fprintf(m, "newmtl %s\nKd %g %g %g\n\n", material.name.c_str(), material.color.x,
                   material.color.y, material.color.z);
    const std::string mtlName = mtl.substr(mtl.find_last_of('/') + 1);
    std::fprintf(o, "mtllib %s\n", mtlName.c_str());
    std::size_t base = 1;
    for (const renderers::Instance& instance : scene.instances) {
      const renderers::Shape& shape = scene.shapes[instance.shape];
      if (shape.isSpheres()) continue;
      std::fprintf(o, "o %s\nusemtl %s\n", shape.name.c_str(),
                   scene.materials[instance.material].name.c_str());
      for (const renderers::Vec3& p : shape.mesh.positions) {
        const renderers::Vec3 w = instance.transform.point(p);
        std::fprintf(o, "v %g %g %g\n", w.x, w.y, w.z);
      }
      for (const auto& t : shape.mesh.triangles)
        std::fprintf(o, "f %zu %zu %zu\n", base + t[0], base + t[1], base + t[2]);
      base += shape.mesh.positions.size();
    }
    std::fclose(m);
    std::fclose(o);
    const renderers::CameraDesc& c = scene.camera;
    std::printf("--vp %g %g %g --vi %g %g %g --vu %g %g %g --fov %g\n", c.position.x, c.position.y,
                c.position.z, c.lookAt.x, c.lookAt.y, c.lookAt.z, c.up.x, c.up.y, c.up.z, c.fovY);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
