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
  using dfb::Clock;
  const auto& pieces = piecesOfTile_.at(static_cast<size_t>(tile.tileIndex));
  for (const Piece& piece : pieces) {
    const auto t0 = Clock::now();
    dfb::Bytes bytes =
        packPiece(tile.frameId, piece.display, piece.local, tile.rgba8->data(), tile.region.width(),
                  piece.canvas.x0 - tile.region.x0, piece.canvas.y0 - tile.region.y0,
                  planeDelta_[static_cast<size_t>(piece.display)]);
    bytesSent_ += bytes.size();
    piecesSent_++;
    if (otherHost_[static_cast<size_t>(piece.display)]) piecesToOtherHosts_++;
    const auto t1 = Clock::now();
    messenger_.send(rankOfDisplay_[static_cast<size_t>(piece.display)], kWallNodeObject,
                    std::move(bytes));
    cutNs_ += dfb::nsBetween(t0, t1);
    sendNs_ += dfb::nsBetween(t1, Clock::now());
  }
}

}  // namespace wall
