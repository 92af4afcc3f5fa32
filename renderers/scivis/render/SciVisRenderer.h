#pragma once
// The scientific-visualization renderer ("scivis"): one camera ray per sample, integrated front
// to back through volumes (emission-absorption, opacity corrected for the step) with the
// surfaces it meets in between (isosurfaces, polygonised when the scene is built, particles,
// meshes: all Embree geometry; opaque or transparent), shaded locally: diffuse + Phong highlight,
// shadows from directional and point lights, ambient occlusion. Secondary rays never leave the
// brick's data (with its ghosts), so the renderer works on one brick of a distributed scene as well
// as on the whole.
//
// Every ray is integrated over an interval [t0, t1] (the brick's clip bounds; the whole scene:
// [0, inf)). Volume samples lie on a grid fixed along the ray, t_k = (k + j) * step with j from
// the pixel's random stream, and a surface is shaded with random numbers keyed by its distance,
// so a ray cut into pieces samples and shades exactly what the whole ray does: composited front
// to back, the pieces give the whole ray's colour up to float rounding.
#include <atomic>
#include <cstdint>

#include "renderers/Camera.h"
#include "renderers/Renderer.h"
#include "renderers/Rng.h"
#include "renderers/scivis/kernels/FirstHitRaster.h"
#include "renderers/scivis/render/VolumeMarch.h"
#include "renderers/scivis/scene/SciVisScene.h"

namespace renderers::scivis {

// Premultiplied RGBA of a piece of a ray and the distance where it became at least half opaque
// (infinity if never).
struct Fragment {
  float rgba[4] = {0, 0, 0, 0};
  float depth = Box3::kInf;
  std::uint32_t volumeSamples = 0;  // taken inside [t0, t1), for benchmarks
};

enum class FirstHits { Auto, Raster, Embree };
// Auto uses the raster where an isosurface voxel cell spans at least this many pixels: the raster
// costs per triangle (about two a crossed cell), Embree per ray, so the raster wins as cells grow
// on screen. The 256^3 contours, raster / Embree frame time: 1 rank x 2 threads 1.09 at 2.25
// pixels a cell, 0.89 at 2.8, 0.76 at 3.4; 2 ranks x 1 thread 1.18 at 2.25, 0.98 at 2.8.
constexpr float kRasterCellPixels = 2.75f;

struct SciVisOptions {
  // true: the background is composited under every pixel (alpha 1, image-parallel rendering);
  // false: pixels keep their alpha for sort-last compositing.
  bool background = true;
  // The instruction set of the one-volume march (VolumeMarch.h); all give the same image.
  MarchKernel march = MarchKernel::Auto;
  // How camera rays find their first hits: Embree, or by rasterising the triangles each frame
  // (FirstHitRaster.h). The raster only where it finds what Embree would (one sample per pixel,
  // a pinhole, every camera surface an opaque triangle, the scene's domain in front of the
  // camera); Auto: there, and only where it is the faster (the isosurfaces' voxel cells span at
  // least kRasterCellPixels on the canvas). Either finds the same surface for a ray; the
  // distances may differ in their last bits, so every brick and the unbricked scene choose
  // alike (from the description, the camera and the canvas only).
  FirstHits firstHits = FirstHits::Auto;
};

class SciVisRenderer final : public Renderer {
 public:
  SciVisRenderer(const SciVisScene& scene, const RenderSettings& settings,
                 SciVisOptions options = {});

  void beginFrame(const dfb::FrameInfo& frame, const CameraDesc& camera) override;
  // Another transfer-function preset or opacity scale: the volume tables are baked again here
  // (the scene stays shared and unchanged).
  void setLiveSettings(const LiveSettings& live) override;
  void render(const dfb::Region& region, std::uint32_t accumulationId, std::uint32_t firstSample,
              std::uint32_t samples, dfb::Tile& out) const override;

  // origin + t dir (dir unit length) over [t0, t1), front to back. `sampler` is the pixel
  // sample's stream (dimension 2 places the volume sample grid).
  Fragment integrate(Vec3 origin, Vec3 dir, float t0, float t1, const Sampler& sampler) const;

