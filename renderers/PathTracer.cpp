#include "renderers/PathTracer.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>

#include "renderers/Bsdf.h"
#include "renderers/PixelBlocks.h"
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
      camera_(scene.desc().camera, settings.width, settings.height, settings.room),
      epsilon_(1e-4f * scene.extent()) {}

void PathTracer::beginFrame(const dfb::FrameInfo& /*frame*/, const CameraDesc& camera) {
  camera_ = Camera(camera, settings_.width, settings_.height, settings_.room);
}

Vec3 PathTracer::radiance(Vec3 origin, Vec3 direction, const Sampler& sampler) const {
  Hit hit;
  const bool found =
      scene_.intersect(origin, direction, 0.0f, std::numeric_limits<float>::infinity(), hit);
  return radiance(origin, direction, found, hit, sampler);
}

Vec3 PathTracer::radiance(Vec3 origin, Vec3 direction, bool found, Hit hit,
                          const Sampler& sampler) const {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  Vec3 result{}, throughput{1.0f};
  float previousPdf = 0;
  bool previousSpecular = true;  // the camera ray counts as specular: no MIS on what it sees
  for (int depth = 0; depth < settings_.maxDepth; ++depth) {
    if (depth > 0) found = scene_.intersect(origin, direction, 0.0f, kInf, hit);
    if (!found) {
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
  // Camera rays go to Embree as packets (PixelBlocks.h): about 1.5x the rays/s of single rays
  // here. The bounces are too incoherent to gain from packets and are traced one by one.
  constexpr int n = RayPacket::kSize;
  RayPacket rays;
  PacketHits hits;
  forEachBlock(region, [&](const PixelBlock& b) {
    Vec3 sum[n] = {};
    for (std::uint32_t s = firstSample; s < firstSample + samples; ++s) {
      Sampler samplers[n];
      for (int i = 0; i < n; ++i) {
        const Sampler& sampler = samplers[i] =
            Sampler(settings_.seed, b.x(i), b.y(i), accumulationId, s);
        // False under a room's bezels: that pixel stays black.
        rays.active[i] = camera_.ray(static_cast<float>(b.x(i)) + sampler.get(0),
                                     static_cast<float>(b.y(i)) + sampler.get(1), sampler.get(2),
                                     sampler.get(3), rays.origin[i], rays.direction[i]);
      }
      scene_.intersect(rays, hits);
      for (int i = 0; i < n; ++i) {
        if (!b.inside(region, i) || !rays.active[i]) continue;
        const Vec3 l =
            radiance(rays.origin[i], rays.direction[i], hits.found[i], hits.hit[i], samplers[i]);
        // A NaN or infinity from a degenerate path would poison the whole accumulation.
        if (std::isfinite(l.x + l.y + l.z)) sum[i] += l;
      }
    }
    for (int i = 0; i < n; ++i) {
      if (!b.inside(region, i)) continue;
      float* px = &out.color[4 * b.index(region, i)];
      px[0] = sum[i].x * inv, px[1] = sum[i].y * inv, px[2] = sum[i].z * inv, px[3] = 1.0f;
    }
  });
}

}  // namespace renderers
