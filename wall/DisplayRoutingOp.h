#pragma once
// The display-routing pixel op (paper 4.4): on the tile owner, right after tone mapping, cut the
// finished tile at display borders and send each piece, RGBA8, to the wall rank that drives its
// display. Pixels no display shows (behind bezels) are dropped. With the DFB's display format
// NONE, no pixel passes through rank 0.
//
// Thread-safe: the DFB runs it for different tiles concurrently.
#include <atomic>
#include <vector>

#include "dfb/Messenger.h"
#include "dfb/PixelOp.h"
#include "wall/Layout.h"
#include "wall/Ranks.h"
#include "wall/Routing.h"

namespace wall {

class DisplayRoutingOp : public dfb::PixelOp {
 public:
  // `tileSize` must be the DFB's; the cut of every tile is computed once, here.
  DisplayRoutingOp(dfb::Messenger& messenger, const Layout& layout, const RankRoles& roles,
                   int tileSize);
  void process(dfb::FinishedTile& tile) override;

  // Pieces handed to the messenger since the last call: their bytes (piece headers included,
  // before Snappy; the messenger's traffic() has them on the wire), how many, and how many went
  // to a wall rank on another host (the ones the messenger compresses).
  struct Sent {
    std::uint64_t bytes = 0, pieces = 0, piecesToOtherHosts = 0;
  };
  Sent takeSent() {
    return {bytesSent_.exchange(0), piecesSent_.exchange(0), piecesToOtherHosts_.exchange(0)};
  }
  // CPU nanoseconds of the calling threads, summed over tiles, since the last call: cutting and
  // packing pieces, and handing them to the messenger (which compresses them there when they
  // leave the host; MPI's copies happen later, on the messenger's thread).
  struct StageNs {
    std::int64_t cut = 0, send = 0;
  };
  StageNs takeStageNs() { return {cutNs_.exchange(0), sendNs_.exchange(0)}; }

 private:
  dfb::Messenger& messenger_;
  std::vector<std::vector<Piece>> piecesOfTile_;
  std::vector<int> rankOfDisplay_;
  std::vector<bool> planeDelta_;  // per display: pre-filter pieces for Snappy
  std::vector<bool> otherHost_;   // per display: its wall rank is on another host
  std::atomic<std::uint64_t> bytesSent_{0}, piecesSent_{0}, piecesToOtherHosts_{0};
  std::atomic<std::int64_t> cutNs_{0}, sendNs_{0};
};

}  // namespace wall
