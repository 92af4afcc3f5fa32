#include "wall/display/WindowPresenter.h"

#include <algorithm>

#include "base/Error.h"

namespace wall {

WindowPresenter::WindowPresenter(Presenter& display, int width, int height, const dfb::Region& part,
                                 std::uint32_t background)
    : display_(display), width_(width), height_(height), part_(part), background_(width, height) {
  if (part.empty() || part.x0 < 0 || part.y0 < 0 || part.x1 > width || part.y1 > height)
    throw base::Error("a window's part of a display lies outside it");
  std::fill(background_.pixels.begin(), background_.pixels.end(), background);
}

void WindowPresenter::presentBackground(Presenter& display, int width, int height,
                                        std::uint32_t background) {
  Image image(width, height);
  std::fill(image.pixels.begin(), image.pixels.end(), background);
  display.present(image.pixels.data(), width, height);
}

// The texture's contents are undefined after beginFrame: the background around the part goes
// in with every frame (at most four strips; the part itself is the job's).
void WindowPresenter::beginFrame(int, int) {
  display_.beginFrame(width_, height_);
  const dfb::Region strips[] = {{0, 0, width_, part_.y0},
                                {0, part_.y1, width_, height_},
                                {0, part_.y0, part_.x0, part_.y1},
                                {part_.x1, part_.y0, width_, part_.y1}};
  for (const dfb::Region& strip : strips)
    if (!strip.empty()) display_.upload(background_.pixels.data(), width_, strip);
}

void WindowPresenter::uploadAt(const std::uint32_t* first, int stride, const dfb::Region& rect) {
  display_.uploadAt(
      first, stride,
      {rect.x0 + part_.x0, rect.y0 + part_.y0, rect.x1 + part_.x0, rect.y1 + part_.y0});
}

Image WindowPresenter::readBack() {
  const Image whole = display_.readBack();
  Image out(part_.width(), part_.height());
  if (whole.width < part_.x1 || whole.height < part_.y1)
    throw base::Error("reading a display back: " + std::to_string(whole.width) + "x" +
                      std::to_string(whole.height) + " pixels, smaller than its frame");
  for (int y = 0; y < out.height; ++y)
    std::copy_n(
        whole.pixels.begin() + static_cast<std::ptrdiff_t>(part_.y0 + y) * whole.width + part_.x0,
        out.width, out.pixels.begin() + static_cast<std::ptrdiff_t>(y) * out.width);
  return out;
}

}  // namespace wall
