#include "api/WallStop.h"

#include <cstring>
#include <stdexcept>
#include <string>

namespace dfbwall {

WallStop::WallStop(messaging::Messenger& messenger) : messenger_(messenger) {
  messenger_.registerObject(kWallStopObject, this);
}

WallStop::~WallStop() { messenger_.unregisterObject(kWallStopObject); }

void WallStop::announceLastFrame(std::uint32_t lastFrame, int firstWallRank, int worldSize) {
  for (int rank = firstWallRank; rank < worldSize; ++rank) {
    messaging::Bytes bytes(sizeof lastFrame);
    std::memcpy(bytes.data(), &lastFrame, sizeof lastFrame);
    messenger_.send(rank, kWallStopObject, std::move(bytes));
  }
}

void WallStop::onLastFrame(std::function<void(std::uint32_t)> stop) {
  std::optional<std::uint32_t> known;
  {
    std::lock_guard lock(mutex_);
    stop_ = stop;
    known = lastFrame_;
  }
  if (known && stop) stop(*known);
}

void WallStop::incoming(int fromRank, messaging::Bytes&& payload) {
  std::uint32_t lastFrame = 0;
  if (payload.size() != sizeof lastFrame)
    throw std::runtime_error("malformed wall-stop message of " + std::to_string(payload.size()) +
                             " bytes from rank " + std::to_string(fromRank));
  std::memcpy(&lastFrame, payload.data(), sizeof lastFrame);
  std::function<void(std::uint32_t)> stop;
  {
    std::lock_guard lock(mutex_);
    lastFrame_ = lastFrame;
    stop = stop_;
  }
  if (stop) stop(lastFrame);
}

}  // namespace dfbwall
