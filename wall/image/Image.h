#pragma once
// An RGBA8 image in memory, the pixel format of everything the wall shows: one uint32 per
// pixel, R in the low byte (bytes R, G, B, A in memory on the little-endian machines we run on,
// as dfb::FinishedTile::rgba8 has them), rows top to bottom.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "dfb/Tile.h"

namespace wall {

struct Image {
  int width = 0, height = 0;
  std::vector<std::uint32_t> pixels;  // width * height, row-major, row 0 at the top

  Image() = default;
  Image(int w, int h, std::uint32_t fill = 0);
  std::uint32_t& at(int x, int y) { return pixels[static_cast<std::size_t>(y) * width + x]; }
  const std::uint32_t& at(int x, int y) const {
    return pixels[static_cast<std::size_t>(y) * width + x];
  }
  bool operator==(const Image&) const = default;
};

constexpr std::uint32_t rgba8(std::uint8_t r, std::uint8_t g, std::uint8_t b,
                              std::uint8_t a = 255) {
  return std::uint32_t{r} | std::uint32_t{g} << 8 | std::uint32_t{b} << 16 | std::uint32_t{a} << 24;
}

// Copies the `w` x `h` pixels at `src` (rows of `w`) into `dst` with their top-left at (x, y).
// The rectangle must lie inside `dst`; throws base::Error otherwise.
void blit(Image& dst, int x, int y, const std::uint32_t* src, int w, int h);

// The pixels of `region` of `src` as a new image (region must lie inside `src`). Tests cut each
// display's rectangle out of a whole-canvas render with it.
Image crop(const Image& src, const dfb::Region& region);

}  // namespace wall
