#include "renderers/SceneToml.h"

#include <toml++/toml.h>

#include <cmath>
#include <filesystem>
#include <new>
#include <optional>
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

void readCamera(TomlReader& r, const toml::table& t, CameraDesc& c) {
  r.onlyKeys(t, "camera", {"position", "look_at", "up", "fov", "lens_radius", "focus_distance"});
  c.position = r.vec3(r.need(t, "position", "camera"), "camera.position");
  c.lookAt = r.vec3(r.need(t, "look_at", "camera"), "camera.look_at");
  c.up = r.vec3(t, "up", "camera", c.up);
  c.fovY = r.number(t, "fov", "camera", c.fovY);
  c.lensRadius = r.number(t, "lens_radius", "camera", 0.0f);
  c.focusDistance = r.number(t, "focus_distance", "camera", 0.0f);
  // (The defaults pass these checks: each fails only for a field that is there.)
  if (!(c.fovY > 0 && c.fovY < 180)) r.problem(*t.get("fov"), "camera.fov", "must be in (0, 180)");
  if (!(c.lensRadius >= 0))
    r.problem(*t.get("lens_radius"), "camera.lens_radius", "must not be negative");
  if (!(c.focusDistance >= 0))
    r.problem(*t.get("focus_distance"), "camera.focus_distance", "must not be negative");
  r.settle();
  // The view direction as Camera computes it, in float: a direction, and not along up.
  const Vec3 view = c.lookAt - c.position;
  const toml::node& lookAt = *t.get("look_at");
  if (!(length(view) > 0))
    r.fail(lookAt, "camera.look_at", "must differ from camera.position (in float precision)");
  if (!std::isfinite(length(view)))
    r.fail(lookAt, "camera.look_at",
           "is too far from camera.position for float arithmetic (the distance squared "
           "overflows)");
  const toml::node& up = t.get("up") ? *t.get("up") : t;
  if (!(length(c.up) > 0 && std::isfinite(length(c.up))))
    r.fail(up, "camera.up", "must be a non-zero direction within the float range");
  if (!(length(cross(normalize(view), normalize(c.up))) > 1e-5f))
    r.fail(up, "camera.up", "must not be parallel to the view direction (look_at - position)");
}

// Positions from a file may hold NaN or inf (TOML numbers are checked as read); a mesh whose
// triangles all have zero area shows nothing and has no normals.
void checkMesh(TomlReader& r, const toml::node& at, const std::string& what,
               const TriangleMesh& m) {
  for (std::size_t i = 0; i < m.positions.size(); ++i)
    if (!isFinite(m.positions[i]))
      r.fail(at, what, "vertex " + std::to_string(i) + " has a non-finite position");
  for (const auto& t : m.triangles) {
    const Vec3 p0 = m.positions[t[0]];
    if (length(cross(m.positions[t[1]] - p0, m.positions[t[2]] - p0)) > 0) return;
  }
  r.fail(at, what, "no triangle has a non-zero area (in float precision): nothing to draw");
}

// The mesh's bounds moved by `m` must stay within the float range (a scale of 1e30 would not).
void checkPlacement(TomlReader& r, const toml::table& t, const std::string& what,
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
             what, "the transform moves its vertices beyond the float range");
  }
}

void readEnvironment(TomlReader& r, const toml::table& t, Environment& e) {
  r.onlyKeys(t, "environment", {"type", "color", "bottom", "top"});
  const toml::node* typeNode = t.get("type");
  const std::string type = typeNode ? r.string(typeNode, "environment.type") : "constant";
  if (type == "constant") {
    e.kind = Environment::Kind::Constant;
    e.color = r.vec3(t, "color", "environment", {});
  } else if (type == "gradient") {
    e.kind = Environment::Kind::Gradient;
    e.bottom = r.vec3(r.need(t, "bottom", "environment"), "environment.bottom");
    e.top = r.vec3(r.need(t, "top", "environment"), "environment.top");
  } else if (typeNode->is_string()) {
    r.problem(*typeNode, "environment.type",
              "must be \"constant\" or \"gradient\", not \"" + type + "\"");
  }
}

