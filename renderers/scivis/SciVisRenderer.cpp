#include "renderers/scivis/SciVisRenderer.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include "renderers/PixelBlocks.h"

#include <emmintrin.h>

namespace renderers {
namespace {

constexpr float kInf = Box3::kInf;

// The accumulated colour of a ray so far: premultiplied RGB and the light still getting through.
struct Accumulator {
  Vec3 rgb;
  float transmittance = 1.0f;
  float depth = kInf;
  void add(Vec3 color, float alpha, float t) {
    rgb += color * (transmittance * alpha);
    transmittance *= 1.0f - alpha;
    if (depth == kInf && transmittance <= 0.5f) depth = t;
  }
};

// Table lookup with linear interpolation between entries.
inline void lookup(const SciVisScene::VolumeLayer& v, float value, float rgba[4]) {
  const float x = std::clamp((value - v.valueMin) * v.tableScale, 0.0f,
                             static_cast<float>(SciVisScene::kTableSize - 1));
  const int i = std::min(static_cast<int>(x), SciVisScene::kTableSize - 2);
  const float f = x - static_cast<float>(i);
  const float* a = &v.table[4 * static_cast<std::size_t>(i)];
  for (int c = 0; c < 4; ++c) rgba[c] = a[c] + f * (a[4 + c] - a[c]);
}

// A cosine-weighted direction about unit n.
Vec3 cosineDirection(Vec3 n, float u0, float u1) {
  Vec3 t, b;
  basis(n, t, b);
  const float r = std::sqrt(u0), phi = 2.0f * kPi * u1;
  const float x = r * std::cos(phi), y = r * std::sin(phi), z = std::sqrt(std::max(0.0f, 1 - u0));
  return t * x + b * y + n * z;
}

std::uint64_t bitsOf(float t) { return std::bit_cast<std::uint32_t>(t); }

// The common case, apart from the generic loop for speed: one visible volume, between two
// surfaces (isosurfaces are surfaces) or none. It composites exactly the samples
// the generic loop composites, with the same arithmetic (same bits): t_k = (k + jitter) step
// from the first k >= kStart with t_k >= t0, while t_k < t1, t_k <= volumeEnd and light gets
// through. Samples are taken four at a time (SSE lanes, each computed as the scalar path does)
// and composited one by one in order; those past the end or past opacity are dropped. Samples
// in empty macrocells have zero opacity: skipping them changes no bit.
template <class T>
std::uint32_t marchOneVolume(const SciVisScene::VolumeLayer& v, Vec3 origin, Vec3 dir, Vec3 invDir,
                             float t0, float t1, float kStart, float volumeEnd, float step,
                             float jitter, float minTransmittance, Accumulator& acc) {
  const VolumeField& field = *v.field;
  const std::uint8_t* empty = v.emptyMacrocells.data();
  float k = std::max(kStart, std::ceil(t0 / step - jitter));
  while (k > kStart && (k - 1 + jitter) * step >= t0) k -= 1;  // rounding: the exact first
  while ((k + jitter) * step < t0) k += 1;

  const __m128 lanes = _mm_setr_ps(0, 1, 2, 3), jitters = _mm_set1_ps(jitter),
               steps = _mm_set1_ps(step);
  const __m128 tableScale = _mm_set1_ps(v.tableScale), valueMin = _mm_set1_ps(v.valueMin);
  const __m128 zero = _mm_setzero_ps(),
               lastEntry = _mm_set1_ps(static_cast<float>(SciVisScene::kTableSize - 1));
  const __m128i lastLower = _mm_set1_epi32(SciVisScene::kTableSize - 2);
  const float* table = v.table.data();
  __m128 rgb = _mm_setr_ps(acc.rgb.x, acc.rgb.y, acc.rgb.z, 0);
  float transmittance = acc.transmittance, depth = acc.depth;
  std::uint32_t samples = 0;
  for (bool done = false; !done && transmittance > minTransmittance; k += 4) {
    alignas(16) float t[4];
    const __m128 ts = _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_set1_ps(k), lanes), jitters), steps);
    _mm_store_ps(t, ts);
    if (t[0] >= t1 || t[0] > volumeEnd) break;
    __m128 values;
    int macro0;
    const int inside = field.sample4<T>(
        _mm_add_ps(_mm_set1_ps(origin.x), _mm_mul_ps(_mm_set1_ps(dir.x), ts)),
        _mm_add_ps(_mm_set1_ps(origin.y), _mm_mul_ps(_mm_set1_ps(dir.y), ts)),
        _mm_add_ps(_mm_set1_ps(origin.z), _mm_mul_ps(_mm_set1_ps(dir.z), ts)), values, macro0);
    if (macro0 >= 0 && empty[macro0]) {
      // Jump to one sample before the sample before the macrocell's exit, as the generic loop
      // does: the margin keeps rounding from skipping a sample of the next macrocell.
      float a = t[0], b = kInf;
      clipToBox(field.macroBounds(macro0), origin, invDir, a, b);
      const float last = std::floor(b / step - jitter) - 1;
      if (last > k + 4) {
        samples += 1;
        k = last - 4;  // the loop's += 4 lands on `last`
        continue;
      }
    }
    // The transfer function, as lookup() computes it: x = clamp(scaled, 0, last entry), entry
    // i = min(int(x), last - 1), weight x - i.
    __m128 x = _mm_mul_ps(_mm_sub_ps(values, valueMin), tableScale);
    x = _mm_andnot_ps(_mm_cmplt_ps(x, zero), x);
    const __m128 over = _mm_cmplt_ps(lastEntry, x);
    x = _mm_or_ps(_mm_and_ps(over, lastEntry), _mm_andnot_ps(over, x));
    __m128i i = _mm_cvttps_epi32(x);
    const __m128i high = _mm_cmpgt_epi32(i, lastLower);
    i = _mm_or_si128(_mm_and_si128(high, lastLower), _mm_andnot_si128(high, i));
    i = _mm_and_si128(i, _mm_cmpgt_epi32(i, _mm_set1_epi32(-1)));  // NaN data: entry 0
    alignas(16) int entry[4];
    alignas(16) float weight[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(entry), i);
    _mm_store_ps(weight, _mm_sub_ps(x, _mm_cvtepi32_ps(i)));
    for (int lane = 0; lane < 4; ++lane) {
      if (transmittance <= minTransmittance || t[lane] >= t1 || t[lane] > volumeEnd) {
        done = true;
        break;
      }
      ++samples;
      if (!(inside >> lane & 1)) continue;
      const float* e = table + 4 * static_cast<std::size_t>(entry[lane]);
      const __m128 a = _mm_loadu_ps(e), b = _mm_loadu_ps(e + 4);
      const __m128 rgba = _mm_add_ps(a, _mm_mul_ps(_mm_set1_ps(weight[lane]), _mm_sub_ps(b, a)));
      const float alpha = _mm_cvtss_f32(_mm_shuffle_ps(rgba, rgba, _MM_SHUFFLE(3, 3, 3, 3)));
      if (!(alpha > 0)) continue;
      // Accumulator::add, channel by channel.
      rgb = _mm_add_ps(rgb, _mm_mul_ps(rgba, _mm_set1_ps(transmittance * alpha)));
      transmittance *= 1.0f - alpha;
      if (depth == kInf && transmittance <= 0.5f) depth = t[lane];
    }
  }
  alignas(16) float sum[4];
  _mm_store_ps(sum, rgb);
  acc.rgb = {sum[0], sum[1], sum[2]};
  acc.transmittance = transmittance;
  acc.depth = depth;
  return samples;
}

}  // namespace

