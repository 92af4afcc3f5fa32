// The displays of a process that several jobs share, each in its window
// (wall/display/WindowStack.h): windows compose newest on top (or by stacking order, raised by
// the window manager), each at its own swap; a window's
// frame shows on every display of the process only whole, also while a job swaps on its thread
// as the presenting thread composes; a window that goes shows what was under it; what a job
// reads back is its own part; and the span composition equals a per-pixel reference on random
// stacks.
#include <gtest/gtest.h>

#include <atomic>
#include <random>
#include <thread>

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

// As a node presents: begin, upload in two halves, draw, (the swap barrier); the swap is the
// caller's.
void upload(wall::Presenter& p, const wall::Image& frame) {
  p.beginFrame(frame.width, frame.height);
  const int half = frame.height / 2;
  p.upload(frame.pixels.data(), frame.width, {0, 0, frame.width, half});
  p.upload(frame.pixels.data(), frame.width, {0, half, frame.width, frame.height});
  p.draw();
}

// What a display must show: the background, then each part given (bottom first), pixel by pixel.
wall::Image expected(int width, int height,
                     const std::vector<std::pair<dfb::Region, const wall::Image*>>& parts) {
  wall::Image out(width, height, kBackground);
  for (const auto& [part, image] : parts)
    for (int y = part.y0; y < part.y1; ++y)
      for (int x = part.x0; x < part.x1; ++x)
        out.pixels[static_cast<size_t>(y * width + x)] = image->at(x - part.x0, y - part.y0);
  return out;
}
wall::Image expected(const std::vector<std::pair<dfb::Region, const wall::Image*>>& parts) {
  return expected(kWidth, kHeight, parts);
}

TEST(WindowStack, WindowsComposeNewestOnTopEachAtItsOwnSwap) {
  wall::WindowStack stack({{kWidth, kHeight}}, kBackground);
  EXPECT_TRUE(stack.compose().empty());

  auto a = stack.add({kPartA});
  auto b = stack.add({kPartB});
  EXPECT_EQ(stack.windows(), 2u);
  // The first window: every display is composed again, the background where nothing shows yet.
  EXPECT_EQ(stack.compose(), std::vector<int>{0});
  EXPECT_EQ(stack.frame(0), wall::Image(kWidth, kHeight, kBackground));
  EXPECT_TRUE(stack.compose().empty());

  const wall::Image a1 = frameOf(kPartA, 1), b1 = frameOf(kPartB, 1);
  upload(*a->presenters()[0], a1);
  a->presenters()[0]->swap();
  // B has shown nothing yet: A over the background.
  EXPECT_EQ(stack.compose(), std::vector<int>{0});
  EXPECT_EQ(stack.frame(0), expected({{kPartA, &a1}}));

  // B's frame is uploaded and drawn but not swapped: nothing to compose yet.
  upload(*b->presenters()[0], b1);
  EXPECT_TRUE(stack.compose().empty());
  b->presenters()[0]->swap();
  EXPECT_EQ(stack.compose(), std::vector<int>{0});
  EXPECT_EQ(stack.frame(0), expected({{kPartA, &a1}, {kPartB, &b1}}));

  // A goes on alone (B is slow or gone quiet): A's new frame under B's last one.
  const wall::Image a2 = frameOf(kPartA, 2);
  upload(*a->presenters()[0], a2);
  a->presenters()[0]->swap();
  stack.compose();
  EXPECT_EQ(stack.frame(0), expected({{kPartA, &a2}, {kPartB, &b1}}));
  // Each job reads back its own part as it presented it, covered or not.
  EXPECT_EQ(a->presenters()[0]->readBack(), a2);
  EXPECT_EQ(b->presenters()[0]->readBack(), b1);

  // B's job ends: its window leaves the display at the next composition, A shows whole.
  b.reset();
  EXPECT_EQ(stack.windows(), 1u);
  EXPECT_EQ(stack.compose(), std::vector<int>{0});
  EXPECT_EQ(stack.frame(0), expected({{kPartA, &a2}}));
  a.reset();
  stack.compose();
  EXPECT_EQ(stack.frame(0), wall::Image(kWidth, kHeight, kBackground));
}

