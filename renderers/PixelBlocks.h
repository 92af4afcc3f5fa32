#pragma once
// The 4x4 pixel blocks that camera rays are traced in, one Embree packet (RayPacket) each.
// Blocks are aligned to the canvas, not to the tile being rendered: a block that sticks out of
// the region is traced whole and its outside lanes are thrown away. So a packet holds the same
// rays whatever the tiling, and a pixel could not depend on the tile size even if a lane's hit
// depended on its neighbours (it does not: see Scene::intersect(RayPacket)).
#include <cstddef>

#include "dfb/Tile.h"
#include "renderers/Scene.h"

namespace renderers {

struct PixelBlock {
  static constexpr int kSide = 4;
  static_assert(kSide * kSide == RayPacket::kSize);
  int x0 = 0, y0 = 0;  // canvas pixel of lane 0; lanes go row by row
  int x(int lane) const { return x0 + lane % kSide; }
  int y(int lane) const { return y0 + lane / kSide; }
  bool inside(const dfb::Region& r, int lane) const {
    return x(lane) >= r.x0 && x(lane) < r.x1 && y(lane) >= r.y0 && y(lane) < r.y1;
  }
  // Index of the lane's pixel in a row-major buffer over `r` (lane inside `r`).
  std::size_t index(const dfb::Region& r, int lane) const {
    return static_cast<std::size_t>(y(lane) - r.y0) * static_cast<std::size_t>(r.width()) +
           static_cast<std::size_t>(x(lane) - r.x0);
  }
};

// Calls f(block) for every canvas-aligned block meeting `region` (canvas coordinates >= 0).
template <typename F>
void forEachBlock(const dfb::Region& region, F&& f) {
  constexpr int k = PixelBlock::kSide;
  for (int y = region.y0 - region.y0 % k; y < region.y1; y += k)
    for (int x = region.x0 - region.x0 % k; x < region.x1; x += k) f(PixelBlock{x, y});
}

}  // namespace renderers
