#pragma once
// A 16x16 float transpose in AVX-512 registers: 16 rays' structs of 16 floats (one 512-bit load
// each) become one register per field, a ray per lane, and back (64 shuffles, where moving the
// fields one lane at a time through memory took a store and a load per float).
#include <immintrin.h>

#include "renderers/scivis/kernels/Avx512.h"

namespace renderers::scivis::lanes {

// Rows r[i] (16 values each) to columns: afterwards r[k] holds value k of rows 0 .. 15.
AVX512_INLINE void transpose16(__m512 r[16]) {
  __m512 t[16];
  for (int i = 0; i < 16; i += 2)
    t[i] = _mm512_unpacklo_ps(r[i], r[i + 1]), t[i + 1] = _mm512_unpackhi_ps(r[i], r[i + 1]);
  // Then r[4g + e], block b (of 128 bits): value 4b + e of rows 4g .. 4g + 3.
  for (int i = 0; i < 16; i += 4) {
    r[i] = _mm512_shuffle_ps(t[i], t[i + 2], 0x44);
    r[i + 1] = _mm512_shuffle_ps(t[i], t[i + 2], 0xee);
    r[i + 2] = _mm512_shuffle_ps(t[i + 1], t[i + 3], 0x44);
    r[i + 3] = _mm512_shuffle_ps(t[i + 1], t[i + 3], 0xee);
  }
  // A 4x4 transpose of blocks: block g of value 4b + e is block b of r[4g + e].
  for (int e = 0; e < 4; ++e) {
    const __m512 ab0 = _mm512_shuffle_f32x4(r[e], r[4 + e], 0x44);
    const __m512 ab1 = _mm512_shuffle_f32x4(r[e], r[4 + e], 0xee);
    const __m512 cd0 = _mm512_shuffle_f32x4(r[8 + e], r[12 + e], 0x44);
    const __m512 cd1 = _mm512_shuffle_f32x4(r[8 + e], r[12 + e], 0xee);
    t[e] = _mm512_shuffle_f32x4(ab0, cd0, 0x88);
    t[4 + e] = _mm512_shuffle_f32x4(ab0, cd0, 0xdd);
    t[8 + e] = _mm512_shuffle_f32x4(ab1, cd1, 0x88);
    t[12 + e] = _mm512_shuffle_f32x4(ab1, cd1, 0xdd);
  }
  for (int i = 0; i < 16; ++i) r[i] = t[i];
}

}  // namespace renderers::scivis::lanes
