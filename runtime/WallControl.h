#pragma once
// What render rank 0 tells the wall's processes about a job, in the same words whichever way the
// wall is reached: its ranks in this MPI job (MpiWallControl) or a wall service the job
// connected to (ServiceWallControl).
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>

#include "base/ObjectIds.h"
#include "messaging/Messenger.h"

namespace wall::service {
class ServiceClient;
}

namespace runtime {

class WallControl {
 public:
  virtual ~WallControl() = default;
  // The job's last frame: each wall process stops once it presented (and captured) it.
  virtual void lastFrame(std::uint32_t frameId, int exitCode) = 0;
  // Nothing new comes for a while (a converged image): the wall processes keep waiting.
  virtual void keepWaiting() = 0;
  // Every display captures frame `frameId` as capture number `sequence`.
  virtual void capture(std::uint32_t frameId, std::uint64_t sequence) = 0;
};

constexpr messaging::ObjectId kWallControlObject =
    base::objectId(base::MessageObject::kWallControl);

// Wall processes that are ranks [firstWallRank, worldSize) of this MPI job. Every rank makes one
// before the start-up barrier (it registers on the messenger); render rank 0 speaks, the wall
// ranks listen. incoming() runs on the messenger's inbox thread.
class MpiWallControl final : public WallControl, public messaging::MessageHandler {
 public:
  MpiWallControl(messaging::Messenger& messenger, int firstWallRank, int worldSize);
  ~MpiWallControl() override;
  MpiWallControl(const MpiWallControl&) = delete;
  MpiWallControl& operator=(const MpiWallControl&) = delete;

  void lastFrame(std::uint32_t frameId, int exitCode) override;
  void keepWaiting() override;
  void capture(std::uint32_t frameId, std::uint64_t sequence) override;

  // Wall ranks: what to do when told, on the inbox thread; the last frame at once when it is
  // known already. An empty Listener stops listening.
  struct Listener {
    std::function<void(std::uint32_t frameId)> lastFrame;
    std::function<void()> keepWaiting;
    std::function<void(std::uint32_t frameId, std::uint64_t sequence)> capture;
  };
  void listen(Listener listener);
  // Wall ranks: the exit code render rank 0 sent with the last frame (0 until then).
  int exitCode() const;

  void incoming(int fromRank, messaging::Bytes&& payload) override;

 private:
  void tellWalls(std::uint32_t kind, std::uint32_t frameId, std::int32_t exitCode,
                 std::uint64_t sequence);

  messaging::Messenger& messenger_;
  const int firstWallRank_, worldSize_;
  mutable std::mutex mutex_;
  Listener listener_;
  std::optional<std::uint32_t> lastFrame_;
  int exitCode_ = 0;
};

// A wall service (dfbwall serve) through render rank 0's link to it. The link's keepalives say
// that the job is alive, so keepWaiting() has nothing to add.
class ServiceWallControl final : public WallControl {
 public:
  explicit ServiceWallControl(wall::service::ServiceClient& client) : client_(client) {}

  void lastFrame(std::uint32_t frameId, int exitCode) override;
  void keepWaiting() override {}
  void capture(std::uint32_t frameId, std::uint64_t sequence) override;

 private:
  wall::service::ServiceClient& client_;
};

}  // namespace runtime
