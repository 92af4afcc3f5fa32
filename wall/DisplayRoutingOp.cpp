#include "wall/DisplayRoutingOp.h"

#include "dfb/Timing.h"
#include "wall/PieceMessage.h"

namespace wall {

DisplayRoutingOp::DisplayRoutingOp(dfb::Messenger& messenger, const Layout& layout,
                                   const RankRoles& roles, int tileSize)
    : messenger_(messenger) {
  const dfb::TileGrid tiles = canvasTiles(layout, tileSize);
  piecesOfTile_.resize(static_cast<size_t>(tiles.tileCount()));
  for (int t = 0; t < tiles.tileCount(); ++t)
    piecesOfTile_[static_cast<size_t>(t)] = piecesOf(layout, tiles.region(t));
  for (const Display& d : layout.displays) {
    rankOfDisplay_.push_back(roles.rankOfProcess(d.process));
    // The filter only pays when Snappy follows it.
    planeDelta_.push_back(messenger.compresses(rankOfDisplay_.back()));
    otherHost_.push_back(!messenger.sameHost(rankOfDisplay_.back()));
  }
}

void DisplayRoutingOp::process(dfb::FinishedTile& tile) {
  const auto& pieces = piecesOfTile_.at(static_cast<size_t>(tile.tileIndex));
  for (const Piece& piece : pieces) {
    const std::int64_t t0 = dfb::threadCpuNs();
    dfb::Bytes bytes =
        packPiece(tile.frameId, piece.display, piece.local, tile.rgba8->data(), tile.region.width(),
                  piece.canvas.x0 - tile.region.x0, piece.canvas.y0 - tile.region.y0,
                  planeDelta_[static_cast<size_t>(piece.display)]);
    bytesSent_ += bytes.size();
    piecesSent_++;
    if (otherHost_[static_cast<size_t>(piece.display)]) piecesToOtherHosts_++;
    const std::int64_t t1 = dfb::threadCpuNs();
    messenger_.send(rankOfDisplay_[static_cast<size_t>(piece.display)], kWallNodeObject,
                    std::move(bytes));
    cutNs_ += t1 - t0;
    sendNs_ += dfb::threadCpuNs() - t1;
  }
}

}  // namespace wall