SciVisRenderer::SciVisRenderer(const SciVisScene& scene, const RenderSettings& settings,
                               SciVisOptions options)
    : scene_(scene),
      settings_(settings),
      options_(options),
      layers_(&scene.volumes()),
      camera_(scene.desc().camera, settings.width, settings.height),
      epsilon_(1e-4f * scene.extent() + 0.05f * scene.volumeStep()) {}

void SciVisRenderer::beginFrame(const dfb::FrameInfo& /*frame*/, const CameraDesc& camera) {
  camera_ = Camera(camera, settings_.width, settings_.height);
}

void SciVisRenderer::setLiveSettings(const LiveSettings& live) {
  if (live.transferFunction == live_.transferFunction && live.opacityScale == live_.opacityScale)
    return;
  live_ = live;
  if (live.transferFunction < 0 && live.opacityScale == 1.0f) {
    layers_ = &scene_.volumes();
    retuned_.clear();
    return;
  }
  retuned_ = scene_.retunedVolumes(live.transferFunction, live.opacityScale);
  layers_ = &retuned_;
}

bool SciVisRenderer::occluded(Vec3 origin, Vec3 dir, float tFar) const {
  // Isosurfaces are triangles in the shading scene, as every other surface.
  return scene_.surfaceOccluded(origin, dir, 0.0f, tFar);
}