Material readMaterial(TomlReader& r, const std::string& name, const toml::table& t) {
  const std::string what = "material '" + name + "'";
  r.onlyKeys(t, what,
             {"type", "color", "emission", "roughness", "ior", "opacity", "specular", "shininess"});
  Material m;
  m.name = name;
  const toml::node* typeNode = r.need(t, "type", what);
  const std::string type = r.string(typeNode, what + ".type");
  if (type == "diffuse")
    m.type = MaterialType::Diffuse;
  else if (type == "emissive")
    m.type = MaterialType::Emissive;
  else if (type == "metal")
    m.type = MaterialType::Metal;
  else if (type == "glass")
    m.type = MaterialType::Glass;
  else if (typeNode && typeNode->is_string())
    r.problem(*typeNode, what + ".type",
              "must be diffuse, emissive, metal or glass, not \"" + type + "\"");
  const Vec3 defaultColor = m.type == MaterialType::Glass      ? Vec3{1.0f}
                            : m.type == MaterialType::Emissive ? Vec3{0.0f}
                                                               : m.color;
  m.color = r.vec3(t, "color", what, defaultColor);
  m.emission = r.vec3(t, "emission", what, {});
  m.roughness = r.number(t, "roughness", what, 0.0f);
  m.ior = r.number(t, "ior", what, 1.5f);
  m.opacity = r.number(t, "opacity", what, 1.0f);
  if (!(m.opacity >= 0 && m.opacity <= 1))
    r.problem(*t.get("opacity"), what + ".opacity", "must be in [0, 1]");
  m.specular = r.number(t, "specular", what, 0.0f);
  if (!(m.specular >= 0)) r.problem(*t.get("specular"), what + ".specular", "must not be negative");
  m.shininess = r.number(t, "shininess", what, 32.0f);
  if (!(m.shininess >= 1))
    r.problem(*t.get("shininess"), what + ".shininess", "must be at least 1");
  if (m.type == MaterialType::Emissive && !t.get("emission"))
    r.problem(t, what + ".emission", "missing (an emissive material needs it)");
  return m;
}

TriangleMesh readInlineMesh(TomlReader& r, const toml::table& t, const std::string& what) {
  TriangleMesh mesh;
  if (const toml::node* vn = r.need(t, "vertices", what)) {
    if (const toml::array* vs = vn->as_array())
      for (const toml::node& v : *vs) mesh.positions.push_back(r.vec3(v, what + ".vertices"));
    else
      r.problem(*vn, what + ".vertices",
                "expected an array of [x, y, z], got " + base::tomlTypeName(*vn));
  }
  const toml::node* fn = r.need(t, "faces", what);
  if (!fn) return mesh;
  const toml::array* fs = fn->as_array();
  if (!fs) {
    r.problem(*fn, what + ".faces",
              "expected an array of index arrays, got " + base::tomlTypeName(*fn));
    return mesh;
  }
  for (const toml::node& f : *fs) {
    const toml::array* idx = f.as_array();
    if (!idx || idx->size() < 3) {
      r.problem(f, what + ".faces", "each face needs 3 or more indices");
      continue;
    }
    std::vector<std::uint32_t> face;
    for (const toml::node& i : *idx) {
      face.push_back(r.index(i, what + ".faces"));
      if (face.back() >= mesh.positions.size())
        r.problem(i, what + ".faces", "vertex " + std::to_string(face.back()) + " does not exist");
    }
    for (std::size_t k = 1; k + 1 < face.size(); ++k)  // fan: faces are convex
      mesh.triangles.push_back({face[0], face[k], face[k + 1]});
  }
  return mesh;
}

