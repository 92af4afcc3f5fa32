// The wall service's idle screen: opaque, the asked size at any size, text where it belongs and
// inside the image, deterministic, and an image without text when the font is missing.
#include "wall/display/IdleScreen.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

#include "base/Error.h"
#include "wall/image/Image.h"
#include "wall/image/Png.h"

namespace {

const wall::IdleText kExample{"left-top",
                              {"dfbwall serve \u2014 connect with: dfbwall --connect wall1:7000",
                               "waiting for a render job"}};

int channel(std::uint32_t p, int k) { return static_cast<int>(p >> (8 * k) & 0xFF); }

// Text pixels: the title is near-white, the background and border are dark.
bool bright(std::uint32_t p) {
  return channel(p, 0) >= 200 && channel(p, 1) >= 200 && channel(p, 2) >= 200;
}

struct Box {
  int count = 0, x0 = 0, y0 = 0, x1 = -1, y1 = -1;  // bounding box, inclusive
};

// Pixels satisfying `pred` inside [x0, x1) x [y0, y1), and their bounding box.
template <class Pred>
Box find(const wall::Image& img, Pred pred, int x0, int y0, int x1, int y1) {
  Box b{0, x1, y1, -1, -1};
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x)
      if (pred(img.at(x, y))) {
        ++b.count;
        b.x0 = std::min(b.x0, x), b.y0 = std::min(b.y0, y);
        b.x1 = std::max(b.x1, x), b.y1 = std::max(b.y1, y);
      }
  return b;
}
Box findBright(const wall::Image& img) { return find(img, bright, 0, 0, img.width, img.height); }

void expectOpaque(const wall::Image& img, int w, int h) {
  ASSERT_EQ(img.width, w);
  ASSERT_EQ(img.height, h);
  ASSERT_EQ(img.pixels.size(), static_cast<std::size_t>(w) * h);
  EXPECT_TRUE(std::all_of(img.pixels.begin(), img.pixels.end(),
                          [](std::uint32_t p) { return (p >> 24) == 0xFF; }));
}

TEST(IdleScreen, HasTheAskedSizeAndIsOpaque) {
  std::string warning = "stale";
  const wall::Image img = wall::renderIdleScreen(640, 360, kExample, &warning);
  expectOpaque(img, 640, 360);
  EXPECT_EQ(warning, "") << "fonts-dejavu-core is installed with the build dependencies";
}

TEST(IdleScreen, TitleInTheMiddleLinesBelowCornersEmpty) {
  const int w = 1920, h = 1080;
  const wall::Image img = wall::renderIdleScreen(w, h, kExample);
  expectOpaque(img, w, h);
  // The title: bright pixels in a band around the middle, centred horizontally.
  const Box title = find(img, bright, 0, h * 3 / 10, w, h * 6 / 10);
  EXPECT_GT(title.count, 2000);
  EXPECT_NEAR((title.x0 + title.x1) / 2.0, w / 2.0, w / 50.0);
  // Nothing bright anywhere else: not in the corners, and the grey lines are not bright.
  EXPECT_EQ(findBright(img).count, title.count);
  for (const auto& [cx, cy] :
       {std::pair{0, 0}, {w * 3 / 4, 0}, {0, h * 3 / 4}, {w * 3 / 4, h * 3 / 4}})
    EXPECT_EQ(find(img, bright, cx, cy, cx + w / 4, cy + h / 4).count, 0) << cx << "," << cy;
  // The lines: lighter-than-background pixels below the title.
  const auto grey = [](std::uint32_t p) { return channel(p, 0) >= 100 && !bright(p); };
  const Box lines = find(img, grey, w / 16, title.y1 + 1, w - w / 16, h - h / 12);
  EXPECT_GT(lines.count, 1000);
  EXPECT_GT(lines.y1 - lines.y0, h / 15) << "two lines, one under the other";
}

TEST(IdleScreen, DeterministicAndTheTitleShows) {
  const wall::Image a = wall::renderIdleScreen(800, 450, kExample);
  EXPECT_TRUE(a == wall::renderIdleScreen(800, 450, kExample));
  wall::IdleText other = kExample;
  other.title = "right-top";
  EXPECT_FALSE(a == wall::renderIdleScreen(800, 450, other));
  other.title = "left-top";
  other.lines[1] = "job from render1 ended";
  EXPECT_FALSE(a == wall::renderIdleScreen(800, 450, other));
}

TEST(IdleScreen, SameFromSeveralThreads) {
  const std::vector<std::string> titles{"a", "left-top", "right-bottom", "\u00c9cran 4"};
  std::vector<wall::Image> expected;
  for (const std::string& t : titles)
    expected.push_back(wall::renderIdleScreen(320, 180, {t, {"x"}}));
  std::vector<wall::Image> got(titles.size() * 4);
  std::vector<std::thread> threads;
  for (std::size_t i = 0; i < got.size(); ++i)
    threads.emplace_back([&, i] {
      got[i] = wall::renderIdleScreen(320, 180, {titles[i % titles.size()], {"x"}});
    });
  for (std::thread& t : threads) t.join();
  for (std::size_t i = 0; i < got.size(); ++i)
    EXPECT_TRUE(got[i] == expected[i % titles.size()]) << i;
}

