#include "renderers/scivis/SciVisScene.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "renderers/EmbreeRays.h"
#include "renderers/Error.h"
#include "renderers/scivis/Bricks.h"
#include "renderers/scivis/TransferFunction.h"

namespace renderers {

std::size_t BrickContent::bytes() const {
  std::size_t total = 0;
  for (const Volume& v : volumes) total += v.bytes();
  for (const ShadingShell& s : shells) total += s.bytes();
  for (const auto* set : {&particles, &ghostParticles})
    for (const ParticlesDesc& p : *set) total += p.bytes();
  for (const auto* set : {&meshes, &ghostMeshes})
    for (const WorldMesh& m : *set)
      total += m.mesh.positions.size() * sizeof(Vec3) +
               m.mesh.triangles.size() * sizeof(m.mesh.triangles[0]);
  return total;
}

std::vector<WorldMesh> worldMeshes(const SceneDesc& desc) {
  std::vector<WorldMesh> out;
  for (const Instance& inst : desc.instances) {
    const Shape& s = desc.shapes.at(inst.shape);
    if (s.isSpheres()) continue;
    WorldMesh m;
    m.material = inst.material;
    m.mesh.triangles = s.mesh.triangles;
    for (const Vec3& p : s.mesh.positions) m.mesh.positions.push_back(inst.transform.point(p));
    out.push_back(std::move(m));
  }
  return out;
}

BrickContent wholeScene(const SceneDesc& desc) {
  // One brick without bounds: every voxel, particle and triangle, nothing as ghost.
  return loadBrick(desc, BrickPlan{0, Box3{}}, GhostReach{});
}

struct SciVisScene::Embree {
  struct Geometry {
    const WorldMesh* mesh = nullptr;           // triangles, or
    const ParticlesDesc* particles = nullptr;  // spheres
    std::vector<Vec3> normals;                 // per triangle, unit
  };
  RTCDevice device = nullptr;
  RTCScene camera = nullptr, shading = nullptr;
  std::vector<Geometry> geometries;  // by geometry ID, the same in both scenes
  std::size_t cameraGeometries = 0;  // none: no ray needs to ask Embree (a volume-only scene)
  std::string message;

  ~Embree() {
    if (camera) rtcReleaseScene(camera);
    if (shading) rtcReleaseScene(shading);
    if (device) rtcReleaseDevice(device);
  }

  void add(const WorldMesh* mesh, const ParticlesDesc* particles, bool seenByCamera) {
    RTCGeometry g;
    Geometry info;
    if (mesh) {
      g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
      auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0,
                                                            RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                            mesh->mesh.positions.size()));
      for (std::size_t i = 0; i < mesh->mesh.positions.size(); ++i) {
        const Vec3 p = mesh->mesh.positions[i];
        v[3 * i] = p.x, v[3 * i + 1] = p.y, v[3 * i + 2] = p.z;
      }
      auto* idx = static_cast<std::uint32_t*>(
          rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                  3 * sizeof(std::uint32_t), mesh->mesh.triangles.size()));
      for (std::size_t i = 0; i < mesh->mesh.triangles.size(); ++i) {
        const auto& t = mesh->mesh.triangles[i];
        if (t[0] >= mesh->mesh.positions.size() || t[1] >= mesh->mesh.positions.size() ||
            t[2] >= mesh->mesh.positions.size()) {
          rtcReleaseGeometry(g);
          throw Error("a mesh has a vertex index out of range");
        }
        std::copy(t.begin(), t.end(), idx + 3 * i);
        const Vec3 p0 = mesh->mesh.positions[t[0]];
        const Vec3 n = cross(mesh->mesh.positions[t[1]] - p0, mesh->mesh.positions[t[2]] - p0);
        info.normals.push_back(length(n) > 0 ? normalize(n) : Vec3{0, 0, 1});
      }
    } else {
      g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
      const std::size_t n = particles->centers.size();
      auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
          g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), n));
      for (std::size_t i = 0; i < n; ++i) {
        const Vec3 c = particles->centers[i];
        v[4 * i] = c.x, v[4 * i + 1] = c.y, v[4 * i + 2] = c.z, v[4 * i + 3] = particles->radius(i);
      }
    }
    info.mesh = mesh;
    info.particles = particles;
    rtcCommitGeometry(g);
    const auto id = static_cast<unsigned>(geometries.size());
    if (seenByCamera) rtcAttachGeometryByID(camera, g, id), ++cameraGeometries;
    rtcAttachGeometryByID(shading, g, id);
    rtcReleaseGeometry(g);
    geometries.push_back(std::move(info));
  }
};