// A window across both displays of a process: its frame shows on them only together, when the
// last of its layers swapped; a display it misses is not composed for it.
TEST(WindowStack, AWindowsFrameShowsOnEveryDisplayOnlyWhole) {
  wall::WindowStack stack({{kWidth, kHeight}, {kWidth, kHeight}, {kWidth, kHeight}}, kBackground);
  const dfb::Region left{30, 5, 64, 40}, right{0, 5, 20, 40};
  auto w = stack.add({left, right, {}});
  ASSERT_EQ(w->presenters().size(), 2u);
  stack.compose();
  const wall::Image l1 = frameOf(left, 1), r1 = frameOf(right, 1);
  upload(*w->presenters()[0], l1);
  upload(*w->presenters()[1], r1);
  w->presenters()[0]->swap();
  EXPECT_TRUE(stack.compose().empty()) << "half a window's frame was shown";
  w->presenters()[1]->swap();
  EXPECT_EQ(stack.compose(), (std::vector<int>{0, 1}));
  EXPECT_EQ(stack.frame(0), expected({{left, &l1}}));
  EXPECT_EQ(stack.frame(1), expected({{right, &r1}}));
  EXPECT_EQ(stack.frame(2), wall::Image(kWidth, kHeight, kBackground));
}

// The job swaps on its own thread while the presenting thread composes: every composition shows
// one frame of the window on both displays, never an older one than the last composition.
TEST(WindowStack, CompositionsWhileAJobSwapsNeverTearNorGoBack) {
  wall::WindowStack stack({{kWidth, kHeight}, {kWidth, kHeight}}, kBackground);
  const dfb::Region left{10, 0, 64, 48}, right{0, 0, 50, 48};
  auto w = stack.add({left, right});
  stack.compose();                        // the background, before the first frame
  constexpr std::uint32_t kFrames = 250;  // frameOf keeps 8 bits of it
  std::atomic<bool> done{false};
  std::thread job([&] {
    for (std::uint32_t f = 1; f <= kFrames; ++f) {
      upload(*w->presenters()[0], frameOf(left, f));
      upload(*w->presenters()[1], frameOf(right, f));
      w->presenters()[0]->swap();
      w->presenters()[1]->swap();
    }
    done = true;
  });
  const auto frameShown = [&](int display, int x, int y) {
    return (stack.frame(display).at(x, y) >> 16) & 0xffu;
  };
  std::uint32_t last = 0;
  int compositions = 0;
  while (true) {
    const bool finished = done;
    const std::vector<int> changed = stack.compose();
    if (changed.size() == 2) {
      ++compositions;
      const std::uint32_t f = frameShown(0, 10, 0);
      // Every pixel of both parts is of frame f (a frame is never half uploaded or half shown).
      const wall::Image lf = frameOf(left, f), rf = frameOf(right, f);
      EXPECT_EQ(stack.frame(0), expected({{left, &lf}}));
      EXPECT_EQ(stack.frame(1), expected({{right, &rf}}));
      EXPECT_GE(f, last);
      last = f;
    } else {
      EXPECT_TRUE(changed.empty() || stack.windows() == 0);
    }
    if (finished && changed.empty()) break;
  }
  job.join();
  EXPECT_EQ(last, kFrames);
  EXPECT_GT(compositions, 0);
}

// Random stacks of windows on a display, composed by spans, against the per-pixel reference.
TEST(WindowStack, SpanCompositionEqualsThePerPixelReference) {
  std::mt19937 random(37);
  for (int trial = 0; trial < 300; ++trial) {
    const int width = 1 + static_cast<int>(random() % 97);
    const int height = 1 + static_cast<int>(random() % 61);
    const int count = static_cast<int>(random() % 6);
    std::vector<wall::Image> images;
    std::vector<dfb::Region> parts;
    images.reserve(static_cast<size_t>(count));
    for (int i = 0; i < count; ++i) {
      const int x0 = static_cast<int>(random() % static_cast<unsigned>(width));
      const int y0 = static_cast<int>(random() % static_cast<unsigned>(height));
      const int x1 = x0 + 1 + static_cast<int>(random() % static_cast<unsigned>(width - x0));
      const int y1 = y0 + 1 + static_cast<int>(random() % static_cast<unsigned>(height - y0));
      parts.push_back({x0, y0, x1, y1});
      images.push_back(frameOf(parts.back(), static_cast<std::uint32_t>(i + 1)));
    }
    std::vector<wall::ComposedLayer> layers;
    std::vector<std::pair<dfb::Region, const wall::Image*>> reference;
    for (int i = 0; i < count; ++i) {
      layers.push_back({parts[static_cast<size_t>(i)], &images[static_cast<size_t>(i)]});
      reference.emplace_back(parts[static_cast<size_t>(i)], &images[static_cast<size_t>(i)]);
    }
    wall::Image frame(width, height, 0x12345678u);  // whatever was there: overwritten
    wall::composeLayers(frame, kBackground, layers);
    ASSERT_EQ(frame, expected(width, height, reference)) << "trial " << trial;
  }
  // A display large enough for the rows to be composed in parallel.
  const dfb::Region a{100, 50, 1500, 900}, b{900, 600, 1920, 1080};
  const wall::Image ia = frameOf(a, 1), ib = frameOf(b, 2);
  wall::Image frame(1920, 1080);
  wall::composeLayers(frame, kBackground, {{a, &ia}, {b, &ib}});
  EXPECT_EQ(frame, expected(1920, 1080, {{a, &ia}, {b, &ib}}));
}

