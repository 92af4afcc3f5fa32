#include "renderers/scivis/scene/SciVisScene.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <string>

#include "base/Error.h"
#include "base/Parallel.h"
#include "renderers/EmbreeRays.h"
#include "renderers/TransferFunction.h"
#include "renderers/scivis/scene/Isosurfaces.h"

namespace renderers::scivis {

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

// Every particle set of the scene: its [[particles]] and the path tracer's sphere shapes.
std::vector<const ParticlesDesc*> particleSets(const SceneDesc& desc,
                                               std::vector<ParticlesDesc>& converted) {
  for (const Instance& inst : desc.instances) {
    const Shape& s = desc.shapes.at(inst.shape);
    if (!s.isSpheres()) continue;
    ParticlesDesc p;
    p.name = s.name;
    for (const Vec3& c : s.spheres.centers) p.centers.push_back(inst.transform.point(c));
    p.radii = s.spheres.radii;
    p.material = inst.material;
    converted.push_back(std::move(p));
  }
  std::vector<const ParticlesDesc*> out;
  for (const ParticlesDesc& p : sciVisDesc(desc).particles) out.push_back(&p);
  for (const ParticlesDesc& p : converted) out.push_back(&p);
  return out;
}

Box3 sceneDomain(const SceneDesc& desc) {
  Box3 domain{Vec3{Box3::kInf}, Vec3{-Box3::kInf}};
  for (const VolumeDesc& v : sciVisDesc(desc).volumes) {
    Vec3 lo, hi;
    v.source.grid.bounds(v.source.grid.wholeBox(), lo, hi);
    grow(domain, lo, hi);
  }
  std::vector<ParticlesDesc> converted;
  for (const ParticlesDesc* p : particleSets(desc, converted))
    for (std::size_t i = 0; i < p->centers.size(); ++i)
      grow(domain, p->centers[i] - Vec3{p->radius(i)}, p->centers[i] + Vec3{p->radius(i)});
  for (const WorldMesh& m : worldMeshes(desc))
    for (const Vec3& v : m.mesh.positions) grow(domain, v, v);
  if (domain.empty()) throw base::Error("the scene is empty: nothing to cut into bricks");
  return domain;
}

struct SciVisScene::Embree {
  struct Geometry {
    const WorldMesh* mesh = nullptr;             // triangles, or
    const ParticlesDesc* particles = nullptr;    // spheres, or
    const IsosurfaceDesc* isosurface = nullptr;  // an isosurface's triangles on `field`
    const VolumeField* field = nullptr;
    std::vector<Vec3> normals;  // per mesh triangle, unit
    // An isosurface seen by the camera: its triangles (Embree's index buffer, alive as long as
    // the scene) and per vertex the field's unit gradient there (zero where it has none).
    const std::uint32_t* triangles = nullptr;
    std::vector<Vec3> vertexNormals;
    // Triangles (meshes, isosurfaces): Embree's buffers, alive as long as the scene.
    const float* vertices = nullptr;
    std::size_t vertexCount = 0, triangleCount = 0;
    bool seenByCamera = false;
  };
  RTCDevice device = nullptr;
  RTCScene camera = nullptr, shading = nullptr;
  std::vector<Geometry> geometries;   // by geometry ID, the same in both scenes
  std::size_t cameraGeometries = 0;   // none: no ray needs to ask Embree (a volume-only scene)
  std::size_t shadingGeometries = 0;  // ghost data: seen by shading rays only
  bool packetsExact = true;           // no spheres among the camera geometries
  // What shading rays test: the camera scene, or (with ghost data) the shading scene, which
  // holds the ghost geometries and the camera scene as an instance (one BVH per triangle).
  RTCScene occluders = nullptr;
  std::string message;
  std::atomic<std::int64_t> bytes{0};  // what Embree holds (its memory monitor)