SciVisScene::SciVisScene(std::shared_ptr<const SceneDesc> sceneDesc, BrickContent content)
    : desc_(std::move(sceneDesc)),
      content_(std::move(content)),
      embree_(std::make_unique<Embree>()) {
  const SceneDesc& desc = *desc_;
  const SciVisSettings& settings = desc.scivis;
  if (content_.volumes.size() != desc.volumes.size())
    throw Error("a scivis brick needs one (possibly empty) volume per scene volume");
  for (const auto* set : {&content_.particles, &content_.ghostParticles})
    for (const ParticlesDesc& p : *set) {
      if (p.material >= desc.materials.size())
        throw Error("particles '" + p.name + "': no such material");
      if (p.radii.size() != 1 && p.radii.size() != p.centers.size())
        throw Error("particles '" + p.name + "': one radius, or one per particle");
      if (!p.attribute.empty() && p.attribute.size() != p.centers.size())
        throw Error("particles '" + p.name + "': one attribute per particle");
    }
  for (const auto* set : {&content_.meshes, &content_.ghostMeshes})
    for (const WorldMesh& m : *set)
      if (m.material >= desc.materials.size()) throw Error("a mesh has no such material");
  for (const IsosurfaceDesc& iso : desc.isosurfaces)
    if (iso.volume >= desc.volumes.size() || iso.material >= desc.materials.size())
      throw Error("an isosurface names a volume or material that does not exist");

  // Volumes: one sampling step for all (the finest spacing over the sampling rate), and each
  // transfer function baked for that step.
  float finest = 0;
  for (const Volume& v : content_.volumes) {
    const Vec3 s = v.grid.spacing;
    const float m = std::min(s.x, std::min(s.y, s.z));
    if (!(m > 0)) throw Error("a volume's spacing must be positive");
    finest = finest > 0 ? std::min(finest, m) : m;
  }
  // Bricks must agree on the step with the whole scene: it comes from the scene's grids, not
  // from what this brick holds.
  finest = 0;
  for (const VolumeDesc& v : desc.volumes) {
    const Vec3 s = v.source.grid.spacing;
    const float m = std::min(s.x, std::min(s.y, s.z));
    finest = finest > 0 ? std::min(finest, m) : m;
  }
  step_ = finest > 0 ? finest / settings.samplingRate : 1.0f;
  for (std::size_t i = 0; i < content_.volumes.size(); ++i) {
    const Volume& v = content_.volumes[i];
    const VolumeDesc& vd = desc.volumes[i];
    VolumeLayer layer;
    layer.visible = vd.visible;
    if (!v.box.empty()) {
      fields_.push_back(std::make_unique<VolumeField>(v));
      layer.field = fields_.back().get();
    }
    if (i < content_.shells.size() && !content_.shells[i].empty())
      layer.shell = &content_.shells[i];
    for (const IsosurfaceDesc& iso : desc.isosurfaces)
      if (iso.volume == i) layer.isosurfaces.push_back(&iso);
    bake(layer, vd, vd.transfer, 1.0f);
    volumes_.push_back(std::move(layer));
  }

  // Surfaces.
  Embree& e = *embree_;
  e.device = rtcNewDevice(nullptr);
  if (!e.device) throw Error("Embree: cannot create a device");
  rtcSetDeviceErrorFunction(e.device, embree::keepFirstError, &e.message);
  e.camera = rtcNewScene(e.device);
  e.shading = rtcNewScene(e.device);
  for (const WorldMesh& m : content_.meshes) e.add(&m, nullptr, true);
  for (const ParticlesDesc& p : content_.particles) e.add(nullptr, &p, true);
  for (const WorldMesh& m : content_.ghostMeshes) e.add(&m, nullptr, false);
  for (const ParticlesDesc& p : content_.ghostParticles) e.add(nullptr, &p, false);
  rtcCommitScene(e.camera);
  rtcCommitScene(e.shading);
  if (!e.message.empty()) throw Error("Embree: building the scivis scene: " + e.message);

  // The scene's extent (for AO distances and ray offsets) from the whole scene's description,
  // not from what this brick holds: every brick offsets and reaches as the whole scene does.
  const Box3 domain = sceneDomain(desc);
  extent_ = std::max(1e-3f, maxComponent(domain.hi - domain.lo));
  aoDistance_ = settings.aoDistance > 0 ? settings.aoDistance : 0.25f * extent_;

  lights_ = resolveLights(desc);
}

std::vector<ResolvedLight> resolveLights(const SceneDesc& desc) {
  std::vector<ResolvedLight> lights;
  if (desc.lights.empty()) {
    lights.push_back({LightDesc::Kind::Ambient, {}, {}, Vec3{0.25f}});
    const Vec3 view = desc.camera.lookAt - desc.camera.position;
    lights.push_back({LightDesc::Kind::Directional,
                      length(view) > 0 ? -normalize(view) : Vec3{0, 0, 1},
                      {},
                      Vec3{0.85f}});
  } else {
    for (const LightDesc& l : desc.lights)
      lights.push_back({l.kind, -l.direction, l.position, l.color * l.intensity});
  }
  return lights;
}

SciVisScene::~SciVisScene() = default;

