#include <algorithm>
#include <cmath>

#include "dfb/PixelOp.h"

namespace dfb {
namespace {

// Narkowicz's fit of the ACES filmic curve: a soft shoulder instead of a hard clip.
float filmicCurve(float x) {
  return std::clamp((x * (2.51f * x + 0.03f)) / (x * (2.43f * x + 0.59f) + 0.14f), 0.0f, 1.0f);
}

std::uint32_t encodeSrgb(float linear) {
  const float v = std::clamp(linear, 0.0f, 1.0f);
  const float encoded = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
  return static_cast<std::uint32_t>(encoded * 255.0f + 0.5f);
}

}  // namespace

std::uint32_t toneMapPixel(const float rgba[4], const ToneMapSettings& settings) {
  std::uint32_t packed = 0;
  for (int c = 0; c < 3; ++c) {
    float v = rgba[c] * settings.exposure;
    if (settings.filmic) v = filmicCurve(v);
    packed |= encodeSrgb(v) << (8 * c);
  }
  const float alpha = std::clamp(rgba[3], 0.0f, 1.0f);
  return packed | static_cast<std::uint32_t>(alpha * 255.0f + 0.5f) << 24;
}

void ToneMapOp::process(FinishedTile& tile) {
  const size_t n = static_cast<size_t>(tile.region.pixelCount());
  tile.rgba8->resize(n);
  const float* color = tile.linear->color.data();
  for (size_t p = 0; p < n; ++p) (*tile.rgba8)[p] = toneMapPixel(color + 4 * p, settings_);
}

}  // namespace dfb
