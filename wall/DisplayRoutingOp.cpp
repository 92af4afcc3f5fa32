#include "wall/DisplayRoutingOp.h"

namespace wall {

DisplayRoutingOp::DisplayRoutingOp(std::shared_ptr<PieceSink> sink, const Layout& layout,
                                   int tileSize)
    : sink_(std::move(sink)) {
  const dfb::TileGrid tiles = canvasTiles(layout, tileSize);
  piecesOfTile_.resize(static_cast<size_t>(tiles.tileCount()));
  for (int t = 0; t < tiles.tileCount(); ++t)
    piecesOfTile_[static_cast<size_t>(t)] = piecesOf(layout, tiles.region(t));
}

DisplayRoutingOp::DisplayRoutingOp(messaging::Messenger& messenger, const Layout& layout,
                                   const RankRoles& roles, int tileSize)
    : DisplayRoutingOp(std::make_shared<MessengerPieceSink>(messenger, layout, roles), layout,
                       tileSize) {}

void DisplayRoutingOp::process(dfb::FinishedTile& tile) {
  const auto& pieces = piecesOfTile_.at(static_cast<size_t>(tile.tileIndex));
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
