#pragma once
// Transfer functions: value -> colour and opacity, from colour points and opacity points over a
// value range, or from a named preset. Opacity is per `unitDistance` of world space (VTK's scalar
// opacity unit distance); a renderer stepping dt uses 1 - (1 - opacity)^(dt / unitDistance).
#include <string>
#include <utility>
#include <vector>

#include "renderers/Math.h"

namespace renderers {

struct TransferFunction {
  float valueMin = 0, valueMax = 1;
  // Control points as (value, colour) and (value, opacity in [0, 1]), ascending values; between
  // points linear, outside the first/last point constant; two points with the same value make a
  // step. No colour points: white; no opacity points: opaque.
  std::vector<std::pair<float, Vec3>> colors;
  std::vector<std::pair<float, float>> opacities;
  float unitDistance = 0;  // world distance the opacities are for; 0: the volume's smallest spacing

  Vec3 color(float value) const;
  float opacity(float value) const;
};

// "cool-warm" (Moreland's diverging map), "viridis", "grayscale", "inferno", "rainbow" (see
// transferFunctionPresetNames()) over [valueMin, valueMax] with a linear opacity ramp from 0 to
// `maxOpacity`. Throws base::Error listing the names for an unknown one.
TransferFunction transferFunctionPreset(const std::string& name, float valueMin, float valueMax,
                                        float maxOpacity = 1.0f);
std::vector<std::string> transferFunctionPresetNames();

// A transfer function baked into `size` evenly spaced entries over [valueMin, valueMax], for the
// renderer's inner loop: colour and opacity with linear interpolation between entries.
class TransferTable {
 public:
  TransferTable() = default;  // empty: lookup gives 0, maxOpacity 0
  // Throws base::Error when tf's range is empty (valueMax <= valueMin). size >= 2.
  TransferTable(const TransferFunction& tf, int size = 1024);
  // RGB and opacity at `value` (clamped to the range).
  void lookup(float value, float rgba[4]) const;
  // The largest opacity over [lo, hi] (for empty-space skipping: 0 means nothing to see there).
  // Conservative: never below the transfer function's opacity nor lookup()'s anywhere in [lo, hi]
  // (clamped to the range), at most one entry's width wider. O(1). NaN bounds: the whole range.
  float maxOpacity(float lo, float hi) const;
  float valueMin() const { return valueMin_; }
  float valueMax() const { return valueMax_; }

 private:
  std::vector<float> rgba_;  // 4 per entry
  // segmentMax_[l][e]: the largest opacity between entries e and e + 2^l (a sparse table).
  std::vector<std::vector<float>> segmentMax_;
  float valueMin_ = 0, valueMax_ = 1, scale_ = 0;
  int size_ = 0;
};

}  // namespace renderers
