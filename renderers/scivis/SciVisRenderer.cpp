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

// The level crossing between (ta, fa) and (tb, fb) (values on opposite sides of `level`), by
// regula falsi on the field itself; both ends must be inside the field's data.
float refineCrossing(const VolumeField& field, Vec3 origin, Vec3 dir, float level, float ta,
                     float fa, float tb, float fb) {
  for (int iteration = 0; iteration < 6; ++iteration) {
    const float tm = ta + (tb - ta) * ((level - fa) / (fb - fa));
    float fm;
    if (!(tm > ta && tm < tb) || !field.sample(origin + dir * tm, fm)) break;
    if ((fm - level) * (fa - level) > 0)
      ta = tm, fa = fm;
    else
      tb = tm, fb = fm;
  }
  return fb == fa ? ta : ta + (tb - ta) * ((level - fa) / (fb - fa));
}

inline bool crosses(float a, float b, float level) { return (a < level) != (b < level); }

// A cosine-weighted direction about unit n.
Vec3 cosineDirection(Vec3 n, float u0, float u1) {
  Vec3 t, b;
  basis(n, t, b);
  const float r = std::sqrt(u0), phi = 2.0f * kPi * u1;
  const float x = r * std::cos(phi), y = r * std::sin(phi), z = std::sqrt(std::max(0.0f, 1 - u0));
  return t * x + b * y + n * z;
}

std::uint64_t bitsOf(float t) { return std::bit_cast<std::uint32_t>(t); }

// The common case, apart from the generic loop for speed: one visible volume without
// isosurfaces, nothing else on the ray before the volume ends. It composites exactly the samples
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

namespace {

// Whether one of `isosurfaces` lies on origin + t dir, t in [0, tFar], in a field of geometry
// `field` (a VolumeField, or a brick's ShadingShell: the same macrocells, so the same samples)
// whose values sample(p, value) gives.
template <class Sample>
bool crossesIsosurface(const FieldGeometry& field, Sample sample,
                       const std::vector<const IsosurfaceDesc*>& isosurfaces, Vec3 origin, Vec3 dir,
                       float tFar, float jitter) {
  float t0 = 0, t1 = tFar;
  if (!clipToBox(field.dataBounds(), origin, reciprocal(dir), t0, t1)) return false;
  // Shading rays step one voxel (not the camera rays' finer step): they only ask yes or no.
  const float step = field.minSpacing();
  float previous = 0;
  bool havePrevious = false;
  for (float k = std::floor(t0 / step - jitter);; k += 1) {
    const float t = (k + jitter) * step;
    if (t > t1) break;
    if (t < t0) continue;
    const Vec3 p = origin + dir * t;
    // Skip macrocells that hold no isosurface.
    const int m = field.macroIndex(p);
    if (m < 0) break;
    bool any = false;
    for (const IsosurfaceDesc* iso : isosurfaces)
      any = any || (iso->value >= field.macroMin(m) && iso->value <= field.macroMax(m));
    if (!any) {
      float e0 = t, e1 = kInf;
      clipToBox(field.macroBounds(m), origin, reciprocal(dir), e0, e1);
      const float next = std::floor(e1 / step - jitter);
      if (next > k) k = next;  // the loop's += 1 steps into the next macrocell
      havePrevious = false;
      continue;
    }
    float value;
    if (!sample(p, value)) {  // a missing value (NaN): no crossing into or out of it
      havePrevious = false;
      continue;
    }
    if (havePrevious)
      for (const IsosurfaceDesc* iso : isosurfaces)
        if (crosses(previous, value, iso->value)) return true;
    previous = value;
    havePrevious = true;
  }
  return false;
}

}  // namespace

bool SciVisRenderer::isosurfaceBetween(Vec3 origin, Vec3 dir, float tFar, float jitter) const {
  for (const SciVisScene::VolumeLayer& v : *layers_) {
    if (v.isosurfaces.empty()) continue;
    const VolumeField* core = v.field;
    const bool crossed =
        v.shell
            ? crossesIsosurface(
                  *v.shell, [&](Vec3 p, float& value) { return v.shell->sample(p, value, core); },
                  v.isosurfaces, origin, dir, tFar, jitter)
        : core ? crossesIsosurface(
                     *core, [&](Vec3 p, float& value) { return core->sample(p, value); },
                     v.isosurfaces, origin, dir, tFar, jitter)
               : false;
    if (crossed) return true;
  }
  return false;
}

