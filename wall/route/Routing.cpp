#include "wall/route/Routing.h"

#include <algorithm>

#include "base/Error.h"

namespace wall {
std::vector<Piece> piecesOf(const Layout& layout, const dfb::Region& tile) {
  std::vector<Piece> out;
  for (size_t i = 0; i < layout.displays.size(); ++i) {
    const dfb::Region& d = layout.displays[i].rect;
    const dfb::Region c = dfb::intersect(tile, d);
    if (c.empty()) continue;
    out.push_back(
        Piece{static_cast<int>(i), c, {c.x0 - d.x0, c.y0 - d.y0, c.x1 - d.x0, c.y1 - d.y0}});
  }
  return out;
}

dfb::TileGrid canvasTiles(const Layout& layout, int tileSize) {
  return dfb::TileGrid(layout.canvasWidth, layout.canvasHeight, tileSize);
}

std::vector<DisplayTile> tilesOfDisplay(const Layout& layout, int display, int tileSize) {
  const dfb::TileGrid tiles = canvasTiles(layout, tileSize);
  const dfb::Region& d = layout.displays.at(static_cast<size_t>(display)).rect;
  std::vector<DisplayTile> out;
  if (d.empty()) return out;
  // Only the tiles under the display's rectangle, not the whole canvas.
  for (int ty = d.y0 / tileSize; ty <= (d.y1 - 1) / tileSize; ++ty) {
    for (int tx = d.x0 / tileSize; tx <= (d.x1 - 1) / tileSize; ++tx) {
      const int index = ty * tiles.tilesX() + tx;
      const dfb::Region t = tiles.region(index);
      const dfb::Region c = dfb::intersect(t, d);
      out.push_back(DisplayTile{
          index, t, Piece{display, c, {c.x0 - d.x0, c.y0 - d.y0, c.x1 - d.x0, c.y1 - d.y0}}});
    }
  }
  return out;
}

std::vector<bool> tilesShownByAnyDisplay(const Layout& layout, int tileSize) {
  const dfb::TileGrid tiles = canvasTiles(layout, tileSize);
  std::vector<bool> shown(static_cast<size_t>(tiles.tileCount()), false);
  for (size_t i = 0; i < layout.displays.size(); ++i)
    for (const DisplayTile& t : tilesOfDisplay(layout, static_cast<int>(i), tileSize))
      shown[static_cast<size_t>(t.tileIndex)] = true;
  return shown;
}

}  // namespace wall
