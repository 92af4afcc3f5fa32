// Window presenting under a private X server (CTest runs this through xvfb-run): a frame shown
// in a GLFW window reads back exactly as the OSMesa presenter's, windowed and fullscreen, with
// one window per display.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>

#include "base/Error.h"
#include "wall/display/GlfwPresenter.h"
#include "wall/display/OsmesaPresenter.h"
#include "wall/layout/Layout.h"

namespace {

// Opaque: a window's framebuffer may have no alpha channel, and the wall shows opaque pixels.
wall::Image opaqueNoise(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  wall::Image img(w, h);
  for (auto& p : img.pixels) p = static_cast<std::uint32_t>(rng()) | 0xff000000u;
  return img;
}

wall::Image throughOsmesa(const wall::Image& img) {
  auto p = wall::makeOsmesaPresenter(img.width, img.height);
  p->present(img.pixels.data(), img.width, img.height);
  return p->readBack();
}

class GlfwPresenter : public ::testing::Test {
 protected:
  wall::GlfwSession session_;
};

TEST_F(GlfwPresenter, WindowShowsWhatOsmesaShows) {
  const wall::Layout l =
      wall::loadLayout(std::string(DFBWALL_SOURCE_DIR) + "/configs/walls/2x2.toml");
  const wall::WindowOptions options = wall::windowOptionsFor(l.displays[1]);
  EXPECT_EQ(options.title, "r0c1");
  EXPECT_EQ(options.width, 200);
  EXPECT_EQ(options.height, 150);
  auto window = wall::makeGlfwPresenter(session_, options);
  EXPECT_NE(window->describe().find("r0c1"), std::string::npos) << window->describe();
  const wall::Image img = opaqueNoise(200, 150, 1);
  window->present(img.pixels.data(), 200, 150);
  const wall::Image shown = window->readBack();
  const wall::Image offscreen = throughOsmesa(img);
  ASSERT_EQ(shown.width, 200);
  ASSERT_EQ(shown.height, 150);
  size_t differing = 0;
  for (size_t i = 0; i < img.pixels.size(); ++i)
    differing += shown.pixels[i] != offscreen.pixels[i];
  EXPECT_EQ(differing, 0u) << "of " << img.pixels.size();
  EXPECT_TRUE(offscreen == img);
  EXPECT_FALSE(window->closeRequested());
}

TEST_F(GlfwPresenter, OneProcessTwoWindows) {
  // Side by side, so neither hides the other (readBack reads the screen).
  auto a = wall::makeGlfwPresenter(session_, {"center-top", 180, 100, false, 0, false, 0, 0});
  auto b = wall::makeGlfwPresenter(session_, {"center-bottom", 180, 70, false, 0, false, 300, 0});
  const wall::Image ia = opaqueNoise(180, 100, 2), ib = opaqueNoise(180, 70, 3);
  for (int frame = 0; frame < 2; ++frame) {  // a second frame through both
    a->present(ia.pixels.data(), 180, 100);
    b->present(ib.pixels.data(), 180, 70);
  }
  EXPECT_TRUE(a->readBack() == ia);
  EXPECT_TRUE(b->readBack() == ib);
}

// A wall process's order: pieces of both windows uploaded interleaved (so the GL context
// switches between uploads), both drawn, then both swapped.
TEST_F(GlfwPresenter, PiecesOfTwoWindowsThenDrawThenSwap) {
  auto a = wall::makeGlfwPresenter(session_, {"left", 150, 90, false, 0, false, 0, 0});
  auto b = wall::makeGlfwPresenter(session_, {"right", 150, 90, false, 0, false, 300, 0});
  const wall::Image ia = opaqueNoise(150, 90, 5), ib = opaqueNoise(150, 90, 6);
  a->beginFrame(150, 90);
  b->beginFrame(150, 90);
  for (int y = 0; y < 90; y += 40)
    for (int x = 0; x < 150; x += 64) {
      const dfb::Region piece{x, y, std::min(x + 64, 150), std::min(y + 40, 90)};
      a->upload(ia.pixels.data(), 150, piece);
      b->upload(ib.pixels.data(), 150, piece);
    }
  a->draw();
  b->draw();
  a->swap();
  b->swap();
  EXPECT_TRUE(a->readBack() == ia);
  EXPECT_TRUE(b->readBack() == ib);
}

TEST_F(GlfwPresenter, FullscreenDrawsOneToOneAtTheTopLeft) {
  ASSERT_GE(session_.monitorCount(), 1);
  // Xvfb's only mode is its screen size, so the frame fills the top-left of a larger window.
  auto window = wall::makeGlfwPresenter(session_, {"full", 210, 130, true, 0, false, -1, -1});
  const wall::Image img = opaqueNoise(210, 130, 4);
  window->present(img.pixels.data(), 210, 130);
  EXPECT_TRUE(window->readBack() == throughOsmesa(img));
}

TEST_F(GlfwPresenter, MissingMonitorIsAClearError) {
  try {
    wall::makeGlfwPresenter(session_, {"r9c9", 100, 100, true, 7, false, -1, -1});
    FAIL() << "no exception";
  } catch (const base::Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("display 'r9c9': monitor 7 requested"), std::string::npos) << m;
  }
}

}  // namespace
