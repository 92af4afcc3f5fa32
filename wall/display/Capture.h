#pragma once
// Where captures go and what the whole-wall preview looks like (--capture DIR):
//   DIR/<display name>/frame-<frame id>.png   one per display, the display's own pixels
//   DIR/wall-<frame id>.png                   the canvas: displays at their places, the rest dark
// Frame ids are zero-padded to 6 digits (wider once they pass 999999, so names stay unique).
#include <cstdint>
#include <string>
#include <vector>

#include "wall/image/Image.h"
#include "wall/layout/Layout.h"

namespace wall {

// Pixels of the canvas that no display shows (bezels, gaps) in the preview.
constexpr std::uint32_t kBezelColor = rgba8(24, 24, 24);

std::string displayCapturePath(const std::string& dir, const std::string& displayName,
                               std::uint32_t frameId);
std::string wallPreviewPath(const std::string& dir, std::uint32_t frameId);

// Writes display `display`'s frame (rect width x height pixels) to its capture path, creating
// DIR/<name>/ when needed; returns the path. Throws base::Error.
std::string writeDisplayCapture(const std::string& dir, const Layout& layout, int display,
                                std::uint32_t frameId, const std::uint32_t* rgba8);

// The canvas with each display's pixels at its place and kBezelColor elsewhere.
// `displayPixels[i]` holds display i's pixels, or is null to leave that display dark too.
Image composeWallPreview(const Layout& layout,
                         const std::vector<const std::uint32_t*>& displayPixels);

}  // namespace wall
