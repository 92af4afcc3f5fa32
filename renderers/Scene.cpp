#include "renderers/Scene.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <limits>
#include <string>

#include "base/Error.h"
#include "base/MemoryBudget.h"
#include "renderers/EmbreeRays.h"

namespace renderers {

int SceneDesc::findMaterial(const std::string& name) const {
  for (std::size_t i = 0; i < materials.size(); ++i)
    if (materials[i].name == name) return static_cast<int>(i);
  return -1;
}

std::vector<std::string> SceneDesc::inputFiles() const {
  std::vector<std::string> files;
  for (const Shape& s : shapes)
    if (!s.file.empty()) files.push_back(s.file);
  for (std::string& file : extensions.inputFiles()) files.push_back(std::move(file));
  return files;
}

std::uint64_t SceneDesc::bytes() const {
  std::uint64_t total = 0;
  for (const Shape& s : shapes) total += s.bytes();
  return total + extensions.bytes();
}

namespace {

struct LightTriangle {
  Vec3 p0, e1, e2, normal, radiance;
};

struct InstanceData {
  const Shape* shape = nullptr;
  Affine toObject;  // inverse of the instance transform
  std::uint32_t material = 0;
  std::vector<int> primitiveLight;  // empty when the instance has no emissive primitive
  // World-space unit normal per triangle of a shape moved to world space, computed as a hit
  // would compute it: a hit then reads 12 bytes instead of an index triple and three vertices
  // (5% of the bunny's time went there). Empty for spheres and instanced shapes.
  std::vector<Vec3> normals;
};

// The memory budget of building the scene: Embree's acceleration structure and its copy of each
// primitive, about kBvhBytesPerPrimitive a triangle or sphere (SceneDesc.h), once per instance
// at most (a shape placed once is moved into the top-level scene), on top of the description.
// Names the shape that asks most.
void checkMemory(const SceneDesc& d) {
  std::uint64_t total = d.bytes(), largestBytes = 0;
  std::size_t largest = 0;
  for (const Instance& inst : d.instances) {
    const Shape& shape = d.shapes.at(inst.shape);
    const std::uint64_t bytes = base::bytesTimes(shape.primitiveCount(), kBvhBytesPerPrimitive);
    total = base::bytesPlus(total, bytes);
    if (bytes > largestBytes) largestBytes = bytes, largest = inst.shape;
  }
  if (const std::string problem = base::memoryProblem(total); !problem.empty()) {
    const Shape& s = d.shapes[largest];
    throw base::Error((s.isSpheres() ? "sphere '" : "mesh '") + s.name + "'" +
                      (s.file.empty() ? std::string() : " (" + s.file + ")") + ": the scene's " +
                      "bounding volume hierarchy over its " + std::to_string(s.primitiveCount()) +
                      " primitives (about " + std::to_string(kBvhBytesPerPrimitive) +
                      " bytes each, per placement) and the rest of the scene " + problem);
  }
}

void validate(const SceneDesc& d) {
  const auto nm = d.materials.size();
  for (const Shape& s : d.shapes) {
    for (const auto& t : s.mesh.triangles)
      for (auto i : t)
        if (i >= s.mesh.positions.size())
          throw base::Error("shape '" + s.name + "': vertex index " + std::to_string(i) +
                            " out of range (" + std::to_string(s.mesh.positions.size()) +
                            " vertices)");
    for (float r : s.spheres.radii)
      if (!(r > 0)) throw base::Error("shape '" + s.name + "': sphere radius must be positive");
    if (s.spheres.radii.size() != s.spheres.centers.size())
      throw base::Error("shape '" + s.name + "': sphere centers and radii differ in count");
    if (!s.primitiveMaterials.empty() && s.primitiveMaterials.size() != s.primitiveCount())
      throw base::Error("shape '" + s.name + "': one material per primitive expected");
    for (auto m : s.primitiveMaterials)
      if (m >= nm) throw base::Error("shape '" + s.name + "': material index out of range");
  }
  for (const Instance& i : d.instances) {
    if (i.shape >= d.shapes.size()) throw base::Error("instance of an undefined shape");
    if (i.material >= nm)
      throw base::Error("instance of '" + d.shapes[i.shape].name +
                        "': material index out of range");
  }
}

// Whether a shape placed by `transform` can be moved to world space: triangles always, spheres
// only when not moved at all (a sphere stays a sphere only under a similarity; identity is
// the case that occurs, every sphere set of a scene file is placed as it is).
bool flattens(const Shape& s, const Affine& transform) {
  const Affine identity;
  return !s.isSpheres() || (transform.vx == identity.vx && transform.vy == identity.vy &&
                            transform.vz == identity.vz && transform.p == identity.p);
}

}  // namespace

struct Scene::Impl {
  Impl() = default;
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
  ~Impl() {
    if (top) rtcReleaseScene(top);
    for (RTCScene s : shapeScenes)
      if (s) rtcReleaseScene(s);
    if (device) rtcReleaseDevice(device);
  }

