#pragma once
// Renders a whole canvas tile by tile, as the frame driver does, without the DFB.
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "renderers/Camera.h"
#include "renderers/CanvasImage.h"
#include "renderers/Renderer.h"
#include "renderers/scivis/scene/Box.h"

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

// A camera ray through the centre of pixel (x, y), entering the box at t0 and leaving at t1.
struct PixelRay {
  int x, y;
  Vec3 origin, dir;
  float t0, t1;
};

// The rays through the pixels (x0 + i dx, y0 + j dy) of a width x height canvas that meet `box`,
// row by row.
inline std::vector<PixelRay> pixelRaysThrough(const Camera& camera, int width, int height, int x0,
                                              int dx, int y0, int dy, const scivis::Box3& box) {
  std::vector<PixelRay> rays;
  for (int y = y0; y < height; y += dy)
    for (int x = x0; x < width; x += dx) {
      PixelRay r{x, y, {}, {}, 0, scivis::Box3::kInf};
      camera.ray(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f, 0.5f, 0.5f, r.origin,
                 r.dir);
      if (scivis::clipToBox(box, r.origin, scivis::reciprocal(r.dir), r.t0, r.t1))
        rays.push_back(r);
    }
  return rays;
}

inline std::vector<float> renderImage(const Renderer& r, int width, int height, int tileSize,
                                      int threads, std::uint32_t spp,
                                      std::uint32_t accumulationId = 0,
                                      std::uint32_t firstSample = 0) {
  return renderCanvas(r, width, height, tileSize, threads, spp, accumulationId, firstSample);
}

}  // namespace renderers::test
