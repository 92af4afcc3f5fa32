#pragma once
// The DFB's side of the tiled case: a display rank's receiving end of dfbwall's route mode
// without the window. Tile owners cut their finished tiles at display borders and send the
// pieces (wall::DisplayRoutingOp); this handler, on the messenger's inbox thread, copies them
// into the display's image and counts them until the display's frame is complete, exactly as a
// wall rank counts pieces (wall::tilesOfDisplay), then stamps the time.
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>

#include "messaging/Messenger.h"
#include "wall/image/Image.h"
#include "wall/layout/Layout.h"

namespace icetbench {

// A canvas of `width` x `height` cut into tilesX x tilesY displays without bezels, display
// ty * tilesX + tx driven by wall process (and, in the bench, rank) of the same number; the last
// column and row take what the division leaves (as IcetCompositor cuts IceT's tiles).
wall::Layout tiledLayout(int width, int height, int tilesX, int tilesY);

class PieceReceiver final : public messaging::MessageHandler {
 public:
  PieceReceiver(const wall::Layout& layout, int display, int tileSize);

  // Called between frames: pieces of `frameId` are expected next.
  void expect(std::uint32_t frameId);
  // Blocks until every piece of the expected frame arrived (or a bad piece came: throws); returns
  // the steady_clock time in ns the last one was copied in.
  std::int64_t wait();
  const wall::Image& image() const { return image_; }

  void incoming(int fromRank, messaging::Bytes&& payload) override;

 private:
  int display_;
  int expectedPieces_;
  wall::Image image_;
  std::mutex mutex_;
  std::condition_variable done_;
  std::uint32_t frameId_ = 0;
  int received_ = 0;
  std::int64_t completeNs_ = 0;
  std::string error_;
};

}  // namespace icetbench
