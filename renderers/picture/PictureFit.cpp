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

Tap nearestTap(int u, int scaled, int source) {
  return {static_cast<int>((2 * i64(u) + 1) * source / (2 * i64(scaled))), 0, 0};
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
    return at(nearestTap(u, p.width, pw).first, nearestTap(v, p.height, ph).first);
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

FittedPicture::FittedPicture(std::shared_ptr<const Picture> picture, int windowWidth,
                             int windowHeight, Filter filter, std::uint32_t background)
    : picture_(std::move(picture)),
      placement_(fitPicture(picture_->width, picture_->height, windowWidth, windowHeight)),
      filter_(filter),
      background_(background) {
  auto taps = [filter](int scaled, int source) {
    std::vector<Tap> out;
    for (int u = 0; u < scaled; ++u) {
      const ::renderers::picture::Tap t = filter == Filter::Nearest
                                              ? nearestTap(u, scaled, source)
                                              : bilinearTap(u, scaled, source);
      out.push_back({t.first, t.second, static_cast<std::uint64_t>(t.weight)});
    }
    return out;
  };
  columns_ = taps(placement_.width, picture_->width);
  rows_ = taps(placement_.height, picture_->height);
}

void FittedPicture::row(int y, int x0, int x1, std::uint32_t* out) const {
  const Placement& p = placement_;
  const int v = y - p.y;
  const int inside0 = std::clamp(p.x, x0, x1), inside1 = std::clamp(p.x + p.width, x0, x1);
  if (v < 0 || v >= p.height || inside0 >= inside1) {
    std::fill(out, out + (x1 - x0), background_);
    return;
  }
  std::fill(out, out + (inside0 - x0), background_);
  std::fill(out + (inside1 - x0), out + (x1 - x0), background_);
  const std::size_t pw = static_cast<std::size_t>(picture_->width);
  const std::uint32_t* const source = picture_->rgba.data();
  const Tap& r = rows_[static_cast<std::size_t>(v)];
  const std::uint32_t* const top = source + static_cast<std::size_t>(r.first) * pw;
  std::uint32_t* o = out + (inside0 - x0);
  if (filter_ == Filter::Nearest) {
    for (int x = inside0; x < inside1; ++x)
      *o++ = top[columns_[static_cast<std::size_t>(x - p.x)].first];
    return;
  }
  const std::uint32_t* const bottom = source + static_cast<std::size_t>(r.second) * pw;
  // Signed 64-bit: the sums stay below 2^43 (and convert to double in one instruction, which
  // unsigned ones do not). The divisor is at most 2^34, so the double quotient is exact enough
  // to floor: a fraction is at least 1/divisor from the next integer, far above a rounding.
  const i64 dx = 2 * i64(p.width), dy = 2 * i64(p.height), wy = static_cast<i64>(r.weight);
  const i64 half = dx * dy / 2;
  const double divisor = static_cast<double>(dx * dy);
  for (int x = inside0; x < inside1; ++x) {
    const Tap& c = columns_[static_cast<std::size_t>(x - p.x)];
    const std::uint32_t c00 = top[c.first], c10 = top[c.second], c01 = bottom[c.first],
                        c11 = bottom[c.second];
    const i64 wx = static_cast<i64>(c.weight), left = dx - wx;
    std::uint32_t pixel = 0;
    for (int k = 0; k < 4; ++k) {
      const i64 upper = i64(channel(c00, k)) * left + i64(channel(c10, k)) * wx;
      const i64 lower = i64(channel(c01, k)) * left + i64(channel(c11, k)) * wx;
      const i64 sum = upper * (dy - wy) + lower * wy + half;
      pixel |= static_cast<std::uint32_t>(static_cast<int>(static_cast<double>(sum) / divisor))
               << (8 * k);
    }
    *o++ = pixel;
  }
}

}  // namespace renderers::picture
