// Known answers of the scivis renderer: emission-absorption through a homogeneous cube, rays cut
// into pieces that composite to the whole ray, a brick with ghost data shading as the whole
// scene, isosurface hits on the analytic Marschner-Lobb level set, and image-parallel tiles.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <vector>

#include "renderers/RenderScene.h"
#include "renderers/scivis/BuiltinScenes.h"
#include "renderers/scivis/bricks/BrickLoad.h"
#include "renderers/scivis/io/SciVisDesc.h"
#include "renderers/scivis/render/SciVisRenderer.h"
#include "renderers/scivis/scene/ShadingShell.h"
#include "tests/renderers/RenderTestUtil.h"

namespace renderers::scivis {
namespace {

// A volume of `n`³ voxels over [-1, 1]³, every voxel `value`.
VolumeDesc constantVolume(int n, float value) {
  VolumeDesc v;
  v.name = "cube";
  v.source.kind = VolumeSource::Kind::Wavelet;  // replaced by the voxels below
  v.source.grid.dims = {n, n, n};
  v.source.grid.origin = Vec3{-1.0f};
  v.source.grid.spacing = Vec3{2.0f / static_cast<float>(n - 1)};
  v.transfer.valueMin = 0, v.transfer.valueMax = 1;
  (void)value;
  return v;
}

Volume constantVoxels(const VolumeDesc& v, float value) {
  Volume out;
  out.grid = v.source.grid;
  out.box = v.source.grid.wholeBox();
  out.type = VoxelType::Float32;
  out.voxels.resize(out.box.voxelCount() * sizeof(float));
  for (std::size_t i = 0; i < out.box.voxelCount(); ++i)
    std::memcpy(&out.voxels[i * sizeof(float)], &value, sizeof(float));
  out.updateRange();
  return out;
}

RenderSettings settingsFor(int w, int h) {
  RenderSettings s;
  s.width = w, s.height = h, s.seed = 5;
  return s;
}

TEST(SciVis, HomogeneousCubeAbsorbsAsBeersLaw) {
  // Extinction sigma and colour c: a chord of length L gives c (1 - exp(-sigma L)).
  const float sigma = 1.3f, unit = 0.1f;
  const Vec3 c{0.2f, 0.6f, 0.9f};
  auto desc = std::make_shared<SceneDesc>();
  VolumeDesc v = constantVolume(8, 0.5f);
  v.transfer.colors = {{0.0f, c}, {1.0f, c}};
  const float opacity = 1.0f - std::exp(-sigma * unit);
  v.transfer.opacities = {{0.0f, opacity}, {1.0f, opacity}};
  v.transfer.unitDistance = unit;
  sciVisDesc(*desc).volumes.push_back(v);
  sciVisDesc(*desc).settings.samplingRate = 4;
  sciVisDesc(*desc).settings.minTransmittance = 0;
  BrickContent content;
  content.volumes.push_back(constantVoxels(v, 0.5f));
  const SciVisScene scene(desc, std::move(content));
  const SciVisRenderer renderer(scene, settingsFor(8, 8));

  struct Chord {
    Vec3 origin, dir;
  };
  const Chord chords[] = {{{0, 0, -5}, {0, 0, 1}},
                          {{0.3f, -0.2f, -5}, normalize(Vec3{0.05f, 0.1f, 1})},
                          {{-4, -3, -2}, normalize(Vec3{4.2f, 3.1f, 2.05f})},
                          {{-0.9f, -5, 0.4f}, normalize(Vec3{0.1f, 1, 0})}};
  for (const Chord& chord : chords) {
    float t0 = 0, t1 = Box3::kInf;
    ASSERT_TRUE(clipToBox(Box3{Vec3{-1}, Vec3{1}}, chord.origin, reciprocal(chord.dir), t0, t1));
    const float length = t1 - t0;
    // The sample count along a chord is L / step on average over the jitter.
    double sum[3] = {0, 0, 0};
    const int n = 400;
    for (int s = 0; s < n; ++s) {
      const Fragment f = renderer.integrate(chord.origin, chord.dir, 0, Box3::kInf,
                                            Sampler(1, 2, 3, 0, static_cast<std::uint32_t>(s)));
      for (int k = 0; k < 3; ++k) sum[k] += f.rgba[k];
    }
    const float expected = 1.0f - std::exp(-sigma * length);
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(sum[k] / n, c[k] * expected, 0.005 * c[k] * expected)
          << "channel " << k << ", chord length " << length;
  }
}

// A small wavelet scene with a visible volume, a glassy and an opaque isosurface, particles and
// a triangle: everything a ray can meet.
std::shared_ptr<SceneDesc> mixedScene(int aoSamples) {
  auto d = std::make_shared<SceneDesc>(waveletScene(40));
  sciVisDesc(*d).volumes[0].transfer.opacities = {{37.0f, 0.0f}, {120.0f, 0.05f}, {277.0f, 0.3f}};
  sciVisDesc(*d).settings.aoSamples = aoSamples;
  sciVisDesc(*d).settings.aoDistance = 0.3f;
  sciVisDesc(*d).settings.minTransmittance = 0;
  ParticlesDesc p;
  p.name = "dots";
  p.centers = {{0.5f, 0.5f, 0.5f}, {-0.6f, 0.2f, 0.7f}, {0.1f, -0.7f, -0.4f}};
  p.radii = {0.15f};
  p.material = 0;
  sciVisDesc(*d).particles.push_back(p);
  Shape tri;
  tri.name = "tri";
  tri.mesh.positions = {{-1, -1, -0.2f}, {1, -1, -0.2f}, {0, 1, -0.2f}};
  tri.mesh.triangles = {{0, 1, 2}};
  d->shapes.push_back(tri);
  d->instances.push_back({0, {}, 1});
  return d;
}

TEST(SciVis, ARayCutInTwoCompositesToTheWholeRay) {
  const auto desc = mixedScene(2);
  const SciVisScene scene(desc, wholeScene(*desc));
  const SciVisRenderer renderer(scene, settingsFor(64, 64));
  Camera camera(desc->camera, 64, 64);
  int compared = 0;
  for (const test::PixelRay& r :
       test::pixelRaysThrough(camera, 64, 64, 3, 7, 4, 9, Box3{Vec3{-1.2f}, Vec3{1.2f}})) {
    const Sampler sampler(9, r.x, r.y, 0, 0);
    const Vec3 o = r.origin, d = r.dir;
    const Fragment whole = renderer.integrate(o, d, r.t0, r.t1, sampler);
    for (float cut : {0.23f, 0.5f, 0.81f}) {
      const float tc = r.t0 + cut * (r.t1 - r.t0);
      const Fragment a = renderer.integrate(o, d, r.t0, tc, sampler);
      const Fragment b = renderer.integrate(o, d, tc, r.t1, sampler);
      for (int k = 0; k < 4; ++k) {
        const float composite = a.rgba[k] + (1.0f - a.rgba[3]) * b.rgba[k];
        EXPECT_NEAR(composite, whole.rgba[k], 1e-5f * std::max(1.0f, std::abs(whole.rgba[k])))
            << "pixel " << r.x << "," << r.y << " cut at " << cut << " channel " << k;
      }
      ++compared;
    }
  }
  EXPECT_GT(compared, 40);
}

TEST(SciVis, ABrickWithItsNeighbourAsGhostShadesLikeTheWholeScene) {
  const auto desc = mixedScene(3);
  const SciVisScene whole(desc, wholeScene(*desc));
  // The brick: everything left of x = 0.1; its neighbour (the rest) as ghost data.
  BrickContent brick = wholeScene(*desc);
  brick.bounds = Box3{Vec3{-Box3::kInf}, Vec3{0.1f, Box3::kInf, Box3::kInf}};
  // A particle reaching into the brick is the brick's (its camera rays are clipped to the
  // bounds, so a particle on the border is drawn half by each brick); the rest is ghost.
  ParticlesDesc inside = brick.particles[0], outside = brick.particles[0];
  inside.centers.clear(), outside.centers.clear();
  for (const Vec3& c : brick.particles[0].centers)
    (c.x - brick.particles[0].radius(0) < 0.1f ? inside : outside).centers.push_back(c);
  brick.particles = {inside};
  brick.ghostParticles = {outside};
  const SciVisScene part(desc, std::move(brick));
  const RenderSettings s = settingsFor(48, 48);
  const SciVisRenderer wholeRenderer(whole, s, {false}), brickRenderer(part, s, {false});
  Camera camera(desc->camera, 48, 48);
  int lit = 0;
  for (int y = 0; y < 48; y += 3)
    for (int x = 0; x < 48; x += 3) {
      const Sampler sampler(4, x, y, 0, 1);
      Vec3 o, d;
      camera.ray(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f, 0.5f, 0.5f, o, d);
      float t0 = 0, t1 = Box3::kInf;
      if (!clipToBox(part.bounds(), o, reciprocal(d), t0, t1)) continue;
      const Fragment a = wholeRenderer.integrate(o, d, t0, t1, sampler);
      const Fragment b = brickRenderer.integrate(o, d, t0, t1, sampler);
      for (int k = 0; k < 4; ++k) EXPECT_EQ(a.rgba[k], b.rgba[k]) << x << "," << y << " " << k;
      if (a.rgba[3] > 0.1f) ++lit;
    }
  EXPECT_GT(lit, 20);
}

// A sparse ghost shell (--ghost reach) is the dense box for shading rays: the same macrocells
// and value ranges, and every point of a macrocell holding an isovalue samples to the same bits
// (from its blocks outside the core, from the core's field inside); it holds fewer voxels.
TEST(SciVis, ShadingShellSamplesAsTheDenseBox) {
  const SceneDesc wavelet = waveletScene(97);
  const VolumeSource& source = sciVisDesc(wavelet).volumes[0].source;
  const VoxelBox box{{5, 0, 11}, {70, 60, 97}}, coreBox{{5, 20, 30}, {50, 60, 80}};
  const std::vector<float> isovalues = {160.0f, 215.0f};
  const Volume denseVoxels = loadVolume(source, box), coreVoxels = loadVolume(source, coreBox);
  const VolumeField dense(denseVoxels), core(coreVoxels);
  const ShadingShell shell =
      ShadingShell::load(source, box, coreBox, isovalues, [](const Box3&) { return true; });
  ASSERT_EQ(shell.macroCount(), dense.macroCount());
  EXPECT_LT(shell.voxelCount(), box.voxelCount());
  EXPECT_GT(shell.blockCount(), 0u);
  std::uint64_t state = 7, sampled = 0, fromBlocks = 0;
  auto unit = [&] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<float>(state >> 40) / static_cast<float>(1 << 24);
  };
  for (int m = 0; m < dense.macroCount(); ++m) {
    ASSERT_EQ(shell.macroMin(m), dense.macroMin(m)) << "macrocell " << m;
    ASSERT_EQ(shell.macroMax(m), dense.macroMax(m)) << "macrocell " << m;
    bool holds = false;
    for (float iso : isovalues)
      holds = holds || (iso >= dense.macroMin(m) && iso <= dense.macroMax(m));
    if (!holds) continue;
    const Box3 b = dense.macroBounds(m);
    for (int i = 0; i < 40; ++i) {
      const Vec3 p{b.lo.x + (b.hi.x - b.lo.x) * unit(), b.lo.y + (b.hi.y - b.lo.y) * unit(),
                   b.lo.z + (b.hi.z - b.lo.z) * unit()};
      float want = 0, got = 0, none = 0;
      ASSERT_TRUE(dense.sample(p, want));
      ASSERT_TRUE(shell.sample(p, got, &core));
      ASSERT_EQ(std::memcmp(&want, &got, sizeof want), 0) << "macrocell " << m;
      fromBlocks += !core.sample(p, none);
      ++sampled;
    }
  }
  EXPECT_GT(fromBlocks, 0u);
  EXPECT_GT(sampled, fromBlocks);