  static bool monitor(void* self, ssize_t bytes, bool /*post*/) {
    static_cast<Embree*>(self)->bytes.fetch_add(bytes, std::memory_order_relaxed);
    return true;
  }

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
          throw base::Error("a mesh has a vertex index out of range");
        }
        std::copy(t.begin(), t.end(), idx + 3 * i);
        const Vec3 p0 = mesh->mesh.positions[t[0]];
        const Vec3 n = cross(mesh->mesh.positions[t[1]] - p0, mesh->mesh.positions[t[2]] - p0);
        info.normals.push_back(length(n) > 0 ? normalize(n) : Vec3{0, 0, 1});
      }
      info.vertices = v, info.triangles = idx;
      info.vertexCount = mesh->mesh.positions.size(),
      info.triangleCount = mesh->mesh.triangles.size();
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
    if (particles && seenByCamera) packetsExact = false;
    attach(g, std::move(info), seenByCamera);
  }

  // An isosurface's triangles; the mesh can go once this returns (Embree holds a copy).
  // `field` gives camera hits their normals (shading rays need none: may be null for them).
  void add(const IsoMesh& mesh, const IsosurfaceDesc& iso, const VolumeField* field,
           bool seenByCamera) {
    if (mesh.triangles.empty()) return;
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
        g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.positions.size()));
    auto* idx = static_cast<std::uint32_t*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                3 * sizeof(std::uint32_t), mesh.triangles.size()));
    if (!v || !idx) {
      rtcReleaseGeometry(g);
      throw base::Error("Embree: cannot allocate an isosurface's buffers: " + message);
    }
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
      const Vec3 p = mesh.positions[i];
      v[3 * i] = p.x, v[3 * i + 1] = p.y, v[3 * i + 2] = p.z;
    }
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
      std::copy(mesh.triangles[i].begin(), mesh.triangles[i].end(), idx + 3 * i);
    Geometry info;
    info.isosurface = &iso;
    info.field = field;
    info.vertices = v, info.triangles = idx;
    info.vertexCount = mesh.positions.size(), info.triangleCount = mesh.triangles.size();
    if (seenByCamera && field) {
      // The field's gradient at each vertex, once, instead of at every hit (6 trilinear samples
      // per camera ray). A vertex has the same bits in every brick that makes it (Isosurfaces.h)
      // and the gradient reads only voxels the brick holds with its ghost layer, so normals
      // match across bricks as the hit-point gradients did.
      info.vertexNormals.resize(mesh.positions.size());
      constexpr std::size_t kChunk = 16384;
      const std::size_t n = mesh.positions.size();
      base::parallelFor((n + kChunk - 1) / kChunk, [&](std::size_t c) {
        for (std::size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) {
          const Vec3 grad = field->gradient(mesh.positions[i], 0.5f * field->minSpacing());
          info.vertexNormals[i] = length(grad) > 0 ? normalize(grad) : Vec3{};
        }
      });
    }
    attach(g, std::move(info), seenByCamera);
  }

  void attach(RTCGeometry g, Geometry info, bool seenByCamera) {
    info.seenByCamera = seenByCamera;
    rtcCommitGeometry(g);
    const auto id = static_cast<unsigned>(geometries.size());
    if (seenByCamera)
      rtcAttachGeometryByID(camera, g, id), ++cameraGeometries;
    else
      rtcAttachGeometryByID(shading, g, id), ++shadingGeometries;
    rtcReleaseGeometry(g);
    geometries.push_back(std::move(info));
  }
};

