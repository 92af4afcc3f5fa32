#pragma once
// Ready-made pictures for `dfbwall show`: PNG (libpng's simplified API) and JPEG (TurboJPEG), as
// the wall's own images and codec read them, into RGBA8. The format is told by the file's first
// bytes, not its name; the size is checked against the memory budget (base/MemoryBudget.h) from
// the header, before any pixel is decoded.
#include <cstdint>
#include <string>
#include <vector>

namespace renderers::picture {

// RGBA8 with R in the low byte (as dfb::Tile::rgba8 and the wall), rows top to bottom.
struct Picture {
  int width = 0, height = 0;
  std::vector<std::uint32_t> rgba;
};

struct PictureHeader {
  int width = 0, height = 0;
  std::string format;  // "PNG" or "JPEG"
};

// The largest side a picture may have, whatever the memory budget says.
constexpr int kMaxPictureSide = 65536;

// The file's format and size. Throws base::Error naming the file: missing, unreadable, neither
// PNG nor JPEG, a header that does not parse, a side over kMaxPictureSide, or more pixels than
// this process may hold.
PictureHeader readPictureHeader(const std::string& path);
// The whole picture; the same errors, and a corrupt or truncated body.
Picture readPicture(const std::string& path);

}  // namespace renderers::picture
