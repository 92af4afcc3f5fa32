#include "renderers/PathTracer.h"

#include <cmath>
#include <limits>

#include "renderers/Bsdf.h"
#include "renderers/Scene.h"

namespace renderers {
namespace {

// Random dimensions: 0-3 for the camera, then kPerBounce per path vertex.
constexpr std::uint32_t kCameraDims = 4, kPerBounce = 7;

float powerHeuristic(float a, float b) {
  const float a2 = a * a, b2 = b * b;
  return a2 + b2 > 0 ? a2 / (a2 + b2) : 0;
}

}  // namespace

PathTracer::PathTracer(const Scene& scene, const RenderSettings& settings)
    : scene_(scene),
      settings_(settings),
      camera_(frameCamera(scene.desc().camera, settings, 1), settings.width, settings.height),
      epsilon_(1e-4f * scene.extent()) {}

void PathTracer::beginFrame(const dfb::FrameInfo& frame) {
  camera_ = Camera(frameCamera(scene_.desc().camera, settings_, frame.frameId), settings_.width,
                   settings_.height);
}

Vec3 PathTracer::radiance(Vec3 origin, Vec3 direction, const Sampler& sampler) const {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  Vec3 result{}, throughput{1.0f};
  float previousPdf = 0;
  bool previousSpecular = true;  // the camera ray counts as specular: no MIS on what it sees
  for (int depth = 0; depth < settings_.maxDepth; ++depth) {
    Hit hit;
    if (!scene_.intersect(origin, direction, 0.0f, kInf, hit)) {
      result += throughput * scene_.desc().environment.radiance(direction);
      break;
    }
    const Material& m = *hit.material;
    const bool front = dot(direction, hit.normal) < 0;
    if (m.type == MaterialType::Emissive) {
      if (front) {
        float w = 1;
        if (!previousSpecular && hit.light >= 0) {
          const float cosL = -dot(direction, hit.normal);
          const float lightPdf = scene_.lightPdfArea(hit.light) * hit.t * hit.t / cosL;
          w = powerHeuristic(previousPdf, lightPdf);
        }
        result += throughput * m.emission * w;
      }
      break;
    }
    const Vec3 n = front ? hit.normal : -hit.normal;
    const Vec3 wo = -direction;
    const std::uint32_t d = kCameraDims + static_cast<std::uint32_t>(depth) * kPerBounce;
    const Vec3 offsetOut = hit.position + n * epsilon_;

    if (!isSpecular(m) && scene_.lightCount() > 0) {
      const LightSample ls =
          scene_.sampleLight(sampler.get(d), sampler.get(d + 1), sampler.get(d + 2));
      Vec3 toLight = ls.position - offsetOut;
      const float dist2 = dot(toLight, toLight), dist = std::sqrt(dist2);
      toLight = toLight / dist;
      const float cosL = -dot(toLight, ls.normal);
      if (cosL > 0 && dot(toLight, n) > 0) {
        float bsdfPdf;
        const Vec3 f = evalBsdf(m, n, wo, toLight, bsdfPdf);
        if (!isBlack(f) && !scene_.occluded(offsetOut, toLight, 0.0f, dist * (1.0f - 1e-4f))) {
          const float lightPdf = ls.pdfArea * dist2 / cosL;
          result += throughput * f * ls.radiance * (powerHeuristic(lightPdf, bsdfPdf) / lightPdf);
        }
      }
    }

    BsdfSample bs;
    if (!sampleBsdf(m, m.type == MaterialType::Glass ? hit.normal : n, wo, front,
                    sampler.get(d + 3), sampler.get(d + 4), sampler.get(d + 5), bs))
      break;
    throughput *= bs.weight;
    previousPdf = bs.pdf;
    previousSpecular = bs.specular;
    // Leave on the side the new direction points to (transmission goes through).
    origin = hit.position + (dot(bs.wi, n) > 0 ? n : -n) * epsilon_;
    direction = bs.wi;

    if (depth >= 3) {
      const float q = std::min(0.95f, maxComponent(throughput));
      if (sampler.get(d + 6) >= q) break;
      throughput *= 1.0f / q;
    }
  }
  return result;
}

void PathTracer::render(const dfb::Region& region, std::uint32_t accumulationId,
                        std::uint32_t firstSample, std::uint32_t samples, dfb::Tile& out) const {
  enableFlushToZero();
  prepareTile(region, accumulationId, firstSample, samples, out);
  const float inv = samples ? 1.0f / static_cast<float>(samples) : 0.0f;
  float* px = out.color.data();
  for (int y = region.y0; y < region.y1; ++y) {
    for (int x = region.x0; x < region.x1; ++x, px += 4) {
      Vec3 sum{};
      for (std::uint32_t s = firstSample; s < firstSample + samples; ++s) {
        const Sampler sampler(settings_.seed, x, y, accumulationId, s);
        Vec3 o, dir;
        camera_.ray(static_cast<float>(x) + sampler.get(0), static_cast<float>(y) + sampler.get(1),
                    sampler.get(2), sampler.get(3), o, dir);
        const Vec3 l = radiance(o, dir, sampler);
        // A NaN or infinity from a degenerate path would poison the whole accumulation.
        if (std::isfinite(l.x + l.y + l.z)) sum += l;
      }
      px[0] = sum.x * inv, px[1] = sum.y * inv, px[2] = sum.z * inv, px[3] = 1.0f;
    }
  }
}

}  // namespace renderers