SciVisScene::SciVisScene(std::shared_ptr<const SceneDesc> sceneDesc, BrickContent content)
    : desc_(std::move(sceneDesc)),
      sciVis_(&sciVisDesc(*desc_)),
      content_(std::move(content)),
      embree_(std::make_unique<Embree>()) {
  const SceneDesc& desc = *desc_;
  const SciVisSettings& settings = sciVis_->settings;
  if (sciVis_->volumes.size() > kMaxVolumes)
    throw base::Error("the scene has " + std::to_string(sciVis_->volumes.size()) +
                      " volumes; the scivis renderer draws at most " + std::to_string(kMaxVolumes));
  if (content_.volumes.size() != sciVis_->volumes.size())
    throw base::Error("a scivis brick needs one (possibly empty) volume per scene volume");
  for (const auto* set : {&content_.particles, &content_.ghostParticles})
    for (const ParticlesDesc& p : *set) {
      if (p.material >= desc.materials.size())
        throw base::Error("particles '" + p.name + "': no such material");
      if (p.radii.size() != 1 && p.radii.size() != p.centers.size())
        throw base::Error("particles '" + p.name + "': one radius, or one per particle");
      if (!p.attribute.empty() && p.attribute.size() != p.centers.size())
        throw base::Error("particles '" + p.name + "': one attribute per particle");
    }
  for (const auto* set : {&content_.meshes, &content_.ghostMeshes})
    for (const WorldMesh& m : *set)
      if (m.material >= desc.materials.size()) throw base::Error("a mesh has no such material");
  for (const IsosurfaceDesc& iso : sciVis_->isosurfaces)
    if (iso.volume >= sciVis_->volumes.size() || iso.material >= desc.materials.size())
      throw base::Error("an isosurface names a volume or material that does not exist");

  // Volumes: one sampling step for all (the finest spacing over the sampling rate), and each
  // transfer function baked for that step.
  float finest = 0;
  for (const Volume& v : content_.volumes) {
    const Vec3 s = v.grid.spacing;
    const float m = std::min(s.x, std::min(s.y, s.z));
    if (!(m > 0)) throw base::Error("a volume's spacing must be positive");
    finest = finest > 0 ? std::min(finest, m) : m;
  }
  // Bricks must agree on the step with the whole scene: it comes from the scene's grids, not
  // from what this brick holds.
  finest = 0;
  for (const VolumeDesc& v : sciVis_->volumes) {
    const Vec3 s = v.source.grid.spacing;
    const float m = std::min(s.x, std::min(s.y, s.z));
    finest = finest > 0 ? std::min(finest, m) : m;
  }
  step_ = finest > 0 ? finest / settings.samplingRate : 1.0f;
  for (std::size_t i = 0; i < content_.volumes.size(); ++i) {
    content_.volumes[i].spreadSlices();  // before any field or isosurface reads them
    const Volume& v = content_.volumes[i];
    const VolumeDesc& vd = sciVis_->volumes[i];
    VolumeLayer layer;
    layer.visible = vd.visible;
    if (!v.box.empty()) {
      fields_.push_back(std::make_unique<VolumeField>(v));
      layer.field = fields_.back().get();
    }
    if (i < content_.shells.size() && !content_.shells[i].empty())
      layer.shell = &content_.shells[i];
    for (const IsosurfaceDesc& iso : sciVis_->isosurfaces)
      if (iso.volume == i) layer.isosurfaces.push_back(&iso);
    bake(layer, vd, vd.transfer, 1.0f);
    volumes_.push_back(std::move(layer));
  }

  // Surfaces.
  Embree& e = *embree_;
  e.device = rtcNewDevice(nullptr);
  if (!e.device) throw base::Error("Embree: cannot create a device");
  rtcSetDeviceErrorFunction(e.device, embree::keepFirstError, &e.message);
  rtcSetDeviceMemoryMonitorFunction(e.device, &Embree::monitor, &e);
  e.camera = rtcNewScene(e.device);
  e.shading = rtcNewScene(e.device);
  // Watertight intersection: a closed isosurface must not let a ray through where two of its
  // triangles meet (without it one pixel of the 1024² contours image saw through).
  rtcSetSceneFlags(e.camera, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneFlags(e.shading, RTC_SCENE_FLAG_ROBUST);
  for (const WorldMesh& m : content_.meshes) e.add(&m, nullptr, true);
  for (const ParticlesDesc& p : content_.particles) e.add(nullptr, &p, true);
  for (const WorldMesh& m : content_.ghostMeshes) e.add(&m, nullptr, false);
  for (const ParticlesDesc& p : content_.ghostParticles) e.add(nullptr, &p, false);
  const auto meshStart = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < volumes_.size(); ++i) addIsosurfaces(i);
  rtcCommitScene(e.camera);
  e.occluders = e.camera;
  if (e.shadingGeometries > 0) {
    if (e.cameraGeometries > 0) {
      RTCGeometry instance = rtcNewGeometry(e.device, RTC_GEOMETRY_TYPE_INSTANCE);
      rtcSetGeometryInstancedScene(instance, e.camera);
      const float identity[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
      rtcSetGeometryTransform(instance, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, identity);
      rtcCommitGeometry(instance);
      rtcAttachGeometryByID(e.shading, instance, static_cast<unsigned>(e.geometries.size()));
      rtcReleaseGeometry(instance);
    }
    rtcCommitScene(e.shading);
    e.occluders = e.shading;
  }
  if (!e.message.empty()) throw base::Error("Embree: building the scivis scene: " + e.message);
  isosurfaceStats_.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - meshStart).count();

  // The scene's extent (for AO distances and ray offsets) from the whole scene's description,
  // not from what this brick holds: every brick offsets and reaches as the whole scene does.
  domain_ = sceneDomain(desc);
  extent_ = std::max(1e-3f, maxComponent(domain_.hi - domain_.lo));
  aoDistance_ = settings.aoDistance > 0 ? settings.aoDistance : 0.25f * extent_;

  lights_ = resolveLights(desc);
}

