#include "apps/RunControl.h"

#include <cstring>
#include <stdexcept>
#include <string>

namespace app {
namespace {

struct ControlMessage {
  std::uint32_t kind;  // kAskToStop (to rank 0) or kLastFrame (to wall ranks)
  std::uint32_t lastFrame;
  std::int32_t exitCode;
};
constexpr std::uint32_t kAskToStop = 1, kLastFrame = 2;

messaging::Bytes pack(const ControlMessage& m) {
  messaging::Bytes bytes(sizeof m);
  std::memcpy(bytes.data(), &m, sizeof m);
  return bytes;
}

}  // namespace

RunControl::RunControl(messaging::Messenger& messenger, StopSignals& signals)
    : messenger_(messenger), signals_(signals) {
  messenger_.registerObject(kRunControlObject, this);
}

RunControl::~RunControl() { messenger_.unregisterObject(kRunControlObject); }

void RunControl::pollSignals() {
  const int signal = signals_.poll();
  if (signal == 0) return;
  askToStop(exitCodeForStop(signal));
}

void RunControl::askToStop(int code) {
  if (messenger_.rank() == 0) {
    std::lock_guard lock(mutex_);
    if (!requested_) requested_ = code;
  } else if (!asked_) {
    asked_ = true;
    messenger_.send(0, kRunControlObject, pack({kAskToStop, 0, code}));
  }
}

std::optional<int> RunControl::stopRequested() const {
  std::lock_guard lock(mutex_);
  return requested_;
}

void RunControl::announceLastFrame(std::uint32_t lastFrame, int exitCode, int firstWallRank,
                                   int worldSize) {
  for (int rank = firstWallRank; rank < worldSize; ++rank)
    messenger_.send(rank, kRunControlObject, pack({kLastFrame, lastFrame, exitCode}));
}

void RunControl::onLastFrame(std::function<void(std::uint32_t)> stop) {
  std::optional<std::uint32_t> known;
  {
    std::lock_guard lock(mutex_);
    stopWall_ = stop;
    known = lastFrame_;
  }
  if (known && stop) stop(*known);
}

void RunControl::incoming(int fromRank, messaging::Bytes&& payload) {
  ControlMessage m;
  if (payload.size() != sizeof m)
    throw std::runtime_error("malformed run-control message of " + std::to_string(payload.size()) +
                             " bytes from rank " + std::to_string(fromRank));
  std::memcpy(&m, payload.data(), sizeof m);
  std::function<void(std::uint32_t)> stop;
  {
    std::lock_guard lock(mutex_);
    if (m.kind == kAskToStop) {
      if (!requested_) requested_ = m.exitCode;
      return;
    }
    if (m.kind != kLastFrame)
      throw std::runtime_error("run-control message of unknown kind " + std::to_string(m.kind) +
                               " from rank " + std::to_string(fromRank));
    lastFrame_ = m.lastFrame;
    exitCode_ = m.exitCode;
    stop = stopWall_;
  }
  if (stop) stop(m.lastFrame);
}

}  // namespace app
