#pragma once
// Where the volume march's kernels (VolumeMarch.cpp, VolumeMarchAvx512.cpp) start and jump: one
// definition, so every kernel samples the same t and composites the same bits.
#include <immintrin.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "renderers/scivis/VolumeMarch.h"

namespace renderers::march {

// The first sample index of the march: the first k >= kStart with (k + jitter) step >= t0, as
// the generic loop reaches it by counting up from kStart (the two loops mend rounding).
inline float firstSample(const MarchRay& r) {
  float k = std::max(r.kStart, std::ceil(r.t0 / r.step - r.jitter));
  while (k > r.kStart && (k - 1 + r.jitter) * r.step >= r.t0) k -= 1;
  while ((k + r.jitter) * r.step < r.t0) k += 1;
  return k;
}

// Where the march may jump when the sample at t lies in empty macrocell m: one sample before
// the sample before the macrocell's exit, as the generic loop does (the margin keeps rounding
// from skipping a sample of the next macrocell).
inline float lastBeforeExit(const VolumeField& field, int m, const MarchRay& r, float t) {
  float a = t, b = Box3::kInf;
  clipToBox(field.macroBounds(m), r.origin, r.invDir, a, b);
  return std::floor(b / r.step - r.jitter) - 1;
}

// Samples ahead of the march the packet kernels prefetch each lane's voxels (2, 4, 6 and 8
// measured with AVX-512; 4 best).
constexpr float kPrefetchAhead = 4.0f;

// The packet kernels' loads, 8 lanes at a time (the AVX-512 kernel takes its 16 lanes as two
// halves: AVX-512's gathers measured slower than these loads and transposes).
#define AVX2_INLINE __attribute__((target("avx2"), always_inline)) inline

// The 8 corner voxels of the cells at offsets[l] of 8 lanes, in VolumeField::interpolate()'s
// order, a register per corner: pairs along x loaded 64 bits at a time and transposed.
// (_mm_loadl_epi64 is an unaligned 64-bit load: a voxel pair is only 4-byte aligned, and
// loading it as a double is undefined behaviour that UBSan reports.)
AVX2_INLINE __m128 pairs(const float* a, const float* b) {
  return _mm_castsi128_ps(_mm_unpacklo_epi64(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(a)),
                                             _mm_loadl_epi64(reinterpret_cast<const __m128i*>(b))));
}

AVX2_INLINE void corners8(const float* voxels, const int offsets[8], int strideY, int strideZ,
                          __m256 c[8]) {
  for (int z = 0; z < 2; ++z) {
    __m256 q[4];
    for (int l = 0; l < 4; ++l) {
      const float* v = voxels + offsets[l] + z * strideZ;
      const float* w = voxels + offsets[l + 4] + z * strideZ;
      q[l] = _mm256_insertf128_ps(_mm256_castps128_ps256(pairs(v, v + strideY)),
                                  pairs(w, w + strideY), 1);
    }
    const __m256 t0 = _mm256_unpacklo_ps(q[0], q[1]), t1 = _mm256_unpackhi_ps(q[0], q[1]);
    const __m256 t2 = _mm256_unpacklo_ps(q[2], q[3]), t3 = _mm256_unpackhi_ps(q[2], q[3]);
    c[4 * z + 0] = _mm256_shuffle_ps(t0, t2, 0x44);
    c[4 * z + 1] = _mm256_shuffle_ps(t0, t2, 0xee);
    c[4 * z + 2] = _mm256_shuffle_ps(t1, t3, 0x44);
    c[4 * z + 3] = _mm256_shuffle_ps(t1, t3, 0xee);
  }
}

// Transfer-function entries at[l] (4 floats per entry) and the next of 8 lanes, loaded whole
// and transposed to a register per channel: c[next][channel].
AVX2_INLINE void tableEntries8(const float* table, const int at[8], __m256 c[2][4]) {
  for (int next = 0; next < 2; ++next) {
    __m256 q[4];
    for (int l = 0; l < 4; ++l)
      q[l] = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(table + at[l] + 4 * next)),
                                  _mm_loadu_ps(table + at[l + 4] + 4 * next), 1);
    const __m256 t0 = _mm256_unpacklo_ps(q[0], q[1]), t1 = _mm256_unpackhi_ps(q[0], q[1]);
    const __m256 t2 = _mm256_unpacklo_ps(q[2], q[3]), t3 = _mm256_unpackhi_ps(q[2], q[3]);
    c[next][0] = _mm256_shuffle_ps(t0, t2, 0x44);
    c[next][1] = _mm256_shuffle_ps(t0, t2, 0xee);
    c[next][2] = _mm256_shuffle_ps(t1, t3, 0x44);
    c[next][3] = _mm256_shuffle_ps(t1, t3, 0xee);
  }
}

// The AVX-512 kernel (VolumeMarchAvx512.cpp): marchPacket() for up to 16 rays, where the CPU
// runs AVX-512 F, DQ, BW and VL.
void marchPacketAvx512(const SciVisScene::VolumeLayer& v, const MarchRay* rays, int count,
                       MarchColor* colors, std::uint32_t* samples);

}  // namespace renderers::march