  // Shading rays that reach only part of the box (a light's sweep through a bounding box): the
  // macrocells and cells they do not reach keep their ranges but no voxels, the others sample
  // as above.
  const float plane = 0.5f * (dense.dataBounds().lo.x + dense.dataBounds().hi.x);
  const auto reached = [&](const Box3& b) { return b.lo.x < plane; };
  const ShadingShell part = ShadingShell::load(source, box, coreBox, isovalues, reached);
  EXPECT_LT(part.blockCount(), shell.blockCount());
  EXPECT_GT(part.blockCount(), 0u);
  int unreached = 0;
  for (int m = 0; m < dense.macroCount(); ++m) {
    ASSERT_EQ(part.macroMin(m), dense.macroMin(m)) << "macrocell " << m;
    ASSERT_EQ(part.macroMax(m), dense.macroMax(m)) << "macrocell " << m;
    const Box3 b = dense.macroBounds(m);
    const Vec3 centre = (b.lo + b.hi) * 0.5f;
    float want = 0, got = 0;
    const bool inCore = core.sample(centre, want);
    if (!shell.sample(centre, want, &core)) continue;  // no isovalue here
    const GridGeometry& g = source.grid;
    const float cellLo =
        g.origin.x + g.spacing.x * std::floor((centre.x - g.origin.x) / g.spacing.x);
    if (cellLo < plane || inCore) {
      ASSERT_TRUE(part.sample(centre, got, &core)) << "macrocell " << m;
      ASSERT_EQ(std::memcmp(&want, &got, sizeof want), 0) << "macrocell " << m;
    } else {
      EXPECT_FALSE(part.sample(centre, got, &core)) << "macrocell " << m;
      ++unreached;
    }
  }
  EXPECT_GT(unreached, 0);
}

TEST(SciVis, MarschnerLobbIsosurfaceHitsLieOnTheLevelSet) {
  // The hits lie on marching-cubes triangles over the trilinear reconstruction. The trilinear
  // level set's distance from the analytic one is the reconstruction error over the gradient,
  // O(h²) against half a voxel's O(h). With f_M = 6 the ripple's error where the gradient is
  // smallest measured 2.3 / 1.35 / 0.79 / 0.50 / 0.40 voxels at 41³ / 81³ / 161³ / 257³ / 321³.
  // The triangles add their chord error where the ripple curves most: at 321³ the hits measured
  // at most 0.256 voxels from the trilinear level set and 0.675 from the analytic one (3 of 1709
  // hits beyond half a voxel): criteria 0.35 and 0.75 voxels.
  const int n = 321;
  auto desc = std::make_shared<SceneDesc>();
  VolumeDesc v;
  v.name = "ml";
  v.source.kind = VolumeSource::Kind::MarschnerLobb;
  v.source.grid.dims = {n, n, n};
  v.source.grid.origin = Vec3{-1.0f};
  const float spacing = 2.0f / static_cast<float>(n - 1);
  v.source.grid.spacing = Vec3{spacing};
  v.transfer.valueMin = 0, v.transfer.valueMax = 1;
  v.transfer.colors = {{0.0f, Vec3{1}}};
  v.transfer.opacities = {{0.0f, 0.0f}};
  v.visible = false;
  sciVisDesc(*desc).volumes.push_back(v);
  Material m;
  m.name = "iso";
  desc->materials = {m};
  const float level = 0.5f;
  sciVisDesc(*desc).isosurfaces = {{0, level, 0}};
  desc->camera = {{1.8f, 2.2f, 2.6f}, {0, 0, 0}, {0, 1, 0}, 40.0f, 0, 0};
  const SciVisScene scene(desc, wholeScene(*desc));
  const SciVisRenderer renderer(scene, settingsFor(64, 64), {false});
  Camera camera(desc->camera, 64, 64);
  auto rho = [](Vec3 p) {
    const float r = std::sqrt(p.x * p.x + p.y * p.y), a = 0.25f, f = 6.0f;
    return (1 - std::sin(kPi * p.z / 2) + a * (1 + std::cos(2 * kPi * f * std::cos(kPi * r / 2)))) /
           (2 * (1 + a));
  };
  const VolumeField& field = *scene.volumes()[0].field;
  int hits = 0;
  float worst = 0, worstTrilinear = 0, worstCos = 1;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      Vec3 o, d;
      camera.ray(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f, 0.5f, 0.5f, o, d);
      const Fragment f = renderer.integrate(o, d, 0, Box3::kInf, Sampler(3, x, y, 0, 0));
      if (!(f.depth < Box3::kInf)) continue;
      ++hits;
      // Distance to the analytic level set, to first order: |rho - level| / |grad rho|.
      const Vec3 p = o + d * f.depth;
      const float h = 1e-3f;
      const Vec3 g{(rho(p + Vec3{h, 0, 0}) - rho(p - Vec3{h, 0, 0})) / (2 * h),
                   (rho(p + Vec3{0, h, 0}) - rho(p - Vec3{0, h, 0})) / (2 * h),
                   (rho(p + Vec3{0, 0, h}) - rho(p - Vec3{0, 0, h})) / (2 * h)};
      const float distance = std::abs(rho(p) - level) / std::max(length(g), 1e-6f);
      worst = std::max(worst, distance);
      EXPECT_LE(distance, 0.75f * spacing) << "pixel " << x << "," << y;
      // The same on the trilinear field the triangles approximate.
      float value = 0;
      ASSERT_TRUE(field.sample(p, value));
      const float fromTrilinear =
          std::abs(value - level) / std::max(length(field.gradient(p, 0.5f * spacing)), 1e-6f);
      worstTrilinear = std::max(worstTrilinear, fromTrilinear);
      EXPECT_LE(fromTrilinear, 0.35f * spacing) << "pixel " << x << "," << y;
      // The shading normal (vertex gradients interpolated) against the trilinear field's
      // gradient at the hit, which it replaced: measured at least 0.9597 (cosine, about 16
      // degrees) where the ripple curves most; criterion 0.95.
      SurfaceHit hit;
      ASSERT_TRUE(scene.intersectSurface(o, d, 0, Box3::kInf, hit));
      const Vec3 gradient = field.gradient(p, 0.5f * spacing);
      if (length(gradient) > 0) worstCos = std::min(worstCos, dot(hit.normal, normalize(gradient)));
    }
  EXPECT_GT(hits, 1000);
  EXPECT_GE(worstCos, 0.95f);
  std::printf(
      "Marschner-Lobb %d³: %d hits, farthest %.3f voxels from the level set, %.3f from the "
      "trilinear one; normals at least %.5f (cosine) from the trilinear gradient\n",
      n, hits, worst / spacing, worstTrilinear / spacing, worstCos);
}

