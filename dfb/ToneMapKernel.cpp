#include "dfb/ToneMapKernel.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define DFB_TONE_MAP_AVX2 1
#endif

namespace dfb {
namespace {

// Narkowicz's fit of the ACES filmic curve: a soft shoulder instead of a hard clip. (Clamped to
// [0, 1] by the encoder: it gives 0 for anything not above 0, NaN included, and clips at 1.)
float filmicCurve(float x) { return (x * (2.51f * x + 0.03f)) / (x * (2.43f * x + 0.59f) + 0.14f); }

// Exactly encodeSrgb8Reference() without a pow per channel (which cost more than all the rest
// of a wall frame's pixel work). The 8-bit result is a non-decreasing step function of
// the linear value with 255 steps, so it is defined by the smallest float reaching each step;
// those are found once by bisection over the float bit patterns, using the reference itself.
// A table on the top 16 bits of the float gives the step at the start of each bucket, and at
// most one more comparison finishes the job. Bit-identical to the reference for every input
// (tests/dfb/TileOperationTest.cpp checks), so every path that tone-maps through here agrees
// with every other bit for bit, as invariant 2 needs.
class SrgbEncoder {
 public:
  SrgbEncoder() {
    constexpr std::uint32_t kOne = 0x3F800000;  // bits of 1.0f; [0, 1] is [0, kOne] in bits
    threshold_[0] = 0.0f;
    for (std::uint32_t k = 1; k < 256; ++k) {
      std::uint32_t lo = 0, hi = kOne;  // reference(lo) < k <= reference(hi)
      while (hi - lo > 1) {
        const std::uint32_t mid = lo + (hi - lo) / 2;
        (encodeSrgb8Reference(std::bit_cast<float>(mid)) >= k ? hi : lo) = mid;
      }
      threshold_[k] = std::bit_cast<float>(hi);
    }
    threshold_[256] = std::numeric_limits<float>::infinity();
    for (std::uint32_t b = 0; b < kBuckets; ++b)
      bucket_[b] = static_cast<std::uint8_t>(encodeSrgb8Reference(std::bit_cast<float>(b << 16)));
  }

  std::uint32_t encode(float v) const {
    if (!(v > 0.0f)) return 0;  // negative, zero, NaN (the reference gives 0 for all of them)
    v = std::min(v, 1.0f);
    // The code moves by at most one step inside a bucket (checked over every bucket), so one
    // branch-free compare finishes the job; a data-dependent loop here mispredicted on noisy
    // pixels and cost half the tone mapping.
    const std::uint32_t k = bucket_[std::bit_cast<std::uint32_t>(v) >> 16];
    return k + static_cast<std::uint32_t>(v >= threshold_[k + 1]);
  }

  // For the AVX2 kernel's gathers: it reads 4 bytes at each bucket (hence the padding).
  const std::uint8_t* buckets() const { return bucket_; }
  const float* thresholds() const { return threshold_; }