Vec3 SciVisRenderer::shade(Vec3 point, Vec3 normal, Vec3 dir, Vec3 baseColor, const Material& m,
                           const Sampler& hitSampler) const {
  const SciVisSettings& settings = scene_.desc().scivis;
  if (dot(normal, dir) > 0) normal = -normal;  // face the viewer
  const Vec3 from = point + normal * epsilon_;
  float ambientVisibility = 1.0f;
  if (settings.aoSamples > 0) {
    int blocked = 0;
    for (int i = 0; i < settings.aoSamples; ++i) {
      const Sampler ray = hitSampler.fork(static_cast<std::uint64_t>(i) + 1);
      if (occluded(from, cosineDirection(normal, ray.get(1), ray.get(2)), scene_.aoDistance()))
        ++blocked;
    }
    ambientVisibility = 1.0f - static_cast<float>(blocked) / static_cast<float>(settings.aoSamples);
  }
  Vec3 color;
  for (std::size_t i = 0; i < scene_.lights().size(); ++i) {
    const ResolvedLight& light = scene_.lights()[i];
    if (light.kind == LightDesc::Kind::Ambient) {
      color += baseColor * light.radiance * ambientVisibility;
      continue;
    }
    Vec3 toLight = light.direction;
    float distance = kInf;
    Vec3 radiance = light.radiance;
    if (light.kind == LightDesc::Kind::Point) {
      toLight = light.position - point;
      distance = length(toLight);
      if (!(distance > 0)) continue;
      toLight = toLight / distance;
      radiance = radiance / (distance * distance);
    }
    const float cosine = dot(normal, toLight);
    if (cosine <= 0) continue;
    if (settings.shadows && occluded(from, toLight, distance)) continue;
    Vec3 lit = baseColor * cosine;
    if (m.specular > 0) {
      const Vec3 half = normalize(toLight - dir);
      lit += Vec3{m.specular * std::pow(std::max(0.0f, dot(normal, half)), m.shininess)};
    }
    color += lit * radiance;
  }
  return color;
}

Fragment SciVisRenderer::integrate(Vec3 origin, Vec3 dir, float t0, float t1,
                                   const Sampler& sampler) const {
  return integrate(origin, dir, reciprocal(dir), t0, t1, sampler);
}

