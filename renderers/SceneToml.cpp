#include "renderers/SceneToml.h"

#include <toml++/toml.h>

#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <new>
#include <string>
#include <string_view>
#include <vector>

#include "base/Error.h"
#include "base/MemoryBudget.h"
#include "renderers/MeshImport.h"
#include "renderers/SceneSections.h"
#include "renderers/TomlReader.h"

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
  if (!(c.lensRadius >= 0))
    r.fail(*t.get("lens_radius"), "camera.lens_radius must not be negative");
  if (!(c.focusDistance >= 0))
    r.fail(*t.get("focus_distance"), "camera.focus_distance must not be negative");
  // The view direction as Camera computes it, in float: a direction, and not along up.
  const Vec3 view = c.lookAt - c.position;
  const toml::node& lookAt = *t.get("look_at");
  if (!(length(view) > 0))
    r.fail(lookAt, "camera.look_at must differ from camera.position (in float precision)");
  if (!std::isfinite(length(view)))
    r.fail(lookAt,
           "camera.look_at is too far from camera.position for float arithmetic "
           "(the distance squared overflows)");
  const toml::node& up = t.get("up") ? *t.get("up") : t;
  if (!(length(c.up) > 0 && std::isfinite(length(c.up))))
    r.fail(up, "camera.up must be a non-zero direction within the float range");
  if (!(length(cross(normalize(view), normalize(c.up))) > 1e-5f))
    r.fail(up, "camera.up must not be parallel to the view direction (look_at - position)");
}

// Positions from a file may hold NaN or inf (TOML numbers are checked as read); a mesh whose
// triangles all have zero area shows nothing and has no normals.
void checkMesh(const TomlReader& r, const toml::node& at, const std::string& what,
               const TriangleMesh& m) {
  for (std::size_t i = 0; i < m.positions.size(); ++i)
    if (!isFinite(m.positions[i]))
      r.fail(at, what + ": vertex " + std::to_string(i) + " has a non-finite position");
  for (const auto& t : m.triangles) {
    const Vec3 p0 = m.positions[t[0]];
    if (length(cross(m.positions[t[1]] - p0, m.positions[t[2]] - p0)) > 0) return;
  }
  r.fail(at, what + ": no triangle has a non-zero area (in float precision): nothing to draw");
}

