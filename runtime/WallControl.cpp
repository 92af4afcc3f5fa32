#include "runtime/WallControl.h"

#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>

#include "wall/service/client/ServiceClient.h"

namespace runtime {
namespace {

struct WallMessage {
  std::uint32_t kind;
  std::uint32_t frameId;
  std::int32_t exitCode;
  std::uint32_t unused;
  std::uint64_t sequence;
};
constexpr std::uint32_t kLastFrame = 1, kKeepWaiting = 2, kCapture = 3;

}  // namespace

MpiWallControl::MpiWallControl(messaging::Messenger& messenger, int firstWallRank, int worldSize)
    : messenger_(messenger), firstWallRank_(firstWallRank), worldSize_(worldSize) {
  messenger_.registerObject(kWallControlObject, this);
}

MpiWallControl::~MpiWallControl() { messenger_.unregisterObject(kWallControlObject); }

void MpiWallControl::tellWalls(std::uint32_t kind, std::uint32_t frameId, std::int32_t exitCode,
                               std::uint64_t sequence) {
  const WallMessage m{kind, frameId, exitCode, 0, sequence};
  for (int rank = firstWallRank_; rank < worldSize_; ++rank) {
    messaging::Bytes bytes(sizeof m);
    std::memcpy(bytes.data(), &m, sizeof m);
    messenger_.send(rank, kWallControlObject, std::move(bytes));
  }
}

void MpiWallControl::lastFrame(std::uint32_t frameId, int exitCode) {
  tellWalls(kLastFrame, frameId, exitCode, 0);
}

void MpiWallControl::keepWaiting() { tellWalls(kKeepWaiting, 0, 0, 0); }

void MpiWallControl::capture(std::uint32_t frameId, std::uint64_t sequence) {
  tellWalls(kCapture, frameId, 0, sequence);
}

void MpiWallControl::listen(Listener listener) {
  std::optional<std::uint32_t> known;
  std::function<void(std::uint32_t)> stop;
  {
    std::lock_guard lock(mutex_);
    listener_ = std::move(listener);
    known = lastFrame_;
    stop = listener_.lastFrame;
  }
  if (known && stop) stop(*known);
}

int MpiWallControl::exitCode() const {
  std::lock_guard lock(mutex_);
  return exitCode_;
}

void MpiWallControl::incoming(int fromRank, messaging::Bytes&& payload) {
  WallMessage m;
  if (payload.size() != sizeof m)
    throw std::runtime_error("malformed wall-control message of " + std::to_string(payload.size()) +
                             " bytes from rank " + std::to_string(fromRank));
  std::memcpy(&m, payload.data(), sizeof m);
  Listener listener;
  {
    std::lock_guard lock(mutex_);
    if (m.kind == kLastFrame) {
      lastFrame_ = m.frameId;
      exitCode_ = m.exitCode;
    } else if (m.kind != kKeepWaiting && m.kind != kCapture) {
      throw std::runtime_error("wall-control message of unknown kind " + std::to_string(m.kind) +
                               " from rank " + std::to_string(fromRank));
    }
    listener = listener_;
  }
  if (m.kind == kLastFrame && listener.lastFrame) listener.lastFrame(m.frameId);
  if (m.kind == kKeepWaiting && listener.keepWaiting) listener.keepWaiting();
  if (m.kind == kCapture && listener.capture) listener.capture(m.frameId, m.sequence);
}

void ServiceWallControl::lastFrame(std::uint32_t frameId, int /*exitCode*/) {
  client_.bye(frameId);
}

void ServiceWallControl::capture(std::uint32_t frameId, std::uint64_t sequence) {
  client_.capture(frameId, sequence);
}

}  // namespace runtime
