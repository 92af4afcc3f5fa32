#pragma once
// How a session's render ranks end its wall's run: a program does not know in advance how many
// frames it shows, so render rank 0 tells every wall rank the last frame when the program closes
// the session, and each wall node stops after presenting (and capturing) it. The same message as
// the dfbwall executable's stop (apps/RunControl.h), without signals: the program owns those.
//
// One object per rank, registered under kWallStopObject. incoming() runs on the messenger's
// inbox thread, the rest on the main one.
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>

#include "base/ObjectIds.h"
#include "messaging/Messenger.h"

namespace dfbwall {

constexpr messaging::ObjectId kWallStopObject = base::objectId(base::MessageObject::kWallStop);

class WallStop : public messaging::MessageHandler {
 public:
  explicit WallStop(messaging::Messenger& messenger);
  ~WallStop() override;
  WallStop(const WallStop&) = delete;
  WallStop& operator=(const WallStop&) = delete;

  // Render rank 0: tells ranks [firstWallRank, worldSize) that `lastFrame` is the last one.
  void announceLastFrame(std::uint32_t lastFrame, int firstWallRank, int worldSize);
  // Wall ranks: `stop(lastFrame)` runs once it is known (at once when it is known already).
  void onLastFrame(std::function<void(std::uint32_t)> stop);

  void incoming(int fromRank, messaging::Bytes&& payload) override;

 private:
  messaging::Messenger& messenger_;
  std::mutex mutex_;
  std::optional<std::uint32_t> lastFrame_;
  std::function<void(std::uint32_t)> stop_;
};

}  // namespace dfbwall
