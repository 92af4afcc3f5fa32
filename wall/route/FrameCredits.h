#pragma once
// Frame pacing between the wall and the renderers (dw2's "frames in flight"): wall process 0
// acknowledges each frame once every display has presented it, and render rank 0 waits for the
// acknowledgement of frame F - K before it starts frame F. Rendering F+1 overlaps presenting F,
// and no wall rank ever buffers more than K + 1 frames.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>

#include "messaging/Messenger.h"

namespace wall {

// Lives on render rank 0: registered under kFrameCreditsObject on the job's messenger, or fed
// by a service link (wall/service/client/ServiceClient.h) through acknowledged().
class FrameCredits : public messaging::MessageHandler {
 public:
  explicit FrameCredits(messaging::Messenger& messenger);
  FrameCredits() = default;
  ~FrameCredits() override;

  // Blocks until frame `frameId` has been presented on every display (ids below 1 return at
  // once). Throws base::Error after `timeout`.
  void waitForPresented(std::int64_t frameId, std::chrono::milliseconds timeout);
  std::int64_t lastPresented() const;
  struct AckTimes {
    std::int64_t completeNs = 0;      // the last display had every piece (from the ack)
    std::int64_t acknowledgedNs = 0;  // the ack reached this rank: every display presented
  };
  // Those times of `frameId` (steady_clock ns), taken once; nothing when that frame's
  // acknowledgement has not come yet.
  std::optional<AckTimes> takeTimes(std::int64_t frameId);

  void incoming(int fromRank, messaging::Bytes&& payload) override;
  // Every display presented `frameId` (the last display had every piece at `completeNs`).
  // Frames are acknowledged in order; anything else throws base::Error naming `from`.
  void acknowledged(std::uint32_t frameId, std::int64_t completeNs, const std::string& from);

 private:
  messaging::Messenger* messenger_ = nullptr;
  mutable std::mutex mutex_;
  std::condition_variable presented_;
  std::int64_t lastPresented_ = 0;
  std::map<std::int64_t, AckTimes> times_;  // at most frames-in-flight + 1 entries
};

// Sent by wall process 0 to render rank 0 (world rank 0), with the time the last display had
// every piece of the frame.
void acknowledgeFrame(messaging::Messenger& messenger, std::uint32_t frameId,
                      std::int64_t completeNs);

}  // namespace wall
