#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#include "dfb/PixelOp.h"

namespace dfb {
namespace {

// Narkowicz's fit of the ACES filmic curve: a soft shoulder instead of a hard clip.
float filmicCurve(float x) {
  return std::clamp((x * (2.51f * x + 0.03f)) / (x * (2.43f * x + 0.59f) + 0.14f), 0.0f, 1.0f);
}

// Exactly encodeSrgb8Reference() without a pow per channel (which cost 45 ns, more than all
// the rest of a wall frame's pixel work). The 8-bit result is a non-decreasing step function of
// the linear value with 255 steps, so it is defined by the smallest float reaching each step;
// those are found once by bisection over the float bit patterns, using the reference itself.
// A table on the top 16 bits of the float gives the step at the start of each bucket, and at
// most a step or two of comparisons finish the job. Bit-identical to the reference for every
// input (tests/dfb/TileOperationTest.cpp checks), so every path that tone-maps through here
// agrees with every other bit for bit, as invariant 2 needs.
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

 private:
  static constexpr std::uint32_t kBuckets = (0x3F800000u >> 16) + 1;
  float threshold_[257];
  std::uint8_t bucket_[kBuckets];
};

const SrgbEncoder& srgbEncoder() {
  static const SrgbEncoder encoder;
  return encoder;
}

std::uint32_t toneMap(const float rgba[4], const ToneMapSettings& settings,
                      const SrgbEncoder& encoder) {
  std::uint32_t packed = 0;
  for (int c = 0; c < 3; ++c) {
    float v = rgba[c] * settings.exposure;
    if (settings.filmic) v = filmicCurve(v);
    packed |= encoder.encode(v) << (8 * c);
  }
  const float alpha = std::clamp(rgba[3], 0.0f, 1.0f);
  return packed | static_cast<std::uint32_t>(alpha * 255.0f + 0.5f) << 24;
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

void ToneMapOp::process(FinishedTile& tile) {
  const size_t n = static_cast<size_t>(tile.region.pixelCount());
  tile.rgba8->resize(n);
  const float* color = tile.linear->color.data();
  std::uint32_t* out = tile.rgba8->data();
  const SrgbEncoder& encoder = srgbEncoder();
  for (size_t p = 0; p < n; ++p) out[p] = toneMap(color + 4 * p, settings_, encoder);
}

}  // namespace dfb
