#include "renderers/CanvasImage.h"

#include <algorithm>
#include <cstring>

#include "base/Parallel.h"
#include "dfb/Tile.h"

namespace renderers {

void renderCanvas(const Renderer& renderer, int width, int height, int tileSize, int threads,
                  std::uint32_t spp, std::vector<float>& image, std::uint32_t accumulationId,
                  std::uint32_t firstSample) {
  image.resize(4 * static_cast<std::size_t>(width) * height);
  std::vector<dfb::Region> regions;
  for (int y = 0; y < height; y += tileSize)
    for (int x = 0; x < width; x += tileSize)
      regions.push_back({x, y, std::min(width, x + tileSize), std::min(height, y + tileSize)});
  base::ThreadLimit limit(threads);
  base::parallelFor(regions.size(), [&](std::size_t i) {
    dfb::Tile tile;
    renderer.render(regions[i], accumulationId, firstSample, spp, tile);
    const dfb::Region& g = tile.region;
    for (int y = g.y0; y < g.y1; ++y)
      std::memcpy(&image[4 * (static_cast<std::size_t>(y) * width + g.x0)],
                  &tile.color[4 * static_cast<std::size_t>(y - g.y0) * g.width()],
                  4 * sizeof(float) * g.width());
  });
}

std::vector<float> renderCanvas(const Renderer& renderer, int width, int height, int tileSize,
                                int threads, std::uint32_t spp, std::uint32_t accumulationId,
                                std::uint32_t firstSample) {
  // -1 where no tile wrote (tests see a tile left out).
  std::vector<float> image(4 * static_cast<std::size_t>(width) * height, -1.0f);
  renderCanvas(renderer, width, height, tileSize, threads, spp, image, accumulationId, firstSample);
  return image;
}

}  // namespace renderers
