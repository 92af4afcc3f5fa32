#include "apps/FrameDirector.h"

#include <cmath>
#include <cstring>

namespace app {
namespace {

using renderers::CameraDesc;
using renderers::Vec3;

// A camera the renderers can build (renderers::Camera throws on anything else).
bool usable(const CameraDesc& c) {
  const Vec3 view = c.lookAt - c.position;
  return renderers::length(view) > 0 && renderers::length(renderers::cross(view, c.up)) > 0 &&
         c.fovY > 0 && c.fovY < 180;
}

}  // namespace

bool FrameView::sameAs(const FrameView& o) const {
  // Bitwise: the frame order is compared as broadcast, and -0.0 vs 0.0 is a change anyway.
  return std::memcmp(this, &o, sizeof o) == 0;
}

FrameDirector::FrameDirector(DirectorOptions options)
    : options_(std::move(options)), base_(options_.initial), view_(options_.initial) {
  pathActive_ = static_cast<bool>(options_.path);
  playing_ = options_.timeSteps > 1;
}

bool steerView(FrameView& view, const CameraDesc& shown, const SteeringRequest& r) {
  using R = SteeringRequest;
  FrameView next = view;
  CameraDesc& c = next.camera;
  if (r.kind == R::kCamera) {
    // Every change starts from what the wall shows now (orbit and camera path included), so a
    // subset of fields changes only those.
    c = shown;
    if (r.has(R::kPosition)) c.position = r.position;
    if (r.has(R::kLookAt)) c.lookAt = r.lookAt;
    if (r.has(R::kUp)) c.up = r.up;
    if (r.has(R::kFov)) c.fovY = r.fov;
    if (r.has(R::kOrbit)) c = renderers::orbitCamera(c, r.orbit);
    if (r.has(R::kPan)) {
      const Vec3 toTarget = c.lookAt - c.position;
      const Vec3 forward = renderers::normalize(toTarget);
      const Vec3 right = renderers::normalize(renderers::cross(forward, c.up));
      const Vec3 up = renderers::cross(right, forward);
      const float height =
          2 * renderers::length(toTarget) * std::tan(0.5f * c.fovY * renderers::kPi / 180.0f);
      const Vec3 offset = (right * r.pan[0] + up * r.pan[1]) * height;
      c.position = c.position + offset;
      c.lookAt = c.lookAt + offset;
    }
    if (r.has(R::kDolly)) c.position = c.lookAt + (c.position - c.lookAt) * (1.0f / r.dolly);
    if (!usable(c)) return false;
  } else if (r.kind == R::kSettings) {
    if (r.has(R::kExposure)) next.exposure = r.exposure;
    if (r.has(R::kSpp)) next.spp = r.spp;
    if (r.has(R::kMaxDepth)) next.maxDepth = r.maxDepth;
    if (r.has(R::kTransferFunction)) next.transferFunction = r.transferFunction;
    if (r.has(R::kOpacityScale)) next.opacityScale = r.opacityScale;
  }
  view = next;
  return true;
}

void FrameDirector::apply(const SteeringRequest& r) {
  // The control server checked this camera against the one it saw; the wall may have moved on.
  if (!steerView(base_, view_.camera, r)) {
    errors_.push_back("camera request " + std::to_string(r.id) +
                      " not applied: look_at would equal position or lie along up");
    return;
  }
  if (r.kind == SteeringRequest::kCamera) {
    pathActive_ = false;  // the operator has the camera now
    orbitFrom_ = 0;       // the orbit continues from where the operator put the camera
  }
}

void FrameDirector::applyTime(const SteeringRequest& r) {
  const std::int64_t steps = options_.timeSteps;
  if (steps <= 1) {
    errors_.push_back("time request " + std::to_string(r.id) +
                      " not applied: the scene has no time series");
    return;
  }
  if (r.has(SteeringRequest::kSeek) && r.seek >= steps) {
    errors_.push_back("time request " + std::to_string(r.id) + " not applied: step " +
                      std::to_string(r.seek) + " is past the series' " + std::to_string(steps) +
                      " steps");
    return;
  }
  const auto period = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(options_.fps > 0 ? 1.0 / options_.fps : 0.0));
  if (r.has(SteeringRequest::kPlay)) {
    if (r.play && !playing_) nextStepDue_ = options_.now() + period;
    playing_ = r.play != 0;
  }
  if (r.has(SteeringRequest::kStepBy)) {
    const std::int64_t to = ((std::int64_t(base_.timeStep) + r.stepBy) % steps + steps) % steps;
    base_.timeStep = static_cast<std::uint32_t>(to);
    playing_ = false;
    timeMoved_ = true;
  }
  if (r.has(SteeringRequest::kSeek)) {
    base_.timeStep = static_cast<std::uint32_t>(r.seek);
    nextStepDue_ = options_.now() + period;
    timeMoved_ = true;
  }
}