 private:
  static constexpr std::uint32_t kBuckets = (0x3F800000u >> 16) + 1;
  float threshold_[257];
  std::uint8_t bucket_[kBuckets + 3] = {};
};

const SrgbEncoder& srgbEncoder() {
  static const SrgbEncoder encoder;
  return encoder;
}

// Alpha to a byte, rounded. NaN gives 0 (as a clamp would leave NaN, whose conversion to an
// integer is undefined; 0 is what x86 made of it before).
std::uint32_t alphaByte(float a) {
  const float clamped = a > 0.0f ? std::min(a, 1.0f) : 0.0f;
  return static_cast<std::uint32_t>(clamped * 255.0f + 0.5f);
}

std::uint32_t toneMap(const float rgba[4], const ToneMapSettings& settings,
                      const SrgbEncoder& encoder) {
  std::uint32_t packed = 0;
  for (int c = 0; c < 3; ++c) {
    float v = rgba[c] * settings.exposure;
    if (settings.filmic) v = filmicCurve(v);
    packed |= encoder.encode(v) << (8 * c);
  }
  return packed | alphaByte(rgba[3]) << 24;
}

}  // namespace

std::uint32_t encodeSrgb8Reference(float linear) {
  if (!(linear > 0.0f)) return 0;  // NaN included, where the formula below is undefined
  const float v = std::min(linear, 1.0f);
  const float encoded = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
  return static_cast<std::uint32_t>(encoded * 255.0f + 0.5f);
}

std::uint32_t encodeSrgb8(float linear) { return srgbEncoder().encode(linear); }

std::uint32_t toneMapPixel(const float rgba[4], const ToneMapSettings& settings) {
  return toneMap(rgba, settings, srgbEncoder());
}

void toneMapPixelsScalar(const float* rgba, std::size_t pixels, std::uint32_t* out,
                         const ToneMapSettings& settings) {
  const SrgbEncoder& encoder = srgbEncoder();
  for (std::size_t p = 0; p < pixels; ++p) out[p] = toneMap(rgba + 4 * p, settings, encoder);
}

#ifdef DFB_TONE_MAP_AVX2

bool toneMapAvx2Available() { return __builtin_cpu_supports("avx2"); }

namespace {

struct Avx2Constants {
  __m256 scale;         // exposure in the colour lanes, 1 in the alpha lanes
  __m256i alphaLanes;   // all ones in the alpha lanes
  __m256i colourLanes;  // the others: only they gather (alpha lanes are blended away)
  bool filmic;
  const int* buckets;  // the encoder's bucket bytes, read 4 at a time
  const float* above;  // threshold of the next step: thresholds() + 1
};

// Two pixels per vector, channels in their lanes (R G B A R G B A): colour lanes are encoded,
// alpha lanes rounded, and both blended, so the interleaved floats need no shuffling. Every
// arithmetic step is the scalar kernel's, in its order and without fused multiply-adds (the
// target is AVX2 alone, so the compiler cannot contract them), hence the same bits.
__attribute__((target("avx2"), always_inline)) inline __m256i codesAvx2(const float* at,
                                                                        const Avx2Constants& k) {
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
  const __m256 x = _mm256_loadu_ps(at);
  const __m256 v = _mm256_mul_ps(x, k.scale);  // alpha lanes times 1: unchanged
  __m256 colour = v;
  if (k.filmic) {
    const __m256 num = _mm256_mul_ps(
        v, _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(2.51f), v), _mm256_set1_ps(0.03f)));
    const __m256 den = _mm256_add_ps(
        _mm256_mul_ps(
            v, _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(2.43f), v), _mm256_set1_ps(0.59f))),
        _mm256_set1_ps(0.14f));
    colour = _mm256_div_ps(num, den);
  }
  // encode(): 0 unless above 0 (NaN fails the ordered compare); such lanes look up bucket 0.
  const __m256 positive = _mm256_cmp_ps(colour, zero, _CMP_GT_OQ);
  const __m256 clipped = _mm256_and_ps(_mm256_min_ps(colour, one), positive);
  const __m256i bucket = _mm256_srli_epi32(_mm256_castps_si256(clipped), 16);
  const __m256i step = _mm256_and_si256(
      _mm256_mask_i32gather_epi32(_mm256_setzero_si256(), k.buckets, bucket, k.colourLanes, 1),
      _mm256_set1_epi32(0xFF));
  const __m256 next = _mm256_mask_i32gather_ps(_mm256_setzero_ps(), k.above, step,
                                               _mm256_castsi256_ps(k.colourLanes), 4);
  const __m256i reached = _mm256_castps_si256(_mm256_cmp_ps(clipped, next, _CMP_GE_OQ));
  const __m256i code =
      _mm256_and_si256(_mm256_sub_epi32(step, reached), _mm256_castps_si256(positive));
  // alphaByte(): NaN and negatives to 0 (max returns its second operand for NaN).
  const __m256 a = _mm256_min_ps(_mm256_max_ps(v, zero), one);
  const __m256i alpha = _mm256_cvttps_epi32(
      _mm256_add_ps(_mm256_mul_ps(a, _mm256_set1_ps(255.0f)), _mm256_set1_ps(0.5f)));
  return _mm256_blendv_epi8(code, alpha, k.alphaLanes);
}

}  // namespace

__attribute__((target("avx2"))) void toneMapPixelsAvx2(const float* rgba, std::size_t pixels,
                                                       std::uint32_t* out,
                                                       const ToneMapSettings& settings) {
  const SrgbEncoder& encoder = srgbEncoder();
  const float e = settings.exposure;
  const Avx2Constants k{
      _mm256_setr_ps(e, e, e, 1.0f, e, e, e, 1.0f),    _mm256_setr_epi32(0, 0, 0, -1, 0, 0, 0, -1),
      _mm256_setr_epi32(-1, -1, -1, 0, -1, -1, -1, 0), settings.filmic,
      reinterpret_cast<const int*>(encoder.buckets()), encoder.thresholds() + 1};
  // packus interleaves 128-bit lanes: the bytes come out as pixels 0 2 4 6 1 3 5 7.
  const __m256i order = _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7);
  std::size_t p = 0;
  for (; p + 8 <= pixels; p += 8) {
    const float* at = rgba + 4 * p;
    const __m256i c0 = codesAvx2(at, k), c1 = codesAvx2(at + 8, k), c2 = codesAvx2(at + 16, k),
                  c3 = codesAvx2(at + 24, k);
    const __m256i bytes =
        _mm256_packus_epi16(_mm256_packus_epi32(c0, c1), _mm256_packus_epi32(c2, c3));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + p),
                        _mm256_permutevar8x32_epi32(bytes, order));
  }
  toneMapPixelsScalar(rgba + 4 * p, pixels - p, out + p, settings);
}

#else

bool toneMapAvx2Available() { return false; }
void toneMapPixelsAvx2(const float* rgba, std::size_t pixels, std::uint32_t* out,
                       const ToneMapSettings& settings) {
  toneMapPixelsScalar(rgba, pixels, out, settings);
}

#endif

void toneMapPixels(const float* rgba, std::size_t pixels, std::uint32_t* out,
                   const ToneMapSettings& settings) {
  static const bool avx2 = toneMapAvx2Available();
  if (avx2)
    toneMapPixelsAvx2(rgba, pixels, out, settings);
  else
    toneMapPixelsScalar(rgba, pixels, out, settings);
}

}  // namespace dfb