void readMesh(TomlReader& r, const toml::table& t, const std::filesystem::path& folder,
              SceneDesc& d, const std::string& name) {
  const std::string what = name.empty() ? "mesh" : "mesh '" + name + "'";
  r.onlyKeys(t, what,
             {"name", "material", "file", "vertices", "faces", "scale", "rotate", "translate"});
  Shape s;
  s.name = name;
  const toml::node* f = t.get("file");
  if (f && f->is_string()) {
    const std::filesystem::path file = folder / r.string(*f, what + ".file");
    // Importing holds at least the file's bytes; the mesh is checked again once known.
    std::error_code sizeError;
    const std::uintmax_t meshFileBytes = std::filesystem::file_size(file, sizeError);
    if (!sizeError)
      r.budget(*f, what + ".file", std::to_string(meshFileBytes) + " bytes",
               d.bytes() + meshFileBytes);
    s.mesh = r.loading(*f, what + ".file", [&] {
      try {
        return importMesh(file.string());
      } catch (const base::Error& e) {
        r.fail(*f, what + ".file", e.what());
      }
    });
    s.file = file.string();
    r.budget(*f, what + ".file",
             std::to_string(s.mesh.positions.size()) + " vertices, " +
                 std::to_string(s.mesh.triangles.size()) + " triangles",
             d.bytes() + s.bytes());
  } else if (f) {
    r.string(*f, what + ".file");  // reports the wrong type
  } else {
    s.mesh = readInlineMesh(r, t, what);
  }
  const std::uint32_t material = r.material(d, t, what);
  const Affine transform = r.transform(t, what);  // settles: every field above read cleanly
  checkMesh(r, f ? *f : *t.get("vertices"), what, s.mesh);
  checkPlacement(r, t, what, s.mesh, transform);
  d.shapes.push_back(std::move(s));
  d.instances.push_back({static_cast<std::uint32_t>(d.shapes.size() - 1), transform, material});
}

void readSphere(TomlReader& r, const toml::table& t, SceneDesc& d) {
  const std::string name = t.get("name") ? r.string(t.get("name"), "sphere.name") : "sphere";
  const std::string what = "sphere '" + name + "'";
  r.onlyKeys(t, what, {"name", "material", "center", "radius"});
  Shape s;
  s.name = name;
  const Vec3 center = r.vec3(r.need(t, "center", what), what + ".center");
  const toml::node* rn = r.need(t, "radius", what);
  const float radius = r.number(rn, what + ".radius");
  const std::uint32_t material = r.material(d, t, what);
  r.settle();
  s.spheres.centers.push_back(center);
  s.spheres.radii.push_back(radius);
  if (!(radius > 0)) r.fail(*rn, what + ".radius", "must be positive");
  if (!isFinite(center + Vec3{radius}) || !isFinite(center - Vec3{radius}))
    r.fail(*rn, what, "center ± radius leaves the float range");
  if (radius < floatStep(maxAbs(center)))
    r.fail(*rn, what + ".radius",
           TomlReader::text(radius) + " is below float precision at its center (steps of " +
               TomlReader::text(floatStep(maxAbs(center))) + " there)");
  d.shapes.push_back(std::move(s));
  d.instances.push_back({static_cast<std::uint32_t>(d.shapes.size() - 1), {}, material});
}

void readInstance(TomlReader& r, const toml::table& t, SceneDesc& d) {
  const toml::node* mn = r.need(t, "mesh", "instance");
  const std::string mesh = r.string(mn, "instance.mesh");
  const std::string what = mn && mn->is_string() ? "instance of '" + mesh + "'" : "instance";
  r.onlyKeys(t, what, {"mesh", "material", "scale", "rotate", "translate"});
  std::uint32_t shape = 0;
  while (shape < d.shapes.size() && d.shapes[shape].name != mesh) ++shape;
  if (mn && mn->is_string() && shape == d.shapes.size()) {
    std::vector<std::string> names;
    for (const Shape& s : d.shapes) names.push_back(s.name);
    r.notDefined(*mn, "instance.mesh", "mesh", mesh, names);
  }
  std::uint32_t material = 0;
  for (const Instance& i : d.instances)
    if (i.shape == shape) material = i.material;
  if (t.get("material")) material = r.material(d, t, what);
  const Affine transform = r.transform(t, what);  // settles
  checkPlacement(r, t, what, d.shapes[shape].mesh, transform);
  d.instances.push_back({shape, transform, material});
}

