#pragma once
// Steering a running wall: requests to move the camera, change settings, capture or
// stop, from any source — the control server's HTTP handlers on render rank 0, a keyboard on a
// wall rank's window — queued on render rank 0 and applied there at the next frame boundary.
// Rank 0 then broadcasts the frame's camera and settings with the frame order
// (apps/FrameOrder.h), so no rank ever renders a frame with another rank's camera, and a change
// starts a new accumulation epoch on every rank at once.
//
// One object per rank, registered under kSteeringObject on the job's messenger before the
// start-up barrier. submit() is thread-safe on every rank; on other ranks it sends the request
// to rank 0. Rank 0 also uses this object to tell the wall ranks what they need between frames
// (keep waiting while the renderers idle; capture a frame).
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

#include "base/ObjectIds.h"
#include "messaging/Messenger.h"
#include "renderers/Math.h"

namespace app {

constexpr messaging::ObjectId kSteeringObject = base::objectId(base::MessageObject::kSteering);

// One request; trivially copyable (it travels from wall ranks to rank 0 as bytes). `fields`
// says which of the values are set; the rest are ignored.
struct SteeringRequest {
  enum Kind : std::uint32_t { kCamera = 1, kSettings = 2, kCapture = 3, kStop = 4, kTime = 5 };
  enum Field : std::uint32_t {
    // kCamera: absolute (any subset) ...
    kPosition = 1u << 0,
    kLookAt = 1u << 1,
    kUp = 1u << 2,
    kFov = 1u << 3,
    // ... or relative to the current camera.
    kOrbit = 1u << 4,  // degrees about the look-at point around up
    kPan = 1u << 5,    // [dx, dy] in view heights at the look-at distance (camera and look-at move)
    kDolly = 1u << 6,  // distance to the look-at point divided by this factor
    // kSettings
    kExposure = 1u << 8,
    kSpp = 1u << 9,  // samples per pixel per frame
    kMaxDepth = 1u << 10,
    kTransferFunction = 1u << 11,  // scivis: preset index in transferFunctionPresetNames()
    kOpacityScale = 1u << 12,      // scivis: multiplies every volume's opacity
    // kTime (a scene with a time series): play or pause, step by some steps (pauses), go to a
    // step (keeps playing or paused).
    kPlay = 1u << 16,
    kStepBy = 1u << 17,
    kSeek = 1u << 18,
  };
  std::uint32_t kind = 0;
  std::uint32_t fields = 0;
  renderers::Vec3 position{}, lookAt{}, up{};
  float fov = 0;
  float orbit = 0, pan[2] = {0, 0}, dolly = 1;
  float exposure = 1;
  std::int32_t spp = 1, maxDepth = 8, transferFunction = -1;
  float opacityScale = 1;
  std::int32_t exitCode = 0;  // kStop
  std::int32_t play = 0;      // kTime: 1 play, 0 pause
  std::int32_t stepBy = 0;    // kTime: steps forward (negative: back), wrapping around
  std::int32_t seek = 0;      // kTime: the step to show
  // Set on rank 0 when the request arrives: its id (1, 2, ...), the steady_clock time and the
  // last frame every display had presented then (for the latency statistics).
  std::uint64_t id = 0;
  std::int64_t receivedNs = 0;
  std::int64_t presentedAtArrival = 0;

  bool has(Field f) const { return (fields & f) != 0; }
};

// Why `r` cannot be applied (a NaN, a value out of range, a field that does not belong to its
// kind), or empty when it can. Ranges: docs in README.md, "Steering the wall".
std::string checkRequest(const SteeringRequest& r);

class Steering : public messaging::MessageHandler {
 public:
  explicit Steering(messaging::Messenger& messenger);
  ~Steering() override;
  Steering(const Steering&) = delete;
  Steering& operator=(const Steering&) = delete;

  // Any rank, any thread: queues `request` for the next frame boundary (rank 0) or sends it to
  // rank 0. Returns its id on rank 0, 0 elsewhere. Throws std::invalid_argument with
  // checkRequest's message for a request that cannot be applied.
  std::uint64_t submit(SteeringRequest request);

  // Rank 0, frame loop: the requests queued since the last call, in arrival order.
  std::vector<SteeringRequest> take();
  // Rank 0: waits (without spinning) until a request is queued, wake() is called, or `until`.
  // True when a request is queued.
  bool waitForRequest(std::chrono::steady_clock::time_point until);
  void wake();
  // Rank 0: how to read the last frame every display presented (stamped on arriving requests).
  void setPresentedProbe(std::function<std::int64_t()> probe);

  void incoming(int fromRank, messaging::Bytes&& payload) override;

 private:
  std::uint64_t enqueue(SteeringRequest request);

  messaging::Messenger& messenger_;
  std::mutex mutex_;
  std::condition_variable queued_;
  std::deque<SteeringRequest> queue_;
  std::uint64_t nextId_ = 1;
  bool woken_ = false;
  std::mutex probeMutex_;  // guards presentedProbe_ (also while it runs)
  std::function<std::int64_t()> presentedProbe_;
};

}  // namespace app
