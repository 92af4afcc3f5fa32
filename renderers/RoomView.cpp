#include "renderers/RoomView.h"

namespace renderers {

int RoomView::screenAt(int x, int y) const {
  // A linear search: a wall has tens of screens, and a ray costs far more than this.
  for (std::size_t s = 0; s < screens.size(); ++s) {
    const dfb::Region& r = screens[s].pixels;
    if (x >= r.x0 && x < r.x1 && y >= r.y0 && y < r.y1) return static_cast<int>(s);
  }
  return -1;
}

Vec3 RoomView::pointOn(int s, float px, float py) const {
  const ScreenView& v = screens[static_cast<std::size_t>(s)];
  const float across =
      (px - static_cast<float>(v.pixels.x0)) / static_cast<float>(v.pixels.width());
  const float down = (py - static_cast<float>(v.pixels.y0)) / static_cast<float>(v.pixels.height());
  return v.bottomLeft + (v.bottomRight - v.bottomLeft) * across +
         (v.topLeft - v.bottomLeft) * (1.0f - down);
}

}  // namespace renderers