Fragment SciVisRenderer::integrate(Vec3 origin, Vec3 dir, Vec3 invDir, float t0, float t1,
                                   const Sampler& sampler) const {
  Accumulator acc;
  Fragment out;
  if (!(t0 < t1)) return out;
  const float minTransmittance = scene_.desc().scivis.minTransmittance;

  // Surfaces come from Embree one at a time, in order; the next one waits in `surface`.
  SurfaceHit surface;
  bool haveSurface = scene_.intersectSurface(origin, dir, t0, t1, surface) && surface.t < t1;
  auto shadeSurface = [&](const SurfaceHit& s) {
    const Vec3 p = origin + dir * s.t;
    const Vec3 c = shade(p, s.normal, dir, s.color, *s.material, sampler.fork(bitsOf(s.t)));
    acc.add(c, s.material->opacity, s.t);
  };
  auto nextSurface = [&] {
    // Behind an opaque surface nothing more is composited: no need to ask Embree again.
    if (acc.transmittance <= minTransmittance) {
      haveSurface = false;
      return;
    }
    const float after = std::nextafter(surface.t, kInf);
    haveSurface = scene_.intersectSurface(origin, dir, after, t1, surface) && surface.t < t1;
  };
  // Surfaces before t, in order.
  auto surfacesBefore = [&](float t) {
    while (haveSurface && surface.t < t && acc.transmittance > minTransmittance) {
      shadeSurface(surface);
      nextSurface();
    }
  };

  // The stretch of the ray where some visible volume has data, widened by a step on each side
  // (so samples lie on the same grid whatever cut [t0, t1) is). Isosurfaces are surfaces: a
  // ray through volumes none of which is visible takes no volume sample at all.
  const float step = scene_.volumeStep();
  float volumeStart = kInf, volumeEnd = -kInf;
  for (const SciVisScene::VolumeLayer& v : *layers_) {
    if (!v.field || !v.visible) continue;
    float a = t0 - step, b = t1 + step;
    if (clipToBox(v.field->dataBounds(), origin, invDir, a, b))
      volumeStart = std::min(volumeStart, a), volumeEnd = std::max(volumeEnd, b);
  }

  const auto& layers = *layers_;
  if (volumeStart <= volumeEnd && layers.size() == 1 && layers[0].visible) {
    // One visible volume: the fast march from surface to surface. A sample at a surface's very
    // distance comes before it (as the generic loop composites them), so each stretch ends just
    // past the surface.
    const float jitter = sampler.get(2);
    const float kStart = std::ceil(volumeStart / step - jitter);
    float from = t0;
    for (;;) {
      const float to = haveSurface ? std::min(t1, std::nextafter(surface.t, kInf)) : t1;
      const auto march = [&]<class T>() {
        return marchOneVolume<T>(layers[0], origin, dir, invDir, from, to, kStart, volumeEnd, step,
                                 jitter, minTransmittance, acc);
      };
      switch (layers[0].field->volume().type) {
        default:
        case VoxelType::Float32:
          out.volumeSamples += march.operator()<float>();
          break;
        case VoxelType::UInt8:
          out.volumeSamples += march.operator()<std::uint8_t>();
          break;
        case VoxelType::UInt16:
          out.volumeSamples += march.operator()<std::uint16_t>();
          break;
      }
      if (!haveSurface || acc.transmittance <= minTransmittance) break;
      shadeSurface(surface);
      nextSurface();
      from = to;
    }
  } else if (volumeStart <= volumeEnd) {
    const std::size_t n = layers.size();
    constexpr std::size_t kMaxLayers = 8;
    float current[kMaxLayers];
    bool hasCurrent[kMaxLayers] = {};
    const float jitter = sampler.get(2);
    std::uint32_t samples = 0;
    float k = std::ceil(volumeStart / step - jitter);
    float tCheck = -kInf;
    for (; acc.transmittance > minTransmittance; k += 1) {
      const float t = (k + jitter) * step;
      const Vec3 p = origin + dir * t;
      for (std::size_t i = 0; i < n && i < kMaxLayers; ++i)
        hasCurrent[i] =
            layers[i].field && layers[i].visible && layers[i].field->sample(p, current[i]);
      surfacesBefore(t);
      if (t >= t1 || t > volumeEnd) break;
      if (t >= t0) {
        for (std::size_t i = 0; i < n && i < kMaxLayers; ++i) {
          if (!hasCurrent[i]) continue;
          float rgba[4];
          lookup(layers[i], current[i], rgba);
          if (rgba[3] > 0) acc.add({rgba[0], rgba[1], rgba[2]}, rgba[3], t);
        }
        ++samples;
      }
      // Empty space: when no volume can show anything in the macrocell here, jump to the last
      // sample before its exit. Macrocells are looked at only when the ray leaves the ones it
      // was in, not at every sample.
      float skipTo = kInf;
      bool skippable = false;
      if (t >= tCheck) {
        skippable = true;
        float nextCheck = kInf;
        for (std::size_t i = 0; i < n && i < kMaxLayers; ++i) {
          if (!layers[i].field || !layers[i].visible) continue;
          const int m = hasCurrent[i] ? layers[i].field->macroIndex(p) : -1;
          float a = t, b = kInf;
          if (m < 0) {
            // Outside this volume's data: skip to where the ray enters it, if it does later.
            if (clipToBox(layers[i].field->dataBounds(), origin, invDir, a, b) && a > t) {
              skipTo = std::min(skipTo, a);
              nextCheck = std::min(nextCheck, a);
            } else if (!(a > t) && b > t) {
              skippable = false;  // inside but not sampled (an edge): look again next sample
              nextCheck = t;
            }
            continue;
          }
          clipToBox(layers[i].field->macroBounds(m), origin, invDir, a, b);
          nextCheck = std::min(nextCheck, b);
          if (layers[i].emptyMacrocells[static_cast<std::size_t>(m)])
            skipTo = std::min(skipTo, b);
          else
            skippable = false;
        }
        tCheck = nextCheck;
      }
      if (skippable && skipTo > t) {
        const float last = std::floor(skipTo / step - jitter) - 1;  // one sample before the exit
        if (last > k) {
          k = last - 1;  // the loop's += 1 lands on `last`
          tCheck = -kInf;
        }
      }
    }
    out.volumeSamples = samples;
  }
  surfacesBefore(t1);

  out.rgba[0] = acc.rgb.x, out.rgba[1] = acc.rgb.y, out.rgba[2] = acc.rgb.z;
  out.rgba[3] = 1.0f - acc.transmittance;
  out.depth = acc.depth;
  return out;
}