TEST(SciVis, TilesAndThreadsDoNotChangeAPixel) {
  const RenderScene scene = buildRenderScene("scivis", *mixedScene(1));
  const auto r = makeRenderer("scivis", scene, settingsFor(61, 47));
  const auto a = test::renderImage(*r, 61, 47, 64, 1, 2);
  const auto b = test::renderImage(*r, 61, 47, 17, 2, 2);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0);
  for (std::size_t i = 3; i < a.size(); i += 4) ASSERT_EQ(a[i], 1.0f);  // background under all
}

// One visible volume takes the fast march from surface to surface (isosurfaces, particles,
// meshes); with a second, invisible volume the generic loop does: the same samples and surfaces
// in the same order, so the same bits.
TEST(SciVis, TheFastMarchBetweenSurfacesCompositesAsTheGenericLoop) {
  const auto one = mixedScene(1);
  auto two = std::make_shared<SceneDesc>(*one);
  VolumeDesc hidden = sciVisDesc(*two).volumes[0];
  hidden.name = "hidden";
  hidden.visible = false;
  sciVisDesc(*two).volumes.push_back(hidden);
  const RenderScene a = buildRenderScene("scivis", *one), b = buildRenderScene("scivis", *two);
  const auto fast =
      test::renderImage(*makeRenderer("scivis", a, settingsFor(40, 32)), 40, 32, 16, 2, 1);
  const auto generic =
      test::renderImage(*makeRenderer("scivis", b, settingsFor(40, 32)), 40, 32, 16, 2, 1);
  ASSERT_EQ(fast.size(), generic.size());
  EXPECT_EQ(std::memcmp(fast.data(), generic.data(), fast.size() * sizeof(float)), 0);
}

