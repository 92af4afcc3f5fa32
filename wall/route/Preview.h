#pragma once
// The whole-wall preview: the canvas (bezels included) shrunk by a box filter of `factor` x
// `factor` pixels, small enough to travel to render rank 0 next to the real frames and to be
// served to a browser, yet detailed enough to steer by: previewFactor keeps it 513-1024 cells
// on its longest side (the canvas itself, factor 1, when that is smaller). The preview's cell
// (cx, cy) covers canvas pixels [cx·f, (cx+1)·f) x [cy·f, (cy+1)·f), clipped to the canvas: edge
// cells of a canvas whose sides are no multiple of f cover fewer pixels and average only those.
#include <cstdint>
#include <vector>

#include "dfb/Tile.h"
#include "wall/image/Image.h"
#include "wall/layout/Layout.h"

namespace wall {

struct PreviewGrid {
  int canvasWidth = 0, canvasHeight = 0;
  int factor = 8;
  int width() const { return (canvasWidth + factor - 1) / factor; }
  int height() const { return (canvasHeight + factor - 1) / factor; }
  // The cells that `canvas` (a region of the canvas) touches.
  dfb::Region cellsOf(const dfb::Region& canvas) const;
  // The canvas pixels of cell (cx, cy), clipped to the canvas.
  dfb::Region cellPixels(int cx, int cy) const;
};

// The factor for a canvas: the smallest power of two (1, 2, 4, ...) that keeps the preview at
// most `maxSide` cells on a side, so the page shows more than maxSide/2 cells across whatever the
// wall's size (a small wall is not a mosaic, a large one not a second wall). A power of two
// divides the tile sizes people pick (64), so every cell lies in one tile (exact averages).
int previewFactor(int canvasWidth, int canvasHeight, int maxSide = 1024);

// Box-filters the RGBA8 pixels of canvas region `region` (rows of `stride` pixels starting at
// `pixels`, whose first pixel is the region's top-left) into the cells grid.cellsOf(region),
// row-major. Each cell is the average of its pixels inside `region`, per channel, rounded to
// nearest (ties up).
std::vector<std::uint32_t> downsample(const PreviewGrid& grid, const dfb::Region& region,
                                      const std::uint32_t* pixels, int stride);
// The same for a whole canvas image: the reference the assembled preview must equal.
Image downsample(const PreviewGrid& grid, const Image& canvas);

// What the controller page shows: the raw preview with every cell whose centre no display
// shows (bezels, gaps) drawn dark, opaque, and each display's outline (its edge cells) mixed
// half and half with light grey. A display whose index is set in `lost` (a service wall lost its
// process: it shows nothing of the job) is crossed out and outlined in red.
Image decoratePreview(const Image& raw, const PreviewGrid& grid, const Layout* layout,
                      const std::vector<bool>& lost = {});

}  // namespace wall
