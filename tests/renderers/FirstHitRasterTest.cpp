// Camera rays' first hits by rasterising triangles (FirstHitRaster) against Embree's ray tests on
// the same isosurface triangles: the same surfaces, no ray let through a closed surface (also
// rays aimed exactly at its vertices and edges), answers that do not depend on how the canvas is
// cut into queries or on the instruction set, and a renderer whose images match Embree's.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <vector>

#include "renderers/Rng.h"
#include "renderers/scivis/BuiltinScenes.h"
#include "renderers/scivis/bricks/BrickLoad.h"
#include "renderers/scivis/bricks/BrickPlan.h"
#include "renderers/scivis/kernels/FirstHitRaster.h"
#include "renderers/scivis/render/SciVisRenderer.h"
#include "renderers/scivis/scene/SciVisScene.h"
#include "tests/renderers/RenderTestUtil.h"

namespace renderers::scivis {
namespace {

constexpr float kInf = Box3::kInf;

// n³ float voxels over [-1, 1]³ of f(world point), as one whole-scene brick.
template <class F>
BrickContent fieldContent(int n, F f) {
  BrickContent content;
  Volume v;
  v.grid.dims = {n, n, n};
  v.grid.origin = Vec3{-1.0f};
  v.grid.spacing = Vec3{2.0f / static_cast<float>(n - 1)};
  v.box = v.grid.wholeBox();
  v.type = VoxelType::Float32;
  v.voxels.resize(v.box.voxelCount() * sizeof(float));
  std::size_t i = 0;
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x, ++i) {
        const float value = f(v.grid.worldOf(x, y, z));
        std::memcpy(&v.voxels[i * sizeof(float)], &value, sizeof value);
      }
  v.updateRange();
  content.volumes.push_back(std::move(v));
  return content;
}

// A scene of one invisible volume of n³ voxels and opaque isosurfaces at `levels`.
std::shared_ptr<SceneDesc> isoScene(int n, std::vector<float> levels, CameraDesc camera) {
  auto desc = std::make_shared<SceneDesc>();
  VolumeDesc v;
  v.name = "field";
  v.source.grid.dims = {n, n, n};
  v.source.grid.origin = Vec3{-1.0f};
  v.source.grid.spacing = Vec3{2.0f / static_cast<float>(n - 1)};
  v.transfer.valueMin = 0, v.transfer.valueMax = 2;
  v.transfer.colors = {{0.0f, Vec3{1}}};
  v.transfer.opacities = {{0.0f, 0.0f}};
  v.visible = false;
  sciVisDesc(*desc).volumes.push_back(v);
  for (std::size_t i = 0; i < levels.size(); ++i) {
    Material m;
    m.name = "iso" + std::to_string(i);
    m.color = Vec3{0.3f + 0.3f * static_cast<float>(i), 0.6f, 0.9f};
    desc->materials.push_back(m);
    sciVisDesc(*desc).isosurfaces.push_back(
        {0, levels[i], static_cast<std::uint32_t>(desc->materials.size() - 1)});
  }
  desc->camera = camera;
  return desc;
}

float ripple(Vec3 p) {
  return length(p) + 0.08f * std::sin(7 * p.x) * std::cos(5 * p.y + 1) * std::sin(6 * p.z + 2);
}

// The camera rays the renderer makes (jittered pixels, sample 0), as structure of arrays.
struct CanvasRays {
  int width, height;
  Vec3 origin;
  std::vector<float> dx, dy, dz, t0, t1;
};

CanvasRays canvasRays(const Camera& camera, int width, int height) {
  CanvasRays r{width, height, camera.position(), {}, {}, {}, {}, {}};
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const Sampler s(11, x, y, 3, 0);
      Vec3 o, d;
      camera.ray(static_cast<float>(x) + s.get(0), static_cast<float>(y) + s.get(1), 0.5f, 0.5f, o,
                 d);
      r.dx.push_back(d.x), r.dy.push_back(d.y), r.dz.push_back(d.z);
      r.t0.push_back(0), r.t1.push_back(kInf);
    }
  return r;
}

