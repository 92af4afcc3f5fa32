#include "apps/Steering.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <type_traits>

#include "renderers/TransferFunction.h"

namespace app {
namespace {

static_assert(std::is_trivially_copyable_v<SteeringRequest>);

// What travels between ranks: a kind, then the request (kRequest), or a frame and a sequence.
enum MessageKind : std::uint32_t { kRequest = 1, kKeepWaiting = 2, kCapture = 3 };
struct WallMessage {
  std::uint32_t frameId;
  std::uint32_t unused;
  std::uint64_t sequence;
};

template <typename T>
messaging::Bytes pack(std::uint32_t kind, const T& body) {
  messaging::Bytes bytes(sizeof kind + sizeof body);
  std::memcpy(bytes.data(), &kind, sizeof kind);
  std::memcpy(bytes.data() + sizeof kind, &body, sizeof body);
  return bytes;
}

bool finite(renderers::Vec3 v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

std::int64_t nowNs() { return std::chrono::steady_clock::now().time_since_epoch().count(); }

}  // namespace

std::string checkRequest(const SteeringRequest& r) {
  using R = SteeringRequest;
  constexpr std::uint32_t cameraFields =
      R::kPosition | R::kLookAt | R::kUp | R::kFov | R::kOrbit | R::kPan | R::kDolly;
  constexpr std::uint32_t settingsFields =
      R::kExposure | R::kSpp | R::kMaxDepth | R::kTransferFunction | R::kOpacityScale;
  switch (r.kind) {
    case R::kCamera:
      if (r.fields == 0) return "a camera request needs at least one field";
      if (r.fields & ~cameraFields) return "a camera request has a settings field";
      break;
    case R::kSettings:
      if (r.fields == 0) return "a settings request needs at least one field";
      if (r.fields & ~settingsFields) return "a settings request has a camera field";
      break;
    case R::kCapture:
    case R::kStop:
      if (r.fields != 0) return "capture and stop take no fields";
      return {};
    default:
      return "unknown steering request kind " + std::to_string(r.kind);
  }
  if (r.has(R::kPosition) && !finite(r.position)) return "position must be finite";
  if (r.has(R::kLookAt) && !finite(r.lookAt)) return "look_at must be finite";
  if (r.has(R::kUp) && (!finite(r.up) || renderers::length(r.up) <= 0))
    return "up must be a finite, non-zero vector";
  if (r.has(R::kFov) && !(r.fov >= 1 && r.fov <= 170)) return "fov must be in [1, 170] degrees";
  if (r.has(R::kOrbit) && !(r.orbit >= -360 && r.orbit <= 360))
    return "orbit must be in [-360, 360] degrees";
  if (r.has(R::kPan) && !(std::abs(r.pan[0]) <= 10 && std::abs(r.pan[1]) <= 10))
    return "pan must be two numbers in [-10, 10] (view heights)";
  if (r.has(R::kDolly) && !(r.dolly >= 0.01f && r.dolly <= 100))
    return "dolly must be a factor in [0.01, 100]";
  if (r.has(R::kExposure) && !(r.exposure > 0 && r.exposure <= 1000))
    return "exposure must be in (0, 1000]";
  if (r.has(R::kSpp) && !(r.spp >= 1 && r.spp <= 1 << 16)) return "spp must be in [1, 65536]";
  if (r.has(R::kMaxDepth) && !(r.maxDepth >= 1 && r.maxDepth <= 64))
    return "max_depth must be in [1, 64]";
  if (r.has(R::kTransferFunction) &&
      !(r.transferFunction >= 0 &&
        r.transferFunction < static_cast<int>(renderers::transferFunctionPresetNames().size())))
    return "unknown transfer function preset";
  if (r.has(R::kOpacityScale) && !(r.opacityScale >= 0 && r.opacityScale <= 100))
    return "opacity_scale must be in [0, 100]";
  return {};
}

Steering::Steering(messaging::Messenger& messenger) : messenger_(messenger) {
  messenger_.registerObject(kSteeringObject, this);
}

Steering::~Steering() { messenger_.unregisterObject(kSteeringObject); }

std::uint64_t Steering::submit(SteeringRequest request) {
  if (std::string problem = checkRequest(request); !problem.empty())
    throw std::invalid_argument(problem);
  if (messenger_.rank() != 0) {
    messenger_.send(0, kSteeringObject, pack(kRequest, request));
    return 0;
  }
  return enqueue(request);
}

std::uint64_t Steering::enqueue(SteeringRequest request) {
  std::int64_t presented = 0;
  {
    // Its own lock, held while the probe runs: setPresentedProbe({}) then waits for a probe in
    // progress before the frame credits it reads go away.
    std::lock_guard probing(probeMutex_);
    if (presentedProbe_) presented = presentedProbe_();
  }
  std::lock_guard lock(mutex_);
  request.id = nextId_++;
  request.receivedNs = nowNs();
  request.presentedAtArrival = presented;
  queue_.push_back(request);
  queued_.notify_all();
  return request.id;
}

std::vector<SteeringRequest> Steering::take() {
  std::lock_guard lock(mutex_);
  std::vector<SteeringRequest> out(queue_.begin(), queue_.end());
  queue_.clear();
  return out;
}

bool Steering::waitForRequest(std::chrono::steady_clock::time_point until) {
  std::unique_lock lock(mutex_);
  queued_.wait_until(lock, until, [&] { return !queue_.empty() || woken_; });
  woken_ = false;
  return !queue_.empty();
}

void Steering::wake() {
  std::lock_guard lock(mutex_);
  woken_ = true;
  queued_.notify_all();
}

void Steering::setPresentedProbe(std::function<std::int64_t()> probe) {
  std::lock_guard lock(probeMutex_);
  presentedProbe_ = std::move(probe);
}

void Steering::tellWallsKeepWaiting(int firstWallRank, int worldSize) {
  for (int rank = firstWallRank; rank < worldSize; ++rank)
    messenger_.send(rank, kSteeringObject, pack(kKeepWaiting, WallMessage{0, 0, 0}));
}

void Steering::tellWallsCapture(std::uint32_t frameId, std::uint64_t sequence, int firstWallRank,
                                int worldSize) {
  for (int rank = firstWallRank; rank < worldSize; ++rank)
    messenger_.send(rank, kSteeringObject, pack(kCapture, WallMessage{frameId, 0, sequence}));
}

void Steering::onKeepWaiting(std::function<void()> callback) {
  std::lock_guard lock(mutex_);
  keepWaiting_ = std::move(callback);
}

void Steering::onCapture(std::function<void(std::uint32_t, std::uint64_t)> callback) {
  std::lock_guard lock(mutex_);
  capture_ = std::move(callback);
}

void Steering::incoming(int fromRank, messaging::Bytes&& payload) {
  std::uint32_t kind = 0;
  if (payload.size() >= sizeof kind) std::memcpy(&kind, payload.data(), sizeof kind);
  const auto malformed = [&] {
    return std::runtime_error("malformed steering message of " + std::to_string(payload.size()) +
                              " bytes from rank " + std::to_string(fromRank));
  };
  if (kind == kRequest && messenger_.rank() == 0) {
    SteeringRequest request;
    if (payload.size() != sizeof kind + sizeof request) throw malformed();
    std::memcpy(&request, payload.data() + sizeof kind, sizeof request);
    // A rank that sends what rank 0 would refuse from HTTP has a bug: say so, drop nothing
    // silently, and keep the wall running (the request is simply not applied).
    if (std::string problem = checkRequest(request); !problem.empty()) {
      std::fprintf(stderr, "dfbwall: steering request from rank %d refused: %s\n", fromRank,
                   problem.c_str());
      return;
    }
    enqueue(request);
    return;
  }
  WallMessage m;
  if ((kind != kKeepWaiting && kind != kCapture) || payload.size() != sizeof kind + sizeof m)
    throw malformed();
  std::memcpy(&m, payload.data() + sizeof kind, sizeof m);
  std::function<void()> keepWaiting;
  std::function<void(std::uint32_t, std::uint64_t)> capture;
  {
    std::lock_guard lock(mutex_);
    keepWaiting = keepWaiting_;
    capture = capture_;
  }
  if (kind == kKeepWaiting && keepWaiting) keepWaiting();
  if (kind == kCapture && capture) capture(m.frameId, m.sequence);
}

}  // namespace app
