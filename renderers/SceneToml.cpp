#include "renderers/SceneToml.h"

#include <toml++/toml.h>

#include <filesystem>
#include <initializer_list>
#include <string_view>

#include "renderers/Error.h"
#include "renderers/MeshImport.h"
#include "renderers/TomlReader.h"
#include "renderers/scivis/SciVisToml.h"

namespace renderers {
namespace {

void readCamera(const TomlReader& r, const toml::table& t, CameraDesc& c) {
  r.onlyKeys(t, "camera", {"position", "look_at", "up", "fov", "lens_radius", "focus_distance"});
  c.position = r.vec3(r.require(t, "position", "camera"), "camera.position");
  c.lookAt = r.vec3(r.require(t, "look_at", "camera"), "camera.look_at");
  c.up = r.vec3(t, "up", "camera", c.up);
  c.fovY = r.number(t, "fov", "camera", c.fovY);
  c.lensRadius = r.number(t, "lens_radius", "camera", 0.0f);
  c.focusDistance = r.number(t, "focus_distance", "camera", 0.0f);
  if (!(c.fovY > 0 && c.fovY < 180)) r.fail(*t.get("fov"), "camera.fov must be in (0, 180)");
}

void readEnvironment(const TomlReader& r, const toml::table& t, Environment& e) {
  r.onlyKeys(t, "environment", {"type", "color", "bottom", "top"});
  const std::string type =
      t.get("type") ? r.string(*t.get("type"), "environment.type") : "constant";
  if (type == "constant") {
    e.kind = Environment::Kind::Constant;
    e.color = r.vec3(t, "color", "environment", {});
  } else if (type == "gradient") {
    e.kind = Environment::Kind::Gradient;
    e.bottom = r.vec3(r.require(t, "bottom", "environment"), "environment.bottom");
    e.top = r.vec3(r.require(t, "top", "environment"), "environment.top");
  } else {
    r.fail(*t.get("type"), "environment.type must be \"constant\" or \"gradient\"");
  }
}

Material readMaterial(const TomlReader& r, const std::string& name, const toml::table& t) {
  const std::string what = "material '" + name + "'";
  r.onlyKeys(t, what,
             {"type", "color", "emission", "roughness", "ior", "opacity", "specular", "shininess"});
  Material m;
  m.name = name;
  const toml::node& typeNode = r.require(t, "type", what);
  const std::string type = r.string(typeNode, what + ".type");
  if (type == "diffuse")
    m.type = MaterialType::Diffuse;
  else if (type == "emissive")
    m.type = MaterialType::Emissive;
  else if (type == "metal")
    m.type = MaterialType::Metal;
  else if (type == "glass")
    m.type = MaterialType::Glass;
  else
    r.fail(typeNode, what + ".type must be diffuse, emissive, metal or glass");
  const Vec3 defaultColor = m.type == MaterialType::Glass      ? Vec3{1.0f}
                            : m.type == MaterialType::Emissive ? Vec3{0.0f}
                                                               : m.color;
  m.color = r.vec3(t, "color", what, defaultColor);
  m.emission = r.vec3(t, "emission", what, {});
  m.roughness = r.number(t, "roughness", what, 0.0f);
  m.ior = r.number(t, "ior", what, 1.5f);
  m.opacity = r.number(t, "opacity", what, 1.0f);
  if (!(m.opacity >= 0 && m.opacity <= 1)) r.fail(*t.get("opacity"), what + ".opacity must be in [0, 1]");
  m.specular = r.number(t, "specular", what, 0.0f);
  if (!(m.specular >= 0)) r.fail(*t.get("specular"), what + ".specular must not be negative");
  m.shininess = r.number(t, "shininess", what, 32.0f);
  if (!(m.shininess >= 1)) r.fail(*t.get("shininess"), what + ".shininess must be at least 1");
  if (m.type == MaterialType::Emissive && !t.get("emission"))
    r.fail(t, what + ": missing field 'emission'");
  return m;
}

TriangleMesh readInlineMesh(const TomlReader& r, const toml::table& t, const std::string& what) {
  TriangleMesh mesh;
  const toml::node& vn = r.require(t, "vertices", what);
  const toml::array* vs = vn.as_array();
  if (!vs) r.fail(vn, what + ".vertices must be an array of [x, y, z]");
  for (const toml::node& v : *vs) mesh.positions.push_back(r.vec3(v, what + ".vertices"));
  const toml::node& fn = r.require(t, "faces", what);
  const toml::array* fs = fn.as_array();
  if (!fs) r.fail(fn, what + ".faces must be an array of index arrays");
  for (const toml::node& f : *fs) {
    const toml::array* idx = f.as_array();
    if (!idx || idx->size() < 3) r.fail(f, what + ".faces: each face needs 3 or more indices");
    std::vector<std::uint32_t> face;
    for (const toml::node& i : *idx) {
      face.push_back(r.index(i, what + ".faces"));
      if (face.back() >= mesh.positions.size())
        r.fail(i, what + ".faces: vertex " + std::to_string(face.back()) + " does not exist");
    }
    for (std::size_t k = 1; k + 1 < face.size(); ++k)  // fan: faces are convex
      mesh.triangles.push_back({face[0], face[k], face[k + 1]});
  }
  return mesh;
}

}  // namespace

SceneDesc readSceneToml(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw Error(path + ": scene file not found");
  toml::table root;
  try {
    root = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    throw Error(path + ":" + std::to_string(e.source().begin.line) + ": " +
                std::string(e.description()));
  }
  const TomlReader r(path);
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  r.onlyKeys(root, "the scene",
             {"camera", "environment", "materials", "meshes", "spheres", "instances", "volumes",
              "isosurfaces", "particles", "lights", "scivis"});
  SceneDesc d;
  readCamera(r, r.table(r.require(root, "camera", "the scene"), "camera"), d.camera);
  if (const toml::node* e = root.get("environment"))
    readEnvironment(r, r.table(*e, "environment"), d.environment);
  if (const toml::node* ms = root.get("materials"))
    for (const auto& [name, node] : r.table(*ms, "materials"))
      d.materials.push_back(readMaterial(
          r, std::string(name.str()), r.table(node, "material '" + std::string(name.str()) + "'")));

  for (const toml::table* t : r.arrayOfTables(root, "meshes")) {
    const std::string name = r.string(r.require(*t, "name", "mesh"), "mesh.name");
    const std::string what = "mesh '" + name + "'";
    r.onlyKeys(*t, what,
               {"name", "material", "file", "vertices", "faces", "scale", "rotate", "translate"});
    Shape s;
    s.name = name;
    if (const toml::node* f = t->get("file")) {
      const std::filesystem::path file = folder / r.string(*f, what + ".file");
      try {
        s.mesh = importMesh(file.string());
        s.file = file.string();
      } catch (const Error& e) {
        r.fail(*f, what + ": " + e.what());
      }
    } else {
      s.mesh = readInlineMesh(r, *t, what);
    }
    const std::uint32_t material = r.material(d, *t, what);
    d.shapes.push_back(std::move(s));
    d.instances.push_back(
        {static_cast<std::uint32_t>(d.shapes.size() - 1), r.transform(*t, what), material});
  }
  for (const toml::table* t : r.arrayOfTables(root, "spheres")) {
    const std::string name = t->get("name") ? r.string(*t->get("name"), "sphere.name") : "sphere";
    const std::string what = "sphere '" + name + "'";
    r.onlyKeys(*t, what, {"name", "material", "center", "radius"});
    Shape s;
    s.name = name;
    s.spheres.centers.push_back(r.vec3(r.require(*t, "center", what), what + ".center"));
    const toml::node& rn = r.require(*t, "radius", what);
    s.spheres.radii.push_back(r.number(rn, what + ".radius"));
    if (!(s.spheres.radii.back() > 0)) r.fail(rn, what + ".radius must be positive");
    const std::uint32_t material = r.material(d, *t, what);
    d.shapes.push_back(std::move(s));
    d.instances.push_back({static_cast<std::uint32_t>(d.shapes.size() - 1), {}, material});
  }
  for (const toml::table* t : r.arrayOfTables(root, "instances")) {
    const toml::node& mn = r.require(*t, "mesh", "instance");
    const std::string mesh = r.string(mn, "instance.mesh");
    const std::string what = "instance of '" + mesh + "'";
    r.onlyKeys(*t, what, {"mesh", "material", "scale", "rotate", "translate"});
    std::uint32_t shape = 0;
    while (shape < d.shapes.size() && d.shapes[shape].name != mesh) ++shape;
    if (shape == d.shapes.size()) r.fail(mn, "mesh '" + mesh + "' of an instance is not defined");
    std::uint32_t material = 0;
    for (const Instance& i : d.instances)
      if (i.shape == shape) material = i.material;
    if (t->get("material")) material = r.material(d, *t, what);
    d.instances.push_back({shape, r.transform(*t, what), material});
  }
  readSciVis(r, root, folder, d);
  if (d.instances.empty() && d.volumes.empty() && d.particles.empty())
    r.fail(root, "the scene has no meshes, spheres, volumes or particles");
  return d;
}

}  // namespace renderers
