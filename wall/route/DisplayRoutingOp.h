#pragma once
// The display-routing pixel op (paper 4.4): on the tile owner, right after tone mapping, cut the
// finished tile at display borders and send each piece, RGBA8, to the wall rank that drives its
// display. Pixels no display shows (behind bezels) are dropped. With the DFB's display format
// NONE, no pixel passes through rank 0.
//
// Thread-safe: the DFB runs it for different tiles concurrently.
#include <atomic>
#include <memory>
#include <vector>

#include "dfb/PixelOp.h"
#include "messaging/Messenger.h"
#include "wall/layout/Layout.h"
#include "wall/layout/Ranks.h"
#include "wall/route/PieceSink.h"
#include "wall/route/Routing.h"

namespace wall {

class DisplayRoutingOp : public dfb::PixelOp {
 public:
  // `tileSize` must be the DFB's; the cut of every tile is computed once, here. `sink` carries
  // the pieces (the job's messenger or a service link). A finished tile that is not one of the
  // canvas's tiles at that size (another size, another canvas) throws base::Error saying so.
  DisplayRoutingOp(std::shared_ptr<PieceSink> sink, const Layout& layout, int tileSize);
  // The single-job wall: pieces to the wall ranks of `roles` through `messenger`.
  DisplayRoutingOp(messaging::Messenger& messenger, const Layout& layout, const RankRoles& roles,
                   int tileSize);
  void process(dfb::FinishedTile& tile) override;
  // This rank finished frame `frameId`: the sink sends what it held back.
  void endFrame(std::uint32_t frameId) { sink_->endFrame(frameId); }

  // Pieces handed to the sink since the last call: their bytes (piece headers included,
  // before compression; the transport counts them on the wire), how many, and how many went to
  // a wall process on another host.
  struct Sent {
    std::uint64_t bytes = 0, pieces = 0, piecesToOtherHosts = 0;
  };
  Sent takeSent() {
    return {bytesSent_.exchange(0), piecesSent_.exchange(0), piecesToOtherHosts_.exchange(0)};
  }
  // CPU nanoseconds of the calling threads, summed over tiles, since the last call: cutting and
  // packing pieces, and handing them to the transport (see PieceSink::takeStageNs).
  using StageNs = PieceSink::StageNs;
  StageNs takeStageNs() { return sink_->takeStageNs(); }

 private:
  std::shared_ptr<PieceSink> sink_;
  dfb::TileGrid tiles_;
  std::vector<std::vector<Piece>> piecesOfTile_;
  std::atomic<std::uint64_t> bytesSent_{0}, piecesSent_{0}, piecesToOtherHosts_{0};
};

}  // namespace wall
