// A display several jobs share, each in its window (wall/display/WindowStack.h), on a real
// offscreen presenter: two overlapping windows, the newest on top; each job's frame shows at its
// own swap while the other's last frame stays; a window that goes shows what was under it; what
// a job reads back is its own part, covered or not.
#include <gtest/gtest.h>

#include "wall/display/OsmesaPresenter.h"
#include "wall/display/WindowStack.h"

namespace {

constexpr int kWidth = 64, kHeight = 48;
constexpr std::uint32_t kBackground = 0xff000000u;
const dfb::Region kPartA{0, 0, 40, 30};    // the older window
const dfb::Region kPartB{24, 10, 64, 48};  // the newer, over A's corner and the display's

// A frame of a window's part: every pixel tells the frame and where it is.
wall::Image frameOf(const dfb::Region& part, std::uint32_t frame) {
  wall::Image image(part.width(), part.height());
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      image.pixels[static_cast<size_t>(y * image.width + x)] =
          0xff000000u | (frame << 16) | static_cast<std::uint32_t>(y << 8 | x);
  return image;
}

// As a node presents: begin, upload in two halves, draw, (the swap barrier), swap.
void upload(wall::Presenter& p, const wall::Image& frame) {
  p.beginFrame(frame.width, frame.height);
  const int half = frame.height / 2;
  p.upload(frame.pixels.data(), frame.width, {0, 0, frame.width, half});
  p.upload(frame.pixels.data(), frame.width, {0, half, frame.width, frame.height});
  p.draw();
}

// What the display must show: the background, then each part given (bottom first).
wall::Image expected(const std::vector<std::pair<dfb::Region, const wall::Image*>>& parts) {
  wall::Image out(kWidth, kHeight, kBackground);
  for (const auto& [part, image] : parts)
    for (int y = part.y0; y < part.y1; ++y)
      for (int x = part.x0; x < part.x1; ++x)
        out.pixels[static_cast<size_t>(y * kWidth + x)] = image->at(x - part.x0, y - part.y0);
  return out;
}

TEST(WindowStack, WindowsComposeNewestOnTopEachAtItsOwnSwap) {
  auto display = wall::makeOsmesaPresenter(kWidth, kHeight);
  wall::WindowStack stack(*display, kWidth, kHeight, kBackground);
  stack.present();
  EXPECT_EQ(display->readBack(), wall::Image(kWidth, kHeight, kBackground));

  auto a = stack.add(kPartA);
  auto b = stack.add(kPartB);
  EXPECT_EQ(stack.layers(), 2u);
  const wall::Image a1 = frameOf(kPartA, 1), b1 = frameOf(kPartB, 1);
  upload(*a, a1);
  a->swap();
  // B has shown nothing yet: A over the background.
  EXPECT_EQ(display->readBack(), expected({{kPartA, &a1}}));

  // B's frame is uploaded and drawn but not swapped: not on the display yet.
  upload(*b, b1);
  EXPECT_EQ(display->readBack(), expected({{kPartA, &a1}}));
  b->swap();
  EXPECT_EQ(display->readBack(), expected({{kPartA, &a1}, {kPartB, &b1}}));

  // A goes on alone (B is slow or gone quiet): A's new frame under B's last one.
  const wall::Image a2 = frameOf(kPartA, 2);
  upload(*a, a2);
  a->swap();
  EXPECT_EQ(display->readBack(), expected({{kPartA, &a2}, {kPartB, &b1}}));
  // Each job reads back its own part as it presented it, covered or not.
  EXPECT_EQ(a->readBack(), a2);
  EXPECT_EQ(b->readBack(), b1);

  // B's job ends: its window leaves the display at once, A shows whole.
  b.reset();
  EXPECT_EQ(stack.layers(), 1u);
  EXPECT_EQ(display->readBack(), expected({{kPartA, &a2}}));
  a.reset();
  EXPECT_EQ(display->readBack(), wall::Image(kWidth, kHeight, kBackground));
}

TEST(WindowStack, ARaisedWindowGoesOnTopAndALateLayerTakesItsPlaceByOrder) {
  auto display = wall::makeOsmesaPresenter(kWidth, kHeight);
  wall::WindowStack stack(*display, kWidth, kHeight, kBackground);
  auto a = stack.add(kPartA, 1);
  auto b = stack.add(kPartB, 2);
  const wall::Image a1 = frameOf(kPartA, 1), b1 = frameOf(kPartB, 1);
  upload(*a, a1);
  a->swap();
  upload(*b, b1);
  b->swap();
  EXPECT_EQ(display->readBack(), expected({{kPartA, &a1}, {kPartB, &b1}}));
  // Raised (the window manager's order 3): A over B at once, without a new frame of either.
  stack.setOrder(*a, 3);
  EXPECT_EQ(display->readBack(), expected({{kPartB, &b1}, {kPartA, &a1}}));
  // A layer added with a lower order (a process that joins a running job, or a Start overtaken
  // by a Raise) goes beneath the higher ones, not on top.
  const dfb::Region partC{0, 0, 64, 48};
  auto c = stack.add(partC, 2);
  const wall::Image c1 = frameOf(partC, 1);
  upload(*c, c1);
  c->swap();
  EXPECT_EQ(display->readBack(), expected({{kPartB, &b1}, {partC, &c1}, {kPartA, &a1}}));
  EXPECT_ANY_THROW(stack.setOrder(*display, 1));  // not a layer
}

TEST(WindowStack, APartOutsideTheDisplayOrAnUploadOutsideThePartIsRefused) {
  auto display = wall::makeOsmesaPresenter(kWidth, kHeight);
  wall::WindowStack stack(*display, kWidth, kHeight, kBackground);
  EXPECT_ANY_THROW(stack.add({40, 0, 80, 10}));
  EXPECT_ANY_THROW(stack.add({10, 10, 10, 20}));
  auto a = stack.add(kPartA);
  const wall::Image big = frameOf({0, 0, 41, 30}, 1);
  EXPECT_ANY_THROW(a->upload(big.pixels.data(), big.width, {0, 0, 41, 30}));
}

}  // namespace
