#pragma once
// Keys pressed in a wall's windows (wall::WallKey) as steering requests, for a wall with a
// keyboard attached: the arrows orbit (left, right) and pan (up, down), '+' and '-' dolly. Esc
// is not a request: the wall rank asks for the graceful stop itself (apps/WallRank.cpp).
#include <optional>

#include "apps/Steering.h"
#include "wall/display/Presenter.h"

namespace app {

constexpr float kKeyOrbitDegrees = 5.0f;
constexpr float kKeyPanViewHeights = 0.05f;
constexpr float kKeyDollyFactor = 1.1f;

std::optional<SteeringRequest> requestForKey(wall::WallKey key);

}  // namespace app