void SciVisRenderer::render(const dfb::Region& region, std::uint32_t accumulationId,
                            std::uint32_t firstSample, std::uint32_t samples,
                            dfb::Tile& out) const {
  enableFlushToZero();
  prepareTile(region, accumulationId, firstSample, samples, out);
  const float inv = samples ? 1.0f / static_cast<float>(samples) : 0.0f;
  const Box3& bounds = scene_.bounds();
  const Environment& background = scene_.desc().environment;
  std::uint64_t volumeSamples = 0;
  for (int y = region.y0; y < region.y1; ++y)
    for (int x = region.x0; x < region.x1; ++x) {
      float sum[4] = {0, 0, 0, 0};
      for (std::uint32_t s = firstSample; s < firstSample + samples; ++s) {
        const Sampler sampler(settings_.seed, x, y, accumulationId, s);
        Vec3 origin, dir;
        camera_.ray(static_cast<float>(x) + sampler.get(0), static_cast<float>(y) + sampler.get(1),
                    0.5f, 0.5f, origin, dir);
        float t0 = 0, t1 = kInf;
        Fragment f;
        const Vec3 invDir = reciprocal(dir);
        if (clipToBox(bounds, origin, invDir, t0, t1))
          f = integrate(origin, dir, invDir, t0, t1, sampler);
        if (options_.background) {
          const Vec3 bg = background.radiance(dir) * (1.0f - f.rgba[3]);
          f.rgba[0] += bg.x, f.rgba[1] += bg.y, f.rgba[2] += bg.z, f.rgba[3] = 1.0f;
        }
        for (int c = 0; c < 4; ++c) sum[c] += f.rgba[c];
        volumeSamples += f.volumeSamples;
      }
      float* px = &out.color[4 * (static_cast<std::size_t>(y - region.y0) * region.width() +
                                  static_cast<std::size_t>(x - region.x0))];
      for (int c = 0; c < 4; ++c) px[c] = sum[c] * inv;
    }
  volumeSamples_.fetch_add(volumeSamples, std::memory_order_relaxed);
}

}  // namespace renderers