  SceneDesc desc;
  RTCDevice device = nullptr;
  RTCScene top = nullptr;
  std::vector<RTCScene> shapeScenes;
  std::vector<InstanceData> instances;
  std::vector<LightTriangle> lights;
  std::vector<float> lightCdf;  // inclusive prefix sums of power, normalised to end at 1
  std::vector<float> lightPdf;  // pdfArea per light
  std::string embreeMessage;
  float extent = 1;
  bool packetsExact = true;  // see Scene::intersect(RayPacket)

  // The world-space unit normal of primitive `prim` of `inst` at `position`.
  static Vec3 normal(const InstanceData& inst, std::uint32_t prim, Vec3 position);
  void fillHit(std::uint32_t instID, std::uint32_t geomID, std::uint32_t prim, float t, Vec3 origin,
               Vec3 direction, Hit& hit) const;

  void check(const char* what) {
    if (!embreeMessage.empty())
      throw base::Error(std::string("Embree: ") + what + ": " + embreeMessage);
  }

  // The Embree geometry of `s`, its vertices moved by `toWorld` (identity for a shared shape,
  // which its instances place).
  RTCGeometry buildGeometry(const Shape& s, const Affine& toWorld) {
    RTCGeometry g;
    if (s.isSpheres()) {
      g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
      auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0,
                                                            RTC_FORMAT_FLOAT4, 4 * sizeof(float),
                                                            s.spheres.centers.size()));
      for (std::size_t i = 0; i < s.spheres.centers.size(); ++i) {
        const Vec3 c = s.spheres.centers[i];
        v[4 * i] = c.x, v[4 * i + 1] = c.y, v[4 * i + 2] = c.z, v[4 * i + 3] = s.spheres.radii[i];
      }
    } else {
      g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
      auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0,
                                                            RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                            s.mesh.positions.size()));
      for (std::size_t i = 0; i < s.mesh.positions.size(); ++i) {
        const Vec3 p = toWorld.point(s.mesh.positions[i]);
        v[3 * i] = p.x, v[3 * i + 1] = p.y, v[3 * i + 2] = p.z;
      }
      auto* idx = static_cast<std::uint32_t*>(
          rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                  3 * sizeof(std::uint32_t), s.mesh.triangles.size()));
      for (std::size_t i = 0; i < s.mesh.triangles.size(); ++i)
        std::copy(s.mesh.triangles[i].begin(), s.mesh.triangles[i].end(), idx + 3 * i);
    }
    rtcCommitGeometry(g);
    return g;
  }

  RTCScene buildShape(const Shape& s) {
    RTCScene scene = rtcNewScene(device);
    RTCGeometry g = buildGeometry(s, Affine{});
    rtcAttachGeometryByID(scene, g, 0);
    rtcReleaseGeometry(g);
    rtcCommitScene(scene);
    check(("building shape '" + s.name + "'").c_str());
    return scene;
  }

  void collectLights(std::uint32_t instanceIndex) {
    const Instance& inst = desc.instances[instanceIndex];
    const Shape& s = desc.shapes[inst.shape];
    if (s.isSpheres()) return;  // emissive spheres are found by BSDF sampling only
    InstanceData& data = instances[instanceIndex];
    for (std::size_t p = 0; p < s.mesh.triangles.size(); ++p) {
      const Material& m =
          desc.materials[s.primitiveMaterials.empty() ? inst.material : s.primitiveMaterials[p]];
      if (m.type != MaterialType::Emissive || isBlack(m.emission)) continue;
      const auto& t = s.mesh.triangles[p];
      const Vec3 p0 = inst.transform.point(s.mesh.positions[t[0]]);
      const Vec3 e1 = inst.transform.point(s.mesh.positions[t[1]]) - p0;
      const Vec3 e2 = inst.transform.point(s.mesh.positions[t[2]]) - p0;
      const Vec3 c = cross(e1, e2);
      if (length(c) <= 0) continue;
      if (data.primitiveLight.empty()) data.primitiveLight.assign(s.mesh.triangles.size(), -1);
      data.primitiveLight[p] = static_cast<int>(lights.size());
      lights.push_back({p0, e1, e2, normalize(c), m.emission});
    }
  }

  void buildLightDistribution() {
    double total = 0;
    std::vector<double> power(lights.size());
    for (std::size_t i = 0; i < lights.size(); ++i) {
      const float area = 0.5f * length(cross(lights[i].e1, lights[i].e2));
      power[i] = area * std::max(luminance(lights[i].radiance), 1e-6f);
      total += power[i];
    }
    double running = 0;
    for (std::size_t i = 0; i < lights.size(); ++i) {
      running += power[i];
      lightCdf.push_back(static_cast<float>(running / total));
      const float area = 0.5f * length(cross(lights[i].e1, lights[i].e2));
      lightPdf.push_back(static_cast<float>(power[i] / total) / area);
    }
    if (!lightCdf.empty()) lightCdf.back() = 1.0f;
  }
};

