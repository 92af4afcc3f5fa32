#include "renderers/scivis/render/SciVisRenderer.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <vector>

#include "renderers/PixelBlocks.h"
#include "renderers/scivis/render/CameraRays.h"
#include "renderers/scivis/render/MarchOnly.h"
#include "renderers/scivis/render/RayBlocks.h"
#include "renderers/scivis/render/VolumeMarch.h"

namespace renderers::scivis {
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
  const float* a = &v.table[SciVisScene::kTableEntryFloats * static_cast<std::size_t>(i)];
  for (int c = 0; c < 4; ++c) rgba[c] = a[c] + f * a[4 + c];
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

// How many pixels of a `height`-pixel canvas the finest isosurface's voxel spacing spans at the
// centre of `domain` (0: no isosurfaces).
float cellPixels(const SceneDesc& desc, const Box3& domain, const CameraDesc& camera, int height) {
  float finest = kInf;
  for (const IsosurfaceDesc& iso : sciVisDesc(desc).isosurfaces) {
    const Vec3 s = sciVisDesc(desc).volumes.at(iso.volume).source.grid.spacing;
    finest = std::min(finest, std::min(s.x, std::min(s.y, s.z)));
  }
  if (!(finest < kInf)) return 0;
  const float distance = length((domain.lo + domain.hi) * 0.5f - camera.position);
  const float halfHeight = std::tan(0.5f * camera.fovY * kPi / 180.0f);
  return finest / (2.0f * distance * halfHeight) * static_cast<float>(height);
}

// Whether every corner of `box` (bounded) lies in front of the camera's plane.
bool inFront(const Box3& box, const CameraDesc& c) {
  if (box.empty()) return false;
  const Vec3 forward = normalize(c.lookAt - c.position);
  for (int i = 0; i < 8; ++i) {
    const Vec3 p{(i & 1) ? box.hi.x : box.lo.x, (i & 2) ? box.hi.y : box.lo.y,
                 (i & 4) ? box.hi.z : box.lo.z};
    if (!inFrontOfCamera(p - c.position, forward)) return false;
  }
  return true;
}

}  // namespace

SciVisRenderer::SciVisRenderer(const SciVisScene& scene, const RenderSettings& settings,
                               SciVisOptions options)
    : scene_(scene),
      settings_(settings),
      options_(options),
      layers_(&scene.volumes()),
      camera_(scene.desc().camera, settings.width, settings.height, settings.room),
      march_(resolveMarchKernel(options.march)),
      epsilon_(1e-4f * scene.extent() + 0.05f * scene.volumeStep()) {
  if (options.firstHits == FirstHits::Embree || !scene.opaqueCameraTriangles(rasterMeshes_))
    rasterMeshes_.clear();
}

void SciVisRenderer::beginFrame(const dfb::FrameInfo& /*frame*/, const CameraDesc& camera) {
  camera_ = Camera(camera, settings_.width, settings_.height, settings_.room);
  if (rasterMeshes_.empty()) return;
  // A still camera (progressive frames) keeps the triangles binned as they are.
  if (raster_.ready() && camera == rasterCamera_) return;
  rasterCamera_ = camera;
  // Only where the whole scene's domain lies in front of the camera: a decision every brick
  // and the unbricked scene make alike, so all find their first hits one way (the hit distance
  // keys a surface's random numbers, and the raster's may differ from Embree's in the last bit).
  if (!inFront(scene_.domain(), camera) ||
      (options_.firstHits == FirstHits::Auto &&
       cellPixels(scene_.desc(), scene_.domain(), camera, settings_.height) < kRasterCellPixels))
    raster_.clear();
  else
    raster_.prepare(camera_, settings_.width, settings_.height, rasterMeshes_);
}

