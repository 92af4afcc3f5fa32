#pragma once
// A scene ready to trace: one Embree 3 device and a two-level BVH (every Instance is an Embree
// instance of its Shape's scene), plus the list of emissive triangles sampled as area lights.
//
// Contracts: construction builds everything and throws renderers::Error on invalid input or an
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