Scene::Scene(SceneDesc desc) : impl_(std::make_unique<Impl>()) {
  validate(desc);
  checkMemory(desc);
  Impl& m = *impl_;
  m.desc = std::move(desc);
  m.device = rtcNewDevice(nullptr);
  if (!m.device) throw base::Error("Embree: cannot create a device");
  rtcSetDeviceErrorFunction(m.device, embree::keepFirstError, &m.embreeMessage);
  // A shape placed once goes into the top-level scene itself, moved to world space: Embree then
  // skips the instance step (a ray transform and a second BVH entry per ray), 13% of the
  // bunny's render time. Shapes placed more than once stay instances, so memory does not grow.
  std::vector<int> uses(m.desc.shapes.size(), 0);
  for (const Instance& inst : m.desc.instances) ++uses[inst.shape];
  for (const Instance& inst : m.desc.instances)
    if (!flattens(m.desc.shapes[inst.shape], inst.transform)) uses[inst.shape] = 2;
  m.shapeScenes.assign(m.desc.shapes.size(), nullptr);
  for (std::size_t s = 0; s < m.desc.shapes.size(); ++s)
    if (uses[s] > 1) m.shapeScenes[s] = m.buildShape(m.desc.shapes[s]);

  m.top = rtcNewScene(m.device);
  for (const Instance& inst : m.desc.instances)
    if (m.desc.shapes[inst.shape].isSpheres()) m.packetsExact = false;
  m.instances.resize(m.desc.instances.size());
  for (std::uint32_t i = 0; i < m.desc.instances.size(); ++i) {
    const Instance& inst = m.desc.instances[i];
    m.instances[i] = {&m.desc.shapes[inst.shape], inverse(inst.transform), inst.material, {}, {}};
    RTCGeometry g;
    if (m.shapeScenes[inst.shape]) {
      g = rtcNewGeometry(m.device, RTC_GEOMETRY_TYPE_INSTANCE);
      rtcSetGeometryInstancedScene(g, m.shapeScenes[inst.shape]);
      rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, &inst.transform.vx.x);
      rtcCommitGeometry(g);
    } else {
      g = m.buildGeometry(m.desc.shapes[inst.shape], inst.transform);
      InstanceData& data = m.instances[i];
      if (!data.shape->isSpheres())
        for (std::uint32_t p = 0; p < data.shape->mesh.triangles.size(); ++p)
          data.normals.push_back(Impl::normal(data, p, Vec3{}));
    }
    rtcAttachGeometryByID(m.top, g, i);
    rtcReleaseGeometry(g);
    m.collectLights(i);
  }
  rtcCommitScene(m.top);
  m.check("building the scene");
  m.buildLightDistribution();
  RTCBounds b;
  rtcGetSceneBounds(m.top, &b);
  if (b.lower_x <= b.upper_x)
    m.extent = std::max({b.upper_x - b.lower_x, b.upper_y - b.lower_y, b.upper_z - b.lower_z,
                         std::abs(b.lower_x), std::abs(b.upper_x), std::abs(b.lower_y),
                         std::abs(b.upper_y), std::abs(b.lower_z), std::abs(b.upper_z), 1e-3f});
}

// The Embree handles are released by Impl, so a constructor that throws halfway (a bad mesh,
// an Embree error) releases what it made too.
Scene::~Scene() = default;

