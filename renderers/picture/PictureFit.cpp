#include "renderers/picture/PictureFit.h"

#include <algorithm>

#include "base/Error.h"

namespace renderers::picture {
namespace {

using u64 = std::uint64_t;
using i64 = std::int64_t;

std::uint32_t channel(std::uint32_t pixel, int c) { return (pixel >> (8 * c)) & 0xffu; }

// Source index and weight numerator (over `denominator` = 2 * scaled) of the bilinear sample for
// destination index u of `scaled` pixels mapped onto `source` pixels.
struct Tap {
  int first, second;
  i64 weight;  // of `second`, over the denominator
};
Tap bilinearTap(int u, int scaled, int source) {
  const i64 denominator = 2 * i64(scaled);
  const i64 n = (2 * i64(u) + 1) * source - scaled;  // (position - 1/2) * denominator
  if (n <= 0) return {0, 0, 0};
  const i64 first = n / denominator;
  if (first >= source - 1) return {source - 1, source - 1, 0};
  return {static_cast<int>(first), static_cast<int>(first + 1), n % denominator};
}

}  // namespace

Filter filterFromName(const std::string& name) {
  if (name == "nearest") return Filter::Nearest;
  if (name == "bilinear") return Filter::Bilinear;
  throw base::Error("--filter must be nearest or bilinear, not '" + name + "'");
}

Placement fitPicture(int pw, int ph, int ww, int wh) {
  Placement p;
  if (i64(pw) * wh <= i64(ph) * ww) {  // as tall as the window
    p.height = wh;
    p.width = static_cast<int>(std::clamp<i64>((2 * i64(pw) * wh + ph) / (2 * i64(ph)), 1, ww));
  } else {  // as wide
    p.width = ww;
    p.height = static_cast<int>(std::clamp<i64>((2 * i64(ph) * ww + pw) / (2 * i64(pw)), 1, wh));
  }
  p.x = (ww - p.width) / 2;
  p.y = (wh - p.height) / 2;
  return p;
}

void flattenOver(Picture& picture, std::uint32_t background) {
  for (std::uint32_t& pixel : picture.rgba) {
    const std::uint32_t a = channel(pixel, 3);
    std::uint32_t out = 0xff000000u;
    for (int c = 0; c < 3; ++c)
      out |= ((channel(pixel, c) * a + channel(background, c) * (255 - a) + 127) / 255) << (8 * c);
    pixel = out;
  }
}

std::uint32_t fittedPixel(const Picture& picture, const Placement& p, Filter filter,
                          std::uint32_t background, int x, int y) {
  const int u = x - p.x, v = y - p.y;
  if (u < 0 || v < 0 || u >= p.width || v >= p.height) return background;
  const int pw = picture.width, ph = picture.height;
  auto at = [&](int sx, int sy) {
    return picture
        .rgba[static_cast<size_t>(sy) * static_cast<size_t>(pw) + static_cast<size_t>(sx)];
  };
  if (filter == Filter::Nearest)
    return at(static_cast<int>((2 * i64(u) + 1) * pw / (2 * i64(p.width))),
              static_cast<int>((2 * i64(v) + 1) * ph / (2 * i64(p.height))));
  const Tap tx = bilinearTap(u, p.width, pw), ty = bilinearTap(v, p.height, ph);
  const u64 dx = 2 * u64(p.width), dy = 2 * u64(p.height);
  const u64 wx = u64(tx.weight), wy = u64(ty.weight);
  const std::uint32_t c00 = at(tx.first, ty.first), c10 = at(tx.second, ty.first),
                      c01 = at(tx.first, ty.second), c11 = at(tx.second, ty.second);
  std::uint32_t out = 0;
  for (int c = 0; c < 4; ++c) {
    const u64 top = channel(c00, c) * (dx - wx) + channel(c10, c) * wx;
    const u64 bottom = channel(c01, c) * (dx - wx) + channel(c11, c) * wx;
    const u64 value = (top * (dy - wy) + bottom * wy + dx * dy / 2) / (dx * dy);
    out |= static_cast<std::uint32_t>(value) << (8 * c);
  }
  return out;
}

}  // namespace renderers::picture