bool SciVisRenderer::occluded(Vec3 origin, Vec3 dir, float tFar, const Sampler& s) const {
  return scene_.surfaceOccluded(origin, dir, 0.0f, tFar) ||
         isosurfaceBetween(origin, dir, tFar, s.get(0));
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
      if (occluded(from, cosineDirection(normal, ray.get(1), ray.get(2)), scene_.aoDistance(), ray))
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
    if (settings.shadows && occluded(from, toLight, distance, hitSampler.fork(0x51u + i))) continue;
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

  // The stretch of the ray where some volume has data, widened by a step on each side: the
  // samples just outside [t0, t1) find the isosurface crossings near its ends.
  const float step = scene_.volumeStep();
  float volumeStart = kInf, volumeEnd = -kInf;
  for (const SciVisScene::VolumeLayer& v : *layers_) {
    if (!v.field) continue;
    float a = t0 - step, b = t1 + step;
    if (clipToBox(v.field->dataBounds(), origin, invDir, a, b))
      volumeStart = std::min(volumeStart, a), volumeEnd = std::max(volumeEnd, b);
  }

  const auto& layers = *layers_;
  if (volumeStart <= volumeEnd && layers.size() == 1 && layers[0].visible &&
      layers[0].isosurfaces.empty() && (!haveSurface || surface.t > volumeEnd)) {
    const float jitter = sampler.get(2);
    const float kStart = std::ceil(volumeStart / step - jitter);
    const auto march = [&]<class T>() {
      return marchOneVolume<T>(layers[0], origin, dir, invDir, t0, t1, kStart, volumeEnd, step,
                               jitter, minTransmittance, acc);
    };
    switch (layers[0].field->volume().type) {
      default:
      case VoxelType::Float32:
        out.volumeSamples = march.operator()<float>();
        break;
      case VoxelType::UInt8:
        out.volumeSamples = march.operator()<std::uint8_t>();
        break;
      case VoxelType::UInt16:
        out.volumeSamples = march.operator()<std::uint16_t>();
        break;
    }
  } else if (volumeStart <= volumeEnd) {
    const std::size_t n = layers.size();
    // Per volume: the value at the previous sample (when it had one) and at this one.
    constexpr std::size_t kMaxLayers = 8;
    float previous[kMaxLayers], current[kMaxLayers];
    bool hadPrevious[kMaxLayers] = {}, hasCurrent[kMaxLayers] = {};
    const float jitter = sampler.get(2);
    std::uint32_t samples = 0;
    float k = std::ceil(volumeStart / step - jitter);
    float tPrevious = -kInf, tCheck = -kInf;
    struct Crossing {
      float t;
      const IsosurfaceDesc* iso;
      const VolumeField* field;
    };
    Crossing crossings[16];
    for (; acc.transmittance > minTransmittance; k += 1) {
      const float t = (k + jitter) * step;
      const Vec3 p = origin + dir * t;
      bool anyData = false;
      for (std::size_t i = 0; i < n && i < kMaxLayers; ++i) {
        hasCurrent[i] = layers[i].field && layers[i].field->sample(p, current[i]);
        anyData = anyData || hasCurrent[i];
      }
      // Isosurface crossings in (tPrevious, t), shaded in order with the surfaces among them.
      int found = 0;
      for (std::size_t i = 0; i < n && i < kMaxLayers; ++i) {
        if (!hasCurrent[i] || !hadPrevious[i]) continue;
        for (const IsosurfaceDesc* iso : layers[i].isosurfaces) {
          if (!crosses(previous[i], current[i], iso->value) || found == 16) continue;
          const float th = refineCrossing(*layers[i].field, origin, dir, iso->value, tPrevious,
                                          previous[i], t, current[i]);
          if (th >= t0 && th < t1) crossings[found++] = {th, iso, layers[i].field};
        }
      }
      std::sort(crossings, crossings + found,
                [](const Crossing& a, const Crossing& b) { return a.t < b.t; });
      for (int c = 0; c < found; ++c) {
        surfacesBefore(crossings[c].t);
        if (acc.transmittance <= minTransmittance) break;
        const Crossing& x = crossings[c];
        const Material& m = scene_.desc().materials[x.iso->material];
        const Vec3 hit = origin + dir * x.t;
        const Vec3 gradient = x.field->gradient(hit, 0.5f * x.field->minSpacing());
        const Vec3 normal = length(gradient) > 0 ? normalize(gradient) : -dir;
        acc.add(shade(hit, normal, dir, m.color, m, sampler.fork(bitsOf(x.t))), m.opacity, x.t);
      }
      surfacesBefore(t);
      if (t >= t1 || t > volumeEnd) break;
      if (t >= t0) {
        for (std::size_t i = 0; i < n && i < kMaxLayers; ++i) {
          if (!hasCurrent[i] || !layers[i].visible) continue;
          float rgba[4];
          lookup(layers[i], current[i], rgba);
          if (rgba[3] > 0) acc.add({rgba[0], rgba[1], rgba[2]}, rgba[3], t);
        }
        ++samples;
      }
      // Empty space: when no volume can show anything in the macrocell here, jump to the last
      // sample before its exit (the crossing test needs the value there). Macrocells are looked
      // at only when the ray leaves the ones it was in, not at every sample.
      float skipTo = kInf;
      bool skippable = false;
      if (t >= tCheck) {
        skippable = true;
        float nextCheck = kInf;
        for (std::size_t i = 0; i < n && i < kMaxLayers; ++i) {
          if (!layers[i].field) continue;
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
      for (std::size_t i = 0; i < n && i < kMaxLayers; ++i) {
        previous[i] = current[i];
        hadPrevious[i] = hasCurrent[i];
      }
      tPrevious = t;
      if (skippable && skipTo > t) {
        const float last = std::floor(skipTo / step - jitter) - 1;  // one sample before the exit
        if (last > k) {
          k = last - 1;  // the loop's += 1 lands on `last`
          tCheck = -kInf;
          for (std::size_t i = 0; i < n && i < kMaxLayers; ++i) hadPrevious[i] = false;
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