void SciVisScene::bake(VolumeLayer& layer, const VolumeDesc& vd, const TransferFunction& tf,
                       float opacityScale) const {
  if (!(tf.valueMax > tf.valueMin))
    throw Error("volume '" + vd.name + "': the transfer function's range is empty");
  const Vec3 s = vd.source.grid.spacing;
  const float unit = tf.unitDistance > 0 ? tf.unitDistance : std::min(s.x, std::min(s.y, s.z));
  const float exponent = step_ / unit;
  layer.valueMin = tf.valueMin;
  layer.tableScale = static_cast<float>(kTableSize - 1) / (tf.valueMax - tf.valueMin);
  layer.table.assign(4 * kTableSize, 0.0f);
  layer.visibleUpTo.assign(kTableSize + 1, 0);
  for (int e = 0; e < kTableSize; ++e) {
    const float value = tf.valueMin + static_cast<float>(e) / layer.tableScale;
    const Vec3 c = tf.color(value);
    const float a = std::clamp(tf.opacity(value) * opacityScale, 0.0f, 1.0f);
    // Opacity for the step: 1 - (1 - a)^(step / unit).
    const float corrected = a >= 1.0f ? 1.0f : 1.0f - std::pow(1.0f - a, exponent);
    float* t = &layer.table[4 * static_cast<std::size_t>(e)];
    t[0] = c.x, t[1] = c.y, t[2] = c.z, t[3] = vd.visible ? corrected : 0.0f;
    layer.visibleUpTo[static_cast<std::size_t>(e) + 1] =
        layer.visibleUpTo[static_cast<std::size_t>(e)] + (t[3] > 0 ? 1u : 0u);
  }
  layer.emptyMacrocells.clear();
  if (layer.field)
    for (int m = 0; m < layer.field->macroCount(); ++m)
      layer.emptyMacrocells.push_back(
          anythingIn(layer, layer.field->macroMin(m), layer.field->macroMax(m)) ? 0 : 1);
}

std::vector<SciVisScene::VolumeLayer> SciVisScene::retunedVolumes(int preset,
                                                                  float opacityScale) const {
  std::vector<VolumeLayer> out = volumes_;
  const std::vector<std::string> names = transferFunctionPresetNames();
  for (std::size_t i = 0; i < out.size(); ++i) {
    const VolumeDesc& vd = desc_->volumes[i];
    TransferFunction tf = vd.transfer;
    if (preset >= 0 && preset < static_cast<int>(names.size())) {
      float peak = 0;
      for (const auto& [value, opacity] : tf.opacities) peak = std::max(peak, opacity);
      if (tf.opacities.empty()) peak = 1;
      tf = transferFunctionPreset(names[static_cast<std::size_t>(preset)], vd.transfer.valueMin,
                                  vd.transfer.valueMax, peak);
      tf.unitDistance = vd.transfer.unitDistance;
    }
    bake(out[i], vd, tf, opacityScale);
  }
  return out;
}

bool SciVisScene::anythingIn(const VolumeLayer& v, float lo, float hi) {
  for (const IsosurfaceDesc* iso : v.isosurfaces)
    if (iso->value >= lo && iso->value <= hi) return true;
  // Table entries whose interpolation reaches [lo, hi].
  const float a = std::clamp((lo - v.valueMin) * v.tableScale, 0.0f, float(kTableSize - 1));
  const float b = std::clamp((hi - v.valueMin) * v.tableScale, 0.0f, float(kTableSize - 1));
  const auto first = static_cast<std::size_t>(a);
  const auto last = std::min<std::size_t>(static_cast<std::size_t>(b) + 1, kTableSize - 1);
  return v.visibleUpTo[last + 1] > v.visibleUpTo[first];
}

bool SciVisScene::intersectSurface(Vec3 origin, Vec3 dir, float tNear, float tFar,
                                   SurfaceHit& hit) const {
  if (embree_->cameraGeometries == 0) return false;
  const RTCRayHit rh = embree::closestHit(embree_->camera, origin, dir, tNear, tFar);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
  const Embree::Geometry& g = embree_->geometries[rh.hit.geomID];
  const std::uint32_t prim = rh.hit.primID;
  hit.t = rh.ray.tfar;
  if (g.mesh) {
    hit.material = &desc_->materials[g.mesh->material];
    hit.normal = g.normals[prim];
    hit.color = hit.material->color;
  } else {
    const ParticlesDesc& p = *g.particles;
    hit.material = &desc_->materials[p.material];
    hit.normal = normalize(origin + dir * hit.t - p.centers[prim]);
    hit.color = p.attribute.empty() ? hit.material->color : p.colorMap.color(p.attribute[prim]);
  }
  return true;
}

bool SciVisScene::surfaceOccluded(Vec3 origin, Vec3 dir, float tNear, float tFar) const {
  if (embree_->geometries.empty()) return false;
  return embree::occluded(embree_->shading, origin, dir, tNear, tFar);
}

}  // namespace renderers
