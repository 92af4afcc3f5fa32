#include "renderers/scivis/render/CameraRays.h"

#include <immintrin.h>

#include "renderers/scivis/kernels/SamplerAvx512.h"

#include "renderers/scivis/kernels/Avx512.h"

namespace renderers::scivis {
namespace {

constexpr float kInf = Box3::kInf;

using lanes::get8;
using lanes::mix64x8;

SciVisRenderer::RayPiece scalarRay(const RowRays& row, int x, int y, std::uint32_t s,
                                   bool& inside) {
  const Sampler sampler(row.seed, x, y, row.accumulationId, s);
  Vec3 origin, dir;
  // Under a room's bezels the ray is not traced: an empty piece, as for one missing the bounds.
  const bool traced =
      row.camera->ray(static_cast<float>(x) + sampler.get(0),
                      static_cast<float>(y) + sampler.get(1), 0.5f, 0.5f, origin, dir);
  float t0 = 0, t1 = kInf;
  inside = traced && clipToBox(row.bounds, origin, reciprocal(dir), t0, t1);
  if (!inside) t0 = t1 = 0;
  return {origin, dir, t0, t1, sampler};
}

AVX512_INLINE __m512 join(__m256 lo, __m256 hi) {
  return _mm512_insertf32x8(_mm512_castps256_ps512(lo), hi, 1);
}

// clipToBox() along one axis, 16 lanes: [t0, t1] narrowed to the slab (NaN bounds ignored).
AVX512_INLINE void clipSlab(float lo, float hi, float o, __m512 inv, __m512& t0, __m512& t1) {
  const __m512 a = _mm512_mul_ps(_mm512_sub_ps(_mm512_set1_ps(lo), _mm512_set1_ps(o)), inv);
  const __m512 b = _mm512_mul_ps(_mm512_sub_ps(_mm512_set1_ps(hi), _mm512_set1_ps(o)), inv);
  // if (near > far) swap: near = far < near ? far : near, far = near > far ? near : far.
  const __m512 near = _mm512_min_ps(b, a), far = _mm512_max_ps(a, b);
  // std::max(t0, near) = t0 < near ? near : t0 = max_ps(near, t0), where near is a number.
  t0 = _mm512_mask_max_ps(t0, _mm512_cmp_ps_mask(near, near, _CMP_ORD_Q), near, t0);
  t1 = _mm512_mask_min_ps(t1, _mm512_cmp_ps_mask(far, far, _CMP_ORD_Q), far, t1);
}

// One component of forward + right * sx + up * sy, added left to right as Vec3's operators do.
AVX512_INLINE __m512 axis(float f, float r, float u, __m512 sx, __m512 sy) {
  return _mm512_add_ps(_mm512_add_ps(_mm512_set1_ps(f), _mm512_mul_ps(_mm512_set1_ps(r), sx)),
                       _mm512_mul_ps(_mm512_set1_ps(u), sy));
}

// 16 pixels x .. x + 15 of row y, sample s: Camera::ray() and clipToBox() as scalarRay() does
// them, lane by lane.
AVX512_TARGET void rays16(const RowRays& row, const Camera::Pinhole& cam, int x, int y,
                          std::uint32_t s, SciVisRenderer::RayPiece* out, std::uint8_t* inside,
                          std::size_t stride) {
  const std::uint64_t sampleKey = Sampler::sampleKey(row.seed, row.accumulationId, s);
  const __m512i lane = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  const __m512i xs = _mm512_add_epi32(_mm512_set1_epi32(x), lane);
  alignas(64) std::uint64_t keys[16];
  __m256 u0[2], u1[2];
  for (int half = 0; half < 2; ++half) {
    // Sampler's constructor: mix64(pixelKey(x, y) ^ sampleKey).
    const __m512i pixel = _mm512_or_si512(
        _mm512_slli_epi64(_mm512_set1_epi64(static_cast<long long>(static_cast<std::uint32_t>(y))),
                          32),
        _mm512_cvtepu32_epi64(half ? _mm512_extracti64x4_epi64(xs, 1)
                                   : _mm512_castsi512_si256(xs)));
    const __m512i key = mix64x8(
        _mm512_xor_si512(mix64x8(pixel), _mm512_set1_epi64(static_cast<long long>(sampleKey))));
    _mm512_store_si512(keys + 8 * half, key);
    u0[half] = get8(key, 0), u1[half] = get8(key, 1);
  }
  const __m512 px = _mm512_add_ps(_mm512_cvtepi32_ps(xs), join(u0[0], u0[1]));
  const __m512 py = _mm512_add_ps(_mm512_set1_ps(static_cast<float>(y)), join(u1[0], u1[1]));
  const __m512 two = _mm512_set1_ps(2.0f), one = _mm512_set1_ps(1.0f);
  const __m512 sx = _mm512_mul_ps(
      _mm512_sub_ps(_mm512_mul_ps(_mm512_mul_ps(two, px), _mm512_set1_ps(cam.invWidth)), one),
      _mm512_set1_ps(cam.halfWidth));
  const __m512 sy = _mm512_mul_ps(
      _mm512_sub_ps(one, _mm512_mul_ps(_mm512_mul_ps(two, py), _mm512_set1_ps(cam.invHeight))),
      _mm512_set1_ps(cam.halfHeight));
  // (forward + right * sx) + up * sy, then normalize(): d * (1 / sqrt((x x + y y) + z z)).
  __m512 dx = axis(cam.forward.x, cam.right.x, cam.up.x, sx, sy);
  __m512 dy = axis(cam.forward.y, cam.right.y, cam.up.y, sx, sy);
  __m512 dz = axis(cam.forward.z, cam.right.z, cam.up.z, sx, sy);
  const __m512 len = _mm512_sqrt_ps(_mm512_add_ps(
      _mm512_add_ps(_mm512_mul_ps(dx, dx), _mm512_mul_ps(dy, dy)), _mm512_mul_ps(dz, dz)));
  const __m512 scale = _mm512_div_ps(one, len);
  dx = _mm512_mul_ps(dx, scale), dy = _mm512_mul_ps(dy, scale), dz = _mm512_mul_ps(dz, scale);
  __m512 t0 = _mm512_setzero_ps(), t1 = _mm512_set1_ps(kInf);
  const Box3& b = row.bounds;
  clipSlab(b.lo.x, b.hi.x, cam.origin.x, _mm512_div_ps(one, dx), t0, t1);
  clipSlab(b.lo.y, b.hi.y, cam.origin.y, _mm512_div_ps(one, dy), t0, t1);
  clipSlab(b.lo.z, b.hi.z, cam.origin.z, _mm512_div_ps(one, dz), t0, t1);
  const __mmask16 hit = _mm512_cmp_ps_mask(t0, t1, _CMP_LE_OQ);
  t0 = _mm512_maskz_mov_ps(hit, t0), t1 = _mm512_maskz_mov_ps(hit, t1);
  alignas(64) float ox[16], oy[16], oz[16], a[16], c[16];
  _mm512_store_ps(ox, dx), _mm512_store_ps(oy, dy), _mm512_store_ps(oz, dz);
  _mm512_store_ps(a, t0), _mm512_store_ps(c, t1);
  for (int l = 0; l < 16; ++l)
    out[static_cast<std::size_t>(l) * stride] = {
        cam.origin, {ox[l], oy[l], oz[l]}, a[l], c[l], Sampler::fromKey(keys[l])};
  if (inside)
    for (int l = 0; l < 16; ++l)
      inside[static_cast<std::size_t>(l) * stride] = static_cast<std::uint8_t>((hit >> l) & 1);
}

}  // namespace

bool cameraRowSimdAvailable() {
  return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
         __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vl");
}

void cameraRowRays(const RowRays& row, int x0, int x1, int y, SciVisRenderer::RayPiece* out,
                   std::uint8_t* inside) {
  const std::size_t stride = row.samples;
  Camera::Pinhole cam;
  int x = x0;
  if (row.simd && row.camera->pinhole(cam))
    for (; x + 16 <= x1; x += 16)
      for (std::uint32_t s = 0; s < row.samples; ++s) {
        const std::size_t i = static_cast<std::size_t>(x - x0) * stride + s;
        rays16(row, cam, x, y, row.firstSample + s, out + i, inside ? inside + i : nullptr, stride);
      }
  for (; x < x1; ++x)
    for (std::uint32_t s = 0; s < row.samples; ++s) {
      const std::size_t i = static_cast<std::size_t>(x - x0) * stride + s;
      bool meets;
      out[i] = scalarRay(row, x, y, row.firstSample + s, meets);
      if (inside) inside[i] = meets ? 1 : 0;
    }
}

}  // namespace renderers::scivis