TEST(IdleScreen, AnySizeFromOnePixelUp) {
  for (const auto& [w, h] : {std::pair{1, 1},
                             {7, 3},
                             {1, 500},
                             {500, 1},
                             {3, 7},
                             {40, 12},
                             {64, 64},
                             {200, 30},
                             {3840, 2160}}) {
    SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h));
    const wall::Image img = wall::renderIdleScreen(w, h, kExample);
    expectOpaque(img, w, h);
    const Box b = findBright(img);
    if (b.count > 0) {  // text, when there is room for it, stays off the edges
      EXPECT_GT(b.x0, 0);
      EXPECT_GT(b.y0, 0);
      EXPECT_LT(b.x1, w - 1);
      EXPECT_LT(b.y1, h - 1);
    }
  }
  EXPECT_GT(findBright(wall::renderIdleScreen(3840, 2160, kExample)).count, 8000);
  EXPECT_THROW(wall::renderIdleScreen(0, 10, kExample), base::Error);
  EXPECT_THROW(wall::renderIdleScreen(10, -1, kExample), base::Error);
}

TEST(IdleScreen, TooWideTextIsShrunkToFit) {
  const int w = 800, h = 450;
  // About four times too wide at the nominal size; a line far too wide even for the smallest
  // legible size is left out rather than cut.
  wall::IdleText text{"WWW the display with a very long name in the left column, row 1 WWW",
                      {std::string(300, 'm'), "waiting for a render job"}};
  const wall::Image img = wall::renderIdleScreen(w, h, text);
  const Box b = findBright(img);
  ASSERT_GT(b.count, 100);
  const int margin = w / 40;
  EXPECT_GE(b.x0, margin);
  EXPECT_LE(b.x1, w - 1 - margin);
  EXPECT_GE(b.y0, margin);
  EXPECT_LE(b.y1, h - 1 - margin);
  EXPECT_GT(b.x1 - b.x0, w / 2) << "shrunk to the width, not to nothing";
  // The same for a portrait display and a short wide one.
  for (const auto& [pw, ph] : {std::pair{300, 1200}, {1600, 90}}) {
    const Box p = findBright(wall::renderIdleScreen(pw, ph, text));
    ASSERT_GT(p.count, 0) << pw << "x" << ph;
    EXPECT_GT(p.x0, 0);
    EXPECT_GT(p.y0, 0);
    EXPECT_LT(p.x1, pw - 1);
    EXPECT_LT(p.y1, ph - 1);
  }
}

TEST(IdleScreen, Utf8LatinAndDashes) {
  const wall::Image dash = wall::renderIdleScreen(640, 360, {"a \u2014 b", {}});
  const wall::Image hyphen = wall::renderIdleScreen(640, 360, {"a - b", {}});
  EXPECT_FALSE(dash == hyphen);
  EXPECT_GT(
      findBright(wall::renderIdleScreen(640, 360, {"\u00c5\u00e9\u00df\u00f1\u00fc\u00ff", {}}))
          .count,
      100);
  // Broken UTF-8 and control characters draw something and do not crash.
  const wall::Image img = wall::renderIdleScreen(
      640, 360,
      {std::string("x\xC3") + "\xE2\x80" + "\xFF" + "\xED\xA0\x80" + "ok\x01\t", {"\xC0\xAF"}});
  expectOpaque(img, 640, 360);
  EXPECT_GT(findBright(img).count, 100);
}

TEST(IdleScreen, MissingFontGivesTheBackgroundAndAWarning) {
  const wall::IdleFonts missing{"/nonexistent/dfbwall/DejaVuSans.ttf",
                                "/nonexistent/dfbwall/DejaVuSans-Bold.ttf"};
  std::string warning;
  const wall::Image img = wall::renderIdleScreen(640, 360, kExample, missing, &warning);
  expectOpaque(img, 640, 360);
  EXPECT_EQ(findBright(img).count, 0);
  EXPECT_TRUE(img == wall::renderIdleScreen(640, 360, {}, missing)) << "background only";
  EXPECT_NE(warning.find("/nonexistent/dfbwall/DejaVuSans.ttf"), std::string::npos) << warning;
  EXPECT_NE(warning.find("fonts-dejavu-core"), std::string::npos) << warning;
  // Asked again (the lookup is cached), the same warning; without `warning` no crash.
  std::string again;
  EXPECT_TRUE(img == wall::renderIdleScreen(640, 360, kExample, missing, &again));
  EXPECT_EQ(again, warning);
  // Only the bold face missing: the regular one draws the title too.
  const wall::IdleFonts noBold{wall::IdleFonts{}.regular,
                               "/nonexistent/dfbwall/DejaVuSans-Bold.ttf"};
  std::string boldWarning;
  const wall::Image regularTitle = wall::renderIdleScreen(640, 360, kExample, noBold, &boldWarning);
  EXPECT_GT(findBright(regularTitle).count, 100);
  EXPECT_NE(boldWarning.find("DejaVuSans-Bold.ttf"), std::string::npos) << boldWarning;
  EXPECT_EQ(boldWarning.find("DejaVuSans.ttf"), std::string::npos) << boldWarning;
}

// An example for a human to look at: build/tests/wall/idle-screen-1920x1080.png.
TEST(IdleScreen, WritesAnExamplePng) {
  const wall::Image img = wall::renderIdleScreen(1920, 1080, kExample);
  const std::string path = std::string(DFBWALL_TEST_BINARY_DIR) + "/idle-screen-1920x1080.png";
  wall::writePng(path, img);
  EXPECT_TRUE(wall::readPng(path) == img);
}

}  // namespace
