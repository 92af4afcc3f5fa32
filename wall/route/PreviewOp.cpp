#include "wall/route/PreviewOp.h"

#include <cstring>

namespace wall {

void PreviewOp::process(dfb::FinishedTile& tile) {
  const std::vector<std::uint32_t> cells =
      downsample(grid_, tile.region, tile.rgba8->data(), tile.region.width());
  const PreviewHeader header{kPreviewMagic,  tile.frameId,   tile.region.x0,
                             tile.region.y0, tile.region.x1, tile.region.y1};
  const size_t body = cells.size() * sizeof(std::uint32_t);
  messaging::Bytes bytes;
  bytes.reserve(sizeof header + body + messaging::Messenger::kSpareCapacity);
  bytes.resize(sizeof header + body);
  std::memcpy(bytes.data(), &header, sizeof header);
  std::memcpy(bytes.data() + sizeof header, cells.data(), body);
  bytesSent_ += bytes.size();
  messenger_.send(toRank_, kPreviewObject, std::move(bytes));
}

}  // namespace wall