// The window manager's raise: a window given a higher stacking order goes on top at the next
// composition, without a new frame of any window, on every display it touches (and only those);
// a window added later with a lower order goes beneath the higher ones, not on top.
TEST(WindowStack, ARaisedWindowGoesOnTopAndALateWindowTakesItsPlaceByOrder) {
  wall::WindowStack stack({{kWidth, kHeight}, {kWidth, kHeight}, {kWidth, kHeight}}, kBackground);
  const dfb::Region aRight{0, 0, 20, 48};  // A also touches display 1
  auto a = stack.add({kPartA, aRight, {}}, 0, 1);
  auto b = stack.add({kPartB, {}, {}}, 0, 2);
  const wall::Image a1 = frameOf(kPartA, 1), ar1 = frameOf(aRight, 1), b1 = frameOf(kPartB, 1);
  upload(*a->presenters()[0], a1);
  upload(*a->presenters()[1], ar1);
  a->presenters()[0]->swap();
  a->presenters()[1]->swap();
  upload(*b->presenters()[0], b1);
  b->presenters()[0]->swap();
  stack.compose();
  EXPECT_EQ(stack.frame(0), expected({{kPartA, &a1}, {kPartB, &b1}}));

  // Raised (the window manager's order 3): A over B, and both of A's displays composed again.
  a->setOrder(3);
  EXPECT_EQ(stack.compose(), (std::vector<int>{0, 1}));
  EXPECT_EQ(stack.frame(0), expected({{kPartB, &b1}, {kPartA, &a1}}));
  EXPECT_EQ(stack.frame(1), expected({{aRight, &ar1}}));
  // Raising B (display 0 only) composes display 0 alone.
  b->setOrder(4);
  EXPECT_EQ(stack.compose(), std::vector<int>{0});
  EXPECT_EQ(stack.frame(0), expected({{kPartA, &a1}, {kPartB, &b1}}));
  a->setOrder(5);
  stack.compose();

  // A window added with a lower order (a Start overtaken by a Raise of another window) goes
  // beneath the higher ones; with an equal order above its equal; without one, on top.
  const dfb::Region partC{0, 0, 64, 48}, partD{30, 20, 50, 40}, partE{0, 40, 10, 48};
  auto c = stack.add({partC, {}, {}}, 0, 4);
  auto d = stack.add({partD, {}, {}}, 0, 5);
  auto e = stack.add({partE, {}, {}});
  const wall::Image c1 = frameOf(partC, 1), d1 = frameOf(partD, 1), e1 = frameOf(partE, 1);
  const std::vector<std::pair<wall::WindowStack::Window*, const wall::Image*>> late{
      {c.get(), &c1}, {d.get(), &d1}, {e.get(), &e1}};
  for (const auto& [window, frame] : late) {
    upload(*window->presenters()[0], *frame);
    window->presenters()[0]->swap();
  }
  stack.compose();
  EXPECT_EQ(stack.frame(0),
            expected({{kPartB, &b1}, {partC, &c1}, {kPartA, &a1}, {partD, &d1}, {partE, &e1}}));
  // Windows that go leave the others in their order; a raise after them still works.
  e.reset();
  d.reset();
  c->setOrder(9);
  stack.compose();
  EXPECT_EQ(stack.frame(0), expected({{kPartB, &b1}, {kPartA, &a1}, {partC, &c1}}));
}

TEST(WindowStack, APartOutsideTheDisplayOrAnUploadOutsideThePartIsRefused) {
  wall::WindowStack stack({{kWidth, kHeight}}, kBackground);
  EXPECT_ANY_THROW(stack.add({{40, 0, 80, 10}}));
  EXPECT_ANY_THROW(stack.add({kPartA, kPartB}));  // two parts, one display
  auto a = stack.add({kPartA});
  const wall::Image big = frameOf({0, 0, 41, 30}, 1);
  EXPECT_ANY_THROW(a->presenters()[0]->upload(big.pixels.data(), big.width, {0, 0, 41, 30}));
  EXPECT_EQ(stack.windows(), 1u);
}

}  // namespace