std::vector<FirstHitRaster::Hit> rasterHits(const FirstHitRaster& raster, const CanvasRays& r) {
  std::vector<FirstHitRaster::Hit> hits(r.dx.size());
  raster.firstHits(0, r.width, 0, r.height, static_cast<std::size_t>(r.width), r.dx.data(),
                   r.dy.data(), r.dz.data(), r.t0.data(), r.t1.data(), hits.data());
  return hits;
}

const CameraDesc kCamera{{1.7f, 1.2f, 2.9f}, {0.05f, -0.03f, 0}, {0, 1, 0}, 42.0f, 0, 0};

// A field's opaque isosurfaces (one mesh per level) seen by kCamera on w x h, binned.
struct RasterCase {
  RasterCase(int n, std::vector<float> levels, float (*field)(Vec3), int width, int height)
      : desc(isoScene(n, levels, kCamera)),
        scene(desc, fieldContent(n, field)),
        camera(kCamera, width, height),
        w(width),
        h(height) {
    ready = scene.opaqueCameraTriangles(meshes) && meshes.size() == levels.size() &&
            raster.prepare(camera, w, h, meshes);
  }
  std::shared_ptr<SceneDesc> desc;
  SciVisScene scene;
  Camera camera;
  int w, h;
  std::vector<FirstHitRaster::Mesh> meshes;
  FirstHitRaster raster;
  bool ready = false;
};

float distanceFromCentre(Vec3 p) { return length(p); }

TEST(FirstHitRaster, FindsTheSurfacesEmbreeFinds) {
  const RasterCase c(64, {0.55f, 0.85f}, ripple, 160, 120);
  ASSERT_TRUE(c.ready);
  const SciVisScene& scene = c.scene;
  const FirstHitRaster& raster = c.raster;
  const Camera& camera = c.camera;
  const int w = c.w, h = c.h;
  const CanvasRays rays = canvasRays(camera, w, h);
  const auto hits = rasterHits(raster, rays);
  int both = 0, onlyOne = 0, otherSurface = 0;
  float worstT = 0;
  for (std::size_t i = 0; i < hits.size(); ++i) {
    const Vec3 d{rays.dx[i], rays.dy[i], rays.dz[i]};
    SurfaceHit embree;
    const bool found = scene.intersectSurface(rays.origin, d, 0, kInf, embree);
    const bool rasterFound = hits[i].mesh != FirstHitRaster::kNone;
    if (found != rasterFound) {
      ++onlyOne;
      continue;
    }
    if (!found) continue;
    ++both;
    SurfaceHit mine;
    scene.fillSurfaceHit(hits[i].mesh, hits[i].triangle, hits[i].u, hits[i].v, hits[i].t,
                         rays.origin, d, mine);
    if (mine.material != embree.material) ++otherSurface;
    worstT = std::max(worstT, std::abs(mine.t - embree.t) / embree.t);
    EXPECT_GT(dot(mine.normal, embree.normal), 0.999f) << "pixel " << i;
  }
  std::printf(
      "raster vs Embree: %d rays hit in both, %d in one only, %d another surface, "
      "distances within %.2g (relative)\n",
      both, onlyOne, otherSurface, worstT);
  EXPECT_GT(both, w * h / 5);
  // Rays that graze a silhouette within float rounding may be hit by one test and missed by the
  // other (measured: 1 of 19200).
  EXPECT_LE(onlyOne, w * h / 2000);
  EXPECT_EQ(otherSurface, 0);
  EXPECT_LT(worstT, 1e-5f);  // measured 2.3e-6
}

