#include "wall/service/server/WindowMoves.h"

namespace wall::service {

std::string windowMoveProblem(const Layout& wall, const dfb::Region& w) {
  const std::string text = std::to_string(w.x0) + "," + std::to_string(w.y0) + "," +
                           std::to_string(w.width()) + "," + std::to_string(w.height());
  if (w.x0 < 0 || w.y0 < 0 || w.x1 > wall.canvasWidth || w.y1 > wall.canvasHeight || w.x1 <= w.x0 ||
      w.y1 <= w.y0)
    return "window " + text + " is not inside the wall's canvas (" +
           std::to_string(wall.canvasWidth) + "x" + std::to_string(wall.canvasHeight) + ")";
  if (w.width() < kMinWindowSide || w.height() < kMinWindowSide)
    return "window " + text + " is smaller than " + std::to_string(kMinWindowSide) + "x" +
           std::to_string(kMinWindowSide);
  for (const Display& d : wall.displays)
    if (!dfb::intersect(d.rect, w).empty()) return {};
  return "window " + text + " touches no display (bezels only)";
}

std::uint32_t switchFrame(std::uint32_t lastCredited, std::uint32_t granted) {
  return lastCredited + granted + 1;
}

}  // namespace wall::service
