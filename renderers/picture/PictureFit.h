#pragma once
// A picture fitted into a window: scaled to the largest size that keeps its aspect, centred,
// letterboxed with a background colour, scaled by nearest or bilinear filtering. Integer
// arithmetic only (exact rationals, rounded once), so every pixel is reproducible anywhere and
// by an independent program (tests/apps/picture_expected.py).
#include <cstdint>
#include <string>

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

}  // namespace renderers::picture
