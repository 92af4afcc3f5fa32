#pragma once
// Sampler (Rng.h) in AVX-512 lanes, 8 keys at a time: the same bits as the scalar stream, for
// the code that sets up 16 rays at once (CameraRays.cpp, MarchOnlyAvx512.cpp).
#include <immintrin.h>

#include <cstdint>

#include "renderers/Rng.h"
#include "renderers/scivis/kernels/Avx512.h"

namespace renderers::scivis::lanes {

// mix64 (Rng.h) in 8 lanes.
AVX512_INLINE __m512i mix64x8(__m512i z) {
  z = _mm512_mullo_epi64(_mm512_xor_si512(z, _mm512_srli_epi64(z, 30)),
                         _mm512_set1_epi64(static_cast<long long>(0xbf58476d1ce4e5b9ull)));
  z = _mm512_mullo_epi64(_mm512_xor_si512(z, _mm512_srli_epi64(z, 27)),
                         _mm512_set1_epi64(static_cast<long long>(0x94d049bb133111ebull)));
  return _mm512_xor_si512(z, _mm512_srli_epi64(z, 31));
}

// Sampler::get(d) of 8 keys.
AVX512_INLINE __m256 get8(__m512i keys, std::uint32_t d) {
  const __m512i h = mix64x8(_mm512_add_epi64(
      keys, _mm512_set1_epi64(static_cast<long long>((d + 1) * Sampler::kDimensionStep))));
  return _mm256_mul_ps(_mm512_cvtepi64_ps(_mm512_srli_epi64(h, 40)),
                       _mm256_set1_ps(1.0f / 16777216.0f));
}

}  // namespace renderers::scivis::lanes
