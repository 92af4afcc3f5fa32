#include "renderers/TransferFunction.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include "base/Error.h"

namespace renderers {
namespace {

template <class T>
T lerp(const T& a, const T& b, float t) {
  return a * (1.0f - t) + b * t;
}

// Piecewise linear through ascending points, constant before the first and after the last. Equal
// values make a step (the later point wins at the step). NaN gives the first point's value.
template <class T>
T evaluate(const std::vector<std::pair<float, T>>& points, float value, T none) {
  if (points.empty()) return none;
  if (!(value > points.front().first)) return points.front().second;
  if (value >= points.back().first) return points.back().second;
  const auto b =
      std::upper_bound(points.begin(), points.end(), value,
                       [](float v, const std::pair<float, T>& p) { return v < p.first; });
  const auto a = b - 1;
  return lerp(a->second, b->second, (value - a->first) / (b->first - a->first));
}

}  // namespace

Vec3 TransferFunction::color(float value) const { return evaluate(colors, value, Vec3{1.0f}); }

float TransferFunction::opacity(float value) const { return evaluate(opacities, value, 1.0f); }

TransferTable::TransferTable(const TransferFunction& tf, int size)
    : valueMin_(tf.valueMin), valueMax_(tf.valueMax), size_(std::max(size, 2)) {
  if (!(tf.valueMax > tf.valueMin))
    throw base::Error("transfer function range [" + std::to_string(tf.valueMin) + ", " +
                      std::to_string(tf.valueMax) + "] is empty");
  const float width = valueMax_ - valueMin_;
  scale_ = static_cast<float>(size_ - 1) / width;
  auto valueOf = [&](int e) {
    return e == size_ - 1
               ? valueMax_
               : valueMin_ + width * static_cast<float>(e) / static_cast<float>(size_ - 1);
  };
  rgba_.resize(static_cast<std::size_t>(size_) * 4);
  for (int e = 0; e < size_; ++e) {
    const float v = valueOf(e);
    const Vec3 c = tf.color(v);
    float* out = &rgba_[static_cast<std::size_t>(e) * 4];
    out[0] = c.x;
    out[1] = c.y;
    out[2] = c.z;
    out[3] = tf.opacity(v);
  }
  // The exact maximum of the (piecewise linear) opacity over each segment between two entries:
  // at its ends or at a control point inside. It bounds both the function and the interpolated
  // table from above.
  const int segments = size_ - 1;
  std::vector<float> level(static_cast<std::size_t>(segments));
  for (int e = 0; e < segments; ++e) {
    const float lo = valueOf(e), hi = valueOf(e + 1);
    float m = std::max(tf.opacity(lo), tf.opacity(hi));
    for (const auto& [value, opacity] : tf.opacities)
      if (value >= lo && value <= hi) m = std::max(m, opacity);
    level[static_cast<std::size_t>(e)] = m;
  }
  // A sparse table: level l holds the maximum over 2^l consecutive segments from each one.
  segmentMax_.push_back(std::move(level));
  for (std::size_t span = 2; span <= static_cast<std::size_t>(segments); span *= 2) {
    const std::vector<float>& prev = segmentMax_.back();
    std::vector<float> next(static_cast<std::size_t>(segments) - span + 1);
    for (std::size_t e = 0; e < next.size(); ++e) next[e] = std::max(prev[e], prev[e + span / 2]);
    segmentMax_.push_back(std::move(next));
  }
}

void TransferTable::lookup(float value, float rgba[4]) const {
  if (size_ == 0) {  // a default-constructed table: nothing to see
    std::fill_n(rgba, 4, 0.0f);
    return;
  }
  float t = (value - valueMin_) * scale_;
  if (!(t > 0)) t = 0;  // below the range, or NaN
  const float last = static_cast<float>(size_ - 1);
  if (t >= last) {
    std::copy_n(&rgba_[static_cast<std::size_t>(size_ - 1) * 4], 4, rgba);
    return;
  }
  const std::size_t i = static_cast<std::size_t>(t);
  const float f = t - static_cast<float>(i);
  const float* a = &rgba_[i * 4];
  for (int c = 0; c < 4; ++c) rgba[c] = a[c] + (a[c + 4] - a[c]) * f;
}

float TransferTable::maxOpacity(float lo, float hi) const {
  if (size_ < 2) return 0;
  const int segments = size_ - 1;
  auto segmentOf = [&](float value) {
    const float t = (value - valueMin_) * scale_;
    if (!(t > 0)) return 0;
    return t >= static_cast<float>(segments) ? segments - 1 : static_cast<int>(t);
  };
  if (std::isnan(lo) || std::isnan(hi)) {
    lo = valueMin_;  // unknown values: the whole range
    hi = valueMax_;
  }
  if (lo > hi) std::swap(lo, hi);
  // One segment more on each side: the rounding of t must never drop the segment holding lo or
  // hi, whatever the order of operations a caller used to get them.
  const int a = std::max(segmentOf(lo) - 1, 0), b = std::min(segmentOf(hi) + 1, segments - 1);
  const auto count = static_cast<unsigned>(b - a + 1);
  const int l = std::bit_width(count) - 1;  // the largest 2^l <= count
  const std::vector<float>& level = segmentMax_[static_cast<std::size_t>(l)];
  return std::max(level[static_cast<std::size_t>(a)],
                  level[static_cast<std::size_t>(b - (1 << l) + 1)]);
}

}  // namespace renderers
