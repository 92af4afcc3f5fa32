// Sort-last compositing with progressive refinement (paper 4.2 with 4.1): every frame the tile's
// dependency tree is alpha-blended (alphaBlendOperation), and the composited tile is one input
// of the accumulate operation, which averages the frames of the epoch. Compositing before
// averaging is what a single renderer does per sample, so a still camera converges to the image
// one process would make.
#include "dfb/TileOperation.h"

namespace dfb {
namespace {

class CompositeAccumulateOperation final : public TileOperation {
 public:
  explicit CompositeAccumulateOperation(const Region& region)
      : blend_(alphaBlendOperation()(region)), accumulate_(accumulateOperation()(region)) {
    // Sized from the start, so the blend's second frame does not allocate its output again.
    composited_.reset(region, true);
  }

  void newFrame(const FrameInfo& frame, std::uint32_t accumulationId, int expectedInputs) override {
    accumulationId_ = accumulationId;
    weight_ = 1;
    blend_->newFrame(frame, accumulationId, expectedInputs);
    accumulate_->newFrame(frame, accumulationId, 1);
  }

  // The tree's inputs, each of the frame's pass (the composited tile is one input of the
  // accumulation, made here).
  InputNeeds needs() const override { return {.tree = true, .accumulation = true}; }

  bool process(Tile&& input) override {
    // The samples behind the frame: the root tile's (every input of a tree renders alike).
    if (input.generation == 0) weight_ = input.weight;
    if (!blend_->process(std::move(input))) return false;
    // The composited tile moves on without a copy: the blend takes composited_'s buffers in
    // exchange (what the accumulation handed back last frame), so in steady state no tile
    // buffer is allocated or copied here (the copy was 80 KB a 64² tile, about 3% of a 1-brick
    // contours frame with its allocation).
    blend_->exchangeFinished(composited_);
    composited_.accumulationId = accumulationId_;
    composited_.sequence = 0;
    composited_.weight = weight_;
    composited_.generation = 0;
    composited_.children = 0;
    return accumulate_->process(std::move(composited_));
  }

  const Tile& finished() const override { return accumulate_->finished(); }
  float error() const override { return accumulate_->error(); }

 private:
  std::unique_ptr<TileOperation> blend_, accumulate_;
  // The blend's result on its way to the accumulation; after it, whatever buffers the
  // accumulation gave back (AccumulateOperation's first frame of an epoch swaps them).
  Tile composited_;
  std::uint32_t accumulationId_ = 0, weight_ = 1;
};

}  // namespace

TileOperationFactory compositeAccumulateOperation() {
  return
      [](const Region& region) { return std::make_unique<CompositeAccumulateOperation>(region); };
}

}  // namespace dfb
