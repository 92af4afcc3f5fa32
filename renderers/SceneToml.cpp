#include "renderers/SceneToml.h"

#include <toml++/toml.h>

#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <string_view>

#include "renderers/Error.h"
#include "renderers/MeshImport.h"

namespace renderers {
namespace {

class Reader {
 public:
  explicit Reader(std::string path) : path_(std::move(path)) {}

  [[noreturn]] void fail(const toml::node& at, const std::string& what) const {
    throw Error(path_ + ":" + std::to_string(at.source().begin.line) + ": " + what);
  }

  const toml::table& table(const toml::node& n, const std::string& what) const {
    if (!n.is_table()) fail(n, what + " must be a table");
    return *n.as_table();
  }

  // Rejects keys outside `known`: a misspelt field would otherwise be silently ignored.
  void onlyKeys(const toml::table& t, const std::string& what,
                std::initializer_list<std::string_view> known) const {
    for (const auto& [key, value] : t) {
      bool ok = false;
      for (auto k : known) ok = ok || key.str() == k;
      if (!ok) fail(value, "unknown field '" + std::string(key.str()) + "' in " + what);
    }
  }

  const toml::node* get(const toml::table& t, std::string_view key) const { return t.get(key); }

  const toml::node& require(const toml::table& t, std::string_view key,
                            const std::string& what) const {
    const toml::node* n = t.get(key);
    if (!n) fail(t, what + ": missing field '" + std::string(key) + "'");
    return *n;
  }

  float number(const toml::node& n, const std::string& what) const {
    if (auto v = n.value<double>(); v && (n.is_integer() || n.is_floating_point())) {
      // TOML spells nan and inf; no scene quantity means either (and a float overflows to inf).
      const float f = static_cast<float>(*v);
      if (!std::isfinite(f)) fail(n, what + " must be a finite number, got " + std::to_string(*v));
      return f;
    }
    fail(n, what + " must be a number");
  }

  float number(const toml::table& t, std::string_view key, const std::string& what,
               float fallback) const {
    const toml::node* n = t.get(key);
    return n ? number(*n, what + "." + std::string(key)) : fallback;
  }

  std::string string(const toml::node& n, const std::string& what) const {
    if (!n.is_string()) fail(n, what + " must be a string");
    return std::string(*n.value<std::string_view>());
  }

  Vec3 vec3(const toml::node& n, const std::string& what) const {
    const toml::array* a = n.as_array();
    if (!a || a->size() != 3) fail(n, what + " must be an array of 3 numbers");
    return {number((*a)[0], what), number((*a)[1], what), number((*a)[2], what)};
  }

  Vec3 vec3(const toml::table& t, std::string_view key, const std::string& what,
            Vec3 fallback) const {
    const toml::node* n = t.get(key);
    return n ? vec3(*n, what + "." + std::string(key)) : fallback;
  }

  std::uint32_t index(const toml::node& n, const std::string& what) const {
    auto v = n.value<std::int64_t>();
    if (!n.is_integer() || !v || *v < 0) fail(n, what + " must be a non-negative integer");
    return static_cast<std::uint32_t>(*v);
  }

  // scale, then rotate = [axis x, y, z, degrees], then translate.
  Affine transform(const toml::table& t, const std::string& what) const {
    Affine m;
    if (const toml::node* s = t.get("scale")) {
      m = s->is_array() ? scaling(vec3(*s, what + ".scale"))
                        : scaling(Vec3{number(*s, what + ".scale")});
    }
    if (const toml::node* r = t.get("rotate")) {
      const toml::array* a = r->as_array();
      if (!a || a->size() != 4) fail(*r, what + ".rotate must be [axis x, y, z, degrees]");
      const Vec3 axis{number((*a)[0], what), number((*a)[1], what), number((*a)[2], what)};
      if (length(axis) <= 0) fail(*r, what + ".rotate: the axis must not be zero");
      m = rotation(axis, number((*a)[3], what + ".rotate")) * m;
    }
    if (t.get("translate")) m = translation(vec3(t, "translate", what, {})) * m;
    return m;
  }

  std::uint32_t material(const SceneDesc& d, const toml::table& t, const std::string& owner) const {
    const toml::node& n = require(t, "material", owner);
    const std::string name = string(n, owner + ".material");
    const int i = d.findMaterial(name);
    if (i < 0) fail(n, "material '" + name + "' of " + owner + " is not defined");
    return static_cast<std::uint32_t>(i);
  }

 private:
  std::string path_;
};

void readCamera(const Reader& r, const toml::table& t, CameraDesc& c) {
  r.onlyKeys(t, "camera", {"position", "look_at", "up", "fov", "lens_radius", "focus_distance"});
  c.position = r.vec3(r.require(t, "position", "camera"), "camera.position");
  c.lookAt = r.vec3(r.require(t, "look_at", "camera"), "camera.look_at");
  c.up = r.vec3(t, "up", "camera", c.up);
  c.fovY = r.number(t, "fov", "camera", c.fovY);
  c.lensRadius = r.number(t, "lens_radius", "camera", 0.0f);
  c.focusDistance = r.number(t, "focus_distance", "camera", 0.0f);
  if (!(c.fovY > 0 && c.fovY < 180)) r.fail(*t.get("fov"), "camera.fov must be in (0, 180)");
}

void readEnvironment(const Reader& r, const toml::table& t, Environment& e) {
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

Material readMaterial(const Reader& r, const std::string& name, const toml::table& t) {
  const std::string what = "material '" + name + "'";
  r.onlyKeys(t, what, {"type", "color", "emission", "roughness", "ior"});
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
  if (m.type == MaterialType::Emissive && !t.get("emission"))
    r.fail(t, what + ": missing field 'emission'");
  return m;
}

TriangleMesh readInlineMesh(const Reader& r, const toml::table& t, const std::string& what) {
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
  const Reader r(path);
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  r.onlyKeys(root, "the scene",
             {"camera", "environment", "materials", "meshes", "spheres", "instances"});
  SceneDesc d;
  readCamera(r, r.table(r.require(root, "camera", "the scene"), "camera"), d.camera);
  if (const toml::node* e = root.get("environment"))
    readEnvironment(r, r.table(*e, "environment"), d.environment);
  if (const toml::node* ms = root.get("materials"))
    for (const auto& [name, node] : r.table(*ms, "materials"))
      d.materials.push_back(readMaterial(
          r, std::string(name.str()), r.table(node, "material '" + std::string(name.str()) + "'")));

  auto entries = [&](std::string_view key) {
    std::vector<const toml::table*> out;
    if (const toml::node* n = root.get(key)) {
      const toml::array* a = n->as_array();
      if (!a)
        r.fail(*n, std::string(key) + " must be an array of tables ([[" + std::string(key) + "]])");
      for (const toml::node& e : *a) out.push_back(&r.table(e, std::string(key) + " entry"));
    }
    return out;
  };

  for (const toml::table* t : entries("meshes")) {
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
  for (const toml::table* t : entries("spheres")) {
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
  for (const toml::table* t : entries("instances")) {
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
  if (d.instances.empty()) r.fail(root, "the scene has no meshes or spheres");
  return d;
}

}  // namespace renderers
