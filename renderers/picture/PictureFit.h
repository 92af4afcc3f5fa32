#pragma once
// A picture fitted into a window: scaled to the largest size that keeps its aspect, centred,
// letterboxed with a background colour, scaled by nearest or bilinear filtering. Integer
// arithmetic only (exact rationals, rounded once), so every pixel is reproducible anywhere and
// by an independent program (tests/apps/picture_expected.py).
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "renderers/picture/PictureFile.h"

namespace renderers::picture {

enum class Filter { Nearest, Bilinear };
// "nearest" or "bilinear"; base::Error otherwise.
Filter filterFromName(const std::string& name);

// Where the picture lands in the window, in window pixels.
struct Placement {
  int x = 0, y = 0, width = 0, height = 0;
};

// The picture pw x ph scaled into ww x wh keeping its aspect: one side fills the window, the
// other is pw*wh/ph (or ph*ww/pw) rounded to the nearest pixel (at least 1), centred with the
// odd pixel of the margin after it.
Placement fitPicture(int pictureWidth, int pictureHeight, int windowWidth, int windowHeight);

// The picture over `background` (RGBA8, R low): every pixel opaque,
// c = (c*a + b*(255 - a) + 127) / 255 per channel. Scaling the flattened picture equals scaling
// it premultiplied and then putting it over the background.
void flattenOver(Picture& picture, std::uint32_t background);

// Window pixel (x, y): the (flattened) picture sampled at the pixel's centre mapped into it,
// or `background` outside the placement.
//  nearest:  source column floor((2u+1) * pw / (2w)) for u = x - placement.x (rows alike);
//  bilinear: the source position (2u+1) * pw / (2w) - 1/2 clamped to [0, pw-1], as the
//            rational n / (2w); the four neighbours weighted by it, rounded to nearest once.
std::uint32_t fittedPixel(const Picture& picture, const Placement& placement, Filter filter,
                          std::uint32_t background, int x, int y);

// The same pixels a row at a time: every column's and row's source taps worked out once per
// picture and window, so a pixel costs multiplications and one exact division per channel
// (cheaper than fittedPixel: docs/benchmarks.md, "Pictures"). Thread-safe once built.
class FittedPicture {
 public:
  FittedPicture(std::shared_ptr<const Picture> picture, int windowWidth, int windowHeight,
                Filter filter, std::uint32_t background);
  // Window pixels x0 .. x1-1 of row y into out[0 .. x1-x0-1]; each equals fittedPixel's.
  void row(int y, int x0, int x1, std::uint32_t* out) const;
  const Placement& placement() const { return placement_; }

 private:
  struct Tap {
    int first = 0, second = 0;
    std::uint64_t weight = 0;  // of `second`, over 2 * the scaled size (bilinear)
  };
  std::shared_ptr<const Picture> picture_;
  Placement placement_;
  Filter filter_;
  std::uint32_t background_;
  std::vector<Tap> columns_, rows_;  // per placement column and row
};

}  // namespace renderers::picture