// The mesh's bounds moved by `m` must stay within the float range (a scale of 1e30 would not).
void checkPlacement(const TomlReader& r, const toml::table& t, const std::string& what,
                    const TriangleMesh& mesh, const Affine& m) {
  Vec3 lo{INFINITY}, hi{-INFINITY};
  for (const Vec3& p : mesh.positions) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 p{corner & 1 ? hi.x : lo.x, corner & 2 ? hi.y : lo.y, corner & 4 ? hi.z : lo.z};
    if (!isFinite(m.point(p)))
      r.fail(t.get("scale")       ? *t.get("scale")
             : t.get("translate") ? *t.get("translate")
                                  : t,
             what + ": the transform moves its vertices beyond the float range");
  }
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
  if (!(m.opacity >= 0 && m.opacity <= 1))
    r.fail(*t.get("opacity"), what + ".opacity must be in [0, 1]");
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
  if (!std::filesystem::is_regular_file(path)) throw base::Error(path + ": scene file not found");
  // TOML++ holds every value as a node of some 50-70 bytes (the number's text: 2 or more).
  constexpr std::uint64_t kTomlBytesPerFileByte = 40;
  std::error_code ec;
  const std::uint64_t fileBytes = std::filesystem::file_size(path, ec);
  if (std::string problem = base::memoryProblem(base::bytesTimes(fileBytes, kTomlBytesPerFileByte));
      !ec && !problem.empty())
    throw base::Error(path + ":1: the scene file (" + std::to_string(fileBytes) +
                      " bytes; reading TOML takes up to " + std::to_string(kTomlBytesPerFileByte) +
                      " times that) " + problem);
  toml::table root;
  try {
    root = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    throw base::Error(path + ":" + std::to_string(e.source().begin.line) + ": " +
                      std::string(e.description()));
  } catch (const std::bad_alloc&) {
    throw base::Error(path + ": out of memory while reading the scene file; this rank may hold " +
                      base::memoryLimitText());
  }
  const TomlReader r(path);
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  // The core's keys, then those of the registered sections (SceneSections.h).
  const std::vector<SceneSections> sections = registeredSceneSections();
  std::vector<std::string_view> keys{"camera", "environment", "materials",
                                     "meshes", "spheres",     "instances"};
  for (const SceneSections& s : sections) keys.insert(keys.end(), s.keys.begin(), s.keys.end());
  r.onlyKeys(root, "the scene", keys);
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
    const toml::node* f = t->get("file");
    if (f) {
      const std::filesystem::path file = folder / r.string(*f, what + ".file");
      // Importing holds at least the file's bytes; the mesh is checked again once known.
      std::error_code sizeError;
      const std::uintmax_t meshFileBytes = std::filesystem::file_size(file, sizeError);
      if (!sizeError)
        r.budget(*f, what + ".file (" + std::to_string(meshFileBytes) + " bytes)",
                 d.bytes() + meshFileBytes);
      s.mesh = r.loading(*f, what + ".file", [&] {
        try {
          return importMesh(file.string());
        } catch (const base::Error& e) {
          r.fail(*f, what + ": " + e.what());
        }
      });
      s.file = file.string();
      r.budget(*f,
               what + ".file (" + std::to_string(s.mesh.positions.size()) + " vertices, " +
                   std::to_string(s.mesh.triangles.size()) + " triangles)",
               d.bytes() + s.bytes());
    } else {
      s.mesh = readInlineMesh(r, *t, what);
    }
    checkMesh(r, f ? *f : *t->get("vertices"), what, s.mesh);
    const std::uint32_t material = r.material(d, *t, what);
    const Affine transform = r.transform(*t, what);
    checkPlacement(r, *t, what, s.mesh, transform);
    d.shapes.push_back(std::move(s));
    d.instances.push_back({static_cast<std::uint32_t>(d.shapes.size() - 1), transform, material});
  }
  for (const toml::table* t : r.arrayOfTables(root, "spheres")) {
    const std::string name = t->get("name") ? r.string(*t->get("name"), "sphere.name") : "sphere";
    const std::string what = "sphere '" + name + "'";
    r.onlyKeys(*t, what, {"name", "material", "center", "radius"});
    Shape s;
    s.name = name;
    const Vec3 center = r.vec3(r.require(*t, "center", what), what + ".center");
    s.spheres.centers.push_back(center);
    const toml::node& rn = r.require(*t, "radius", what);
    const float radius = r.number(rn, what + ".radius");
    s.spheres.radii.push_back(radius);
    if (!(radius > 0)) r.fail(rn, what + ".radius must be positive");
    if (!isFinite(center + Vec3{radius}) || !isFinite(center - Vec3{radius}))
      r.fail(rn, what + ": center ± radius leaves the float range");
    if (radius < floatStep(maxAbs(center)))
      r.fail(rn, what + ".radius " + TomlReader::text(radius) +
                     " is below float precision at its center (steps of " +
                     TomlReader::text(floatStep(maxAbs(center))) + " there)");
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
    const Affine transform = r.transform(*t, what);
    checkPlacement(r, *t, what, d.shapes[shape].mesh, transform);
    d.instances.push_back({shape, transform, material});
  }
  for (const SceneSections& s : sections) s.read(r, root, folder, d);
  if (d.instances.empty() && d.volumes.empty() && d.particles.empty())
    r.fail(root, "the scene has no meshes, spheres, volumes or particles");
  return d;
}

}  // namespace renderers