std::vector<ResolvedLight> resolveLights(const SceneDesc& desc) {
  const SciVisDesc& parts = sciVisDesc(desc);
  std::vector<ResolvedLight> lights;
  if (parts.lights.empty()) {
    lights.push_back({LightDesc::Kind::Ambient, {}, {}, Vec3{0.25f}});
    const Vec3 view = desc.camera.lookAt - desc.camera.position;
    lights.push_back({LightDesc::Kind::Directional,
                      length(view) > 0 ? -normalize(view) : Vec3{0, 0, 1},
                      {},
                      Vec3{0.85f}});
  } else {
    for (const LightDesc& l : parts.lights)
      lights.push_back({l.kind, -l.direction, l.position, l.color * l.intensity});
  }
  return lights;
}

SciVisScene::~SciVisScene() = default;

std::size_t SciVisScene::bytes() const {
  std::size_t normals = 0;
  for (const Embree::Geometry& g : embree_->geometries)
    normals += (g.normals.size() + g.vertexNormals.size()) * sizeof(Vec3);
  return content_.bytes() + normals +
         static_cast<std::size_t>(std::max<std::int64_t>(0, embree_->bytes));
}

void SciVisScene::addIsosurfaces(std::size_t volume) {
  const VolumeLayer& layer = volumes_[volume];
  // A brick without dense voxels of the volume may still hold a shell for its shading rays.
  if (layer.isosurfaces.empty() || (!layer.field && !layer.shell)) return;
  const VolumeField* field = layer.field;
  const Volume& voxels = content_.volumes[volume];
  const GridGeometry& grid = voxels.grid;
  std::vector<float> isovalues;
  for (const IsosurfaceDesc* iso : layer.isosurfaces) isovalues.push_back(iso->value);
  auto holdsIsovalue = [&](float lo, float hi) {
    return std::any_of(isovalues.begin(), isovalues.end(),
                       [&](float v) { return v >= lo && v <= hi; });
  };
  auto intersect = [](const VoxelBox& a, const VoxelBox& b) {
    return VoxelBox{{std::max(a.lo.x, b.lo.x), std::max(a.lo.y, b.lo.y), std::max(a.lo.z, b.lo.z)},
                    {std::min(a.hi.x, b.hi.x), std::min(a.hi.y, b.hi.y), std::min(a.hi.z, b.hi.z)}};
  };
  // Cells of the dense core; those camera rays can hit: around the clip bounds, a cell beyond
  // (a hit inside the bounds lies in a cell that overlaps them).
  const VoxelBox coreCells{voxels.box.lo,
                           {voxels.box.hi.x - 1, voxels.box.hi.y - 1, voxels.box.hi.z - 1}};
  VoxelBox cameraCells;
  for (int a = 0; a < 3; ++a) {
    const double lo =
        std::floor((double(content_.bounds.lo[a]) - grid.origin[a]) / grid.spacing[a]) - 1;
    const double hi =
        std::floor((double(content_.bounds.hi[a]) - grid.origin[a]) / grid.spacing[a]) + 2;
    const int i0 = static_cast<int>(std::clamp(lo, -1.0, double(grid.dims[a])));
    const int i1 = static_cast<int>(std::clamp(hi, -1.0, double(grid.dims[a])));
    (a == 0 ? cameraCells.lo.x : a == 1 ? cameraCells.lo.y : cameraCells.lo.z) = i0;
    (a == 0 ? cameraCells.hi.x : a == 1 ? cameraCells.hi.y : cameraCells.hi.z) = i1;
  }
  cameraCells = intersect(cameraCells, coreCells);
  // Per macrocell holding an isovalue: its cells camera rays can hit, and the rest of its cells
  // (shading rays only).
  std::vector<CellBlock> camera, shading;
  for (int m = 0; field && m < field->macroCount(); ++m) {
    if (!holdsIsovalue(field->macroMin(m), field->macroMax(m))) continue;
    const Index3 o = field->macroOrigin(m);
    const VoxelBox cells =
        intersect(VoxelBox{o,
                           {o.x + FieldGeometry::kMacro, o.y + FieldGeometry::kMacro,
                            o.z + FieldGeometry::kMacro}},
                  coreCells);
    const VoxelBox seen = intersect(cells, cameraCells);
    if (!seen.empty()) camera.push_back({seen, {}, 0});
    if (!(seen == cells)) shading.push_back({cells, cameraCells, 0});
  }
  // The sparse shell's cells outside the core (its blocks hold only macrocells with an
  // isovalue).
  std::vector<std::pair<Index3, const float*>> shellBlocks;
  if (layer.shell) {
    const VoxelBox core = layer.shell->core();
    const VoxelBox skip = core.empty()
                              ? VoxelBox{}
                              : VoxelBox{core.lo, {core.hi.x - 1, core.hi.y - 1, core.hi.z - 1}};
    layer.shell->forEachBlock([&](Index3 lo, Index3 size, const float* data) {
      shading.push_back({{lo, {lo.x + size.x - 1, lo.y + size.y - 1, lo.z + size.z - 1}},
                         skip,
                         static_cast<int>(shellBlocks.size()) + 1});
      shellBlocks.emplace_back(size, data);
    });
  }
  const BlockReader read = [&](const CellBlock& b, float* out) {
    const Index3 n{b.cells.hi.x - b.cells.lo.x + 1, b.cells.hi.y - b.cells.lo.y + 1,
                   b.cells.hi.z - b.cells.lo.z + 1};
    if (b.source > 0) {  // a shell block: exactly these voxels
      const auto& [size, data] = shellBlocks[static_cast<std::size_t>(b.source - 1)];
      std::copy(data, data + std::size_t(size.x) * size.y * size.z, out);
      return;
    }
    for (int z = 0; z < n.z; ++z)
      for (int y = 0; y < n.y; ++y)
        for (int x = 0; x < n.x; ++x)
          *out++ = voxels.at(b.cells.lo.x + x, b.cells.lo.y + y, b.cells.lo.z + z);
  };
  for (bool seenByCamera : {true, false}) {
    const std::vector<IsoMesh> meshes =
        polygonise(grid, seenByCamera ? camera : shading, isovalues, read);
    for (std::size_t k = 0; k < meshes.size(); ++k) {
      (seenByCamera ? isosurfaceStats_.cameraTriangles : isosurfaceStats_.shadingTriangles) +=
          meshes[k].triangles.size();
      embree_->add(meshes[k], *layer.isosurfaces[k], field, seenByCamera);
    }
  }
}