void FrameDirector::advanceTime() {
  if (!playing_ || options_.timeSteps <= 1) return;
  const auto now = options_.now();
  const auto period = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(options_.fps > 0 ? 1.0 / options_.fps : 0.0));
  // The first frame shows the first step; a request that moved the step holds it a frame.
  if (!haveView_ || timeMoved_) {
    nextStepDue_ = now + period;
    return;
  }
  if (options_.fps > 0 && now < nextStepDue_) return;
  base_.timeStep = (base_.timeStep + 1) % options_.timeSteps;
  // On schedule while frames keep up; one step a frame from now on when they fall behind.
  nextStepDue_ = nextStepDue_ + period < now ? now + period : nextStepDue_ + period;
}

void FrameDirector::restartAccumulation() {
  haveView_ = false;
  epoch_ = 0;
  epochSpp_ = 0;
}

FrameOrder FrameDirector::next(std::uint32_t frameId,
                               const std::vector<SteeringRequest>& requests) {
  FrameOrder order;
  for (const SteeringRequest& r : requests) {
    if (order.requestId == 0) {
      order.requestNs = r.receivedNs;
      order.presentedAtRequest = r.presentedAtArrival;
    }
    order.requestId = r.id;
    switch (r.kind) {
      case SteeringRequest::kStop:
        if (!order.stop) order.stop = 1, order.exitCode = r.exitCode;
        break;
      case SteeringRequest::kCapture:
        order.captureSequence = ++captures_;
        break;
      case SteeringRequest::kTime:
        applyTime(r);
        break;
      default:
        apply(r);
    }
  }
  const std::optional<std::uint32_t> pathStep =
      pathActive_ && options_.pathStep ? options_.pathStep(frameId) : std::nullopt;
  if (pathStep)
    base_.timeStep = *pathStep;
  else
    advanceTime();
  timeMoved_ = false;
  if (orbitFrom_ == 0) orbitFrom_ = frameId;
  FrameView view = base_;
  if (pathActive_) view.camera = options_.path(frameId);
  if (options_.orbitDegrees != 0) {
    // In double and reduced to one turn, so long runs keep the angle exact enough.
    const double degrees =
        std::fmod(double(options_.orbitDegrees) * double(frameId - orbitFrom_), 360.0);
    view.camera = renderers::orbitCamera(view.camera, static_cast<float>(degrees));
  }
  if (haveView_ && !view.sameAs(view_)) {
    ++epoch_;
    epochSpp_ = 0;
  }
  haveView_ = true;
  view_ = view;
  lastFrame_ = frameId;
  if (order.requestId > 0) {
    lastRequest_ = order.requestId;
    lastRequestFrame_ = frameId;
  }
  epochSpp_ += view.spp;
  order.frame = {frameId, epoch_};
  order.view = view;
  return order;
}

bool FrameDirector::converged() const {
  if (options_.maxSpp <= 0 || epochSpp_ < options_.maxSpp || options_.orbitDegrees != 0)
    return false;
  if (playing_ && options_.timeSteps > 1) return false;
  if (options_.content && options_.content(lastFrame_ + 1) != options_.content(lastFrame_))
    return false;
  // A camera path that has reached its last keyframe holds still.
  if (!pathActive_) return true;
  const renderers::CameraDesc next = options_.path(lastFrame_ + 1);
  if (options_.pathStep &&
      options_.pathStep(lastFrame_ + 1).value_or(view_.timeStep) != view_.timeStep)
    return false;
  return std::memcmp(&next, &view_.camera, sizeof next) == 0;
}

std::vector<std::string> FrameDirector::takeErrors() {
  std::vector<std::string> out;
  out.swap(errors_);
  return out;
}

}  // namespace app
