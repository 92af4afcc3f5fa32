#pragma once
// What the owner of a tile does with the inputs it receives (paper 3.1, listing 1). The DFB
// makes one operation per owned tile through a factory and calls it, for one tile, from one
// thread at a time; different tiles' operations run concurrently.
#include <cstdint>
#include <functional>
#include <memory>

#include "dfb/Tile.h"

namespace dfb {

struct FrameInfo {
  std::uint32_t frameId = 0;
  // Accumulation restarts whenever the epoch changes (e.g. the camera moved).
  std::uint32_t epoch = 0;
};

// What an operation needs of every input; the DFB's door (dfb/TileDoor.h) refuses an input that
// does not provide it, so an operation never checks its inputs itself. Every input has its
// tile's region and color (4 floats a pixel); depth (1), normal and albedo (3) and display
// pixels (1) are either absent or sized for the region. Only a tree's inputs may carry several
// samples apart (Tile::samples, at most kMaxTileSamples): color and depth then hold that many
// blocks, and no normal, albedo or display pixels.
struct InputNeeds {
  // Display pixels (Tile::rgba8) may stand in for color: color may then be empty.
  bool displayPixelsForColor = false;
  // Inputs form a dependency tree: generation in [0, kMaxGeneration], children in
  // [0, kMaxChildren]. Without it both must be 0.
  bool tree = false;
  // Inputs belong to the frame's accumulation pass (Tile::accumulationId) and weigh something
  // (Tile::weight > 0).
  bool accumulation = false;
};
// A tile's tree is at most this deep and a tile announces at most this many children: far more
// than bricks a tile can meet, few enough that no count overflows.
constexpr int kMaxGeneration = 64;
constexpr int kMaxChildren = 1 << 16;

class TileOperation {
 public:
  virtual ~TileOperation() = default;
  // A new frame begins; `accumulationId` is the sample pass within the epoch (0 after a reset),
  // `expectedInputs` how many inputs the renderer will send this tile (operations whose inputs
  // announce themselves, like the alpha-blend tree, ignore it).
  virtual void newFrame(const FrameInfo& frame, std::uint32_t accumulationId,
                        int expectedInputs) = 0;
  // What every input must provide; the DFB checks it before process().
  virtual InputNeeds needs() const = 0;
  // Takes one input (moved in: an operation keeps it without a copy when it needs to) that
  // passed the door (dfb/TileDoor.h) with needs(). Returns true exactly once per frame: when the
  // tile is complete, after which finished() holds the result. Throws base::Error on an input
  // that does not fit what came before it this frame (one too many, a repeated sequence, a
  // generation the tree did not announce).
  virtual bool process(Tile&& input) = 0;
  // RGBA linear color (and depth) of the completed tile, valid until the next newFrame.
  virtual const Tile& finished() const = 0;
  // An estimate of the remaining error in the tile (0 when the operation keeps none).
  virtual float error() const { return 0.0f; }
  // Exchanges the completed tile with `other` (one the caller no longer needs, e.g. last frame's
  // result handed back), so an operation that consumes the result moves it on without copying
  // it; finished() is unspecified afterwards until the next completion. Operations that do not
  // give their result away copy it.
  virtual void exchangeFinished(Tile& other) { other = finished(); }
  // Moves the completed tile's display pixels (Tile::rgba8) out, so the owner keeps them without
  // a copy; finished().rgba8 is empty afterwards. Operations that never take them return none.
  virtual std::vector<std::uint32_t> takeDisplayPixels() { return {}; }
};

using TileOperationFactory = std::function<std::unique_ptr<TileOperation>(const Region& region)>;

// Image-parallel: exactly one input per tile and frame, written as it is.
TileOperationFactory writeOperation();
// Progressive refinement: averages every frame of the epoch, and in one frame any number of
// redundant inputs (`expectedInputs` of them), combined in
// `sequence` order weighted by `weight`. Keeps a per-tile error estimate.
TileOperationFactory accumulateOperation();
// Sort-last compositing: collects the whole dependency tree (any order, children before
// parents), then per pixel sorts fragments by depth and blends front to back. Colors are
// premultiplied by alpha. Inputs that carry S samples apart are blended sample by sample and
// the S composites averaged (meanOfComposites); every input then carries S or 1 (a fragment
// that stands for every sample, such as a constant background), and the result's depth is
// sample 0's.
TileOperationFactory alphaBlendOperation();
// One pixel of two fragments as alphaBlendOperation() blends them, bit for bit: `a` (depth
// `da`) comes first in the tree's order, so it goes in front on a tie. Writes the blended RGBA
// to `out` and returns the blended depth (the front one's). Also for a renderer that blends a
// tile's two fragments itself and hands the DFB the result as a lone root.
inline float blendPixelPair(const float a[4], float da, const float b[4], float db, float out[4]) {
  const bool bFirst = db < da;
  const float* front = bFirst ? b : a;
  const float* back = bFirst ? a : b;
  float sum[4] = {0, 0, 0, 0};  // the blend adds to nothing: a -0 becomes +0, as there
  for (int k = 0; k < 4; ++k) sum[k] += 1.0f * front[k];
  const float transmitted = 1.0f - sum[3];
  for (int k = 0; k < 4; ++k) out[k] = sum[k] + transmitted * back[k];
  return bFirst ? db : da;
}
// The pixel of a tile whose samples were composited apart (Tile::samples): the mean of the
// `samples` composites (4 floats each, in sample order), summed in that order.
// alphaBlendOperation() and a renderer that blends a lone root itself both average with it, so they
// agree bit for bit.
inline void meanOfComposites(const float* composites, std::uint32_t samples, float out[4]) {
  float sum[4] = {0, 0, 0, 0};
  for (std::uint32_t s = 0; s < samples; ++s)
    for (int k = 0; k < 4; ++k) sum[k] += composites[4 * s + static_cast<std::uint32_t>(k)];
  const float inv = 1.0f / static_cast<float>(samples);
  for (int k = 0; k < 4; ++k) out[k] = sum[k] * inv;
}
// Sort-last compositing with progressive refinement: each frame's tree is alpha-blended, then the
// composited tiles of the epoch are averaged (weighted by the root tile's `weight`).
TileOperationFactory compositeAccumulateOperation();

}  // namespace dfb
