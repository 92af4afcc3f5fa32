// Progressive refinement (paper 4.1) with redundant inputs per frame (paper 4.1.1).
//
// The running sum of weighted color over every input of the epoch is kept per pixel, in double:
// a float sum stops growing once it is 2^24 times the increment (a still view accumulated for
// 10^7 frames drifted by percents); a double stays exact to 1e-9 for 10^8 frames. The finished
// tile is sum / total weight. Inputs of one frame are combined in `sequence` order once
// all have arrived, so any arrival order gives the same bits. The error estimate is the standard
// error of the per-frame luminance means, relative to the luminance, averaged over the tile.
//
// The first frame of an epoch with one input of weight 1 (every frame of a moving camera at
// 1 spp) writes no sums: the finished tile is the input itself (-0 made +0, as adding it to a
// cleared double sum does), and the sums it would have written are exactly derivable from it,
// so they are materialized only if a second frame of the epoch comes. Writing 48 bytes of sums
// per pixel that the next frame's new epoch overwrites unread was most of a float tile's cost
// on its owner (memory-bound).
#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#include <string>

#include "base/Error.h"
#include "dfb/TileOperation.h"

namespace dfb {
namespace {

float luminance(const float* rgba) {
  return 0.2126f * rgba[0] + 0.7152f * rgba[1] + 0.0722f * rgba[2];
}

class AccumulateOperation final : public TileOperation {
 public:
  // The sums are allocated when first written (holdSums): a moving camera at 1 spp never writes
  // them, and allocating them for every owned tile (192 KB a 64² tile, page-faulted and zeroed)
  // was most of a first frame's set-up.
  explicit AccumulateOperation(const Region& region) : region_(region) { finished_.reset(region); }

  void newFrame(const FrameInfo&, std::uint32_t accumulationId, int expectedInputs) override {
    if (accumulationId == 0) {
      // No clearing: the first combine of an epoch overwrites the sums (a moving camera starts
      // an epoch every frame, and clearing 24 bytes a pixel cost as much as the combine).
      totalWeight_ = 0;
      frames_ = 0;
      sumsPending_ = false;
    }
    accumulationId_ = accumulationId;
    expected_ = std::max(1, expectedInputs);
    inputs_.clear();
    received_ = 0;
  }

  InputNeeds needs() const override { return {.accumulation = true}; }

  bool process(Tile&& input) override {
    if (received_ >= expected_)
      throw base::Error(where() + ": more than the " + std::to_string(expected_) +
                        " expected inputs");
    ++received_;
    if (expected_ == 1 && accumulationId_ == 0 && input.weight == 1) {
      startEpoch(std::move(input));
      return true;
    }
    if (expected_ == 1) {  // the common case: no copy of the input
      const Tile* only = &input;
      combine(std::span<const Tile* const>(&only, 1));
      return true;
    }
    inputs_.push_back(std::move(input));
    if (static_cast<int>(inputs_.size()) < expected_) return false;
    std::sort(inputs_.begin(), inputs_.end(),
              [](const Tile& a, const Tile& b) { return a.sequence < b.sequence; });
    std::vector<const Tile*> ordered;
    for (size_t i = 0; i < inputs_.size(); ++i) {
      if (i > 0 && inputs_[i].sequence == inputs_[i - 1].sequence)
        throw base::Error(
            where() + ": two inputs with sequence " + std::to_string(inputs_[i].sequence) +
            "; redundant inputs need distinct sequences to be combined deterministically");
      ordered.push_back(&inputs_[i]);
    }
    combine(ordered);
    return true;
  }

  const Tile& finished() const override { return finished_; }
  float error() const override { return error_; }

 private:
  std::string where() const {
    return "tile at (" + std::to_string(region_.x0) + ", " + std::to_string(region_.y0) + ")";
  }

  // The first frame of an epoch from one input of weight 1, without sums (see the top).
  void startEpoch(Tile&& input) {
    const size_t n = static_cast<size_t>(region_.pixelCount());
    finished_.color.swap(input.color);
    // float((0.0 + double(1 * c)) * 1.0) is c for every c but -0, which becomes +0 (with
    // denormals flushed and treated as zero, as on render threads, or neither, as elsewhere).
    for (float& v : finished_.color) v += 0.0f;
    if (input.depth.size() == n)
      finished_.depth.swap(input.depth);
    else
      finished_.depth.clear();
    totalWeight_ = 1;
    frames_ = 1;
    sumsPending_ = true;
    error_ = std::numeric_limits<float>::infinity();
    finished_.accumulationId = accumulationId_;
    finished_.weight = 1;
  }

