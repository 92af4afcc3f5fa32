#pragma once
// The control API's routes (docs/service.md, "Steering the wall"): what rank 0 reports and the
// steering requests it queues. Handlers only read the status board and queue requests, so a
// client never stalls a frame; they answer at once (never wait for the wall).
//
//   GET  /api/status    frame, fps, spp, camera, displays, renderer, errors
//   POST /api/camera    {"position", "look_at", "up", "fov"} (any subset), "orbit", "pan", "dolly"
//   POST /api/settings  {"exposure", "spp", "max_depth", "transfer_function", "opacity_scale"}
//   POST /api/time      a time series: {"play": bool}, {"step": n} (n steps on, pausing),
//                       {"seek": n} (show step n); the status' "time" has step, steps, playing
//   POST /api/capture   every display captures the next frame to the --capture folder
//   POST /api/stop      graceful stop: statistics and captures written, exit 0
//
// A POST without a body is taken as {}. Malformed JSON, unknown fields, NaN, values out of
// range: 400 with a message; the wall keeps running.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "apps/Steering.h"

namespace app {

class ControlRequests;
class StatusBoard;

// The job's fixed facts the API reports and checks against.
struct ControlFacts {
  std::string renderer;
  std::int64_t maxSpp = 0;
  std::vector<std::string> displays;
  bool canCapture = false;  // a wall and a --capture folder
};

// `submit` queues a request and returns its id (Steering::submit); it may throw
// std::invalid_argument. `status` must outlive the routes.
void addApiRoutes(ControlRequests& requests, ControlFacts facts,
                  std::function<std::uint64_t(const SteeringRequest&)> submit,
                  const StatusBoard& status);

}  // namespace app