// Camera rays ask Embree for their first surface in packets of 16 (SciVisScene::
// intersectSurfaces): each ray must get the very hit a ray alone gets (the same t, normal and
// material bits), with or without spheres in the scene, over whole rays and pieces of them, and
// integrating a batch must give each piece the fragment it gets alone.
TEST(SciVis, SurfacePacketsHitAsSingleRays) {
  for (bool spheres : {false, true}) {
    auto desc = mixedScene(0);
    if (!spheres) sciVisDesc(*desc).particles.clear();
    sciVisDesc(*desc).volumes[0].visible = spheres;  // also the one-volume march between surfaces
    const SciVisScene scene(desc, wholeScene(*desc));
    const SciVisRenderer renderer(scene, settingsFor(48, 48), {false});
    Camera camera(desc->camera, 48, 48);
    std::vector<SciVisScene::SurfaceQuery> queries;
    std::vector<SciVisRenderer::RayPiece> pieces;
    for (int y = 0; y < 48; ++y)
      for (int x = 0; x < 48; ++x) {
        const Sampler sampler(7, x, y, 0, 0);
        Vec3 o, d;
        camera.ray(static_cast<float>(x) + sampler.get(0), static_cast<float>(y) + sampler.get(1),
                   0.5f, 0.5f, o, d);
        const float cut = 1.0f + 0.1f * static_cast<float>((x + y) % 40);
        queries.push_back({o, d, 0, Box3::kInf, true});
        queries.push_back({o, d, cut, Box3::kInf, (x + y) % 7 != 0});
        pieces.push_back({o, d, 0, cut, sampler});
        pieces.push_back({o, d, cut, Box3::kInf, sampler});
      }
    int found = 0;
    for (std::size_t base = 0; base < queries.size(); base += SciVisScene::kSurfacePacket) {
      const int n = static_cast<int>(
          std::min<std::size_t>(SciVisScene::kSurfacePacket, queries.size() - base));
      SurfaceHit hits[SciVisScene::kSurfacePacket];
      bool got[SciVisScene::kSurfacePacket];
      scene.intersectSurfaces(&queries[base], n, hits, got);
      for (int i = 0; i < n; ++i) {
        const SciVisScene::SurfaceQuery& q = queries[base + static_cast<std::size_t>(i)];
        SurfaceHit want;
        const bool has = q.active && scene.intersectSurface(q.origin, q.dir, q.tNear, q.tFar, want);
        ASSERT_EQ(got[i], has) << "ray " << base + static_cast<std::size_t>(i);
        if (!has) continue;
        ++found;
        EXPECT_EQ(std::memcmp(&want.t, &hits[i].t, sizeof want.t), 0);
        EXPECT_EQ(std::memcmp(&want.normal, &hits[i].normal, sizeof want.normal), 0);
        EXPECT_EQ(want.material, hits[i].material);
        EXPECT_NEAR(length(hits[i].normal), 1.0f, 1e-5f);
      }
    }
    EXPECT_GT(found, 1000) << "spheres " << spheres;
    std::vector<Fragment> batch(pieces.size());
    renderer.integrate(pieces.data(), pieces.size(), batch.data());
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      const SciVisRenderer::RayPiece& r = pieces[i];
      const Fragment alone = renderer.integrate(r.origin, r.dir, r.t0, r.t1, r.sampler);
      ASSERT_EQ(std::memcmp(alone.rgba, batch[i].rgba, sizeof alone.rgba), 0) << "piece " << i;
      ASSERT_EQ(std::memcmp(&alone.depth, &batch[i].depth, sizeof alone.depth), 0);
    }
  }
}

// Steering: another transfer-function preset or opacity scale changes the picture
// without rebuilding the scene, and going back to the scene's own gives it back bit for bit.
TEST(SciVis, LiveTransferFunctionChangesAndRestores) {
  const RenderScene scene = buildRenderScene("scivis", *mixedScene(1));
  const auto r = makeRenderer("scivis", scene, settingsFor(48, 40));
  const auto own = test::renderImage(*r, 48, 40, 16, 2, 1);
  r->setLiveSettings({8, 1, 1.0f});  // preset 1
  const auto preset = test::renderImage(*r, 48, 40, 16, 2, 1);
  r->setLiveSettings({8, -1, 3.0f});
  const auto denser = test::renderImage(*r, 48, 40, 16, 2, 1);
  r->setLiveSettings({8, -1, 1.0f});
  const auto back = test::renderImage(*r, 48, 40, 16, 2, 1);
  const auto bytes = own.size() * sizeof(float);
  EXPECT_NE(std::memcmp(own.data(), preset.data(), bytes), 0);
  EXPECT_NE(std::memcmp(own.data(), denser.data(), bytes), 0);
  EXPECT_EQ(std::memcmp(own.data(), back.data(), bytes), 0);
}

}  // namespace
}  // namespace renderers::scivis
