#pragma once
// Where the volume march's kernels (VolumeMarch.cpp, VolumeMarchAvx512.cpp) start and jump: one
// definition, so every kernel samples the same t and composites the same bits.
#include <immintrin.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "renderers/scivis/render/VolumeMarch.h"

namespace renderers::scivis::march {

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
// measured with AVX-512, 4 best; since a packet's first samples are prefetched while the packet
// before it marches, 3, 4, 5, 6 and 8: 5 best by 1-2%).
constexpr float kPrefetchAhead = 5.0f;

// Voxels up to this many bytes stay in the caches once read (a core's L2 is 1 MB on this
// machine's EPYC, the L3 32 MB): there the prefetches only cost instructions, 64 a step.
constexpr std::size_t kPrefetchAboveBytes = std::size_t{4} << 20;

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

// Rows r[i] (lane i's 8 values) to columns: out[k] holds value k of lanes 0 .. 7.
AVX2_INLINE void transpose8(const __m256 r[8], __m256 out[8]) {
  __m256 t[8], u[8];
  for (int i = 0; i < 8; i += 2)
    t[i] = _mm256_unpacklo_ps(r[i], r[i + 1]), t[i + 1] = _mm256_unpackhi_ps(r[i], r[i + 1]);
  for (int i = 0; i < 8; i += 4) {
    u[i] = _mm256_shuffle_ps(t[i], t[i + 2], 0x44);
    u[i + 1] = _mm256_shuffle_ps(t[i], t[i + 2], 0xee);
    u[i + 2] = _mm256_shuffle_ps(t[i + 1], t[i + 3], 0x44);
    u[i + 3] = _mm256_shuffle_ps(t[i + 1], t[i + 3], 0xee);
  }
  for (int k = 0; k < 4; ++k) {
    out[k] = _mm256_permute2f128_ps(u[k], u[k + 4], 0x20);
    out[k + 4] = _mm256_permute2f128_ps(u[k], u[k + 4], 0x31);
  }
}

// Transfer-function entries at[l] (floats from the table's start) of 8 lanes, a register per
// float: c[0][channel] the entry's RGBA, c[1][channel] its difference to the next
// (SciVisScene::VolumeLayer::table). Each lane's 8 floats are one 256-bit load, transposed 8x8.
AVX2_INLINE void tableEntries8(const float* table, const int at[8], __m256 c[2][4]) {
  __m256 rows[8], out[8];
  for (int l = 0; l < 8; ++l) rows[l] = _mm256_loadu_ps(table + at[l]);
  transpose8(rows, out);
  for (int k = 0; k < 4; ++k) c[0][k] = out[k], c[1][k] = out[k + 4];
}

// The AVX-512 kernel (VolumeMarchAvx512.cpp): marchPacket() for up to 16 rays, where the CPU
// runs AVX-512 F, DQ, BW and VL.
void marchPacketAvx512(const SciVisScene::VolumeLayer& v, const MarchRay* rays, int count,
                       MarchColor* colors, std::uint32_t* samples, const MarchRay* next,
                       int nextCount);

}  // namespace renderers::scivis::march
