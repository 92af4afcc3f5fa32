#pragma once
// serve --control [ADDR:]PORT: the wall's own window manager, on the head (process 0), behind
// the same control server as a job's --control (apps/ControlServer.h, apps/ControlRequests.h:
// token, Host, Origin, body and time limits), with routes of its own (docs/service.md, "The
// wall's control page"):
//
//   GET    /api/wall         {"canvas": {"w", "h"}, "displays": [{"name", "rect", "process"}],
//                             "background": "#rrggbb", "max_jobs"}
//   GET    /api/windows      [{"id", "job", "host", "rect": {"x", "y", "w", "h"}, "z", "fps",
//                              "state", "frames", "page"}], the oldest job first; z 0 at the bottom
//   POST   /api/windows/ID   {"raise": true}: on top on every display; any of {"x", "y", "w",
//                            "h"} (the others kept), or {"fullscreen": true}: the window moves
//                            and resizes (its job re-plans), answered {"id", "rect"}
//   DELETE /api/windows/ID   the job is ended, told kClosedFromThePage; its window closes at once
//   GET    /api/windows/ID/thumbnail   what the window shows, shrunk, as PNG (503 before the
//                            first, and on a --max-jobs 1 wall)
// The page itself (/, /index.html, /wall.js, /wall.css, from apps/control/wall/) is served by
// addWallPageRoutes (apps/PageRoutes.h).
//
// The handlers read the desk's last published windows and hand a raise, a move or a close to the
// desk thread (wall::service::Desk), which answers within a turn: a client never holds up a
// frame.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "wall/layout/Layout.h"
#include "wall/service/server/JobDesk.h"

namespace app {

class ControlRequests;

// What the routes ask of the wall: wall::service::WallService on the head.
struct WallWindows {
  std::function<std::vector<wall::service::JobDesk::Window>()> list;
  // False: no job of that number on the wall.
  std::function<bool(std::uint64_t number)> raise;
  std::function<bool(std::uint64_t number, const std::string& why)> close;
  // The window moved and resized to `rect` (WallService::moveWindow): empty when under way, else
  // why not, with `code` 400 (a window the wall cannot show), 404 (gone) or 409 (the job cannot
  // move now, or at all).
  std::function<std::string(std::uint64_t number, const dfb::Region& rect, int& code)> move;
};

// The wall's fixed facts for GET /api/wall.
struct WallFacts {
  const wall::Layout* layout = nullptr;    // outlives the routes
  std::uint32_t background = 0xff000000u;  // RGBA8 as in wall::Image
  int maxJobs = 1;
};

// What a job closed from the page is told (its log: "the wall at … ended the job: …").
constexpr const char* kClosedFromThePage = "closed from the wall's control page";

// Before the server starts: the API routes above.
void addWallRoutes(ControlRequests& requests, WallFacts facts, WallWindows windows);

// The window number an id names ("3": 3): decimal digits only, no sign or leading zero, within
// 64 bits; nullopt otherwise.
std::optional<std::uint64_t> windowNumber(const std::string& id);

}  // namespace app
