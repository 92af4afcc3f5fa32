// The scivis renderer's camera rays (CameraRays.h): the AVX-512 rows give every pixel the ray,
// clip and random stream that Sampler, Camera::ray() and clipToBox() give it one at a time.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "renderers/scivis/render/CameraRays.h"

namespace renderers::scivis {
namespace {

bool sameBits(const SciVisRenderer::RayPiece& a, const SciVisRenderer::RayPiece& b) {
  const std::uint64_t ka = a.sampler.key(), kb = b.sampler.key();
  return std::memcmp(&a.origin, &b.origin, sizeof a.origin) == 0 &&
         std::memcmp(&a.dir, &b.dir, sizeof a.dir) == 0 &&
         std::memcmp(&a.t0, &b.t0, sizeof a.t0) == 0 &&
         std::memcmp(&a.t1, &b.t1, sizeof a.t1) == 0 && ka == kb;
}

TEST(CameraRays, RowsGiveEachPixelItsOwnRayAndStream) {
  constexpr int kW = 53, kH = 7;  // rows not a multiple of 16 pixels
  const Box3 bounds{Vec3{-1.0f, -0.8f, -1.2f}, Vec3{1.0f, 0.9f, 1.1f}};
  std::vector<bool> simdModes = {false};
  if (cameraRowSimdAvailable()) simdModes.push_back(true);
  int hits = 0, misses = 0;
  for (float degrees : {0.0f, 37.0f, 90.0f, 211.0f}) {
    const CameraDesc desc =
        orbitCamera({{0.3f, 0.2f, 4.0f}, {0.1f, 0.0f, 0.0f}, {0, 1, 0}, 40.0f, 0, 0}, degrees);
    const Camera camera(desc, kW, kH);
    for (std::uint32_t samples : {1u, 3u}) {
      for (bool simd : simdModes) {
        const RowRays row{&camera, bounds, 77, 5, 2, samples, simd};
        for (int y = 0; y < kH; ++y) {
          std::vector<SciVisRenderer::RayPiece> got(std::size_t{samples} * kW);
          std::vector<std::uint8_t> inside(got.size(), 2);
          cameraRowRays(row, 0, kW, y, got.data(), inside.data());
          for (int x = 0; x < kW; ++x)
            for (std::uint32_t s = 0; s < samples; ++s) {
              // The ray as the renderer made it before rows: one pixel, one sample at a time.
              const Sampler sampler(77, x, y, 5, 2 + s);
              Vec3 origin, dir;
              camera.ray(static_cast<float>(x) + sampler.get(0),
                         static_cast<float>(y) + sampler.get(1), 0.5f, 0.5f, origin, dir);
              float t0 = 0, t1 = Box3::kInf;
              const bool meets = clipToBox(bounds, origin, reciprocal(dir), t0, t1);
              if (!meets) t0 = t1 = 0;
              const SciVisRenderer::RayPiece want{origin, dir, t0, t1, sampler};
              const auto& r = got[static_cast<std::size_t>(x) * samples + s];
              EXPECT_TRUE(sameBits(want, r)) << "simd " << simd << " degrees " << degrees
                                             << " pixel " << x << "," << y << " sample " << s;
              EXPECT_EQ(r.sampler.get(2), sampler.get(2));
              EXPECT_EQ(inside[static_cast<std::size_t>(x) * samples + s], meets ? 1 : 0);
              (t0 < t1 ? hits : misses) += 1;
            }
        }
      }
    }
  }
  EXPECT_GT(hits, 100) << "rays through the box";
  EXPECT_GT(misses, 100) << "rays beside it";
}

}  // namespace
}  // namespace renderers::scivis
