#pragma once
// Where the display-routing pixel op (wall/route/DisplayRoutingOp.h) hands each piece: the job's
// messenger to a wall rank of the same MPI job (MessengerPieceSink), or a service link to a
// persistent wall (ServiceClient, wall/service/client/ServiceClient.h). One op, two transports.
#include <atomic>
#include <cstdint>
#include <vector>

#include "dfb/Tile.h"
#include "messaging/Messenger.h"
#include "wall/layout/Layout.h"
#include "wall/layout/Ranks.h"

namespace wall {

class PieceSink {
 public:
  virtual ~PieceSink() = default;
  // Thread-safe (the DFB completes tiles on several threads): piece `local` (display
  // coordinates) of display `display` in frame `frameId`, whose top-left pixel is `pixels` in an
  // image of rows `stride` pixels apart. Returns the bytes it put in messages before any
  // compression (piece headers included).
  virtual std::size_t send(std::uint32_t frameId, int display, const dfb::Region& local,
                           const std::uint32_t* pixels, int stride) = 0;
  // Every tile this rank owns in frame `frameId` is done: send whatever is still held back.
  virtual void endFrame(std::uint32_t /*frameId*/) {}
  // Whether display `display`'s pieces leave this host.
  virtual bool otherHost(int display) const = 0;
  // CPU nanoseconds of the calling threads since the last call: packing pieces (copying and
  // filtering or encoding their pixels), and handing them to the transport.
  struct StageNs {
    std::int64_t cut = 0, send = 0;
  };
  StageNs takeStageNs() { return {cutNs_.exchange(0), sendNs_.exchange(0)}; }

 protected:
  std::atomic<std::int64_t> cutNs_{0}, sendNs_{0};
};

// One message per piece (wall/route/PieceMessage.h) to the wall rank of the display, through the
// job's messenger (which Snappy-compresses what leaves the host; the plane-delta filter goes
// first there).
class MessengerPieceSink : public PieceSink {
 public:
  MessengerPieceSink(messaging::Messenger& messenger, const Layout& layout, const RankRoles& roles);
  std::size_t send(std::uint32_t frameId, int display, const dfb::Region& local,
                   const std::uint32_t* pixels, int stride) override;
  bool otherHost(int display) const override {
    return otherHost_[static_cast<std::size_t>(display)];
  }

 private:
  messaging::Messenger& messenger_;
  std::vector<int> rankOfDisplay_;
  std::vector<bool> planeDelta_;  // per display: pre-filter pieces for Snappy
  std::vector<bool> otherHost_;   // per display: its wall rank is on another host
};

}  // namespace wall
