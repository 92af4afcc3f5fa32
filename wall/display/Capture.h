#pragma once
// Where captures go and what the whole-wall preview looks like (--capture DIR):
//   DIR/<display name>/frame-<frame id>.png   one per display, the display's own pixels
//   DIR/wall-<frame id>.png                   the canvas: displays at their places, the rest dark
// Frame ids are zero-padded to 6 digits (wider once they pass 999999, so names stay unique).
// The operator's own --capture DIR may be any folder; a service wall writes a job's captures only
// beneath its --capture-root, no link followed, up to a byte quota (docs/security.md,
// "Captures stay in their folder").
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "base/ConfinedFolder.h"
#include "base/Error.h"
#include "wall/image/Image.h"
#include "wall/layout/Layout.h"

namespace wall {

// Pixels of the canvas that no display shows (bezels, gaps) in the preview.
constexpr std::uint32_t kBezelColor = rgba8(24, 24, 24);

std::string displayCapturePath(const std::string& dir, const std::string& displayName,
                               std::uint32_t frameId);
std::string wallPreviewPath(const std::string& dir, std::uint32_t frameId);

// A capture that could not be written (a folder refused, the quota spent, a full disk): a service
// wall ends the job with it rather than leaving the job's other processes to go on.
class CaptureError : public base::Error {
 public:
  using base::Error::Error;
};

// One run's captures, written atomically (base/AtomicFile.h) and counted.
class CaptureWriter {
 public:
  // Into the operator's folder `dir`, made with its parents as needed; no quota.
  explicit CaptureWriter(std::string dir);
  // Into `relative` beneath `root` (what resolveCaptureRequest returned), folders reached and
  // made without following a link, at most `quota` bytes in all (0: no limit). `whose` names
  // the captures in the quota's message.
  CaptureWriter(std::shared_ptr<const base::ConfinedFolder> root, std::string relative,
                std::uint64_t quota, std::string whose = "the job's captures");

  // Display `display`'s frame (its rect's width x height pixels); returns the path. Throws
  // CaptureError.
  std::string writeDisplay(const Layout& layout, int display, std::uint32_t frameId,
                           const std::uint32_t* rgba8);
  std::string writeWallPreview(std::uint32_t frameId, const Image& canvas);
  std::uint64_t bytesWritten() const { return written_; }

 private:
  // A width x height PNG as `name` in the capture folder's sub-folder `sub` ("" for the folder
  // itself). It is written to its temporary, weighed, and given its name only within the quota.
  std::string write(const std::string& sub, const std::string& name, const std::uint32_t* rgba8,
                    int width, int height);

  std::string dir_;  // the operator's folder, or the job's beneath root_
  std::shared_ptr<const base::ConfinedFolder> root_;
  std::uint64_t quota_ = 0, written_ = 0;
  std::string whose_;
};

// Writes display `display`'s frame into the operator's folder `dir`; returns the path.
std::string writeDisplayCapture(const std::string& dir, const Layout& layout, int display,
                                std::uint32_t frameId, const std::uint32_t* rgba8);

// For setup, before any frame: the folder of each display of wall process `process` under `dir`
// made and writable. Returns the first problem, or an empty string.
std::string checkCaptureFolders(const std::string& dir, const Layout& layout, int process);

// serve --capture DIR, at start: the folder of each display of wall process `process` beneath
// `dir` made (no link followed) and writable. Returns the first problem, or an empty string.
std::string checkWallCaptureFolders(const base::ConfinedFolder& dir, const Layout& layout,
                                    int process);

// A service wall, when a job asks for captures in `request`: its folder beneath `root`, as a path
// relative to it ("." for the root itself), with the folders of process `process`'s displays
// checked the same way. Creates nothing: the folders are made at the first capture, once the job
// was accepted. Throws base::Error saying why (no root: the option that allows captures).
std::string resolveCaptureRequest(const base::ConfinedFolder* root, const std::string& request,
                                  const Layout& layout, int process);

// The canvas with each display's pixels at its place and kBezelColor elsewhere.
// `displayPixels[i]` holds display i's pixels, or is null to leave that display dark too.
Image composeWallPreview(const Layout& layout,
                         const std::vector<const std::uint32_t*>& displayPixels);

}  // namespace wall
