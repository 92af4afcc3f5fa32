#include "renderers/scivis/render/MarchOnly.h"

#include <immintrin.h>

#include <cstddef>

#include "renderers/scivis/kernels/SamplerAvx512.h"
#include "renderers/scivis/kernels/Transpose16.h"

#include "renderers/scivis/kernels/Avx512.h"

namespace renderers::scivis {
namespace {

using RayPiece = SciVisRenderer::RayPiece;

// A RayPiece is 10 floats (its sampler's key the last two): one masked 512-bit load.
static_assert(offsetof(RayPiece, dir) == 3 * sizeof(float) &&
              offsetof(RayPiece, t0) == 6 * sizeof(float) &&
              offsetof(RayPiece, t1) == 7 * sizeof(float) &&
              offsetof(RayPiece, sampler) == 8 * sizeof(float) &&
              sizeof(Sampler) == 2 * sizeof(float) && sizeof(RayPiece) == 10 * sizeof(float));
static_assert(sizeof(MarchRay) == 16 * sizeof(float));

// clipToSlab() lane by lane: [t0, t1] narrowed to lo <= o + t dir <= hi (inv: 1 / dir).
AVX512_INLINE void clipSlab(float lo, float hi, __m512 o, __m512 inv, __m512& t0, __m512& t1) {
  const __m512 a = _mm512_mul_ps(_mm512_sub_ps(_mm512_set1_ps(lo), o), inv);
  const __m512 b = _mm512_mul_ps(_mm512_sub_ps(_mm512_set1_ps(hi), o), inv);
  // if (near > far) swap: near = far < near ? far : near, far = near > far ? near : far.
  const __m512 near = _mm512_min_ps(b, a), far = _mm512_max_ps(a, b);
  // std::max(t0, near) = t0 < near ? near : t0 = max_ps(near, t0), where near is a number.
  t0 = _mm512_mask_max_ps(t0, _mm512_cmp_ps_mask(near, near, _CMP_ORD_Q), near, t0);
  t1 = _mm512_mask_min_ps(t1, _mm512_cmp_ps_mask(far, far, _CMP_ORD_Q), far, t1);
}

}  // namespace

AVX512_TARGET unsigned marchOnly16(const RayPiece* rays, const Box3& dataBounds, float step,
                                   float minTransmittance, MarchRay* out) {
  __m512 c[16];
  for (int l = 0; l < 16; ++l)
    c[l] = _mm512_maskz_loadu_ps(0x3ff, reinterpret_cast<const float*>(rays + l));
  lanes::transpose16(c);
  const __m512 one = _mm512_set1_ps(1.0f), steps = _mm512_set1_ps(step);
  const __m512 ox = c[0], oy = c[1], oz = c[2], dx = c[3], dy = c[4], dz = c[5];
  const __m512 t0 = c[6], t1 = c[7];
  __mmask16 take = _mm512_cmp_ps_mask(t0, t1, _CMP_LT_OQ);  // marchOnly: !(t0 < t1): no
  // reciprocal(dir), and marchOnly's clip of [t0 - step, t1 + step] to the data.
  const __m512 ix = _mm512_div_ps(one, dx), iy = _mm512_div_ps(one, dy),
               iz = _mm512_div_ps(one, dz);
  __m512 start = _mm512_sub_ps(t0, steps), end = _mm512_add_ps(t1, steps);
  clipSlab(dataBounds.lo.x, dataBounds.hi.x, ox, ix, start, end);
  clipSlab(dataBounds.lo.y, dataBounds.hi.y, oy, iy, start, end);
  clipSlab(dataBounds.lo.z, dataBounds.hi.z, oz, iz, start, end);
  take &= _mm512_cmp_ps_mask(start, end, _CMP_LE_OQ);
  if (!take) return 0;
  // sampler.get(2): the keys (two floats' bits each) as 64-bit lanes, 8 at a time.
  const __m512i lo = _mm512_castps_si512(c[8]), hi = _mm512_castps_si512(c[9]);
  const __m512i first = _mm512_setr_epi32(0, 16, 1, 17, 2, 18, 3, 19, 4, 20, 5, 21, 6, 22, 7, 23);
  const __m512i second =
      _mm512_setr_epi32(8, 24, 9, 25, 10, 26, 11, 27, 12, 28, 13, 29, 14, 30, 15, 31);
  const __m512 jitter = _mm512_insertf32x8(
      _mm512_castps256_ps512(lanes::get8(_mm512_permutex2var_epi32(lo, first, hi), 2)),
      lanes::get8(_mm512_permutex2var_epi32(lo, second, hi), 2), 1);
  const __m512 kStart = _mm512_roundscale_ps(_mm512_sub_ps(_mm512_div_ps(start, steps), jitter),
                                             _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC);
  // MarchRay's fields in its order, transposed to a ray per register.
  __m512 r[16] = {ox, oy, oz, dx,     dy,  dz,    ix,     iy,
                  iz, t0, t1, kStart, end, steps, jitter, _mm512_set1_ps(minTransmittance)};
  lanes::transpose16(r);
  float* to = reinterpret_cast<float*>(out);
  for (int l = 0; l < 16; ++l) {
    const unsigned taken = (take >> l) & 1u;
    _mm512_mask_storeu_ps(to, static_cast<__mmask16>(0u - taken), r[l]);
    to += 16 * taken;
  }
  return take;
}

}  // namespace renderers::scivis