// Every entry is read on its own (TomlReader::entry): a problem in one is reported and the
// others are still checked.
void readScene(TomlReader& r, const toml::table& root, const std::filesystem::path& folder,
               SceneDesc& d) {
  // The core's keys, then those of the registered sections (SceneSections.h).
  const std::vector<SceneSections> sections = registeredSceneSections();
  std::vector<std::string_view> keys{"camera", "environment", "materials",
                                     "meshes", "spheres",     "instances"};
  for (const SceneSections& s : sections) keys.insert(keys.end(), s.keys.begin(), s.keys.end());
  r.onlyKeys(root, "", keys);
  r.entry([&] {
    const toml::node* camera = r.need(root, "camera", "");
    const toml::table* t = camera ? r.table(*camera, "camera") : nullptr;
    if (!t) r.skip();
    readCamera(r, *t, d.camera);
  });
  if (const toml::node* e = root.get("environment"))
    r.entry([&] {
      if (const toml::table* t = r.table(*e, "environment")) readEnvironment(r, *t, d.environment);
    });
  if (const toml::node* ms = root.get("materials"))
    if (const toml::table* materials = r.table(*ms, "materials"))
      for (const auto& [key, value] : *materials) {
        const std::string name(key.str());
        const toml::node& node = value;  // a lambda may not capture a structured binding (clang 14)
        const bool ok = r.entry([&] {
          const toml::table* t = r.table(node, "material '" + name + "'");
          if (!t) r.skip();
          Material m = readMaterial(r, name, *t);
          r.settle();
          d.materials.push_back(std::move(m));
        });
        if (!ok) r.markFailed("material", name);
      }

  for (const toml::table* t : r.arrayOfTables(root, "meshes")) {
    const toml::node* nameNode = t->get("name");
    const std::string name = nameNode ? nameNode->value_or(std::string()) : std::string();
    const bool ok = r.entry([&] {
      if (!nameNode)
        r.need(*t, "name", "mesh");
      else if (!nameNode->is_string())
        r.string(*nameNode, "mesh.name");
      readMesh(r, *t, folder, d, name);
    });
    if (!ok && !name.empty()) r.markFailed("mesh", name);
  }
  for (const toml::table* t : r.arrayOfTables(root, "spheres"))
    r.entry([&] { readSphere(r, *t, d); });
  for (const toml::table* t : r.arrayOfTables(root, "instances"))
    r.entry([&] { readInstance(r, *t, d); });
  for (const SceneSections& s : sections) s.read(r, root, folder, d);
  // Only for a file read cleanly: entries that failed would otherwise count as missing.
  if (r.diagnostics().ok() && d.instances.empty() && d.extensions.drawnBy().empty()) {
    std::string more;  // ", volumes or particles"
    for (const SceneSections& s : sections)
      if (!s.draws.empty()) more += ", " + s.draws;
    r.problem(root, "",
              "the scene has no meshes" + (more.empty() ? " or spheres" : ", spheres" + more));
  }
}

}  // namespace

SceneDesc readSceneToml(const std::string& path) {
  if (!std::filesystem::is_regular_file(path))
    throw base::Error(base::SourceLocation{path}, "scene file not found");
  // TOML++ holds every value as a node of some 50-70 bytes (the number's text: 2 or more).
  constexpr std::uint64_t kTomlBytesPerFileByte = 40;
  std::error_code ec;
  const std::uint64_t fileBytes = std::filesystem::file_size(path, ec);
  if (std::string problem = base::memoryProblem(base::bytesTimes(fileBytes, kTomlBytesPerFileByte));
      !ec && !problem.empty())
    throw base::Error(base::SourceLocation{path}, "the scene file (" + std::to_string(fileBytes) +
                                                      " bytes; reading TOML takes up to " +
                                                      std::to_string(kTomlBytesPerFileByte) +
                                                      " times that) " + problem);
  base::TomlDiagnostics diagnostics(path);
  std::optional<toml::table> root;
  try {
    if (diagnostics.readFile("scene file")) root = diagnostics.parse();
  } catch (const std::bad_alloc&) {
    throw base::Error(base::SourceLocation{path},
                      "out of memory while reading the scene file; this rank may hold " +
                          base::memoryLimitText());
  }
  TomlReader r(diagnostics);
  SceneDesc d;
  if (root) r.entry([&] { readScene(r, *root, std::filesystem::path(path).parent_path(), d); });
  diagnostics.throwIfAny();
  return d;
}

}  // namespace renderers
