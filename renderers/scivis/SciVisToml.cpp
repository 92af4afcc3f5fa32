#include "renderers/scivis/SciVisToml.h"

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "base/MemoryBudget.h"
#include "renderers/scivis/io/Particles.h"
#include "renderers/scivis/io/VolumeToml.h"
#include "renderers/scivis/scene/SciVisScene.h"

namespace renderers::scivis {
namespace {

// Reads `key` as one number or an array of numbers.
std::vector<float> numbers(TomlReader& r, const toml::node& n, const std::string& field) {
  std::vector<float> out;
  if (const toml::array* a = n.as_array()) {
    for (const toml::node& e : *a) out.push_back(r.number(e, field));
  } else {
    out.push_back(r.number(n, field));
  }
  return out;
}

void readIsosurface(TomlReader& r, const toml::table& t, SceneDesc& d) {
  SciVisDesc& parts = sciVisDesc(d);
  const std::string what = "isosurface";
  r.onlyKeys(t, what, {"volume", "value", "values", "material", "materials"});
  const toml::node* vn = r.need(t, "volume", what);
  const std::string volume = r.string(vn, what + ".volume");
  std::uint32_t v = 0;
  while (v < parts.volumes.size() && parts.volumes[v].name != volume) ++v;
  if (vn && vn->is_string() && v == parts.volumes.size()) {
    std::vector<std::string> names;
    for (const VolumeDesc& other : parts.volumes) names.push_back(other.name);
    r.notDefined(*vn, what + ".volume", "volume", volume, names);
  }

  if (t.get("value") && t.get("values"))
    r.fail(*t.get("values"), what, "give value or values, not both");
  const toml::node* valuesNode = t.get("values") ? t.get("values") : t.get("value");
  if (!valuesNode) r.problem(t, what + ".values", "missing");
  const std::vector<float> values =
      valuesNode ? numbers(r, *valuesNode, what + ".values") : std::vector<float>{};
  if (valuesNode && values.empty()) r.problem(*valuesNode, what + ".values", "must not be empty");

  std::vector<std::uint32_t> materials;
  if (const toml::node* ms = t.get("materials")) {
    const toml::array* a = ms->as_array();
    if (!a || a->size() != values.size())
      r.fail(*ms, what + ".materials", "must be an array with one material per value");
    std::vector<std::string> defined;
    for (const Material& m : d.materials) defined.push_back(m.name);
    for (const toml::node& m : *a) {
      const std::string name = r.string(m, what + ".materials");
      const int i = d.findMaterial(name);
      if (m.is_string() && i < 0) r.notDefined(m, what + ".materials", "material", name, defined);
      materials.push_back(static_cast<std::uint32_t>(i));
    }
  } else {
    materials.assign(values.size(), r.material(d, t, what));
  }
  r.settle();
  for (std::size_t i = 0; i < values.size(); ++i)
    parts.isosurfaces.push_back({v, values[i], materials[i]});
}

void readParticles(TomlReader& r, const toml::table& t, const std::filesystem::path& folder,
                   SceneDesc& d) {
  const std::string name = t.get("name") ? r.string(t.get("name"), "particles.name") : "particles";
  const std::string what = "particles '" + name + "'";
  r.onlyKeys(t, what,
             {"name", "material", "radius", "radii", "centers", "file", "layout", "generator",
              "count", "seed", "center", "size", "attribute", "color_map"});
  ParticlesDesc p;
  p.name = name;
  p.material = r.material(d, t, what);
  const int sources =
      (t.get("centers") ? 1 : 0) + (t.get("file") ? 1 : 0) + (t.get("generator") ? 1 : 0);
  if (sources != 1) r.fail(t, what, "give exactly one of centers, file or generator");
  const float radius = r.number(t, "radius", what, 0.0f);
  if (t.get("radius") && !(radius > 0))
    r.problem(*t.get("radius"), what + ".radius", "must be positive");

  if (const toml::node* c = t.get("centers")) {
    const toml::array* a = c->as_array();
    if (!a)
      r.fail(*c, what + ".centers",
             "expected an array of [x, y, z], got " + base::tomlTypeName(*c));
    for (const toml::node& e : *a) p.centers.push_back(r.vec3(e, what + ".centers"));
  } else if (const toml::node* f = t.get("file")) {
    const std::string layout =
        t.get("layout") ? r.string(t.get("layout"), what + ".layout") : std::string("xyz");
    const std::string fileName = r.string(*f, what + ".file");
    r.settle();  // the file is read only as the fields above say
    p.file = (folder / fileName).string();
    // Reading holds the file's records and the particles made of them (no more than as many
    // bytes again).
    std::error_code ec;
    const std::uint64_t fileBytes = std::filesystem::file_size(p.file, ec);
    if (!ec)
      r.budget(*f, what + ".file", std::to_string(fileBytes) + " bytes",
               d.bytes() + base::bytesTimes(fileBytes, 2));
    r.loading(*f, what + ".file", [&] {
      try {
        readParticleFile(p.file, layout, p);
      } catch (const base::Error& e) {
        r.fail(*f, what + ".file", e.what());
      }
    });
  } else {
    const toml::node& g = *t.get("generator");
    const std::string generator = r.string(g, what + ".generator");
    if (g.is_string() && generator != "clusters")
      r.problem(g, what + ".generator", "must be \"clusters\", not \"" + generator + "\"");
    const std::size_t before = r.problems();
    const toml::node* countNode = r.need(t, "count", what);
    const std::uint32_t count = r.index(countNode, what + ".count");
    if (r.problems() == before && (count == 0 || count > 100'000'000))
      r.problem(*countNode, what + ".count", "must be between 1 and 100000000");
    const std::uint64_t seed = t.get("seed") ? r.index(t.get("seed"), what + ".seed") : 1;
    const float size = r.number(t, "size", what, 2.0f);
    if (!(size > 0)) r.problem(*t.get("size"), what + ".size", "must be positive");
    const Vec3 center = r.vec3(t, "center", what, {});
    r.settle();
    r.budget(*countNode, what + ".count", std::to_string(count) + " particles",
             d.bytes() + std::uint64_t{count} * (sizeof(Vec3) + sizeof(float)));
    p = r.loading(*countNode, what + ".count", [&] {
      return clusteredParticles(count, seed, center, size, radius > 0 ? radius : 0.002f * size);
    });
    p.name = name;
    p.material = r.material(d, t, what);
  }

  if (const toml::node* rs = t.get("radii")) {
    if (t.get("radius")) r.fail(*rs, what, "give radius or radii, not both");
    p.radii = numbers(r, *rs, what + ".radii");
  } else if (radius > 0) {
    p.radii = {radius};
  }
  r.settle();
  if (p.radii.empty()) r.fail(t, what + ".radius", "missing (or 'radii', or 'r' in the layout)");
  if (p.radii.size() != 1 && p.radii.size() != p.centers.size())
    r.fail(*t.get("radii"), what + ".radii", "must have one radius per particle");
  // Radii and attributes from a file may be anything; a sphere must stay within the float range
  // and be wider than a float step where it is.
  const toml::node& radiiAt = t.get("radii")    ? *t.get("radii")
                              : t.get("radius") ? *t.get("radius")
                              : t.get("file")   ? *t.get("file")
                                                : t;
  for (float x : p.radii)
    if (!(x > 0 && std::isfinite(x)))
      r.fail(radiiAt, what, "every radius must be positive and finite, not " + TomlReader::text(x));
  for (std::size_t i = 0; i < p.centers.size(); ++i) {
    const Vec3 c = p.centers[i];
    const float ri = p.radius(i);
    if (!isFinite(c) || !isFinite(c + Vec3{ri}) || !isFinite(c - Vec3{ri}))
      r.fail(radiiAt, what,
             "particle " + std::to_string(i) + " reaches beyond the float range (center ± radius)");
    if (ri < floatStep(maxAbs(c)))
      r.fail(radiiAt, what,
             "the radius of particle " + std::to_string(i) + ", " + TomlReader::text(ri) +
                 ", is below float precision at its center (steps of " +
                 TomlReader::text(floatStep(maxAbs(c))) + " there)");
  }
  if (const toml::node* a = t.get("attribute")) {
    p.attribute = numbers(r, *a, what + ".attribute");
    r.settle();
    if (p.attribute.size() != p.centers.size())
      r.fail(*a, what + ".attribute", "must have one value per particle");
  }
  for (std::size_t i = 0; i < p.attribute.size(); ++i)
    if (!std::isfinite(p.attribute[i]))
      r.fail(t.get("attribute") ? *t.get("attribute") : radiiAt, what,
             "the attribute of particle " + std::to_string(i) + " is not finite");
  if (const toml::node* cm = t.get("color_map")) {
    p.colorMap = readTransferFunction(r, *cm, what + ".color_map");
    if (p.attribute.empty()) r.fail(*cm, what + ".color_map", "needs an attribute per particle");
  } else if (!p.attribute.empty()) {
    float lo = p.attribute[0], hi = p.attribute[0];
    for (float x : p.attribute) lo = std::min(lo, x), hi = std::max(hi, x);
    p.colorMap = transferFunctionPreset("viridis", lo, hi > lo ? hi : lo + 1);
  }
  if (p.centers.empty()) r.fail(t, what, "no particles");
  r.settle();
  sciVisDesc(d).particles.push_back(std::move(p));
}

LightDesc readLight(TomlReader& r, const toml::table& t) {
  const std::string what = "light";
  r.onlyKeys(t, what, {"type", "direction", "position", "color", "intensity"});
  LightDesc l;
  const toml::node* typeNode = r.need(t, "type", what);
  const std::string type = r.string(typeNode, what + ".type");
  if (type == "directional") {
    l.kind = LightDesc::Kind::Directional;
    const std::size_t before = r.problems();
    const toml::node* dn = r.need(t, "direction", what);
    l.direction = r.vec3(dn, what + ".direction");
    if (r.problems() == before && !(length(l.direction) > 0))
      r.problem(*dn, what + ".direction", "must not be zero");
    l.direction = normalize(l.direction);
  } else if (type == "point") {
    l.kind = LightDesc::Kind::Point;
    l.position = r.vec3(r.need(t, "position", what), what + ".position");
  } else if (type == "ambient") {
    l.kind = LightDesc::Kind::Ambient;
  } else if (typeNode && typeNode->is_string()) {
    r.problem(*typeNode, what + ".type",
              "must be directional, point or ambient, not \"" + type + "\"");
  }
  l.color = r.vec3(t, "color", what, Vec3{1.0f});
  l.intensity = r.number(t, "intensity", what, 1.0f);
  if (!(l.intensity >= 0))
    r.problem(*t.get("intensity"), what + ".intensity", "must not be negative");
  r.settle();
  if (!isFinite(l.color * l.intensity))
    r.fail(t.get("intensity") ? *t.get("intensity") : *t.get("color"), what,
           "color x intensity is beyond the float range");
  return l;
}

void readSettings(TomlReader& r, const toml::table& t, SciVisSettings& s) {
  const std::string what = "scivis";
  r.onlyKeys(t, what,
             {"ao_samples", "ao_distance", "sampling_rate", "shadows", "min_transmittance"});
  if (const toml::node* n = t.get("ao_samples")) {
    const std::uint32_t v = r.index(*n, what + ".ao_samples");
    if (v > 256)
      r.problem(*n, what + ".ao_samples", "must be at most 256");
    else
      s.aoSamples = static_cast<int>(v);
  }
  s.aoDistance = r.number(t, "ao_distance", what, s.aoDistance);
  if (!(s.aoDistance >= 0))
    r.problem(*t.get("ao_distance"), what + ".ao_distance", "must not be negative");
  s.samplingRate = r.number(t, "sampling_rate", what, s.samplingRate);
  if (!(s.samplingRate >= 0.01f && s.samplingRate <= 64))
    r.problem(*t.get("sampling_rate"), what + ".sampling_rate", "must be in [0.01, 64]");
  s.shadows = r.boolean(t, "shadows", what, s.shadows);
  s.minTransmittance = r.number(t, "min_transmittance", what, s.minTransmittance);
  if (!(s.minTransmittance >= 0 && s.minTransmittance < 1))
    r.problem(*t.get("min_transmittance"), what + ".min_transmittance", "must be in [0, 1)");
}

// The renderer marches rays in steps of the finest spacing over the sampling rate, counting
// the steps from the camera in float: beyond 2^22 steps a float no longer counts them exactly
// (a ray would stand still), so a scene whose volumes lie that many steps from its camera is
// refused, naming the volume with the finest spacing.
void checkSampling(TomlReader& r, const std::vector<const toml::table*>& tables,
                   const SceneDesc& d) {
  constexpr double kMaxSteps = 1 << 22;
  const SciVisDesc& parts = sciVisDesc(d);
  std::size_t finest = 0;
  Vec3 lo{INFINITY}, hi{-INFINITY};
  for (std::size_t i = 0; i < parts.volumes.size(); ++i) {
    const GridGeometry& g = parts.volumes[i].source.grid;
    if (minComponent(g.spacing) < minComponent(parts.volumes[finest].source.grid.spacing))
      finest = i;
    Vec3 a, b;
    g.bounds(g.wholeBox(), a, b);
    lo = {std::min(lo.x, a.x), std::min(lo.y, a.y), std::min(lo.z, a.z)};
    hi = {std::max(hi.x, b.x), std::max(hi.y, b.y), std::max(hi.z, b.z)};
  }
  if (parts.volumes.empty()) return;
  const double step = double(minComponent(parts.volumes[finest].source.grid.spacing)) /
                      double(parts.settings.samplingRate);
  const Vec3 eye = d.camera.position;
  double reach = 0;
  for (int corner = 0; corner < 8; ++corner) {
    const double dx = double(corner & 1 ? hi.x : lo.x) - eye.x;
    const double dy = double(corner & 2 ? hi.y : lo.y) - eye.y;
    const double dz = double(corner & 4 ? hi.z : lo.z) - eye.z;
    reach = std::max(reach, std::sqrt(dx * dx + dy * dy + dz * dz));
  }
  if (reach / step > kMaxSteps) {
    const toml::table& t = *tables[finest];
    r.problem(t.get("spacing") ? *t.get("spacing") : t,
              "volume '" + parts.volumes[finest].name + "'.spacing",
              "the volumes are sampled every " + TomlReader::text(step) +
                  " world units (the finest spacing / scivis.sampling_rate) and reach " +
                  TomlReader::text(reach) + " from the camera: " + TomlReader::text(reach / step) +
                  " samples along a ray, more than a float counts exactly (2^22); use a coarser "
                  "spacing or put the camera nearer");
  }
}

// The series of a scene play together: the same number of steps at the same rate.
void checkSeries(TomlReader& r, const std::vector<const toml::table*>& tables, const SceneDesc& d) {
  const std::vector<VolumeDesc>& volumes = sciVisDesc(d).volumes;
  const VolumeDesc* first = nullptr;
  for (std::size_t i = 0; i < volumes.size(); ++i) {
    const VolumeDesc& v = volumes[i];
    if (v.steps.empty()) continue;
    if (!first) {
      first = &v;
      continue;
    }
    const toml::table& t = *tables[i];
    if (v.steps.size() != first->steps.size())
      r.problem(t.get("time_steps") ? *t.get("time_steps") : *t.get("file"),
                "volume '" + v.name + "'.time_steps",
                "is " + std::to_string(v.steps.size()) + ", volume '" + first->name + "' has " +
                    std::to_string(first->steps.size()) + ": the series of a scene play together");
    if (v.fps != first->fps)
      r.problem(t.get("fps") ? *t.get("fps") : t, "volume '" + v.name + "'.fps",
                "differs from volume '" + first->name + "''s: the series of a scene play together");
  }
}

}  // namespace

void readSciVis(TomlReader& r, const toml::table& root, const std::filesystem::path& folder,
                SceneDesc& d) {
  SciVisDesc& parts = sciVisDesc(d);
  const std::vector<const toml::table*> volumes = r.arrayOfTables(root, "volumes");
  for (std::size_t i = 0; i < volumes.size(); ++i) {
    const toml::table& t = *volumes[i];
    if (i == SciVisScene::kMaxVolumes)
      r.problem(t, "volumes",
                "the scivis renderer draws at most " + std::to_string(SciVisScene::kMaxVolumes) +
                    " volumes, and this is volume " + std::to_string(i + 1));
    if (i >= SciVisScene::kMaxVolumes) continue;
    const std::string name = t.get("name") ? t.get("name")->value_or(std::string()) : "";
    const bool ok = r.entry([&] {
      VolumeDesc v = r.loading(t, "volume", [&] { return readVolume(r, t, folder); });
      r.settle();
      for (const VolumeDesc& other : parts.volumes)
        if (other.name == v.name) r.fail(t, "volume '" + v.name + "'", "is defined twice");
      parts.volumes.push_back(std::move(v));
    });
    if (!ok && !name.empty()) r.markFailed("volume", name);
  }
  for (const toml::table* t : r.arrayOfTables(root, "isosurfaces"))
    r.entry([&] { readIsosurface(r, *t, d); });
  for (const toml::table* t : r.arrayOfTables(root, "particles"))
    r.entry([&] { readParticles(r, *t, folder, d); });
  for (const toml::table* t : r.arrayOfTables(root, "lights"))
    r.entry([&] { parts.lights.push_back(readLight(r, *t)); });
  if (const toml::node* s = root.get("scivis"))
    r.entry([&] {
      if (const toml::table* t = r.table(*s, "scivis")) readSettings(r, *t, parts.settings);
    });
  // Judged on a file read cleanly: a volume that failed is not in parts.volumes.
  if (r.diagnostics().ok()) checkSampling(r, volumes, d);
  if (r.diagnostics().ok()) checkSeries(r, volumes, d);
}

}  // namespace renderers::scivis
