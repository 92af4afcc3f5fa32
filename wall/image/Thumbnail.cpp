#include "wall/image/Thumbnail.h"

#include <algorithm>
#include <string>

#include "base/Error.h"

namespace wall {

ThumbnailGrid thumbnailGrid(int windowWidth, int windowHeight, int maxSide) {
  const int longer = std::max({windowWidth, windowHeight, 1});
  // At most kMaxThumbnailFactor: a cell's sums then fit 32 bits (a canvas side of 2^20 pixels
  // still gives at most 256 cells).
  const int factor = std::clamp((longer + std::max(maxSide, 1) - 1) / std::max(maxSide, 1), 1,
                                kMaxThumbnailFactor);
  return {factor, (windowWidth + factor - 1) / factor, (windowHeight + factor - 1) / factor};
}

dfb::Region cellsOf(const ThumbnailGrid& grid, const dfb::Region& pixels) {
  if (pixels.empty()) return {};
  const int f = grid.factor;
  return {pixels.x0 / f, pixels.y0 / f, (pixels.x1 + f - 1) / f, (pixels.y1 + f - 1) / f};
}

CellSums emptySums(const dfb::Region& cells) {
  CellSums out;
  out.cells = cells;
  out.sums.assign(static_cast<std::size_t>(std::max(0, cells.pixelCount())) * CellSums::kChannels,
                  0);
  return out;
}

void addPixels(CellSums& into, const ThumbnailGrid& grid, const Image& image, int x, int y) {
  const dfb::Region touched = cellsOf(grid, {x, y, x + image.width, y + image.height});
  if (touched.empty()) return;
  const dfb::Region& c = into.cells;
  if (touched.x0 < c.x0 || touched.y0 < c.y0 || touched.x1 > c.x1 || touched.y1 > c.y1)
    throw base::Error("thumbnail: pixels outside the cells summed");
  const int f = grid.factor, stride = c.width();
  // By runs of a row inside one cell: the channels summed in registers, one division per cell.
  for (int row = 0; row < image.height; ++row) {
    const std::uint32_t* in = image.pixels.data() + static_cast<std::size_t>(row) * image.width;
    std::uint32_t* cellRow = into.sums.data() + static_cast<std::size_t>((y + row) / f - c.y0) *
                                                    stride * CellSums::kChannels;
    for (int col = 0; col < image.width;) {
      const int cx = (x + col) / f;
      const int end = std::min(image.width, (cx + 1) * f - x);
      std::uint32_t r = 0, g = 0, b = 0, a = 0;
      for (int i = col; i < end; ++i) {
        const std::uint32_t p = in[i];
        r += p & 0xffu;
        g += (p >> 8) & 0xffu;
        b += (p >> 16) & 0xffu;
        a += p >> 24;
      }
      std::uint32_t* cell = cellRow + static_cast<std::size_t>(cx - c.x0) * CellSums::kChannels;
      cell[0] += r;
      cell[1] += g;
      cell[2] += b;
      cell[3] += a;
      cell[4] += static_cast<std::uint32_t>(end - col);
      col = end;
    }
  }
}

std::uint32_t cellArea(const ThumbnailGrid& grid, int windowWidth, int windowHeight, int cx,
                       int cy) {
  const int f = grid.factor;
  const int w = std::min(windowWidth, (cx + 1) * f) - cx * f;
  const int h = std::min(windowHeight, (cy + 1) * f) - cy * f;
  return w > 0 && h > 0 ? static_cast<std::uint32_t>(w) * static_cast<std::uint32_t>(h) : 0;
}

Image averageCells(const ThumbnailGrid& grid, const CellSums& sums, const Image* previous) {
  if (sums.cells != dfb::Region{0, 0, grid.width, grid.height})
    throw base::Error("thumbnail: the sums are not of the whole grid");
  const bool keep = previous && previous->width == grid.width && previous->height == grid.height;
  Image out(grid.width, grid.height);
  for (std::size_t i = 0; i < out.pixels.size(); ++i) {
    const std::uint32_t* cell = sums.sums.data() + i * CellSums::kChannels;
    const std::uint32_t n = cell[4];
    if (n == 0) {
      out.pixels[i] = keep ? previous->pixels[i] : 0;
      continue;
    }
    std::uint32_t pixel = 0;
    for (int ch = 0; ch < 4; ++ch) pixel |= ((cell[ch] + n / 2) / n) << (8 * ch);
    out.pixels[i] = pixel;
  }
  return out;
}

}  // namespace wall
