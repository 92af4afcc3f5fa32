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

// What travels to rank 0: a kind, then the request. (What rank 0 tells the wall ranks goes
// through runtime/WallControl.h.)
enum MessageKind : std::uint32_t { kRequest = 1 };

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
    case R::kTime:
      if (r.fields == 0) return "a time request needs play, step or seek";
      if (r.fields & ~(R::kPlay | R::kStepBy | R::kSeek))
        return "a time request has a camera or settings field";
      if (r.has(R::kStepBy) && r.has(R::kSeek)) return "a time request steps or seeks, not both";
      if (r.has(R::kPlay) && r.play != 0 && r.play != 1) return "play must be true or false";
      if (r.has(R::kStepBy) && !(r.stepBy >= -(1 << 20) && r.stepBy <= 1 << 20))
        return "step must be in [-1048576, 1048576]";
      if (r.has(R::kSeek) && r.seek < 0) return "seek must not be negative";
      return {};  // steps beyond the series: checked by the director, which knows its length
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

void Steering::incoming(int fromRank, messaging::Bytes&& payload) {
  std::uint32_t kind = 0;
  if (payload.size() >= sizeof kind) std::memcpy(&kind, payload.data(), sizeof kind);
  const auto malformed = [&] {
    return std::runtime_error("malformed steering message of " + std::to_string(payload.size()) +
                              " bytes from rank " + std::to_string(fromRank));
  };
  if (kind != kRequest || messenger_.rank() != 0) throw malformed();
  {
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
  }
}

}  // namespace app