// A closed sphere-like surface seen from outside: every ray through its inner disc hits it, also
// rays aimed exactly at its vertices and at its edges' midpoints, where two or more triangles
// meet (the places a ray test that is not watertight lets rays through).
TEST(FirstHitRaster, LetsNoRayThroughAClosedSurface) {
  const RasterCase c(40, {0.6f}, distanceFromCentre, 200, 150);
  ASSERT_TRUE(c.ready);
  const FirstHitRaster& raster = c.raster;
  const Camera& camera = c.camera;
  const std::vector<FirstHitRaster::Mesh>& meshes = c.meshes;
  const int w = c.w, h = c.h;
  const Vec3 eye = kCamera.position;
  const float innerAngle = std::asin(0.58f / length(eye));
  // Rays through the pixels whose ray passes inside radius 0.58 all hit.
  CanvasRays rays = canvasRays(camera, w, h);
  auto hits = rasterHits(raster, rays);
  int inner = 0;
  for (std::size_t i = 0; i < hits.size(); ++i) {
    const Vec3 d{rays.dx[i], rays.dy[i], rays.dz[i]};
    if (std::acos(std::clamp(dot(d, normalize(-eye)), -1.0f, 1.0f)) >= innerAngle) continue;
    ++inner;
    EXPECT_NE(hits[i].mesh, FirstHitRaster::kNone) << "pixel " << i;
  }
  EXPECT_GT(inner, 2000);
  // Rays aimed at vertices and edge midpoints facing the camera, each in the pixel its target
  // projects to (one target per pixel per round).
  const FirstHitRaster::Mesh& m = meshes[0];
  auto at = [&](std::uint32_t v) {
    return Vec3{m.vertices[3 * v], m.vertices[3 * v + 1], m.vertices[3 * v + 2]};
  };
  Camera::Pinhole pin;
  ASSERT_TRUE(camera.pinhole(pin));
  auto project = [&](Vec3 p, int& px, int& py) {
    const Vec3 v = p - pin.origin;
    const float depth = dot(v, pin.forward);
    px = static_cast<int>(std::floor((dot(v, pin.right) / depth / pin.halfWidth + 1) * 0.5f * w));
    py = static_cast<int>(std::floor((1 - dot(v, pin.up) / depth / pin.halfHeight) * 0.5f * h));
    return px >= 0 && px < w && py >= 0 && py < h;
  };
  int aimed = 0;
  for (int round = 0; round < 2; ++round) {
    std::vector<std::uint8_t> used(static_cast<std::size_t>(w * h), 0);
    for (std::size_t i = 0; i < rays.t1.size(); ++i) rays.t0[i] = kInf, rays.t1[i] = -kInf;
    for (std::size_t t = 0; t < m.triangleCount; ++t) {
      const std::uint32_t a = m.triangles[3 * t], b = m.triangles[3 * t + 1];
      const Vec3 target = round == 0 ? at(a) : (at(a) + at(b)) * 0.5f;
      if (dot(target, normalize(eye)) < 0.3f) continue;  // the side facing the camera
      int px, py;
      if (!project(target, px, py)) continue;
      const std::size_t i = static_cast<std::size_t>(py * w + px);
      if (used[i]) continue;
      used[i] = 1;
      const Vec3 d = normalize(target - eye);
      rays.dx[i] = d.x, rays.dy[i] = d.y, rays.dz[i] = d.z, rays.t0[i] = 0, rays.t1[i] = kInf;
    }
    hits = rasterHits(raster, rays);
    for (std::size_t i = 0; i < hits.size(); ++i) {
      if (!used[i]) continue;
      ++aimed;
      EXPECT_NE(hits[i].mesh, FirstHitRaster::kNone) << "round " << round << " pixel " << i;
    }
  }
  EXPECT_GT(aimed, 1000);
}

