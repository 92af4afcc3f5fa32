#include "renderers/BuiltinScenes.h"

#include <mutex>
#include <utility>

#include "base/Error.h"
#include "renderers/Rng.h"
#include "renderers/SceneToml.h"

namespace renderers {
namespace {

// Adds a shape of convex quads (each split into two triangles) and an instance of it.
void addQuads(SceneDesc& d, const std::string& name, const std::string& material,
              const std::vector<Vec3>& corners) {
  Shape s;
  s.name = name;
  s.mesh.positions = corners;
  for (std::uint32_t q = 0; q + 3 < corners.size(); q += 4) {
    s.mesh.triangles.push_back({q, q + 1, q + 2});
    s.mesh.triangles.push_back({q, q + 2, q + 3});
  }
  d.shapes.push_back(std::move(s));
  d.instances.push_back({static_cast<std::uint32_t>(d.shapes.size() - 1),
                         {},
                         static_cast<std::uint32_t>(d.findMaterial(material))});
}

Material diffuse(const std::string& name, Vec3 color) {
  return {name, MaterialType::Diffuse, color, {}, 0, 1.5f};
}

}  // namespace

SceneDesc cornellBox() {
  SceneDesc d;
  d.materials = {diffuse("white", {0.725f, 0.71f, 0.68f}),
                 diffuse("red", {0.63f, 0.065f, 0.05f}),
                 diffuse("green", {0.14f, 0.45f, 0.091f}),
                 {"light", MaterialType::Emissive, Vec3{0.0f}, {17.0f, 12.0f, 4.0f}, 0, 1.5f}};
  // Vertex coordinates as published in millimetres, quads in the published order.
  addQuads(d, "floor", "white", {{552.8f, 0, 0}, {0, 0, 0}, {0, 0, 559.2f}, {549.6f, 0, 559.2f}});
  addQuads(d, "ceiling", "white",
           {{556, 548.8f, 0}, {556, 548.8f, 559.2f}, {0, 548.8f, 559.2f}, {0, 548.8f, 0}});
  addQuads(d, "back_wall", "white",
           {{549.6f, 0, 559.2f}, {0, 0, 559.2f}, {0, 548.8f, 559.2f}, {556, 548.8f, 559.2f}});
  addQuads(d, "right_wall", "green",
           {{0, 0, 559.2f}, {0, 0, 0}, {0, 548.8f, 0}, {0, 548.8f, 559.2f}});
  addQuads(d, "left_wall", "red",
           {{552.8f, 0, 0}, {549.6f, 0, 559.2f}, {556, 548.8f, 559.2f}, {556, 548.8f, 0}});
  addQuads(d, "short_block", "white",
           {{130, 165, 65},  {82, 165, 225},  {240, 165, 272}, {290, 165, 114}, {290, 0, 114},
            {290, 165, 114}, {240, 165, 272}, {240, 0, 272},   {130, 0, 65},    {130, 165, 65},
            {290, 165, 114}, {290, 0, 114},   {82, 0, 225},    {82, 165, 225},  {130, 165, 65},
            {130, 0, 65},    {240, 0, 272},   {240, 165, 272}, {82, 165, 225},  {82, 0, 225}});
  addQuads(d, "tall_block", "white",
           {{423, 330, 247}, {265, 330, 296}, {314, 330, 456}, {472, 330, 406}, {423, 0, 247},
            {423, 330, 247}, {472, 330, 406}, {472, 0, 406},   {472, 0, 406},   {472, 330, 406},
            {314, 330, 456}, {314, 0, 456},   {314, 0, 456},   {314, 330, 456}, {265, 330, 296},
            {265, 0, 296},   {265, 0, 296},   {265, 330, 296}, {423, 330, 247}, {423, 0, 247}});
  // The published light lies in the ceiling plane (y = 548.8); 0.1 mm lower keeps the two from
  // fighting over the same hits, as pbrt's and Mitsuba's versions do. It faces down.
  addQuads(d, "light", "light",
           {{343, 548.7f, 227}, {343, 548.7f, 332}, {213, 548.7f, 332}, {213, 548.7f, 227}});
  d.camera = {{278, 273, -800}, {278, 273, -799}, {0, 1, 0}, 39.3f, 0, 0};
  d.environment = {};
  return d;
}

SceneDesc manySpheres(int countX, int countZ) {
  SceneDesc d;
  d.materials = {diffuse("floor", {0.5f, 0.5f, 0.5f}),
                 {"light", MaterialType::Emissive, Vec3{0.0f}, {6, 6, 5.5f}, 0, 1.5f},
                 {"mirror", MaterialType::Metal, {0.9f, 0.9f, 0.9f}, {}, 0, 1.5f},
                 {"gold", MaterialType::Metal, {1.0f, 0.78f, 0.34f}, {}, 0.35f, 1.5f},
                 {"glass", MaterialType::Glass, Vec3{1.0f}, {}, 0, 1.5f}};
  const Vec3 palette[6] = {{0.8f, 0.2f, 0.2f}, {0.2f, 0.7f, 0.2f}, {0.2f, 0.3f, 0.8f},
                           {0.8f, 0.7f, 0.2f}, {0.7f, 0.7f, 0.7f}, {0.6f, 0.3f, 0.7f}};
  for (int i = 0; i < 6; ++i)
    d.materials.push_back(diffuse("paint" + std::to_string(i), palette[i]));
  const float halfX = 0.5f * static_cast<float>(countX), depth = static_cast<float>(countZ);
  addQuads(d, "floor", "floor",
           {{-halfX - 20, 0, -20},
            {-halfX - 20, 0, depth + 20},
            {halfX + 20, 0, depth + 20},
            {halfX + 20, 0, -20}});
  // Facing down: corners ordered so cross(e1, e2) points to -y.
  addQuads(d, "light", "light", {{-12, 30, 4}, {12, 30, 4}, {12, 30, 28}, {-12, 30, 28}});
  Shape balls;
  balls.name = "spheres";
  for (int iz = 0; iz < countZ; ++iz) {
    for (int ix = 0; ix < countX; ++ix) {
      const std::uint64_t h =
          mix64(static_cast<std::uint64_t>(iz) << 32 | static_cast<unsigned>(ix));
      const auto unit = [&](int k) { return static_cast<float>((h >> (8 * k)) & 0xFF) / 255.0f; };
      const float r = 0.2f + 0.15f * unit(0);
      const float x = static_cast<float>(ix) - halfX + 0.5f + 0.3f * (unit(1) - 0.5f);
      const float z = static_cast<float>(iz) + 0.5f + 0.3f * (unit(2) - 0.5f);
      balls.spheres.centers.push_back({x, r, z});
      balls.spheres.radii.push_back(r);
      // Specular spheres are far more common on the right half: uneven tile cost on purpose.
      const float specularShare = x > 0 ? 0.7f : 0.1f;
      std::uint32_t m;
      if (unit(3) < specularShare)
        m = 2 + static_cast<std::uint32_t>(unit(4) * 2.99f);
      else
        m = 5 + static_cast<std::uint32_t>(unit(5) * 5.99f);
      balls.primitiveMaterials.push_back(m);
    }
  }
  d.shapes.push_back(std::move(balls));
  d.instances.push_back({static_cast<std::uint32_t>(d.shapes.size() - 1), {}, 0});
  d.camera = {{0, 9, -14}, {0, 0, 14}, {0, 1, 0}, 50.0f, 0, 0};
  d.environment.kind = Environment::Kind::Gradient;
  d.environment.bottom = {0.05f, 0.05f, 0.05f};
  d.environment.top = {0.35f, 0.45f, 0.7f};
  return d;
}

namespace {

struct Registered {
  std::string name;
  std::function<SceneDesc()> make;
};

struct Registry {
  std::mutex mutex;
  std::vector<Registered> scenes;
};

Registry& registry() {
  static Registry r;
  return r;
}

// The registered scene `name`'s maker, or an empty function.
std::function<SceneDesc()> findBuiltinScene(const std::string& name) {
  Registry& r = registry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  for (const Registered& e : r.scenes)
    if (e.name == name) return e.make;
  return {};
}

}  // namespace

void registerBuiltinScene(const std::string& name, std::function<SceneDesc()> make) {
  Registry& r = registry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  for (Registered& e : r.scenes)
    if (e.name == name) {
      e.make = std::move(make);
      return;
    }
  r.scenes.push_back({name, std::move(make)});
}

std::vector<std::string> builtinSceneNames() {
  std::vector<std::string> names{"cornell", "spheres"};
  Registry& r = registry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  for (const Registered& e : r.scenes) names.push_back(e.name);
  return names;
}

SceneDesc loadSceneDesc(const std::string& spec) {
  const std::string prefix = "builtin:";
  if (spec.rfind(prefix, 0) != 0) return readSceneToml(spec);
  const std::string name = spec.substr(prefix.size());
  if (name == "cornell") return cornellBox();
  if (name == "spheres") return manySpheres();
  if (const std::function<SceneDesc()> make = findBuiltinScene(name)) return make();
  std::string names;
  for (const auto& n : builtinSceneNames()) names += (names.empty() ? "" : ", ") + n;
  throw base::Error("unknown built-in scene '" + name + "' (choose " + names + ")");
}

}  // namespace renderers