void SciVisScene::bake(VolumeLayer& layer, const VolumeDesc& vd, const TransferFunction& tf,
                       float opacityScale) const {
  if (!(tf.valueMax > tf.valueMin))
    throw base::Error("volume '" + vd.name + "': the transfer function's range is empty");
  const Vec3 s = vd.source.grid.spacing;
  const float unit = tf.unitDistance > 0 ? tf.unitDistance : std::min(s.x, std::min(s.y, s.z));
  const float exponent = step_ / unit;
  layer.valueMin = tf.valueMin;
  layer.tableScale = static_cast<float>(kTableSize - 1) / (tf.valueMax - tf.valueMin);
  layer.table.assign(kTableEntryFloats * kTableSize, 0.0f);
  layer.visibleUpTo.assign(kTableSize + 1, 0);
  for (int e = 0; e < kTableSize; ++e) {
    const float value = tf.valueMin + static_cast<float>(e) / layer.tableScale;
    const Vec3 c = tf.color(value);
    const float a = std::clamp(tf.opacity(value) * opacityScale, 0.0f, 1.0f);
    // Opacity for the step: 1 - (1 - a)^(step / unit).
    const float corrected = a >= 1.0f ? 1.0f : 1.0f - std::pow(1.0f - a, exponent);
    float* t = &layer.table[kTableEntryFloats * static_cast<std::size_t>(e)];
    t[0] = c.x, t[1] = c.y, t[2] = c.z, t[3] = vd.visible ? corrected : 0.0f;
    if (e > 0) {  // the previous entry's difference to this one
      float* previous = t - kTableEntryFloats;
      for (int k = 0; k < 4; ++k) previous[4 + k] = t[k] - previous[k];
    }
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
    const VolumeDesc& vd = sciVis_->volumes[i];
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
  fillSurfaceHit(rh.hit.geomID, rh.hit.primID, rh.hit.u, rh.hit.v, rh.ray.tfar, origin, dir, hit);
  return true;
}

bool SciVisScene::hasCameraSurfaces() const { return embree_->cameraGeometries > 0; }

bool SciVisScene::opaqueCameraTriangles(std::vector<FirstHitRaster::Mesh>& out) const {
  out.clear();
  const Embree& e = *embree_;
  if (!e.packetsExact) return false;  // spheres among the camera data
  for (std::size_t id = 0; id < e.geometries.size(); ++id) {
    const Embree::Geometry& g = e.geometries[id];
    if (!g.seenByCamera) continue;
    if (!g.vertices || !g.triangles) return false;
    const std::uint32_t material = g.isosurface ? g.isosurface->material : g.mesh->material;
    if (!(desc_->materials[material].opacity >= 1.0f)) return false;
    out.push_back(
        {g.vertices, g.vertexCount, g.triangles, g.triangleCount, static_cast<std::uint32_t>(id)});
  }
  return true;
}

void SciVisScene::intersectSurfaces(const SurfaceQuery* queries, int count, SurfaceHit* hits,
                                    bool* found) const {
  constexpr int n = kSurfacePacket;
  if (count > n) throw base::Error("intersectSurfaces: more rays than a packet holds");
  if (embree_->cameraGeometries == 0 || !embree_->packetsExact) {
    for (int i = 0; i < count; ++i) {
      const SurfaceQuery& q = queries[i];
      found[i] = q.active && intersectSurface(q.origin, q.dir, q.tNear, q.tFar, hits[i]);
    }
    return;
  }
  static_assert(n == 16, "traced with rtcIntersect16");
  alignas(64) int valid[n];
  alignas(64) RTCRayHit16 rh;
  for (int i = 0; i < n; ++i) {
    const bool on = i < count && queries[i].active;
    valid[i] = on ? -1 : 0;
    const SurfaceQuery q = on ? queries[i] : SurfaceQuery{{}, {0, 0, 1}, 0, 0, false};
    embree::setLane(rh, i, q.origin, q.dir, q.tNear, q.tFar);
  }
  embree::closestHits16(embree_->camera, valid, rh);
  for (int i = 0; i < count; ++i) {
    found[i] = valid[i] && rh.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID;
    if (found[i])
      fillSurfaceHit(rh.hit.geomID[i], rh.hit.primID[i], rh.hit.u[i], rh.hit.v[i], rh.ray.tfar[i],
                     queries[i].origin, queries[i].dir, hits[i]);
  }
}

void SciVisScene::fillSurfaceHit(std::uint32_t geomID, std::uint32_t prim, float u, float v,
                                 float t, Vec3 origin, Vec3 dir, SurfaceHit& hit) const {
  const Embree::Geometry& g = embree_->geometries[geomID];
  hit.t = t;
  if (g.isosurface) {
    // Shaded as the field's level set: the normal from the field's gradient at the triangle's
    // vertices, interpolated (Phong normals) with the hit's barycentric coordinates.
    hit.material = &desc_->materials[g.isosurface->material];
    hit.color = hit.material->color;
    const std::uint32_t* tri = g.triangles + 3 * std::size_t{prim};
    const Vec3 n = g.vertexNormals[tri[0]] * (1.0f - u - v) + g.vertexNormals[tri[1]] * u +
                   g.vertexNormals[tri[2]] * v;
    hit.normal = length(n) > 0 ? normalize(n) : -dir;
  } else if (g.mesh) {
    hit.material = &desc_->materials[g.mesh->material];
    hit.normal = g.normals[prim];
    hit.color = hit.material->color;
  } else {
    const ParticlesDesc& p = *g.particles;
    hit.material = &desc_->materials[p.material];
    hit.normal = normalize(origin + dir * hit.t - p.centers[prim]);
    hit.color = p.attribute.empty() ? hit.material->color : p.colorMap.color(p.attribute[prim]);
  }
}

bool SciVisScene::surfaceOccluded(Vec3 origin, Vec3 dir, float tNear, float tFar) const {
  if (embree_->geometries.empty()) return false;
  return embree::occluded(embree_->occluders, origin, dir, tNear, tFar);
}

}  // namespace renderers::scivis
