// Known-answer renders and the determinism that makes a wall equal one process.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "renderers/BuiltinScenes.h"
#include "renderers/PathTracer.h"
#include "renderers/Rng.h"
#include "renderers/Scene.h"
#include "tests/renderers/RenderTestUtil.h"

namespace renderers {
namespace {

// A diffuse sphere of albedo 1 in a uniform environment of radiance L: every pixel is L.
TEST(PathTracer, WhiteFurnace) {
  const float L = 0.7f;
  SceneDesc d;
  d.materials = {{"white", MaterialType::Diffuse, Vec3{1.0f}, {}, 0, 1.5f}};
  Shape s;
  s.name = "ball";
  s.spheres = {{{0, 0, 0}}, {1.0f}};
  d.shapes = {s};
  d.instances = {{0, {}, 0}};
  d.camera = {{0, 0, -3}, {0, 0, 0}, {0, 1, 0}, 45.0f, 0, 0};
  d.environment.color = Vec3{L};
  const Scene scene(d);
  const int w = 48, h = 48;
  const std::uint32_t spp = 16;
  PathTracer pt(scene, {w, h, 7, 8});
  const auto img = test::renderImage(pt, w, h, 16, 2, spp);
  // Each sample lies in [0, L]; Hoeffding bounds a pixel mean's error by
  // L * sqrt(ln(2 / delta) / (2 spp)) with probability 1 - delta, delta = 1e-9.
  const float bound = L * std::sqrt(std::log(2e9f) / (2.0f * spp));
  double sum = 0;
  int sphere = 0;
  for (int i = 0; i < w * h; ++i) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(img[4 * i + c], L, bound) << "pixel " << i;
    EXPECT_EQ(img[4 * i + 3], 1.0f);
    sum += img[4 * i];
  }
  // The image mean, over w * h * spp independent samples, is far tighter.
  EXPECT_NEAR(sum / (w * h), L, L * std::sqrt(std::log(2e9) / (2.0 * w * h * spp)));
  // The sphere is in the picture: rays that hit it must return L too.
  Hit hit;
  for (int i = 0; i < 100; ++i)
    sphere += scene.intersect({0, 0, -3}, normalize(Vec3{0.003f * i, 0, 1}), 0, 1e9f, hit);
  EXPECT_EQ(sphere, 100);
}

// Irradiance at a point below a corner of an a x b Lambertian rectangle at height h, divided by
// the emitted radiance and pi: the corner form factor (Howell's catalogue, configuration B-3).
double cornerFactor(double a, double b, double h) {
  const double A = a / h, B = b / h;
  const double sa = std::sqrt(1 + A * A), sb = std::sqrt(1 + B * B);
  return (A / sa * std::atan(B / sa) + B / sb * std::atan(A / sb)) / (2 * M_PI);
}

// A diffuse floor (albedo rho) under a square light (radiance Le, side 2, height 1): the floor's
// radiance is rho * Le * (form factor), summed over the four rectangles meeting at the point.
TEST(PathTracer, PlaneUnderAreaLightMatchesAnalyticIrradiance) {
  const float rho = 0.5f, Le = 3.0f, half = 1.0f, height = 1.0f;
  SceneDesc d;
  d.materials = {{"floor", MaterialType::Diffuse, Vec3{rho}, {}, 0, 1.5f},
                 {"light", MaterialType::Emissive, Vec3{0.0f}, Vec3{Le}, 0, 1.5f}};
  Shape floor, light;
  floor.name = "floor";
  floor.mesh = {{{-50, 0, -50}, {-50, 0, 50}, {50, 0, 50}, {50, 0, -50}}, {{0, 1, 2}, {0, 2, 3}}};
  light.name = "light";  // corners ordered so the normal points down
  light.mesh = {
      {{-half, height, -half}, {half, height, -half}, {half, height, half}, {-half, height, half}},
      {{0, 1, 2}, {0, 2, 3}}};
  d.shapes = {floor, light};
  d.instances = {{0, {}, 0}, {1, {}, 1}};
  d.camera = {{0, 0.5f, 0}, {0, 0, 0}, {0, 0, 1}, 60.0f, 0, 0};
  const Scene scene(d);
  ASSERT_EQ(scene.lightCount(), 2);
  const int w = 32, hgt = 32;
  PathTracer pt(scene, {w, hgt, 3, 4});
  const auto img = test::renderImage(pt, w, hgt, 16, 2, 32);
  const Camera camera(d.camera, w, hgt);
  double rendered = 0, expected = 0;
  for (int y = 0; y < hgt; ++y) {
    for (int x = 0; x < w; ++x) {
      Vec3 o, dir;
      camera.ray(x + 0.5f, y + 0.5f, 0.5f, 0.5f, o, dir);
      const Vec3 p = o + dir * (-o.y / dir.y);  // where the pixel centre sees the floor
      double f = 0;
      for (double dx : {half - p.x, half + p.x})
        for (double dz : {half - p.z, half + p.z}) f += cornerFactor(dx, dz, height);
      expected += rho * Le * f;
      rendered += img[4 * (y * w + x) + 1];
    }
  }
  // Averaged over 32 * 32 pixels x 32 samples the Monte Carlo error is about 0.2%; pixel
  // centres against jittered samples add under 0.1% here.
  EXPECT_NEAR(rendered / expected, 1.0, 0.01);
}

class BitExact : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { scene_ = new Scene(cornellBox()); }
  static void TearDownTestSuite() { delete scene_; }
  static Scene* scene_;
};
Scene* BitExact::scene_ = nullptr;

