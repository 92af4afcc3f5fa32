#pragma once
// The scivis renderer's camera rays, a pixel row at a time: each sample's random stream (seeded
// from seed, pixel, accumulation id and sample, Rng.h), its ray through the jittered pixel and
// that ray clipped to the scene's bounds (an empty piece where it misses them). Where the CPU
// runs AVX-512 and the camera is a pinhole, 16 pixels at a time with the scalar code's
// operations in its order (no fused multiply-adds): the same rays and streams bit for bit.
#include <cstdint>

#include "renderers/Camera.h"
#include "renderers/scivis/render/SciVisRenderer.h"

namespace renderers::scivis {

struct RowRays {
  const Camera* camera;
  Box3 bounds;
  std::uint64_t seed;
  std::uint32_t accumulationId, firstSample, samples;
  bool simd;  // the AVX-512 version, where cameraRowSimdAvailable()
};

bool cameraRowSimdAvailable();

// The rays of pixels x0 .. x1 - 1 of row y, samples firstSample .. firstSample + samples - 1 of
// each: out[(x - x0) * samples + (s - firstSample)]; and (unless null) inside[the same index]:
// whether the ray meets `bounds` (clipToBox's answer, which an empty piece cannot tell from a
// piece of length 0 at t = 0).
void cameraRowRays(const RowRays& row, int x0, int x1, int y, SciVisRenderer::RayPiece* out,
                   std::uint8_t* inside = nullptr);

}  // namespace renderers::scivis
