#include "wall/FrameCredits.h"

#include <cstring>
#include <string>

#include "wall/Error.h"
#include "wall/PieceMessage.h"

namespace wall {

FrameCredits::FrameCredits(dfb::Messenger& messenger) : messenger_(messenger) {
  messenger_.registerObject(kFrameCreditsObject, this);
}

FrameCredits::~FrameCredits() { messenger_.unregisterObject(kFrameCreditsObject); }

void FrameCredits::waitForPresented(std::int64_t frameId, std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  if (!presented_.wait_for(lock, timeout, [&] { return lastPresented_ >= frameId; }))
    throw Error("the wall did not present frame " + std::to_string(frameId) + " within " +
                std::to_string(timeout.count()) +
                " ms (last presented: " + std::to_string(lastPresented_) + ")");
}

std::int64_t FrameCredits::lastPresented() const {
  std::lock_guard lock(mutex_);
  return lastPresented_;
}

void FrameCredits::incoming(int, dfb::Bytes&& payload) {
  std::uint32_t frameId = 0;
  if (payload.size() != sizeof frameId) throw Error("malformed frame acknowledgement");
  std::memcpy(&frameId, payload.data(), sizeof frameId);
  {
    std::lock_guard lock(mutex_);
    lastPresented_ = std::max<std::int64_t>(lastPresented_, frameId);
  }
  presented_.notify_all();
}

void acknowledgeFrame(dfb::Messenger& messenger, std::uint32_t frameId) {
  dfb::Bytes payload(sizeof frameId);
  std::memcpy(payload.data(), &frameId, sizeof frameId);
  messenger.send(0, kFrameCreditsObject, std::move(payload));
}

}  // namespace wall