// Camera rays are traced in 4x4 packets aligned to the canvas (renderers/PixelBlocks.h): tile
// sizes that are not multiples of 4 (17, 50, 5) cut blocks, and partial tiles end mid-block.
TEST_F(BitExact, TileSizeAndThreadsDoNotChangeAPixel) {
  const int w = 72, h = 56;  // not multiples of the tile sizes: partial tiles too
  PathTracer pt(*scene_, {w, h, 42, 8});
  const auto a = test::renderImage(pt, w, h, 64, 1, 2, 3);
  for (const int tile : {32, 16, 17, 50, 48, 5}) {
    const auto b = test::renderImage(pt, w, h, tile, 2, 2, 3);
    ASSERT_EQ(a.size(), b.size());
    EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(float))) << "tile " << tile;
  }
  double sum = 0;
  for (std::size_t i = 0; i < a.size(); i += 4) sum += a[i];
  EXPECT_GT(sum / (w * h), 0.05) << "the Cornell box renders black";
}

// The packet render equals tracing every camera ray alone through the public radiance(), bit
// for bit: packets change the speed, not one pixel.
TEST_F(BitExact, PacketRenderEqualsSingleRays) {
  const int w = 37, h = 29;
  const RenderSettings settings{w, h, 42, 8};
  PathTracer pt(*scene_, settings);
  const std::uint32_t spp = 3, accumulationId = 1, first = 2;
  const auto image = test::renderImage(pt, w, h, 17, 2, spp, accumulationId, first);
  const Camera camera(scene_->desc().camera, w, h);
  int differ = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      Vec3 sum{};
      for (std::uint32_t s = first; s < first + spp; ++s) {
        const Sampler sampler(settings.seed, x, y, accumulationId, s);
        Vec3 o, d;
        camera.ray(static_cast<float>(x) + sampler.get(0), static_cast<float>(y) + sampler.get(1),
                   sampler.get(2), sampler.get(3), o, d);
        const Vec3 l = pt.radiance(o, d, sampler);
        if (std::isfinite(l.x + l.y + l.z)) sum += l;
      }
      const float inv = 1.0f / spp;
      const float expected[4] = {sum.x * inv, sum.y * inv, sum.z * inv, 1.0f};
      differ += std::memcmp(expected, &image[4 * (static_cast<std::size_t>(y) * w + x)],
                            sizeof expected) != 0;
    }
  }
  EXPECT_EQ(differ, 0) << "pixels that differ from single-ray tracing";
}

