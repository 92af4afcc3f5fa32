#include "apps/WallKeys.h"

#include <algorithm>
#include <cmath>

namespace app {

std::optional<SteeringRequest> requestForKey(wall::WallKey key) {
  SteeringRequest r;
  r.kind = SteeringRequest::kCamera;
  switch (key) {
    case wall::WallKey::Left:
    case wall::WallKey::Right:
      r.fields = SteeringRequest::kOrbit;
      r.orbit = key == wall::WallKey::Left ? -kKeyOrbitDegrees : kKeyOrbitDegrees;
      return r;
    case wall::WallKey::Up:
    case wall::WallKey::Down:
      r.fields = SteeringRequest::kPan;
      r.pan[1] = key == wall::WallKey::Up ? kKeyPanViewHeights : -kKeyPanViewHeights;
      return r;
    case wall::WallKey::Plus:
    case wall::WallKey::Minus:
      r.fields = SteeringRequest::kDolly;
      r.dolly = key == wall::WallKey::Plus ? kKeyDollyFactor : 1.0f / kKeyDollyFactor;
      return r;
    case wall::WallKey::Escape:
      break;
  }
  return std::nullopt;
}

std::optional<SteeringRequest> requestForInput(const wall::service::WindowInput& in, int width,
                                               int height) {
  using wall::service::WindowInput;
  if (width <= 0 || height <= 0) return std::nullopt;
  SteeringRequest r;
  r.kind = SteeringRequest::kCamera;
  switch (in.kind) {
    case WindowInput::kKey:
      if (in.key >= WindowInput::kKeyCount) return std::nullopt;
      return requestForKey(static_cast<wall::WallKey>(in.key));
    case WindowInput::kDrag:
      if (in.pan) {
        r.fields = SteeringRequest::kPan;
        r.pan[0] =
            std::clamp(-static_cast<float>(in.dx) / static_cast<float>(height), -10.0f, 10.0f);
        r.pan[1] =
            std::clamp(static_cast<float>(in.dy) / static_cast<float>(height), -10.0f, 10.0f);
      } else {
        r.fields = SteeringRequest::kOrbit;
        r.orbit = std::clamp(-static_cast<float>(in.dx) * 180.0f / static_cast<float>(width),
                             -360.0f, 360.0f);
      }
      if (in.dx == 0 && in.dy == 0) return std::nullopt;
      return r;
    case WindowInput::kScroll:
      if (in.dy == 0) return std::nullopt;
      r.fields = SteeringRequest::kDolly;
      r.dolly = std::clamp(std::pow(kKeyDollyFactor, static_cast<float>(in.dy)), 0.01f, 100.0f);
      return r;
    default:
      return std::nullopt;
  }
}

}  // namespace app
