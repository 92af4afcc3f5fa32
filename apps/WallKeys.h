#pragma once
// Keys pressed in a wall's windows (wall::WallKey) as steering requests, for a wall with a
// keyboard attached: the arrows orbit (left, right) and pan (up, down), '+' and '-' dolly. Esc
// is not a request: the wall rank asks for the graceful stop itself (apps/WallRank.cpp).
// A service wall's keys and mouse over a job's window (wall::service::WindowInput) steer it the
// same way, drags and the wheel as on the job's page (apps/control/page/app.js).
#include <optional>

#include "apps/Steering.h"
#include "wall/display/Presenter.h"
#include "wall/service/protocol/Protocol.h"

namespace app {

constexpr float kKeyOrbitDegrees = 5.0f;
constexpr float kKeyPanViewHeights = 0.05f;
constexpr float kKeyDollyFactor = 1.1f;

std::optional<SteeringRequest> requestForKey(wall::WallKey key);
// For a job in a `width` x `height` window: a key as above; a drag across the window's width
// orbits 180 degrees (pan: a view height per window height); a wheel notch dollies as '+'.
// Within checkRequest's ranges.
std::optional<SteeringRequest> requestForInput(const wall::service::WindowInput& input, int width,
                                               int height);

}  // namespace app