// The answer for a ray depends on the ray and the triangles only: queries of any shape (a cell
// cut in parts, rows of any stride) and the scalar and AVX-512 kernels give the same bits.
TEST(FirstHitRaster, QueriesAndKernelsDoNotChangeAnAnswer) {
  const auto desc = isoScene(48, {0.5f, 0.8f}, kCamera);
  const SciVisScene scene(desc, fieldContent(48, ripple));
  std::vector<FirstHitRaster::Mesh> meshes;
  ASSERT_TRUE(scene.opaqueCameraTriangles(meshes));
  const int w = 93, h = 71;
  const Camera camera(kCamera, w, h);
  FirstHitRaster simd, scalar;
  ASSERT_TRUE(simd.prepare(camera, w, h, meshes));
  ASSERT_TRUE(scalar.prepare(camera, w, h, meshes, false));
  const CanvasRays rays = canvasRays(camera, w, h);
  const auto whole = rasterHits(simd, rays);
  const auto scalarWhole = rasterHits(scalar, rays);
  ASSERT_EQ(std::memcmp(whole.data(), scalarWhole.data(), whole.size() * sizeof(whole[0])), 0);
  int found = 0;
  for (const auto& hit : whole) found += hit.mesh != FirstHitRaster::kNone;
  EXPECT_GT(found, w * h / 5);
  // Blocks of 13 x 7 pixels (across the raster's 16-pixel cells), each queried alone with its
  // own stride.
  for (int y0 = 0; y0 < h; y0 += 7)
    for (int x0 = 0; x0 < w; x0 += 13) {
      const int x1 = std::min(w, x0 + 13), y1 = std::min(h, y0 + 7), bw = x1 - x0;
      const std::size_t stride = static_cast<std::size_t>(bw + 3);
      std::vector<float> dx, dy, dz, t0, t1;
      for (int y = y0; y < y1; ++y)
        for (std::size_t k = 0; k < stride; ++k) {
          const std::size_t i =
              static_cast<std::size_t>(y * w + x0) + std::min(k, static_cast<std::size_t>(bw - 1));
          dx.push_back(rays.dx[i]), dy.push_back(rays.dy[i]), dz.push_back(rays.dz[i]);
          t0.push_back(0), t1.push_back(kInf);
        }
      std::vector<FirstHitRaster::Hit> part(dx.size());
      simd.firstHits(x0, x1, y0, y1, stride, dx.data(), dy.data(), dz.data(), t0.data(), t1.data(),
                     part.data());
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
          const FirstHitRaster::Hit& a =
              part[static_cast<std::size_t>(y - y0) * stride + static_cast<std::size_t>(x - x0)];
          const FirstHitRaster::Hit& b = whole[static_cast<std::size_t>(y * w + x)];
          ASSERT_EQ(std::memcmp(&a, &b, sizeof a), 0) << "pixel " << x << "," << y;
        }
    }
}

// Each cell's triangles are tested nearest first and most are skipped behind nearer hits; the
// order is the raster's own business: the same triangles listed in reverse give every ray the
// same hit (the same distance bits, the same triangle), with either kernel.
TEST(FirstHitRaster, TheTrianglesOrderDoesNotChangeAnAnswer) {
  const auto desc = isoScene(48, {0.5f, 0.8f}, kCamera);
  const SciVisScene scene(desc, fieldContent(48, ripple));
  std::vector<FirstHitRaster::Mesh> meshes;
  ASSERT_TRUE(scene.opaqueCameraTriangles(meshes));
  std::vector<std::vector<std::uint32_t>> reversedTriangles;
  std::vector<FirstHitRaster::Mesh> reversed = meshes;
  for (FirstHitRaster::Mesh& m : reversed) {
    std::vector<std::uint32_t> list(m.triangles, m.triangles + 3 * m.triangleCount);
    std::vector<std::uint32_t> flipped;
    for (std::size_t t = m.triangleCount; t-- > 0;)
      flipped.insert(flipped.end(), list.begin() + static_cast<std::ptrdiff_t>(3 * t),
                     list.begin() + static_cast<std::ptrdiff_t>(3 * t + 3));
    reversedTriangles.push_back(std::move(flipped));
    m.triangles = reversedTriangles.back().data();
  }
  const int w = 150, h = 110;
  const Camera camera(kCamera, w, h);
  const CanvasRays rays = canvasRays(camera, w, h);
  for (const bool simd : {true, false}) {
    FirstHitRaster forward, backward;
    ASSERT_TRUE(forward.prepare(camera, w, h, meshes, simd));
    ASSERT_TRUE(backward.prepare(camera, w, h, reversed, simd));
    const auto a = rasterHits(forward, rays), b = rasterHits(backward, rays);
    int found = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      ASSERT_EQ(a[i].mesh, b[i].mesh) << "pixel " << i;
      if (a[i].mesh == FirstHitRaster::kNone) continue;
      ++found;
      const std::size_t count = meshes[a[i].mesh == meshes[0].id ? 0 : 1].triangleCount;
      EXPECT_EQ(a[i].triangle, count - 1 - b[i].triangle) << "pixel " << i;
      EXPECT_EQ(std::memcmp(&a[i].t, &b[i].t, sizeof(float)), 0) << "pixel " << i;
      EXPECT_EQ(std::memcmp(&a[i].u, &b[i].u, sizeof(float)), 0) << "pixel " << i;
    }
    EXPECT_GT(found, w * h / 5);
  }
}

