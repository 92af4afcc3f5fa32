#include "wall/route/DisplayRoutingOp.h"

#include <string>

#include "base/Error.h"

namespace wall {

DisplayRoutingOp::DisplayRoutingOp(std::shared_ptr<PieceSink> sink, const Layout& layout,
                                   int tileSize)
    : sink_(std::move(sink)), tiles_(canvasTiles(layout, tileSize)) {
  piecesOfTile_.resize(static_cast<size_t>(tiles_.tileCount()));
  for (int t = 0; t < tiles_.tileCount(); ++t)
    piecesOfTile_[static_cast<size_t>(t)] = piecesOf(layout, tiles_.region(t));
}

DisplayRoutingOp::DisplayRoutingOp(messaging::Messenger& messenger, const Layout& layout,
                                   const RankRoles& roles, int tileSize)
    : DisplayRoutingOp(std::make_shared<MessengerPieceSink>(messenger, layout, roles), layout,
                       tileSize) {}

void DisplayRoutingOp::process(dfb::FinishedTile& tile) {
  // The cuts are the canvas's tiles at the op's tile size: a DFB of another size or canvas would
  // send pieces of the wrong pixels, or none.
  if (tile.tileIndex < 0 || tile.tileIndex >= tiles_.tileCount() ||
      tiles_.region(tile.tileIndex) != tile.region) {
    const dfb::Region& r = tile.region;
    throw base::Error(
        "display routing: finished tile " + std::to_string(tile.tileIndex) + " [" +
        std::to_string(r.x0) + ", " + std::to_string(r.x1) + ") x [" + std::to_string(r.y0) + ", " +
        std::to_string(r.y1) + ") is not a tile of the wall's " + std::to_string(tiles_.width()) +
        "x" + std::to_string(tiles_.height()) + " canvas in tiles of " +
        std::to_string(tiles_.tileSize()) + " (the DFB's tile size must be the op's)");
  }
  const auto& pieces = piecesOfTile_[static_cast<size_t>(tile.tileIndex)];
  for (const Piece& piece : pieces) {
    const int width = tile.region.width();
    const std::uint32_t* at = tile.rgba8->data() +
                              static_cast<size_t>(piece.canvas.y0 - tile.region.y0) * width +
                              (piece.canvas.x0 - tile.region.x0);
    bytesSent_ += sink_->send(tile.frameId, piece.display, piece.local, at, width);
    piecesSent_++;
    if (sink_->otherHost(piece.display)) piecesToOtherHosts_++;
  }
}

}  // namespace wall
