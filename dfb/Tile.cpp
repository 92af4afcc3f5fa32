#include "dfb/Tile.h"

#include <algorithm>
#include <string>

#include "base/Error.h"

namespace dfb {

Region intersect(const Region& a, const Region& b) {
  Region r{std::max(a.x0, b.x0), std::max(a.y0, b.y0), std::min(a.x1, b.x1), std::min(a.y1, b.y1)};
  if (r.empty()) return Region{};
  return r;
}

bool isSaneRegion(const Region& r, int maxSide) {
  const std::int64_t w = std::int64_t{r.x1} - r.x0, h = std::int64_t{r.y1} - r.y0;
  return w > 0 && h > 0 && w <= maxSide && h <= maxSide;
}

void Tile::reset(const Region& r, bool withDepth) {
  region = r;
  const size_t n = static_cast<size_t>(r.pixelCount());
  color.assign(4 * n, 0.0f);
  if (withDepth)
    depth.assign(n, 0.0f);
  else
    depth.clear();
}

TileGrid::TileGrid(int width, int height, int tileSize)
    : width_(width), height_(height), tileSize_(tileSize) {
  if (width <= 0 || height <= 0 || tileSize <= 0)
    throw base::Error("image " + std::to_string(width) + "x" + std::to_string(height) +
                      " with tile size " + std::to_string(tileSize) + ": all must be positive");
  tilesX_ = (width + tileSize - 1) / tileSize;
  tilesY_ = (height + tileSize - 1) / tileSize;
}

Region TileGrid::region(int tileIndex) const {
  const int tx = tileIndex % tilesX_, ty = tileIndex / tilesX_;
  return Region{tx * tileSize_, ty * tileSize_, std::min(width_, (tx + 1) * tileSize_),
                std::min(height_, (ty + 1) * tileSize_)};
}

int TileGrid::indexOfOrigin(int x0, int y0) const {
  if (x0 < 0 || y0 < 0 || x0 >= width_ || y0 >= height_ || x0 % tileSize_ || y0 % tileSize_)
    return -1;
  return (y0 / tileSize_) * tilesX_ + x0 / tileSize_;
}

}  // namespace dfb
