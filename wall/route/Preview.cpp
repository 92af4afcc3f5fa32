#include "wall/route/Preview.h"

#include <algorithm>

#include "base/Error.h"

namespace wall {

dfb::Region PreviewGrid::cellsOf(const dfb::Region& canvas) const {
  if (canvas.empty()) return {};
  return {canvas.x0 / factor, canvas.y0 / factor, (canvas.x1 + factor - 1) / factor,
          (canvas.y1 + factor - 1) / factor};
}

dfb::Region PreviewGrid::cellPixels(int cx, int cy) const {
  return dfb::intersect({cx * factor, cy * factor, (cx + 1) * factor, (cy + 1) * factor},
                        {0, 0, canvasWidth, canvasHeight});
}

int previewFactor(int canvasWidth, int canvasHeight, int maxSide) {
  const int longest = std::max(canvasWidth, canvasHeight);
  int factor = 1;
  while ((longest + factor - 1) / factor > std::max(1, maxSide)) factor *= 2;
  return factor;
}

std::vector<std::uint32_t> downsample(const PreviewGrid& grid, const dfb::Region& region,
                                      const std::uint32_t* pixels, int stride) {
  const dfb::Region cells = grid.cellsOf(region);
  std::vector<std::uint32_t> out(static_cast<size_t>(cells.pixelCount()));
  // Channel sums two at a time: R and B, G and A, each in a 32-bit lane of a 64-bit word (no
  // lane overflows below 2^24 pixels a cell). The owner runs this on every finished tile, so it
  // is one pass over the pixels in memory order, with no division per pixel.
  std::vector<std::uint64_t> rb(static_cast<size_t>(cells.width()));
  std::vector<std::uint64_t> ga(static_cast<size_t>(cells.width()));
  for (int cy = cells.y0; cy < cells.y1; ++cy) {
    std::fill(rb.begin(), rb.end(), 0);
    std::fill(ga.begin(), ga.end(), 0);
    const int y0 = std::max(region.y0, cy * grid.factor);
    const int y1 = std::min(region.y1, (cy + 1) * grid.factor);
    for (int y = y0; y < y1; ++y) {
      const std::uint32_t* row = pixels + static_cast<size_t>(y - region.y0) * stride;
      for (int cx = cells.x0; cx < cells.x1; ++cx) {
        const int x0 = std::max(region.x0, cx * grid.factor);
        const int x1 = std::min(region.x1, (cx + 1) * grid.factor);
        std::uint64_t sumRb = 0, sumGa = 0;
        for (int x = x0; x < x1; ++x) {
          const std::uint64_t p = row[x - region.x0];
          sumRb += (p & 0xff) | (p & 0xff0000) << 16;
          sumGa += (p >> 8 & 0xff) | (p >> 24) << 32;
        }
        rb[static_cast<size_t>(cx - cells.x0)] += sumRb;
        ga[static_cast<size_t>(cx - cells.x0)] += sumGa;
      }
    }
    for (int cx = cells.x0; cx < cells.x1; ++cx) {
      const int x0 = std::max(region.x0, cx * grid.factor);
      const int x1 = std::min(region.x1, (cx + 1) * grid.factor);
      const std::uint64_t n = static_cast<std::uint64_t>((x1 - x0) * (y1 - y0));
      const size_t i = static_cast<size_t>(cx - cells.x0);
      const std::uint64_t sums[4] = {rb[i] & 0xffffffff, ga[i] & 0xffffffff, rb[i] >> 32,
                                     ga[i] >> 32};
      std::uint32_t p = 0;
      for (int c = 0; c < 4; ++c) p |= static_cast<std::uint32_t>((sums[c] + n / 2) / n) << (8 * c);
      out[static_cast<size_t>((cy - cells.y0) * cells.width() + (cx - cells.x0))] = p;
    }
  }
  return out;
}

Image downsample(const PreviewGrid& grid, const Image& canvas) {
  if (canvas.width != grid.canvasWidth || canvas.height != grid.canvasHeight)
    throw base::Error("downsample: the image is not the preview grid's canvas");
  Image out(grid.width(), grid.height());
  out.pixels =
      downsample(grid, {0, 0, canvas.width, canvas.height}, canvas.pixels.data(), canvas.width);
  return out;
}

Image decoratePreview(const Image& raw, const PreviewGrid& grid, const Layout* layout,
                      const std::vector<bool>& lost) {
  Image out = raw;
  for (std::uint32_t& p : out.pixels) p |= 0xff000000u;  // a preview is opaque
  if (!layout) return out;
  constexpr std::uint32_t kBezel = rgba8(24, 24, 28);
  constexpr std::uint32_t kOutline = rgba8(200, 200, 200);
  auto shown = [&](int x, int y) {
    for (const Display& d : layout->displays)
      if (x >= d.rect.x0 && x < d.rect.x1 && y >= d.rect.y0 && y < d.rect.y1) return true;
    return false;
  };
  for (int cy = 0; cy < out.height; ++cy)
    for (int cx = 0; cx < out.width; ++cx) {
      const dfb::Region c = grid.cellPixels(cx, cy);
      if (!shown((c.x0 + c.x1) / 2, (c.y0 + c.y1) / 2)) out.at(cx, cy) = kBezel;
    }
  // Outlines half over the picture: on a small canvas a cell is a lot of it.
  constexpr std::uint32_t kLost = rgba8(220, 40, 30);
  std::uint32_t color = kOutline;
  auto outline = [&](int x, int y) {
    const std::uint32_t p = out.at(x, y);
    std::uint32_t mixed = 0xff000000u;
    for (int c = 0; c < 3; ++c)
      mixed |= (((p >> (8 * c) & 0xff) + (color >> (8 * c) & 0xff) + 1) / 2) << (8 * c);
    out.at(x, y) = mixed;
  };
  for (size_t i = 0; i < layout->displays.size(); ++i) {
    const Display& d = layout->displays[i];
    const dfb::Region r = dfb::intersect(grid.cellsOf(d.rect), {0, 0, out.width, out.height});
    if (r.empty()) continue;
    const bool isLost = i < lost.size() && lost[i];
    color = isLost ? kLost : kOutline;
    if (isLost) {
      // Both diagonals: readable at any preview size, and not a picture a scene could make.
      const int w = r.width(), h = r.height();
      for (int k = 0; k < std::max(w, h); ++k) {
        const int x = r.x0 + k * w / std::max(w, h), y = r.y0 + k * h / std::max(w, h);
        out.at(x, y) = kLost;
        out.at(r.x1 - 1 - (x - r.x0), y) = kLost;
      }
    }
    for (int x = r.x0; x < r.x1; ++x) {
      outline(x, r.y0);
      if (r.y1 - 1 > r.y0) outline(x, r.y1 - 1);
    }
    for (int y = r.y0 + 1; y < r.y1 - 1; ++y) {
      outline(r.x0, y);
      if (r.x1 - 1 > r.x0) outline(r.x1 - 1, y);
    }
  }
  return out;
}

}  // namespace wall
