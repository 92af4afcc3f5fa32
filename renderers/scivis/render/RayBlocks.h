#pragma once
// The order a batch of tile rows' camera rays go to SciVisRenderer::integrate() in: 4x4 pixel
// blocks (each pixel's samples together), so each 16-ray Embree packet integrate() makes of
// consecutive rays is a compact square of the screen, not a 16-pixel run of one row. Embree's
// packet traversal keeps a packet together while its rays visit the same nodes: a square's rays
// diverge less than a row's. The order changes no ray's hit (packet and single-ray hits agree
// bit for bit, SciVisScene::intersectSurfaces), only how fast they are found.
#include <algorithm>
#include <cstdint>
#include <vector>

namespace renderers::scivis {

constexpr int kRayBlockSide = 4;

// order[k] = the row-major index (row * width * samples + x * samples + s) of the k-th ray of
// `rows` rows of `width` pixels with `samples` rays each, in block order: bands of 4 rows, in
// each band columns of 4 pixels, in each column its rows top down, each row's rays left to right
// (bands and columns at the edges are what is left).
inline void rayBlockOrder(int width, int rows, std::uint32_t samples,
                          std::vector<std::uint32_t>& order) {
  const std::uint32_t rowLength = static_cast<std::uint32_t>(width) * samples;
  order.clear();
  order.reserve(static_cast<std::size_t>(rows) * rowLength);
  for (int y0 = 0; y0 < rows; y0 += kRayBlockSide)
    for (int x0 = 0; x0 < width; x0 += kRayBlockSide) {
      const int y1 = std::min(rows, y0 + kRayBlockSide), x1 = std::min(width, x0 + kRayBlockSide);
      for (int y = y0; y < y1; ++y) {
        const std::uint32_t row = static_cast<std::uint32_t>(y) * rowLength;
        for (std::uint32_t i = static_cast<std::uint32_t>(x0) * samples;
             i < static_cast<std::uint32_t>(x1) * samples; ++i)
          order.push_back(row + i);
      }
    }
}

// rayBlockOrder() of the last shape asked for, made again only when the shape changes: a tile's
// row batches (and most tiles) share one, so the per-batch hot path only reads it.
class RayBlockOrderCache {
 public:
  const std::vector<std::uint32_t>& of(int width, int rows, std::uint32_t samples) {
    if (width != width_ || rows != rows_ || samples != samples_) {
      rayBlockOrder(width, rows, samples, order_);
      width_ = width, rows_ = rows, samples_ = samples;
    }
    return order_;
  }

 private:
  int width_ = -1, rows_ = -1;
  std::uint32_t samples_ = 0;
  std::vector<std::uint32_t> order_;
};

}  // namespace renderers::scivis
