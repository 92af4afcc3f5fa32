#pragma once
// Renders a whole canvas tile by tile, as the frame driver does, without the DFB.
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "dfb/Tile.h"
#include "renderers/Parallel.h"
#include "renderers/Renderer.h"

namespace renderers::test {

// The Stanford bunny (75 k triangles) from Debian's libcgal-demo, unpacked once per machine into
// /tmp (each caller unpacks into a folder of its own and renames the file into place, so tests
// running in parallel never read half a file). Empty when the package is missing.
inline std::string cgalBunny() {
  namespace fs = std::filesystem;
  const fs::path target = "/tmp/dfbwall-assets/data/meshes/bunny00.off";
  const fs::path archive = "/usr/share/doc/libcgal-dev/data.tar.gz";
  if (fs::exists(target)) return target.string();
  if (!fs::exists(archive)) return {};
  const fs::path scratch =
      fs::temp_directory_path() / ("dfbwall-bunny-" + std::to_string(::getpid()));
  fs::create_directories(scratch);
  fs::create_directories(target.parent_path());
  const std::string command =
      "tar -xzf " + archive.string() + " -C " + scratch.string() + " data/meshes/bunny00.off";
  if (std::system(command.c_str()) == 0) {
    std::error_code ec;
    fs::rename(scratch / "data/meshes/bunny00.off", target, ec);
  }
  fs::remove_all(scratch);
  return fs::exists(target) ? target.string() : std::string();
}

inline std::vector<float> renderImage(const Renderer& r, int width, int height, int tileSize,
                                      int threads, std::uint32_t spp,
                                      std::uint32_t accumulationId = 0,
                                      std::uint32_t firstSample = 0) {
  std::vector<float> image(4 * static_cast<std::size_t>(width) * height, -1.0f);
  std::vector<dfb::Region> regions;
  for (int y = 0; y < height; y += tileSize)
    for (int x = 0; x < width; x += tileSize)
      regions.push_back({x, y, std::min(width, x + tileSize), std::min(height, y + tileSize)});
  ThreadLimit limit(threads);
  parallelFor(regions.size(), [&](std::size_t i) {
    dfb::Tile tile;
    r.render(regions[i], accumulationId, firstSample, spp, tile);
    const dfb::Region& g = tile.region;
    for (int y = g.y0; y < g.y1; ++y)
      std::memcpy(&image[4 * (static_cast<std::size_t>(y) * width + g.x0)],
                  &tile.color[4 * static_cast<std::size_t>(y - g.y0) * g.width()],
                  4 * sizeof(float) * g.width());
  });
  return image;
}

}  // namespace renderers::test
