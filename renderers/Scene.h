#pragma once
// A scene ready to trace: one Embree 3 device and a two-level BVH (every Instance is an Embree
// instance of its Shape's scene), plus the list of emissive triangles sampled as area lights.
//
// Contracts: construction builds everything and throws base::Error on invalid input or an
// Embree error; afterwards every const method is thread-safe and never blocks.
#include <cstdint>
#include <memory>

#include "renderers/SceneDesc.h"

// Embree's handle type, declared as rtcore.h does, so this header does not need Embree.
typedef struct RTCSceneTy* RTCScene;

namespace renderers {

struct Hit {
  float t = 0;
  Vec3 position;
  Vec3 normal;  // world-space geometric normal of the primitive's front side, unit length
  const Material* material = nullptr;
  int light = -1;  // index of the area light hit, or -1
};

// Rays traced together through Embree's 16-wide packet kernels, e.g. a 4x4 block of camera rays.
// Inactive lanes are not traced.
struct RayPacket {
  static constexpr int kSize = 16;
  Vec3 origin[kSize], direction[kSize];
  bool active[kSize] = {};
};

struct PacketHits {
  Hit hit[RayPacket::kSize];
  bool found[RayPacket::kSize] = {};
};

struct LightSample {
  Vec3 position, normal, radiance;
  float pdfArea = 0;  // probability density over the light's area, light selection included
};

class Scene {
 public:
  explicit Scene(SceneDesc desc);
  ~Scene();
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  const SceneDesc& desc() const;
  // The closest hit along origin + t * direction, t in (tNear, tFar).
  bool intersect(Vec3 origin, Vec3 direction, float tNear, float tFar, Hit& hit) const;
  bool occluded(Vec3 origin, Vec3 direction, float tNear, float tFar) const;
  // The closest hits of a packet's active lanes, t in (0, inf). Each lane gets what intersect()
  // gives that ray alone, bit for bit, whatever the other lanes hold (tests/renderers/
  // PacketTest.cpp): Embree's triangle packet kernels compute a lane with the single-ray
  // arithmetic, instanced or not. Its sphere kernels do not (t differs in the last bits for
  // about a fifth of sphere hits), so in a scene with spheres the lanes are traced one by one.
  void intersect(const RayPacket& rays, PacketHits& out) const;
  // Whether intersect(RayPacket) uses Embree's packet kernels (no spheres in the scene).
  bool tracesPackets() const;

  int lightCount() const;
  // A point on one emissive triangle, chosen in proportion to its power; (u0, u1, u2) uniform.
  LightSample sampleLight(float u0, float u1, float u2) const;
  // pdfArea of sampleLight() for a point on light `light`.
  float lightPdfArea(int light) const;

  // A length scale for ray offsets (the scene's bounding-box extent).
  float extent() const;
  RTCScene embreeScene() const;  // for benchmarks that call Embree directly

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace renderers
