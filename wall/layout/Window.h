#pragma once
// A job's window on a wall (docs/service.md, "A job in a window"): the part of the wall's canvas a
// render job covers. The job asks for it by rectangle, by a display's name, or as the whole
// canvas; the wall resolves the request against its layout and gives the job the window's own
// layout, so the job renders the window as its canvas and routes pieces as to any wall.
#include <cstdint>
#include <string>

#include "dfb/Tile.h"
#include "wall/layout/Layout.h"

namespace wall {

struct WindowRequest {
  enum class Kind : std::uint8_t { Full = 0, Rect = 1, Display = 2 };
  Kind kind = Kind::Full;
  dfb::Region rect;     // Rect: on the wall's canvas (bezels included)
  std::string display;  // Display: its name
};

// "full", "X,Y,W,H" or a display's name (letters, digits, '-', '_'). Throws base::Error naming
// what is wrong.
WindowRequest parseWindowRequest(const std::string& text);
// As the job wrote it, for messages and logs.
std::string windowText(const WindowRequest& request);

// The rectangle on `wall`'s canvas the request names; throws base::Error for an empty rectangle,
// one outside the canvas or an unknown display name (with the canvas size or the names).
dfb::Region resolveWindow(const Layout& wall, const WindowRequest& request);

// The layout a job in `window` (inside the canvas, non-empty) sees: its canvas is the window,
// its displays every display the window touches, clipped to it, in window coordinates, with
// the wall's names and processes (so process indices may have gaps), in the wall's order.
// processCount stays the wall's.
Layout windowLayout(const Layout& wall, const dfb::Region& window);

}  // namespace wall
