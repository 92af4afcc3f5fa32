#include "bench/icet/PieceReceiver.h"

#include <stdexcept>

#include "base/Timing.h"
#include "wall/route/PieceMessage.h"
#include "wall/route/Routing.h"

namespace icetbench {

wall::Layout tiledLayout(int width, int height, int tilesX, int tilesY) {
  wall::Layout layout;
  layout.file = "(icet_bench tiles)";
  layout.canvasWidth = width, layout.canvasHeight = height;
  layout.processCount = tilesX * tilesY;
  const int w = width / tilesX, h = height / tilesY;
  for (int ty = 0; ty < tilesY; ++ty)
    for (int tx = 0; tx < tilesX; ++tx) {
      wall::Display d;
      d.name = "r" + std::to_string(ty) + "c" + std::to_string(tx);
      d.rect = {tx * w, ty * h, tx + 1 == tilesX ? width : (tx + 1) * w,
                ty + 1 == tilesY ? height : (ty + 1) * h};
      d.process = ty * tilesX + tx;
      layout.displays.push_back(d);
    }
  return layout;
}

PieceReceiver::PieceReceiver(const wall::Layout& layout, int display, int tileSize)
    : display_(display),
      expectedPieces_(static_cast<int>(wall::tilesOfDisplay(layout, display, tileSize).size())),
      image_(layout.displays.at(static_cast<std::size_t>(display)).rect.width(),
             layout.displays.at(static_cast<std::size_t>(display)).rect.height()) {}

void PieceReceiver::expect(std::uint32_t frameId) {
  std::lock_guard lock(mutex_);
  frameId_ = frameId;
  received_ = 0;
  completeNs_ = 0;
}

std::int64_t PieceReceiver::wait() {
  std::unique_lock lock(mutex_);
  done_.wait(lock, [&] { return received_ == expectedPieces_ || !error_.empty(); });
  if (!error_.empty()) throw std::runtime_error(error_);
  return completeNs_;
}

void PieceReceiver::incoming(int fromRank, messaging::Bytes&& payload) {
  std::lock_guard lock(mutex_);
  try {
    const wall::PieceHeader header = wall::readPieceHeader(payload);
    if (header.display != display_ || header.frameId != frameId_ || received_ >= expectedPieces_)
      throw std::runtime_error("unexpected piece (display " + std::to_string(header.display) +
                               ", frame " + std::to_string(header.frameId) + ") from rank " +
                               std::to_string(fromRank));
    wall::copyPiece(payload, header, image_);
    if (++received_ == expectedPieces_) {
      completeNs_ = base::Clock::now().time_since_epoch().count();
      done_.notify_all();
    }
  } catch (const std::exception& e) {
    error_ = e.what();
    done_.notify_all();
  }
}

}  // namespace icetbench