// A raster whose meshes change (an isovalue steered: new triangles) clusters them afresh over
// the buffers of the last ones and answers bit for bit as a raster that never saw the old ones,
// from many meshes too (clusters are made in parallel, each from its own triangles).
TEST(FirstHitRaster, NewMeshesAnswerAsAFreshRaster) {
  RasterCase before(64, {0.45f, 0.6f, 0.75f, 0.9f, 1.05f}, ripple, 160, 120);
  const RasterCase after(48, {0.7f}, distanceFromCentre, 160, 120);
  ASSERT_TRUE(before.ready);
  ASSERT_TRUE(after.ready);
  const CanvasRays rays = canvasRays(after.camera, after.w, after.h);
  const auto beforeHits = rasterHits(before.raster, rays);
  ASSERT_TRUE(before.raster.prepare(after.camera, after.w, after.h, after.meshes));
  const auto fresh = rasterHits(after.raster, rays), reused = rasterHits(before.raster, rays);
  int found = 0, changed = 0;
  for (std::size_t i = 0; i < fresh.size(); ++i) {
    ASSERT_EQ(fresh[i].mesh, reused[i].mesh) << "pixel " << i;
    changed += beforeHits[i].mesh != fresh[i].mesh || beforeHits[i].triangle != fresh[i].triangle;
    if (fresh[i].mesh == FirstHitRaster::kNone) continue;
    ++found;
    EXPECT_EQ(fresh[i].triangle, reused[i].triangle) << "pixel " << i;
    EXPECT_EQ(std::memcmp(&fresh[i].t, &reused[i].t, sizeof(float)), 0) << "pixel " << i;
    EXPECT_EQ(std::memcmp(&fresh[i].u, &reused[i].u, sizeof(float)), 0) << "pixel " << i;
    EXPECT_EQ(std::memcmp(&fresh[i].v, &reused[i].v, sizeof(float)), 0) << "pixel " << i;
  }
  EXPECT_GT(found, after.w * after.h / 10);
  EXPECT_GT(changed, after.w * after.h / 10);  // the old meshes did answer otherwise
}

// Nothing to bin (a mesh without triangles: an isovalue outside the field's range) is a raster
// that finds nothing, with either kernel.
TEST(FirstHitRaster, NoTrianglesFindNothing) {
  const float vertex[3] = {0, 0, 0};
  const std::vector<FirstHitRaster::Mesh> meshes{{vertex, 1, nullptr, 0, 0}};
  const int w = 40, h = 30;
  const Camera camera(kCamera, w, h);
  const CanvasRays rays = canvasRays(camera, w, h);
  for (const bool simd : {true, false}) {
    FirstHitRaster raster;
    ASSERT_TRUE(raster.prepare(camera, w, h, meshes, simd));
    for (const auto& hit : rasterHits(raster, rays)) EXPECT_EQ(hit.mesh, FirstHitRaster::kNone);
  }
}