// The primary renderer, whose every pixel is one packet lane, across the same tilings, and
// against a single ray per pixel.
TEST_F(BitExact, PrimaryRendererTilesAndPacketsDoNotChangeAPixel) {
  const int w = 45, h = 38;
  const auto primary = makeRenderer("primary", *scene_, {w, h, 42, 8});
  const auto a = test::renderImage(*primary, w, h, 64, 1, 1);
  for (const int tile : {17, 50, 48, 5, 1}) {
    const auto b = test::renderImage(*primary, w, h, tile, 2, 1);
    EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(float))) << "tile " << tile;
  }
  const Camera camera(scene_->desc().camera, w, h);
  Hit hit;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      Vec3 o, d;
      camera.ray(x + 0.5f, y + 0.5f, 0.5f, 0.5f, o, d);
      if (!scene_->intersect(o, d, 0.0f, std::numeric_limits<float>::infinity(), hit)) continue;
      const Vec3 c = hit.material->emission +
                     hit.material->color * (0.15f + 0.85f * std::abs(dot(d, hit.normal)));
      ASSERT_EQ(c.x, a[4 * (static_cast<std::size_t>(y) * w + x)]) << x << ", " << y;
      ASSERT_EQ(c.y, a[4 * (static_cast<std::size_t>(y) * w + x) + 1]) << x << ", " << y;
    }
}

TEST_F(BitExact, SampleRangesAccumulationIdsAndSeedsGiveDistinctSamples) {
  const int w = 16, h = 16;
  PathTracer pt(*scene_, {w, h, 42, 8});
  const auto base = test::renderImage(pt, w, h, 16, 1, 2, 0, 0);
  const auto again = test::renderImage(pt, w, h, 16, 2, 2, 0, 0);
  const auto later = test::renderImage(pt, w, h, 16, 1, 2, 0, 2);
  const auto nextPass = test::renderImage(pt, w, h, 16, 1, 2, 1, 0);
  PathTracer other(*scene_, {w, h, 43, 8});
  const auto otherSeed = test::renderImage(other, w, h, 16, 1, 2, 0, 0);
  EXPECT_EQ(base, again);
  EXPECT_NE(base, later);
  EXPECT_NE(base, nextPass);
  EXPECT_NE(base, otherSeed);
}

TEST(Scene, CornellBoxHasTheClassicLightAndColours) {
  const Scene scene(cornellBox());
  EXPECT_EQ(scene.lightCount(), 2);  // the 130 x 105 quad, two triangles
  // Looking from the camera towards x = 556 finds the red wall on the image's left.
  Hit hit;
  ASSERT_TRUE(scene.intersect({278, 273, -800}, normalize(Vec3{0.3f, 0, 1}), 0, 1e9f, hit));
  EXPECT_EQ(hit.material->name, "red");
  ASSERT_TRUE(scene.intersect({278, 273, 0}, {0, 1, 0}, 0, 1e9f, hit));
  EXPECT_EQ(hit.material->name, "white");  // the ceiling beside the light
  ASSERT_TRUE(scene.intersect({278, 273, 280}, {0, 1, 0}, 0, 1e9f, hit));
  EXPECT_EQ(hit.material->name, "light");
  EXPECT_NEAR(hit.t, 548.7f - 273.0f, 1e-3f);
  EXPECT_LT(hit.normal.y, -0.999f);  // it faces down
}

TEST(Scene, ManySpheresIsHeavy) {
  const SceneDesc d = manySpheres();
  std::size_t spheres = 0;
  for (const Shape& s : d.shapes) spheres += s.spheres.centers.size();
  EXPECT_GE(spheres, 3000u);
  const Scene scene(d);
  EXPECT_EQ(scene.lightCount(), 2);
}

}  // namespace
}  // namespace renderers
