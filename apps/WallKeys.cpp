#include "apps/WallKeys.h"

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

}  // namespace app
