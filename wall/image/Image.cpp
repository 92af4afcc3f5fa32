#include "wall/image/Image.h"

#include <algorithm>
#include <string>

#include "base/Error.h"

namespace wall {
namespace {

void requireInside(int w, int h, const dfb::Region& r, const char* what) {
  if (r.x0 < 0 || r.y0 < 0 || r.x1 > w || r.y1 > h || r.x1 < r.x0 || r.y1 < r.y0)
    throw base::Error(std::string(what) + ": rectangle [" + std::to_string(r.x0) + ", " +
                      std::to_string(r.y0) + "] to [" + std::to_string(r.x1) + ", " +
                      std::to_string(r.y1) + ") is not inside the " + std::to_string(w) + "x" +
                      std::to_string(h) + " image");
}

}  // namespace

Image::Image(int w, int h, std::uint32_t fill)
    : width(w), height(h), pixels(static_cast<size_t>(std::max(w, 0)) * std::max(h, 0), fill) {}

void blit(Image& dst, int x, int y, const std::uint32_t* src, int w, int h) {
  requireInside(dst.width, dst.height, {x, y, x + w, y + h}, "blit");
  for (int row = 0; row < h; ++row)
    std::copy_n(src + static_cast<size_t>(row) * w, w, &dst.at(x, y + row));
}

Image crop(const Image& src, const dfb::Region& r) {
  requireInside(src.width, src.height, r, "crop");
  Image out(r.width(), r.height());
  for (int row = 0; row < out.height; ++row)
    std::copy_n(&src.at(r.x0, r.y0 + row), out.width, &out.at(0, row));
  return out;
}

}  // namespace wall