  // A piece of a camera ray for integrate() (t0 >= t1: nothing, an empty fragment).
  struct RayPiece {
    Vec3 origin, dir;
    float t0, t1;
    Sampler sampler;
  };
  // out[i] = integrate(rays[i]) for i < count, the same bits; the rays of the one-volume march
  // go through it together in SIMD lanes where its kernel takes packets (VolumeMarch.h).
  void integrate(const RayPiece* rays, std::size_t count, Fragment* out) const;
  // A ray's first surface in its [t0, t1], found before integrate() is called.
  struct FirstSurface {
    bool found;
    SurfaceHit hit;
  };
  // integrate() with each ray's first surface given (firsts[i] for rays[i]; null: asked here).
  void integrate(const RayPiece* rays, std::size_t count, Fragment* out,
                 const FirstSurface* firsts) const;
  // Whether rasterFirstHits() answers this frame for `samples` samples per pixel a frame.
  bool firstHitsRasterised(std::uint32_t samples) const { return samples == 1 && raster_.ready(); }
  // The first surfaces of the camera rays of pixels x0 .. x1 - 1 of rows y0 .. y1 - 1, one ray
  // per pixel, row-major (as SciVisRenderer::render and the brick driver make them), from this
  // frame's raster; a ray with active[i] == 0 (active null: all are) or t0 >= t1 finds none.
  // `accept` (unless null): hits count where the ray is inside it, not in [t0, t1] (a brick's
  // bounds without its faces on the domain's boundary, see BrickFrameDriver).
  void rasterFirstHits(int x0, int x1, int y0, int y1, const RayPiece* rays,
                       const std::uint8_t* active, FirstSurface* out,
                       const Box3* accept = nullptr) const;
  // How many rays a caller should hand integrate() at once, about: enough to fill the packets,
  // few enough to stay in cache.
  static constexpr std::size_t kBatch = 1024;

  // Volume samples taken by camera rays since construction (for benchmarks).
  std::uint64_t volumeSamples() const { return volumeSamples_.load(); }

 private:
  struct March;
  // integrate() with 1 / dir, which the caller has already, and the first surface (null: asked
  // here).
  Fragment integrate(Vec3 origin, Vec3 dir, Vec3 invDir, float t0, float t1, const Sampler& sampler,
                     const FirstSurface* first = nullptr) const;
  // Whether origin + t dir over [t0, t1) holds nothing but one visible volume without
  // isosurfaces (integrate()'s march alone); then `ray` is that march.
  bool marchOnly(Vec3 origin, Vec3 dir, Vec3 invDir, float t0, float t1, const Sampler& sampler,
                 const FirstSurface& first, MarchRay& ray) const;
  Vec3 shade(Vec3 point, Vec3 normal, Vec3 dir, Vec3 baseColor, const Material& m,
             const Sampler& hitSampler) const;
  bool occluded(Vec3 origin, Vec3 dir, float tFar) const;
  // Whether a ray's one-volume march takes it in SIMD packets (VolumeMarch.h): one volume layer
  // that the kernel marches packets of.
  bool marchesPacketsHere() const;

  const SciVisScene& scene_;
  RenderSettings settings_;
  SciVisOptions options_;
  // The volume layers rays read: the scene's own, or retuned_ after setLiveSettings.
  std::vector<SciVisScene::VolumeLayer> retuned_;
  const std::vector<SciVisScene::VolumeLayer>* layers_;
  LiveSettings live_;
  Camera camera_;
  CameraDesc rasterCamera_;                         // what raster_ was prepared for
  std::vector<FirstHitRaster::Mesh> rasterMeshes_;  // empty: no raster for this scene
  FirstHitRaster raster_;
  MarchKernel march_;
  float epsilon_;
  mutable std::atomic<std::uint64_t> volumeSamples_{0};  // added once per tile
};

}  // namespace renderers::scivis
