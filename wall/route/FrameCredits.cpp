#include "wall/route/FrameCredits.h"

#include <cstring>
#include <string>

#include "base/Error.h"
#include "wall/route/PieceMessage.h"

namespace wall {

FrameCredits::FrameCredits(messaging::Messenger& messenger) : messenger_(&messenger) {
  messenger_->registerObject(kFrameCreditsObject, this);
}

FrameCredits::~FrameCredits() {
  if (messenger_) messenger_->unregisterObject(kFrameCreditsObject);
}

void FrameCredits::waitForPresented(std::int64_t frameId, std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  if (!presented_.wait_for(lock, timeout, [&] { return lastPresented_ >= frameId; }))
    throw base::DeadlineError("the wall did not present frame " + std::to_string(frameId) +
                              " within " + std::to_string(timeout.count()) +
                              " ms (last presented: " + std::to_string(lastPresented_) + ")");
}

std::int64_t FrameCredits::lastPresented() const {
  std::lock_guard lock(mutex_);
  return lastPresented_;
}

std::optional<FrameCredits::AckTimes> FrameCredits::takeTimes(std::int64_t frameId) {
  std::lock_guard lock(mutex_);
  auto found = times_.find(frameId);
  if (found == times_.end()) return std::nullopt;
  const AckTimes times = found->second;
  times_.erase(times_.begin(), std::next(found));  // older ones are never asked for
  return times;
}

namespace {
struct Acknowledgement {
  std::uint32_t frameId;
  std::uint32_t reserved;
  std::int64_t completeNs;
};
}  // namespace

void FrameCredits::incoming(int fromRank, messaging::Bytes&& payload) {
  Acknowledgement ack;
  if (payload.size() != sizeof ack)
    throw base::Error("malformed frame acknowledgement of " + std::to_string(payload.size()) +
                      " bytes from rank " + std::to_string(fromRank));
  std::memcpy(&ack, payload.data(), sizeof ack);
  acknowledged(ack.frameId, ack.completeNs, "rank " + std::to_string(fromRank));
}

void FrameCredits::acknowledged(std::uint32_t frameId, std::int64_t completeNs,
                                const std::string& from) {
  {
    std::lock_guard lock(mutex_);
    if (frameId != lastPresented_ + 1)
      throw base::Error("frame acknowledgement for frame " + std::to_string(frameId) + " from " +
                        from + " after frame " + std::to_string(lastPresented_));
    lastPresented_ = frameId;
    times_[frameId] = {completeNs, std::chrono::steady_clock::now().time_since_epoch().count()};
    // Kept only until the frame's statistics are written; a run without them never asks.
    while (times_.size() > 64) times_.erase(times_.begin());
  }
  presented_.notify_all();
}

void acknowledgeFrame(messaging::Messenger& messenger, std::uint32_t frameId,
                      std::int64_t completeNs) {
  const Acknowledgement ack{frameId, 0, completeNs};
  messaging::Bytes payload(sizeof ack);
  std::memcpy(payload.data(), &ack, sizeof ack);
  messenger.send(0, kFrameCreditsObject, std::move(payload));
}

}  // namespace wall
