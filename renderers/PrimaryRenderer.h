#pragma once
// One primary ray through each pixel centre and simple shading (albedo under a head light plus
// emission, environment behind): fast previews, and a ray-cast load between pattern and path
// tracing. Ignores the sample range beyond recording it: every sample would be the same.
#include "renderers/Camera.h"
#include "renderers/Renderer.h"

namespace renderers {

class PrimaryRenderer final : public Renderer {
 public:
  PrimaryRenderer(const Scene& scene, const RenderSettings& settings);
  // Moves the camera along the orbit of RenderSettings (a no-op without one).
  void beginFrame(const dfb::FrameInfo& frame, const CameraDesc& camera) override;
  void render(const dfb::Region& region, std::uint32_t accumulationId, std::uint32_t firstSample,
              std::uint32_t samples, dfb::Tile& out) const override;

 private:
  const Scene& scene_;
  RenderSettings settings_;
  Camera camera_;
};

}  // namespace renderers
