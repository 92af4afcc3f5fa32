#include "renderers/PrimaryRenderer.h"

#include <cmath>
#include <limits>

#include "renderers/Scene.h"

namespace renderers {

PrimaryRenderer::PrimaryRenderer(const Scene& scene, const RenderSettings& settings)
    : scene_(scene),
      settings_(settings),
      camera_(frameCamera(scene.desc().camera, settings, 1), settings.width, settings.height) {}

void PrimaryRenderer::beginFrame(const dfb::FrameInfo& frame) {
  camera_ = Camera(frameCamera(scene_.desc().camera, settings_, frame.frameId), settings_.width,
                   settings_.height);
}

void PrimaryRenderer::render(const dfb::Region& region, std::uint32_t accumulationId,
                             std::uint32_t firstSample, std::uint32_t samples,
                             dfb::Tile& out) const {
  enableFlushToZero();
  prepareTile(region, accumulationId, firstSample, samples, out);
  float* px = out.color.data();
  for (int y = region.y0; y < region.y1; ++y) {
    for (int x = region.x0; x < region.x1; ++x, px += 4) {
      Vec3 o, d;
      camera_.ray(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f, 0.5f, 0.5f, o, d);
      Hit hit;
      Vec3 c;
      if (!scene_.intersect(o, d, 0.0f, std::numeric_limits<float>::infinity(), hit)) {
        c = scene_.desc().environment.radiance(d);
      } else {
        const float cosine = std::abs(dot(d, hit.normal));
        c = hit.material->emission + hit.material->color * (0.15f + 0.85f * cosine);
      }
      px[0] = c.x, px[1] = c.y, px[2] = c.z, px[3] = 1.0f;
    }
  }
}

}  // namespace renderers
