#include "wall/display/Capture.h"

#include <fcntl.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <system_error>

#include "base/AtomicFile.h"
#include "base/MemoryBudget.h"
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

CaptureWriter::CaptureWriter(std::string dir) : dir_(std::move(dir)) {}

CaptureWriter::CaptureWriter(std::shared_ptr<const base::ConfinedFolder> root, std::string relative,
                             std::uint64_t quota, std::string whose)
    : dir_(std::move(relative)), root_(std::move(root)), quota_(quota), whose_(std::move(whose)) {}

std::string CaptureWriter::writeDisplay(const Layout& layout, int display, std::uint32_t frameId,
                                        const std::uint32_t* rgba8) {
  const Display& d = layout.displays.at(static_cast<size_t>(display));
  return write(d.name, frameName("frame", frameId), rgba8, d.rect.width(), d.rect.height());
}

std::string CaptureWriter::writeWallPreview(std::uint32_t frameId, const Image& canvas) {
  return write({}, frameName("wall", frameId), canvas.pixels.data(), canvas.width, canvas.height);
}

std::string CaptureWriter::write(const std::string& sub, const std::string& name,
                                 const std::uint32_t* rgba8, int width, int height) {
  const std::filesystem::path folder = std::filesystem::path(dir_) / sub;
  const std::string path =
      ((root_ ? std::filesystem::path(root_->path()) / folder : folder) / name).string();
  std::uint64_t bytes = 0;
  try {
    base::FileDescriptor at;
    if (root_) {
      at = root_->openFolder(folder.string(), true);
    } else {
      std::error_code ec;
      std::filesystem::create_directories(folder, ec);
      if (ec) throw base::Error(path + ": cannot create the capture folder: " + ec.message());
      at = base::FileDescriptor(open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
      if (!at.valid())
        throw base::Error(path + ": cannot open the capture folder: " + std::strerror(errno));
    }
    base::AtomicFile file(at.get(), name, path);
    writePngTo(file.stream(), path, rgba8, width, height);
    const long end = std::ftell(file.stream());
    bytes = end > 0 ? static_cast<std::uint64_t>(end) : 0;
    // Past the quota the temporary goes with `file`: the capture never gets its name.
    if (quota_ > 0 && written_ + bytes > quota_)
      throw CaptureError(path + ": not written: " + whose_ + " would pass the capture quota of " +
                         base::byteText(quota_) + " on this wall process (serve --capture-quota)");
    file.commit();  // a full disk shows here
  } catch (const CaptureError&) {
    throw;
  } catch (const base::Error& e) {
    throw CaptureError(e.what());
  }
  written_ += bytes;
  return path;
}

std::string writeDisplayCapture(const std::string& dir, const Layout& layout, int display,
                                std::uint32_t frameId, const std::uint32_t* rgba8) {
  return CaptureWriter(dir).writeDisplay(layout, display, frameId, rgba8);
}

std::string checkCaptureFolders(const std::string& dir, const Layout& layout, int process) {
  for (int d : layout.displaysOfProcess(process)) {
    const std::string folder =
        (std::filesystem::path(dir) / layout.displays[static_cast<size_t>(d)].name).string();
    if (std::string problem = base::checkWritableFolder(folder); !problem.empty()) return problem;
  }
  return {};
}

std::string checkWallCaptureFolders(const base::ConfinedFolder& dir, const Layout& layout,
                                    int process) {
  for (int d : layout.displaysOfProcess(process)) {
    const std::string& name = layout.displays[static_cast<size_t>(d)].name;
    try {
      dir.openFolder(name, true);
    } catch (const std::exception& e) {
      return e.what();
    }
    // Reached without a link just now: the probe's path leads where the captures will go.
    const std::string folder = (std::filesystem::path(dir.path()) / name).string();
    if (std::string problem = base::checkWritableFolder(folder); !problem.empty()) return problem;
  }
  return {};
}

std::string resolveCaptureRequest(const base::ConfinedFolder* root, const std::string& request,
                                  const Layout& layout, int process) {
  if (!root)
    throw base::Error(
        "this wall writes no captures for jobs; its operator allows them beneath a "
        "folder with serve --capture-root DIR");
  std::string relative = root->resolve(request);
  if (relative.empty()) relative = ".";
  for (int d : layout.displaysOfProcess(process))
    root->resolve(relative + "/" + layout.displays[static_cast<size_t>(d)].name);
  return relative;
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
