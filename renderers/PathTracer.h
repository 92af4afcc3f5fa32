#pragma once
// Unidirectional path tracer: next-event estimation on emissive triangles combined with BSDF
// sampling by multiple importance sampling (power heuristic), Russian roulette after three
// segments, at most RenderSettings::maxDepth segments.
#include "renderers/Camera.h"
#include "renderers/Renderer.h"
#include "renderers/Rng.h"
#include "renderers/Scene.h"

namespace renderers {

class PathTracer final : public Renderer {
 public:
  PathTracer(const Scene& scene, const RenderSettings& settings);
  // Moves the camera along the orbit of RenderSettings (a no-op without one).
  void beginFrame(const dfb::FrameInfo& frame, const CameraDesc& camera) override;
  void setLiveSettings(const LiveSettings& live) override { settings_.maxDepth = live.maxDepth; }
  void render(const dfb::Region& region, std::uint32_t accumulationId, std::uint32_t firstSample,
              std::uint32_t samples, dfb::Tile& out) const override;
  // Radiance along one camera ray; public for known-answer tests.
  Vec3 radiance(Vec3 origin, Vec3 direction, const Sampler& sampler) const;

 private:
  // The same, given what the camera ray hits (found, hit) as Scene::intersect reports it.
  Vec3 radiance(Vec3 origin, Vec3 direction, bool found, Hit hit, const Sampler& sampler) const;

  const Scene& scene_;
  RenderSettings settings_;
  Camera camera_;
  float epsilon_;
};

}  // namespace renderers