const SceneDesc& Scene::desc() const { return impl_->desc; }
int Scene::lightCount() const { return static_cast<int>(impl_->lights.size()); }
float Scene::lightPdfArea(int light) const { return impl_->lightPdf[light]; }
float Scene::extent() const { return impl_->extent; }
RTCScene Scene::embreeScene() const { return impl_->top; }

// The hit record of Embree's answer: instance (or flattened geometry), primitive and distance.
void Scene::Impl::fillHit(std::uint32_t instID, std::uint32_t geomID, std::uint32_t prim, float t,
                          Vec3 origin, Vec3 direction, Hit& hit) const {
  const InstanceData& inst = instances[instID != RTC_INVALID_GEOMETRY_ID ? instID : geomID];
  const Shape& s = *inst.shape;
  hit.t = t;
  hit.position = origin + direction * t;
  hit.material =
      &desc.materials[s.primitiveMaterials.empty() ? inst.material : s.primitiveMaterials[prim]];
  hit.light = inst.primitiveLight.empty() ? -1 : inst.primitiveLight[prim];
  hit.normal = inst.normals.empty() ? normal(inst, prim, hit.position) : inst.normals[prim];
}

Vec3 Scene::Impl::normal(const InstanceData& inst, std::uint32_t prim, Vec3 position) {
  const Shape& s = *inst.shape;
  Vec3 n;
  if (s.isSpheres()) {
    n = inst.toObject.point(position) - s.spheres.centers[prim];
  } else {
    // From our own object-space vertices rather than Embree's Ng, so the normal and its side
    // do not depend on which kernel found the hit.
    const auto& tri = s.mesh.triangles[prim];
    const Vec3 p0 = s.mesh.positions[tri[0]];
    n = cross(s.mesh.positions[tri[1]] - p0, s.mesh.positions[tri[2]] - p0);
  }
  return normalize(transformNormal(inst.toObject, n));
}

bool Scene::intersect(Vec3 origin, Vec3 direction, float tNear, float tFar, Hit& hit) const {
  const RTCRayHit rh = embree::closestHit(impl_->top, origin, direction, tNear, tFar);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
  impl_->fillHit(rh.hit.instID[0], rh.hit.geomID, rh.hit.primID, rh.ray.tfar, origin, direction,
                 hit);
  return true;
}

bool Scene::tracesPackets() const { return impl_->packetsExact; }

void Scene::intersect(const RayPacket& rays, PacketHits& out) const {
  constexpr int n = RayPacket::kSize;
  if (!impl_->packetsExact) {
    for (int i = 0; i < n; ++i)
      out.found[i] =
          rays.active[i] && intersect(rays.origin[i], rays.direction[i], 0.0f,
                                      std::numeric_limits<float>::infinity(), out.hit[i]);
    return;
  }
  static_assert(n == 16, "RayPacket is traced with rtcIntersect16");
  alignas(64) int valid[n];
  alignas(64) RTCRayHit16 rh;
  for (int i = 0; i < n; ++i) {
    valid[i] = rays.active[i] ? -1 : 0;
    embree::setLane(rh, i, rays.origin[i], rays.direction[i], 0.0f,
                    std::numeric_limits<float>::infinity());
  }
  embree::closestHits16(impl_->top, valid, rh);
  for (int i = 0; i < n; ++i) {
    out.found[i] = rays.active[i] && rh.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID;
    if (out.found[i])
      impl_->fillHit(rh.hit.instID[0][i], rh.hit.geomID[i], rh.hit.primID[i], rh.ray.tfar[i],
                     rays.origin[i], rays.direction[i], out.hit[i]);
  }
}

bool Scene::occluded(Vec3 origin, Vec3 direction, float tNear, float tFar) const {
  return embree::occluded(impl_->top, origin, direction, tNear, tFar);
}

LightSample Scene::sampleLight(float u0, float u1, float u2) const {
  const Impl& m = *impl_;
  const auto it = std::upper_bound(m.lightCdf.begin(), m.lightCdf.end(), u0);
  const std::size_t i = std::min<std::size_t>(it - m.lightCdf.begin(), m.lights.size() - 1);
  const LightTriangle& l = m.lights[i];
  // Uniform over the triangle: fold the unit square onto it.
  const float su = std::sqrt(u1);
  const float b1 = 1.0f - su, b2 = u2 * su;
  return {l.p0 + l.e1 * b1 + l.e2 * b2, l.normal, l.radiance, m.lightPdf[i]};
}

}  // namespace renderers