// The renderer with its first hits rasterised against the renderer asking Embree: the same
// surfaces, shaded alike up to the last bits of the hit distances.
TEST(FirstHitRaster, RenderedImagesMatchEmbreesFirstHits) {
  const auto desc = isoScene(64, {0.55f, 0.85f}, kCamera);
  const SciVisScene scene(desc, fieldContent(64, ripple));
  RenderSettings settings;
  settings.width = 120, settings.height = 96, settings.seed = 9;
  SciVisOptions rasterOptions, embreeOptions, autoOptions;
  rasterOptions.firstHits = FirstHits::Raster;
  embreeOptions.firstHits = FirstHits::Embree;
  SciVisRenderer rasterised(scene, settings, rasterOptions), traced(scene, settings, embreeOptions);
  const dfb::FrameInfo frame{};
  rasterised.beginFrame(frame, kCamera);
  traced.beginFrame(frame, kCamera);
  ASSERT_TRUE(rasterised.firstHitsRasterised(1));
  ASSERT_FALSE(traced.firstHitsRasterised(1));
  ASSERT_FALSE(rasterised.firstHitsRasterised(2));  // more samples a frame: Embree
  // Auto: here a voxel cell spans about 1.1 pixels, where Embree is the faster; at 4x the
  // canvas, 4.4 pixels, the raster.
  SciVisRenderer automatic(scene, settings, autoOptions);
  automatic.beginFrame(frame, kCamera);
  EXPECT_FALSE(automatic.firstHitsRasterised(1));
  RenderSettings large = settings;
  large.width *= 4, large.height *= 4;
  SciVisRenderer automaticLarge(scene, large, autoOptions);
  automaticLarge.beginFrame(frame, kCamera);
  EXPECT_TRUE(automaticLarge.firstHitsRasterised(1));
  const auto a = test::renderImage(rasterised, 120, 96, 32, 2, 1);
  const auto b = test::renderImage(traced, 120, 96, 32, 2, 1);
  ASSERT_EQ(a.size(), b.size());
  float worst = 0;
  int lit = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    worst = std::max(worst, std::abs(a[i] - b[i]));
    lit += i % 4 == 0 && a[i] > 0.05f;
  }
  // Measured 2.1e-4: the barycentric coordinates (which interpolate the normals) come from the
  // edge values here and from Embree's own arithmetic there.
  EXPECT_LT(worst, 1e-3f);
  EXPECT_GT(lit, 2000);
}

// The same with the volume drawn too: rays march it up to the first (opaque) surface the
// raster found, as they do up to Embree's.
TEST(FirstHitRaster, AVisibleVolumeMarchesUpToTheRastersSurface) {
  auto desc = isoScene(64, {0.55f, 0.85f}, kCamera);
  sciVisDesc(*desc).volumes[0].visible = true;
  sciVisDesc(*desc).volumes[0].transfer.colors = {{0.0f, Vec3{1, 0.5f, 0.2f}},
                                                  {2.0f, Vec3{0.2f, 0.5f, 1}}};
  sciVisDesc(*desc).volumes[0].transfer.opacities = {{0.0f, 0.02f}, {2.0f, 0.05f}};
  const SciVisScene scene(desc, fieldContent(64, ripple));
  RenderSettings settings;
  settings.width = 120, settings.height = 96, settings.seed = 9;
  SciVisOptions rasterOptions, embreeOptions;
  rasterOptions.firstHits = FirstHits::Raster;
  embreeOptions.firstHits = FirstHits::Embree;
  SciVisRenderer rasterised(scene, settings, rasterOptions), traced(scene, settings, embreeOptions);
  rasterised.beginFrame(dfb::FrameInfo{}, kCamera);
  traced.beginFrame(dfb::FrameInfo{}, kCamera);
  ASSERT_TRUE(rasterised.firstHitsRasterised(1));
  const auto a = test::renderImage(rasterised, 120, 96, 32, 2, 1);
  const auto b = test::renderImage(traced, 120, 96, 32, 2, 1);
  ASSERT_EQ(a.size(), b.size());
  float worst = 0, haze = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    worst = std::max(worst, std::abs(a[i] - b[i]));
    if (i % 4 == 2) haze = std::max(haze, a[i]);
  }
  EXPECT_LT(worst, 1e-3f);
  EXPECT_GT(haze, 0.05f) << "the volume should show";
}

}  // namespace
}  // namespace renderers::scivis

