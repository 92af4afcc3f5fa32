// A display seen by a job in a window (wall/display/WindowPresenter.h), on a real offscreen
// presenter: the display shows the window's part at its offset, uploaded piece by piece as a
// wall node does, and the background everywhere else, frame after frame; what the job reads back
// is its part only.
#include <gtest/gtest.h>

#include <random>

#include "wall/display/OsmesaPresenter.h"
#include "wall/display/WindowPresenter.h"

namespace {

wall::Image noise(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  wall::Image img(w, h);
  for (auto& p : img.pixels) p = static_cast<std::uint32_t>(rng());
  return img;
}

// The part's frame uploaded in pieces of `tile` pixels (clipped at its edges), as a node would.
void presentInPieces(wall::Presenter& p, const wall::Image& frame, int tile) {
  p.beginFrame(frame.width, frame.height);
  for (int y = 0; y < frame.height; y += tile)
    for (int x = 0; x < frame.width; x += tile)
      p.upload(frame.pixels.data(), frame.width,
               {x, y, std::min(x + tile, frame.width), std::min(y + tile, frame.height)});
  p.draw();
  p.swap();
}

TEST(WindowPresenter, ThePartSitsAtItsOffsetOverTheBackground) {
  constexpr int kWidth = 203, kHeight = 151;
  constexpr std::uint32_t kBackground = 0xff336699u;
  const dfb::Region part{37, 20, 160, 151};  // touches the bottom edge, not the others
  auto display = wall::makeOsmesaPresenter(kWidth, kHeight);
  wall::WindowPresenter window(*display, kWidth, kHeight, part, kBackground);
  for (unsigned frame = 1; frame <= 2; ++frame) {
    SCOPED_TRACE(frame);
    const wall::Image image = noise(part.width(), part.height(), frame);
    presentInPieces(window, image, 32);
    const wall::Image shown = display->readBack();
    ASSERT_EQ(shown.width, kWidth);
    ASSERT_EQ(shown.height, kHeight);
    size_t wrong = 0;
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x) {
        const bool inside = x >= part.x0 && x < part.x1 && y >= part.y0 && y < part.y1;
        const std::uint32_t expected = inside ? image.at(x - part.x0, y - part.y0) : kBackground;
        wrong += shown.at(x, y) != expected;
      }
    EXPECT_EQ(wrong, 0u) << "of " << kWidth * kHeight << " pixels";
    EXPECT_EQ(window.readBack(), image);  // the job's capture: its part only
  }
}

TEST(WindowPresenter, ADisplayOutsideTheWindowShowsTheBackground) {
  auto display = wall::makeOsmesaPresenter(64, 48);
  wall::WindowPresenter::presentBackground(*display, 64, 48, 0xff000000u);
  EXPECT_EQ(display->readBack(), wall::Image(64, 48, 0xff000000u));
  EXPECT_THROW(wall::WindowPresenter(*display, 64, 48, {60, 0, 65, 10}, 0), std::exception);
}

}  // namespace
