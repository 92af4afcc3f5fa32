#pragma once
// Moving and resizing a running job's window (docs/design.md, "Moving and resizing a window"):
// the rules the head applies before it re-plans the job, apart from any socket, so they are
// tested on their own.
#include <cstdint>
#include <string>

#include "dfb/Tile.h"
#include "wall/layout/Layout.h"

namespace wall::service {

// The smallest side a window may have: one the job could not fit a tile row into is a mistake
// (a drag that collapsed it), not a window.
constexpr int kMinWindowSide = 16;

// Why `window` cannot be a job's window on `wall` (empty: it can): not inside the canvas,
// smaller than kMinWindowSide a side, or touching no display (bezels only).
std::string windowMoveProblem(const Layout& wall, const dfb::Region& window);

// The frame a job switches to its new window at: the first frame it cannot have started when it
// hears of the move. Render rank 0 starts frame f once frame f - granted is credited, and the
// move reaches it before any credit after `lastCredited`, so every frame up to
// lastCredited + granted may be in flight in the old shape: the switch is the one after.
std::uint32_t switchFrame(std::uint32_t lastCredited, std::uint32_t granted);

}  // namespace wall::service