namespace renderers::scivis {
namespace {

// Bricks find, ray for ray, what the whole scene finds: each brick rasterises its own triangles
// for the rays clipped to its bounds, and the nearest of the bricks' hits is the whole scene's.
TEST(FirstHitRaster, BricksFindWhatTheWholeSceneFinds) {
  auto desc = std::make_shared<SceneDesc>(waveletScene(96));
  sciVisDesc(*desc).volumes[0].visible = false;
  for (Material& m : desc->materials) m.opacity = 1.0f;
  desc->camera = orbitCamera(desc->camera, 30.0f);
  const int w = 384, h = 384;
  const Camera camera(desc->camera, w, h);
  const SciVisScene whole(desc, wholeScene(*desc));
  std::vector<FirstHitRaster::Mesh> meshes;
  ASSERT_TRUE(whole.opaqueCameraTriangles(meshes));
  FirstHitRaster wholeRaster;
  ASSERT_TRUE(wholeRaster.prepare(camera, w, h, meshes));
  const CanvasRays rays = canvasRays(camera, w, h);
  const auto wholeHits = rasterHits(wholeRaster, rays);
  std::vector<float> nearest(wholeHits.size(), kInf);
  for (HeldBrick& brick : loadOwnBricks(*desc, 4, 1, 0, 1)) {
    const SciVisScene scene(desc, std::move(brick.content));
    ASSERT_TRUE(scene.opaqueCameraTriangles(meshes));
    FirstHitRaster raster;
    ASSERT_TRUE(raster.prepare(camera, w, h, meshes));
    CanvasRays clipped = rays;
    for (std::size_t i = 0; i < rays.dx.size(); ++i) {
      const Vec3 d{rays.dx[i], rays.dy[i], rays.dz[i]};
      // As the brick driver accepts them: up to the domain's boundary where the brick meets it.
      const Box3 accept = openAtDomainBoundary(scene.bounds(), scene.domain());
      float t0 = 0, t1 = kInf;
      if (!clipToBox(accept, rays.origin, reciprocal(d), t0, t1)) t0 = kInf, t1 = -kInf;
      clipped.t0[i] = t0, clipped.t1[i] = t1;
    }
    const auto hits = rasterHits(raster, clipped);
    for (std::size_t i = 0; i < hits.size(); ++i)
      if (hits[i].mesh != FirstHitRaster::kNone) nearest[i] = std::min(nearest[i], hits[i].t);
  }
  int found = 0, differ = 0, embreeDiffers = 0;
  for (std::size_t i = 0; i < wholeHits.size(); ++i) {
    const float t = wholeHits[i].mesh != FirstHitRaster::kNone ? wholeHits[i].t : kInf;
    found += t < kInf;
    if (t != nearest[i] && ++differ < 10)
      std::printf("pixel %zu,%zu: whole %.7g, bricks %.7g\n", i % w, i / w, t, nearest[i]);
    // And Embree on the whole scene: the same surface (measured at 2048^2 on the 256^3 wavelet:
    // 0 to 2 rays of 4.2 M differ; with edge planes from the long vectors, 584).
    SurfaceHit e;
    const bool hit =
        whole.intersectSurface(rays.origin, {rays.dx[i], rays.dy[i], rays.dz[i]}, 0, kInf, e);
    if (hit != (t < kInf) || (hit && std::abs(e.t - t) > 1e-4f * e.t)) ++embreeDiffers;
  }
  EXPECT_GT(found, w * h / 5);
  EXPECT_EQ(differ, 0);
  EXPECT_LE(embreeDiffers, w * h / 10000);
  std::printf("4 bricks vs the whole scene: %d of %d rays differ; raster vs Embree: %d\n", differ,
              w * h, embreeDiffers);
}

}  // namespace
}  // namespace renderers::scivis
