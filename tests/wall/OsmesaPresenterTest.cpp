// The offscreen presenter shows exactly the pixels it is given: readback equals input, for
// odd sizes, for a size change, and for two presenters taking turns on one thread.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>
#include <vector>

#include "wall/display/OsmesaPresenter.h"

namespace {

wall::Image noise(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  wall::Image img(w, h);
  for (auto& p : img.pixels) p = static_cast<std::uint32_t>(rng());  // alpha varies too
  return img;
}

TEST(OsmesaPresenter, ReadBackEqualsInput) {
  auto presenter = wall::makeOsmesaPresenter(203, 151);
  EXPECT_NE(presenter->describe().find("Core Profile"), std::string::npos) << presenter->describe();
  const wall::Image img = noise(203, 151, 1);
  presenter->present(img.pixels.data(), img.width, img.height);
  const wall::Image back = presenter->readBack();
  ASSERT_EQ(back.width, 203);
  ASSERT_EQ(back.height, 151);
  size_t differing = 0;
  for (size_t i = 0; i < img.pixels.size(); ++i) differing += back.pixels[i] != img.pixels[i];
  EXPECT_EQ(differing, 0u) << "of " << img.pixels.size() << " pixels";
  // Orientation: row 0 is the top row, column 0 the left.
  EXPECT_EQ(back.at(0, 0), img.at(0, 0));
  EXPECT_EQ(back.at(202, 150), img.at(202, 150));
  EXPECT_FALSE(presenter->closeRequested());
}

TEST(OsmesaPresenter, SecondFrameAndSizeChange) {
  auto presenter = wall::makeOsmesaPresenter(64, 48);
  const wall::Image first = noise(64, 48, 2);
  presenter->present(first.pixels.data(), 64, 48);
  const wall::Image second = noise(64, 48, 3);
  presenter->present(second.pixels.data(), 64, 48);
  EXPECT_TRUE(presenter->readBack() == second);
  const wall::Image bigger = noise(97, 33, 4);
  presenter->present(bigger.pixels.data(), 97, 33);
  EXPECT_TRUE(presenter->readBack() == bigger);
}

TEST(OsmesaPresenter, TwoPresentersOnOneThread) {
  // One wall process driving two displays: each presenter keeps its own context and frame.
  auto a = wall::makeOsmesaPresenter(180, 100);
  auto b = wall::makeOsmesaPresenter(180, 70);
  const wall::Image ia = noise(180, 100, 5), ib = noise(180, 70, 6);
  a->present(ia.pixels.data(), 180, 100);
  b->present(ib.pixels.data(), 180, 70);
  EXPECT_TRUE(a->readBack() == ia);
  EXPECT_TRUE(b->readBack() == ib);
}

// As a wall uploads: piece by piece in any order, from a frame buffer that is only partly
// filled at each upload, two displays interleaved, drawn both before swapping both.
TEST(OsmesaPresenter, PiecesUploadedInAnyOrderShowTheWholeFrame) {
  constexpr int kW = 203, kH = 151, kTile = 32;
  auto a = wall::makeOsmesaPresenter(kW, kH);
  auto b = wall::makeOsmesaPresenter(kW, kH);
  for (unsigned frame = 0; frame < 2; ++frame) {
    const wall::Image ia = noise(kW, kH, 10 + frame), ib = noise(kW, kH, 20 + frame);
    wall::Image bufferA(kW, kH), bufferB(kW, kH);  // filled piece by piece, like a wall slot
    std::vector<dfb::Region> pieces;
    for (int y = 0; y < kH; y += kTile)
      for (int x = 0; x < kW; x += kTile)
        pieces.push_back({x, y, std::min(x + kTile, kW), std::min(y + kTile, kH)});
    std::shuffle(pieces.begin(), pieces.end(), std::mt19937(frame));
    a->beginFrame(kW, kH);
    b->beginFrame(kW, kH);
    for (const dfb::Region& r : pieces) {
      for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x) {
          bufferA.at(x, y) = ia.at(x, y);
          bufferB.at(x, y) = ib.at(x, y);
        }
      a->upload(bufferA.pixels.data(), kW, r);
      b->upload(bufferB.pixels.data(), kW, r);
    }
    a->draw();
    b->draw();
    a->swap();
    b->swap();
    EXPECT_TRUE(a->readBack() == ia) << "frame " << frame;
    EXPECT_TRUE(b->readBack() == ib) << "frame " << frame;
  }
}

TEST(OsmesaPresenter, RejectsAnEmptyDrawable) {
  EXPECT_THROW(wall::makeOsmesaPresenter(0, 10), std::exception);
}

TEST(OsmesaPresenter, FullHdPresentTime) {
  // A figure for the report, and proof the big case is exact too.
  auto presenter = wall::makeOsmesaPresenter(1920, 1080);
  const wall::Image img = noise(1920, 1080, 7);
  presenter->present(img.pixels.data(), 1920, 1080);  // warm-up: texture allocation, shader JIT
  const int frames = 5;
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < frames; ++i) presenter->present(img.pixels.data(), 1920, 1080);
  const auto t1 = std::chrono::steady_clock::now();
  const wall::Image back = presenter->readBack();
  const auto t2 = std::chrono::steady_clock::now();
  const double presentMs = std::chrono::duration<double, std::milli>(t1 - t0).count() / frames;
  const double readMs = std::chrono::duration<double, std::milli>(t2 - t1).count();
  std::printf("OSMesa 1920x1080: present %.2f ms/frame, readBack %.2f ms\n", presentMs, readMs);
  RecordProperty("present_ms_1080p", std::to_string(presentMs));
  EXPECT_TRUE(back == img);
}

}  // namespace