  // The sums startEpoch() left out, from its finished tile: sum = 0.0 + double(1 * c) is
  // double(finished) exactly, and the luminance of the finished colour gives the same double
  // sums as the input's (a zero's sign changes neither a non-zero sum nor 0.0 + lum). combine()
  // allocates the sums (holdSums) before it calls this.
  void materializeSums() {
    const size_t n = static_cast<size_t>(region_.pixelCount());
    for (size_t p = 0; p < n; ++p) {
      const float* c = &finished_.color[4 * p];
      for (int k = 0; k < 4; ++k) sum_[4 * p + static_cast<size_t>(k)] = static_cast<double>(c[k]);
      const double frameLum = 0.0 + static_cast<double>(luminance(c) * 1.0f);
      lumSum_[p] = frameLum;
      lumSquareSum_[p] = 0.0 + frameLum * frameLum;
    }
    sumsPending_ = false;
  }

  void holdSums() {
    const size_t n = static_cast<size_t>(region_.pixelCount());
    if (lumSum_.size() == n) return;
    sum_.resize(4 * n);
    lumSum_.resize(n);
    lumSquareSum_.resize(n);
  }

  // `inputs` in ascending sequence order.
  void combine(std::span<const Tile* const> inputs) {
    const size_t n = static_cast<size_t>(region_.pixelCount());
    holdSums();
    if (sumsPending_) materializeSums();
    std::uint64_t frameWeight = 0;
    for (const Tile* t : inputs) frameWeight += t->weight;
    const float invFrameWeight = 1.0f / static_cast<float>(frameWeight);
    const bool first = frames_ == 0;  // the sums hold a previous epoch: overwrite them
    totalWeight_ += frameWeight;
    ++frames_;
    const double invTotal = 1.0 / static_cast<double>(totalWeight_);

    double relativeError = 0;
    for (size_t p = 0; p < n; ++p) {
      float frame[4] = {0, 0, 0, 0};
      for (const Tile* t : inputs) {
        const float w = static_cast<float>(t->weight);
        for (int c = 0; c < 4; ++c) frame[c] += w * t->color[4 * p + static_cast<size_t>(c)];
      }
      // 0.0 + x, not x: the same bits as adding to a cleared sum, -0 included.
      for (int c = 0; c < 4; ++c) {
        double& sum = sum_[4 * p + static_cast<size_t>(c)];
        sum = (first ? 0.0 : sum) + static_cast<double>(frame[c]);
        finished_.color[4 * p + static_cast<size_t>(c)] = static_cast<float>(sum * invTotal);
      }
      const double frameLum = static_cast<double>(luminance(frame) * invFrameWeight);
      lumSum_[p] = (first ? 0.0 : lumSum_[p]) + frameLum;
      lumSquareSum_[p] = (first ? 0.0 : lumSquareSum_[p]) + frameLum * frameLum;
      if (frames_ > 1) {
        const double k = static_cast<double>(frames_);
        const double mean = lumSum_[p] / k;
        const double variance = std::max(0.0, lumSquareSum_[p] / k - mean * mean);
        relativeError += std::sqrt(variance / k) / std::sqrt(std::max(mean, 1e-3));
      }
    }
    error_ = frames_ > 1 ? static_cast<float>(relativeError / static_cast<double>(n))
                         : std::numeric_limits<float>::infinity();
    if (inputs.front()->depth.size() == n)
      finished_.depth = inputs.front()->depth;
    else
      finished_.depth.clear();
    finished_.accumulationId = accumulationId_;
    finished_.weight = static_cast<std::uint32_t>(totalWeight_);
  }

  Region region_;
  std::vector<double> sum_, lumSum_, lumSquareSum_;
  std::uint64_t totalWeight_ = 0;
  std::uint32_t frames_ = 0, accumulationId_ = 0;
  bool sumsPending_ = false;  // the epoch's sums are still only implied by finished_
  int expected_ = 1, received_ = 0;
  std::vector<Tile> inputs_;
  Tile finished_;
  float error_ = std::numeric_limits<float>::infinity();
};

}  // namespace

TileOperationFactory accumulateOperation() {
  return [](const Region& region) { return std::make_unique<AccumulateOperation>(region); };
}

}  // namespace dfb
