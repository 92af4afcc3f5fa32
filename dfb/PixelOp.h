#pragma once
// Post-processing run on the tile owner after a tile completes (paper 3.1.2): tone mapping,
// and the hook a display wall uses to send finished tiles to its displays. Operations of a
// chain run in order; the DFB may run the chain for different tiles concurrently.
#include <cstdint>
#include <vector>

#include "dfb/Tile.h"

namespace dfb {

struct FinishedTile {
  int tileIndex = 0;
  Region region;
  std::uint32_t frameId = 0;
  std::uint32_t accumulationId = 0;
  const Tile* linear = nullptr;  // RGBA linear color (+ depth) from the tile operation
  std::vector<std::uint32_t>* rgba8 = nullptr;  // display pixels, R in the low byte
  float error = 0.0f;
};

class PixelOp {
 public:
  virtual ~PixelOp() = default;
  virtual void process(FinishedTile& tile) = 0;
};

struct ToneMapSettings {
  float exposure = 1.0f;
  bool filmic = false;  // ACES-style filmic curve before sRGB encoding; otherwise clamp
};

// Linear RGBA → exposure → optional filmic curve → sRGB-encoded RGBA8 into `tile.rgba8`.
class ToneMapOp : public PixelOp {
 public:
  explicit ToneMapOp(ToneMapSettings settings = {}) : settings_(settings) {}
  void process(FinishedTile& tile) override;

 private:
  ToneMapSettings settings_;
};

// The tone mapping of one pixel, shared with anything that must match the DFB bit for bit.
std::uint32_t toneMapPixel(const float rgba[4], const ToneMapSettings& settings);

// Linear [0, 1] (clamped) to an sRGB-encoded byte: the definition, with std::pow ...
std::uint32_t encodeSrgb8Reference(float linear);
// ... and what toneMapPixel uses: the same value for every float, through a table.
std::uint32_t encodeSrgb8(float linear);

}  // namespace dfb
