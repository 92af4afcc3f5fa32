#include "wall/display/Capture.h"

#include <cstdio>
#include <filesystem>
#include <system_error>

#include "base/Error.h"
#include "wall/image/Png.h"

namespace wall {
namespace {

std::string frameName(const char* prefix, std::uint32_t frameId) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%s-%06u.png", prefix, static_cast<unsigned>(frameId));
  return buffer;
}

}  // namespace

std::string displayCapturePath(const std::string& dir, const std::string& displayName,
                               std::uint32_t frameId) {
  return (std::filesystem::path(dir) / displayName / frameName("frame", frameId)).string();
}

std::string wallPreviewPath(const std::string& dir, std::uint32_t frameId) {
  return (std::filesystem::path(dir) / frameName("wall", frameId)).string();
}

std::string writeDisplayCapture(const std::string& dir, const Layout& layout, int display,
                                std::uint32_t frameId, const std::uint32_t* rgba8) {
  const Display& d = layout.displays.at(static_cast<size_t>(display));
  const std::string path = displayCapturePath(dir, d.name, frameId);
  std::error_code ec;
  std::filesystem::create_directories(std::filesystem::path(path).parent_path(), ec);
  if (ec) throw base::Error(path + ": cannot create the capture folder: " + ec.message());
  writePng(path, rgba8, d.rect.width(), d.rect.height());
  return path;
}

Image composeWallPreview(const Layout& layout,
                         const std::vector<const std::uint32_t*>& displayPixels) {
  if (displayPixels.size() != layout.displays.size())
    throw base::Error("composeWallPreview: " + std::to_string(displayPixels.size()) +
                      " pixel buffers for " + std::to_string(layout.displays.size()) + " displays");
  Image canvas(layout.canvasWidth, layout.canvasHeight, kBezelColor);
  for (size_t i = 0; i < layout.displays.size(); ++i) {
    if (!displayPixels[i]) continue;
    const dfb::Region& r = layout.displays[i].rect;
    blit(canvas, r.x0, r.y0, displayPixels[i], r.width(), r.height());
  }
  return canvas;
}

}  // namespace wall