void SciVisRenderer::rasterFirstHits(int x0, int x1, int y0, int y1, const RayPiece* rays,
                                     const std::uint8_t* active, FirstSurface* out,
                                     const Box3* accept) const {
  const std::size_t width = static_cast<std::size_t>(x1 - x0);
  const std::size_t n = static_cast<std::size_t>(y1 - y0) * width;
  thread_local std::vector<float> dx, dy, dz, t0, t1;
  thread_local std::vector<FirstHitRaster::Hit> hits;
  dx.resize(n), dy.resize(n), dz.resize(n), t0.resize(n), t1.resize(n), hits.resize(n);
  bool bounded[3] = {false, false, false};
  if (accept)
    for (int axis = 0; axis < 3; ++axis)
      bounded[axis] = accept->lo[axis] > -kInf || accept->hi[axis] < kInf;
  for (std::size_t i = 0; i < n; ++i) {
    const RayPiece& r = rays[i];
    dx[i] = r.dir.x, dy[i] = r.dir.y, dz[i] = r.dir.z;
    bool on = (!active || active[i]) && r.t0 < r.t1;  // integrate() skips t0 >= t1
    float a = r.t0, b = r.t1;
    if (on && accept) {
      // clipToBox() along the axes where `accept` has a face (the others leave [0, inf) as it
      // is; a brick that spans the domain has none).
      a = 0, b = kInf;
      for (int axis = 0; axis < 3; ++axis)
        if (bounded[axis])
          clipToSlab(accept->lo[axis], accept->hi[axis], r.origin[axis], 1.0f / r.dir[axis], a, b);
      on = a <= b;
    }
    t0[i] = on ? a : kInf, t1[i] = on ? b : -kInf;
  }
  raster_.firstHits(x0, x1, y0, y1, width, dx.data(), dy.data(), dz.data(), t0.data(), t1.data(),
                    hits.data());
  for (std::size_t i = 0; i < n; ++i) {
    const FirstHitRaster::Hit& h = hits[i];
    out[i].found = h.mesh != FirstHitRaster::kNone;
    if (out[i].found)
      scene_.fillSurfaceHit(h.mesh, h.triangle, h.u, h.v, h.t, rays[i].origin, rays[i].dir,
                            out[i].hit);
  }
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
  const SciVisSettings& settings = scene_.sciVis().settings;
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
                                   const Sampler& sampler, const FirstSurface* first) const {
  Accumulator acc;
  Fragment out;
  if (!(t0 < t1)) return out;
  const float minTransmittance = scene_.sciVis().settings.minTransmittance;
  const int aoSamples = scene_.sciVis().settings.aoSamples;

  // Surfaces come from Embree one at a time, in order; the next one waits in `surface`.
  SurfaceHit surface;
  bool haveSurface;
  if (first)
    surface = first->hit, haveSurface = first->found && surface.t < t1;
  else
    haveSurface = scene_.intersectSurface(origin, dir, t0, t1, surface) && surface.t < t1;
  auto shadeSurface = [&](const SurfaceHit& s) {
    const Vec3 p = origin + dir * s.t;
    // The hit's random numbers are for ambient occlusion only: no stream to derive without it.
    const Sampler hitSampler = aoSamples > 0 ? sampler.fork(bitsOf(s.t)) : Sampler{};
    const Vec3 c = shade(p, s.normal, dir, s.color, *s.material, hitSampler);
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
      MarchColor color{acc.rgb, acc.transmittance, acc.depth};
      out.volumeSamples += marchOneVolume(
          layers[0],
          {origin, dir, invDir, from, to, kStart, volumeEnd, step, jitter, minTransmittance},
          color);
      acc.rgb = color.rgb, acc.transmittance = color.transmittance, acc.depth = color.depth;
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

bool SciVisRenderer::marchOnly(Vec3 origin, Vec3 dir, Vec3 invDir, float t0, float t1,
                               const Sampler& sampler, const FirstSurface& first,
                               MarchRay& ray) const {
  // integrate()'s test for its one-volume march, when nothing else lies on the ray at all (its
  // isosurfaces are triangles: the surface query below sees them).
  const auto& layers = *layers_;
  if (layers.size() != 1 || !layers[0].visible || !layers[0].field) return false;
  if (first.found && first.hit.t < t1) return false;
  return marchRayOf({origin, dir, t0, t1, sampler}, invDir, layers[0].field->dataBounds(),
                    scene_.volumeStep(), scene_.sciVis().settings.minTransmittance, ray);
}

bool SciVisRenderer::marchesPacketsHere() const {
  return layers_->size() == 1 && marchesPackets((*layers_)[0], march_);
}

void SciVisRenderer::integrate(const RayPiece* rays, std::size_t count, Fragment* out) const {
  integrate(rays, count, out, nullptr);
}

void SciVisRenderer::integrate(const RayPiece* rays, std::size_t count, Fragment* out,
                               const FirstSurface* given) const {
  const bool packets = marchesPacketsHere();
  const int packetSize = marchPacketSize(march_);
  // Rays for the march, a packet at a time; the next packet's rays wait while one goes, so the
  // march can ask for their first voxels (marchPacket's `next`).
  MarchRay waiting[3 * kMarchPacket];
  std::size_t waitingIndex[3 * kMarchPacket];
  int waitingCount = 0;
  auto marchWaiting = [&] {
    MarchColor colors[kMarchPacket];
    std::uint32_t taken[kMarchPacket];
    const int n = std::min(waitingCount, packetSize);
    marchPacket((*layers_)[0], march_, waiting, n, colors, taken, waiting + n, waitingCount - n);
    for (int i = 0; i < n; ++i) {
      Fragment& f = out[waitingIndex[i]];  // integrate()'s fragment of the march alone
      f = Fragment{};
      f.rgba[0] = colors[i].rgb.x, f.rgba[1] = colors[i].rgb.y, f.rgba[2] = colors[i].rgb.z;
      f.rgba[3] = 1.0f - colors[i].transmittance;
      f.depth = colors[i].depth;
      f.volumeSamples = taken[i];
    }
    std::copy(waiting + n, waiting + waitingCount, waiting);
    std::copy(waitingIndex + n, waitingIndex + waitingCount, waitingIndex);
    waitingCount -= n;
  };
  // Each ray's first surface is asked for once, for packets of consecutive rays together
  // (the same hits as one at a time), and handed to marchOnly() and integrate().
  constexpr int kSurfaces = SciVisScene::kSurfacePacket;
  const bool surfaces = scene_.hasCameraSurfaces();  // none: nothing to ask (a volume alone)
  const bool ask = surfaces && !given;
  static const FirstSurface none{false, SurfaceHit{}};
  SciVisScene::SurfaceQuery queries[kSurfaces];
  SurfaceHit hits[kSurfaces];
  bool found[kSurfaces];
  FirstSurface firsts[kSurfaces];
  // A volume alone under the AVX-512 march: marchOnly() for 16 rays at a time in its lanes (the
  // same rays bit for bit); the rest below, one at a time.
  std::size_t done = 0;
  if (packets && march_ == MarchKernel::Avx512 && !surfaces && !given && (*layers_)[0].visible) {
    const Box3& data = (*layers_)[0].field->dataBounds();
    const float step = scene_.volumeStep(), minT = scene_.sciVis().settings.minTransmittance;
    for (; done + 16 <= count; done += 16) {
      const unsigned take = marchOnly16(rays + done, data, step, minT, waiting + waitingCount);
      for (std::size_t i = done; i < done + 16; ++i) {
        if (take >> (i - done) & 1u) {
          waitingIndex[waitingCount++] = i;
          continue;
        }
        // A piece the march does not take is empty or misses the data (integrate() clips it
        // to them as marchRayOf does): with nothing else in the scene, integrate() gives it the
        // empty fragment. (Half the bench's camera rays at 1024^2, counted: they clip to the
        // scene's bounds but miss the data.)
        out[i] = Fragment{};
      }
      if (waitingCount >= 2 * packetSize) marchWaiting();
    }
  }
  for (std::size_t base = done; base < count; base += kSurfaces) {
    const int n = static_cast<int>(std::min<std::size_t>(kSurfaces, count - base));
    if (ask) {
      for (int j = 0; j < n; ++j) {
        const RayPiece& r = rays[base + static_cast<std::size_t>(j)];
        queries[j] = {r.origin, r.dir, r.t0, r.t1, r.t0 < r.t1};
      }
      scene_.intersectSurfaces(queries, n, hits, found);
      for (int j = 0; j < n; ++j) firsts[j] = {found[j], hits[j]};
    }
    for (int j = 0; j < n; ++j) {
      const std::size_t i = base + static_cast<std::size_t>(j);
      const RayPiece& r = rays[i];
      const Vec3 invDir = reciprocal(r.dir);
      const FirstSurface& first = given ? given[i] : surfaces ? firsts[j] : none;
      if (packets &&
          marchOnly(r.origin, r.dir, invDir, r.t0, r.t1, r.sampler, first, waiting[waitingCount])) {
        waitingIndex[waitingCount++] = i;
        if (waitingCount >= 2 * packetSize) marchWaiting();
        continue;
      }
      out[i] = integrate(r.origin, r.dir, invDir, r.t0, r.t1, r.sampler, &first);
    }
  }
  while (waitingCount > 0) marchWaiting();
}

void SciVisRenderer::render(const dfb::Region& region, std::uint32_t accumulationId,
                            std::uint32_t firstSample, std::uint32_t samples,
                            dfb::Tile& out) const {
  enableFlushToZero();
  prepareTile(region, accumulationId, firstSample, samples, out);
  const float inv = samples ? 1.0f / static_cast<float>(samples) : 0.0f;
  const Box3& bounds = scene_.bounds();
  const Environment& background = scene_.desc().environment;
  // Rows of the tile's rays at a time (about kBatch rays; a ray outside the scene's bounds is an
  // empty piece), integrated together, then each pixel's samples summed in order.
  thread_local std::vector<RayPiece> rays;
  thread_local std::vector<Fragment> fragments;
  thread_local std::vector<Sampler> samplers;
  thread_local std::vector<float> px, py;
  thread_local std::vector<Vec3> dirs, invDirs, origins;
  thread_local std::vector<std::uint8_t> traced;
  // Camera rays go in 4x4 pixel blocks (RayBlocks.h) where they ask Embree for surfaces, and
  // where a volume marches them in SIMD packets: a packet of a square's rays reads fewer voxel
  // cache lines than one of a 16-pixel run (the scivis bench: 5-7% less time a sample where a
  // voxel covers a pixel or less, the same where it covers more). One ray at a time, row order.
  const bool blocks = scene_.hasCameraSurfaces() || marchesPacketsHere();
  thread_local RayBlockOrderCache blockOrder;
  thread_local std::vector<RayPiece> blockRays;
  thread_local std::vector<Fragment> blockFragments;
  const int width = region.width();
  const int rows = std::max(
      1, static_cast<int>(kBatch / std::max<std::size_t>(1, std::size_t{samples} * width)));
  std::uint64_t volumeSamples = 0;
  // The camera rays in SIMD lanes where the march runs AVX-512 (the same rays either way).
  const RowRays row{&camera_,
                    bounds,
                    settings_.seed,
                    accumulationId,
                    firstSample,
                    samples,
                    march_ == MarchKernel::Avx512 && cameraRowSimdAvailable()};
  for (int y0 = region.y0; y0 < region.y1; y0 += rows) {
    const int y1 = std::min(region.y1, y0 + rows);
    if (row.simd) {  // AVX-512: 16 pixels' rays and streams at a time
      const std::size_t rowRays = std::size_t{samples} * static_cast<std::size_t>(width);
      rays.resize(static_cast<std::size_t>(y1 - y0) * rowRays);
      for (int y = y0; y < y1; ++y)
        cameraRowRays(row, region.x0, region.x1, y,
                      rays.data() + static_cast<std::size_t>(y - y0) * rowRays);
    } else {
      rays.clear();
      // Every ray's random stream and canvas point first, then their directions together
      // (Camera::pinholeRays: the bits of one at a time, without its latency), then the clips.
      const std::size_t n = static_cast<std::size_t>(y1 - y0) * width * samples;
      samplers.resize(n), px.resize(n), py.resize(n), dirs.resize(n), invDirs.resize(n);
      origins.resize(camera_.pinhole() ? 0 : n);
      traced.assign(n, 1);
      std::size_t filled = 0;
      for (int y = y0; y < y1; ++y)
        for (int x = region.x0; x < region.x1; ++x)
          for (std::uint32_t s = firstSample; s < firstSample + samples; ++s, ++filled) {
            samplers[filled] = Sampler(settings_.seed, x, y, accumulationId, s);
            px[filled] = static_cast<float>(x) + samplers[filled].get(0);
            py[filled] = static_cast<float>(y) + samplers[filled].get(1);
          }
      if (camera_.pinhole()) {
        camera_.pinholeRays(n, px.data(), py.data(), dirs.data(), invDirs.data());
      } else {
        for (std::size_t r = 0; r < n; ++r) {
          traced[r] = camera_.ray(px[r], py[r], 0.5f, 0.5f, origins[r], dirs[r]) ? 1 : 0;
          invDirs[r] = reciprocal(dirs[r]);
        }
      }
      for (std::size_t r = 0; r < n; ++r) {
        const Vec3 origin = origins.empty() ? camera_.position() : origins[r];
        float t0 = 0, t1 = kInf;
        // An empty piece under a room's bezels: nothing is traced, only the background.
        if (!traced[r] || !clipToBox(bounds, origin, invDirs[r], t0, t1)) t0 = t1 = 0;
        rays.push_back({origin, dirs[r], t0, t1, samplers[r]});
      }
    }
    fragments.resize(rays.size());
    if (firstHitsRasterised(samples)) {  // first hits from this frame's raster, in row order
      thread_local std::vector<FirstSurface> firsts;
      firsts.resize(rays.size());
      rasterFirstHits(region.x0, region.x1, y0, y1, rays.data(), nullptr, firsts.data());
      integrate(rays.data(), rays.size(), fragments.data(), firsts.data());
    } else if (blocks) {  // to Embree in 4x4 pixel blocks, the fragments back in row order
      const std::vector<std::uint32_t>& order = blockOrder.of(width, y1 - y0, samples);
      blockRays.resize(rays.size()), blockFragments.resize(rays.size());
      for (std::size_t k = 0; k < order.size(); ++k) blockRays[k] = rays[order[k]];
      integrate(blockRays.data(), blockRays.size(), blockFragments.data());
      for (std::size_t k = 0; k < order.size(); ++k) fragments[order[k]] = blockFragments[k];
    } else {
      integrate(rays.data(), rays.size(), fragments.data());
    }
    std::size_t next = 0;
    const std::size_t first = static_cast<std::size_t>(y0 - region.y0) * width;
    const std::size_t last = static_cast<std::size_t>(y1 - region.y0) * width;
    for (std::size_t pixel = first; pixel < last; ++pixel) {
      float sum[4] = {0, 0, 0, 0};
      for (std::uint32_t s = 0; s < samples; ++s, ++next) {
        Fragment& f = fragments[next];
        if (options_.background) {
          const Vec3 bg = background.radiance(rays[next].dir) * (1.0f - f.rgba[3]);
          f.rgba[0] += bg.x, f.rgba[1] += bg.y, f.rgba[2] += bg.z, f.rgba[3] = 1.0f;
        }
        for (int c = 0; c < 4; ++c) sum[c] += f.rgba[c];
        volumeSamples += f.volumeSamples;
      }
      for (int c = 0; c < 4; ++c) out.color[4 * pixel + static_cast<std::size_t>(c)] = sum[c] * inv;
    }
  }
  volumeSamples_.fetch_add(volumeSamples, std::memory_order_relaxed);
}

}  // namespace renderers::scivis
