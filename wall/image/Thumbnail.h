#pragma once
// A window's thumbnail for the wall's control page (docs/service.md, "The wall's control
// page"): the window's pixels shrunk by a box filter of a whole factor, each cell the rounded mean
// of the window's pixels inside it that some display shows (bezels show nothing). Each wall
// process sums the cells over its own displays' parts of the window (CellSums), so only the sums
// travel; the head adds every process's sums and averages them.
#include <cstdint>
#include <vector>

#include "dfb/Tile.h"
#include "wall/image/Image.h"

namespace wall {

// The longest side a thumbnail may have (serve --thumbnail-size takes 16 up to this).
constexpr int kMaxThumbnailSide = 320;

// The cells of a window's thumbnail: `factor` x `factor` pixels each, the last column and row
// cut by the window's edge.
struct ThumbnailGrid {
  int factor = 1, width = 0, height = 0;
  bool operator==(const ThumbnailGrid&) const = default;
};
// 255 x 4096^2 + 4096^2 / 2 < 2^32: a cell's sums and their rounding fit 32 bits.
constexpr int kMaxThumbnailFactor = 4096;
// The smallest whole factor (up to kMaxThumbnailFactor) that keeps the longer side at most
// `maxSide` cells.
ThumbnailGrid thumbnailGrid(int windowWidth, int windowHeight, int maxSide);
// The cells that window pixels `pixels` (in the window's coordinates) touch.
dfb::Region cellsOf(const ThumbnailGrid& grid, const dfb::Region& pixels);

// Per cell of `cells` (row-major), kChannels values: the sums of R, G, B and A over the pixels
// added, and their count (at most kMaxThumbnailFactor^2 pixels of at most 255: 32 bits hold it).
struct CellSums {
  static constexpr int kChannels = 5;
  dfb::Region cells;
  std::vector<std::uint32_t> sums;
};
CellSums emptySums(const dfb::Region& cells);
// Adds `image`, whose top-left pixel is pixel (x, y) of the window, into `into` (whose cells must
// cover it; throws base::Error otherwise).
void addPixels(CellSums& into, const ThumbnailGrid& grid, const Image& image, int x, int y);
// The pixels of the window a cell covers (the last column and row are cut).
std::uint32_t cellArea(const ThumbnailGrid& grid, int windowWidth, int windowHeight, int cx,
                       int cy);
// The thumbnail: each cell the mean of its sums rounded to nearest; a cell with none keeps
// `previous`'s pixel when it is of the grid's size, else is transparent (0).
Image averageCells(const ThumbnailGrid& grid, const CellSums& sums, const Image* previous);

}  // namespace wall
