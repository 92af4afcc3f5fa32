#include "dfb/PixelOp.h"
#include "dfb/ToneMapKernel.h"

namespace dfb {

void ToneMapOp::process(FinishedTile& tile) {
  const size_t n = static_cast<size_t>(tile.region.pixelCount());
  tile.rgba8->resize(n);
  toneMapPixels(tile.linear->color.data(), n, tile.rgba8->data(), settings_);
}

}  // namespace dfb
