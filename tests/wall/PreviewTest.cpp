// The preview's box filter and decoration (wall/route/Preview.h), without ranks.
#include "wall/route/Preview.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <random>

#include "wall/image/Png.h"
#include "wall/layout/Layout.h"

namespace wall {
namespace {

Image randomImage(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  Image image(w, h);
  for (auto& p : image.pixels) p = static_cast<std::uint32_t>(rng());
  return image;
}

// The definition, pixel by pixel in double: the mean of the cell's pixels inside the canvas.
std::uint32_t boxAverage(const Image& image, int cx, int cy, int f) {
  double sums[4] = {0, 0, 0, 0};
  int n = 0;
  for (int y = cy * f; y < std::min((cy + 1) * f, image.height); ++y)
    for (int x = cx * f; x < std::min((cx + 1) * f, image.width); ++x, ++n)
      for (int c = 0; c < 4; ++c) sums[c] += image.at(x, y) >> (8 * c) & 0xff;
  std::uint32_t p = 0;
  for (int c = 0; c < 4; ++c)
    p |= static_cast<std::uint32_t>(std::floor(sums[c] / n + 0.5)) << (8 * c);
  return p;
}

TEST(Preview, GridSizesRoundUpAndCellsClipToTheCanvas) {
  const PreviewGrid grid{101, 63, 8};
  EXPECT_EQ(grid.width(), 13);
  EXPECT_EQ(grid.height(), 8);
  EXPECT_EQ(grid.cellPixels(12, 7), (dfb::Region{96, 56, 101, 63}));  // 5 x 7 pixels
  EXPECT_EQ(grid.cellsOf({8, 0, 17, 8}), (dfb::Region{1, 0, 3, 1}));
}

// The shrink factor follows the canvas: the page shows 513-1024 cells across the longest side
// whatever the wall's size, or the whole canvas when it is smaller (issue 23: the 2x2 demo wall
// was a mosaic of 51x38 cells at the old fixed factor of 8).
TEST(Preview, FactorKeepsFiveHundredToAThousandCellsAcross) {
  const Layout demo = loadLayout(std::string(DFBWALL_SOURCE_DIR) + "/configs/walls/2x2.toml");
  ASSERT_EQ(demo.canvasWidth, 412);
  ASSERT_EQ(demo.canvasHeight, 310);
  const PreviewGrid small{412, 310, previewFactor(demo.canvasWidth, demo.canvasHeight)};
  EXPECT_EQ(small.factor, 1);
  EXPECT_EQ(small.width(), 412);  // every pixel a cell
  EXPECT_EQ(small.height(), 310);

  const PreviewGrid uhd{3840, 2160, previewFactor(3840, 2160)};  // a 2x2 wall of 1080p panels
  EXPECT_EQ(uhd.factor, 4);
  EXPECT_EQ(uhd.width(), 960);
  EXPECT_EQ(uhd.height(), 540);
  const PreviewGrid large{16000, 2000, previewFactor(16000, 2000)};
  EXPECT_EQ(large.factor, 16);
  EXPECT_EQ(large.width(), 1000);
  EXPECT_EQ(previewFactor(2000, 16000), 16);  // the longest side counts, portrait too
  EXPECT_EQ(previewFactor(1024, 768), 1);
  EXPECT_EQ(previewFactor(1025, 768), 2);  // 513 cells

  for (int side = 1; side <= 70000; side += side / 7 + 1) {
    const int f = previewFactor(side, side / 3 + 1);
    const int cells = (side + f - 1) / f;
    EXPECT_LE(cells, 1024) << side;
    EXPECT_GE(cells, std::min(side, 513)) << side;
    EXPECT_EQ(64 % f == 0 || f % 64 == 0, true) << "a power of two: " << f;
  }
}

TEST(Preview, WholeImageIsTheExactBoxAverageIncludingPartialEdgeCells) {
  for (int f : {2, 8, 16}) {
    const Image image = randomImage(101, 63, static_cast<unsigned>(f));  // no multiple of f
    const PreviewGrid grid{image.width, image.height, f};
    const Image small = downsample(grid, image);
    ASSERT_EQ(small.width, grid.width());
    for (int cy = 0; cy < small.height; ++cy)
      for (int cx = 0; cx < small.width; ++cx)
        ASSERT_EQ(small.at(cx, cy), boxAverage(image, cx, cy, f))
            << "factor " << f << " cell " << cx << "," << cy;
  }
}

TEST(Preview, ConstantAndKnownValues) {
  Image image(10, 3, rgba8(10, 20, 30, 255));
  image.at(9, 2) = rgba8(0, 0, 0, 0);
  image.at(8, 2) = rgba8(1, 0, 0, 0);
  const Image small = downsample(PreviewGrid{10, 3, 8}, image);
  EXPECT_EQ(small.at(0, 0), rgba8(10, 20, 30, 255));
  // The 2 x 3 edge cell: R (10*4 + 1 + 0) / 6 = 6.83 -> 7, G 80/6 = 13.3 -> 13, B 120/6 = 20,
  // A 1020/6 = 170.
  EXPECT_EQ(small.at(1, 0), rgba8(7, 13, 20, 170));
}

// A tile that is no multiple of the factor, not aligned to the cells: its cells average only
// its own pixels (the assembler weights the parts of a straddling cell).
TEST(Preview, TileRegionsAverageTheirOwnPixels) {
  const Image image = randomImage(60, 40, 7);
  const PreviewGrid grid{60, 40, 8};
  const dfb::Region tile{20, 10, 40, 30};  // tile size 20: cells 2..4 x 1..3, all partial
  std::vector<std::uint32_t> pixels;
  for (int y = tile.y0; y < tile.y1; ++y)
    for (int x = tile.x0; x < tile.x1; ++x) pixels.push_back(image.at(x, y));
  const std::vector<std::uint32_t> cells = downsample(grid, tile, pixels.data(), tile.width());
  const dfb::Region c = grid.cellsOf(tile);
  ASSERT_EQ(c, (dfb::Region{2, 1, 5, 4}));
  ASSERT_EQ(cells.size(), 9u);
  // Cell (2, 1) covers x 16..24, y 8..16; inside the tile: x 20..24, y 10..16.
  Image part(4, 6);
  for (int y = 0; y < 6; ++y)
    for (int x = 0; x < 4; ++x) part.at(x, y) = image.at(20 + x, 10 + y);
  EXPECT_EQ(cells[0], boxAverage(part, 0, 0, 8));
}

TEST(Preview, DecorationDarkensBezelsAndOutlinesDisplays) {
  Layout layout;
  Display a, b;
  a.name = "a";
  a.rect = {0, 0, 64, 32};
  b.name = "b";
  b.rect = {80, 0, 144, 32};  // a 16-pixel bezel: cells 8 and 9
  b.process = 1;
  layout.displays = {a, b};
  computeCanvas(layout);
  const PreviewGrid grid{layout.canvasWidth, layout.canvasHeight, 8};
  Image raw(grid.width(), grid.height(), rgba8(100, 150, 200, 0));
  const Image shown = decoratePreview(raw, grid, &layout);
  EXPECT_EQ(shown.at(3, 2), rgba8(100, 150, 200, 255));  // inside a: opaque picture
  EXPECT_EQ(shown.at(8, 2), rgba8(24, 24, 28));          // bezel
  EXPECT_EQ(shown.at(0, 0), rgba8(150, 175, 200));       // a's outline, half grey
  EXPECT_EQ(shown.at(10, 1), rgba8(150, 175, 200));      // b's left edge
  EXPECT_EQ(shown.at(7, 3), rgba8(150, 175, 200));       // a's bottom-right corner, mixed once
  EXPECT_EQ(decoratePreview(raw, grid, nullptr).at(8, 2), rgba8(100, 150, 200, 255));
}

// What the control server sends: PNG bytes in memory that decode to the image.
TEST(Preview, EncodedPngDecodesToTheImage) {
  const Image image = randomImage(13, 8, 3);
  const std::string bytes = encodePng(image);
  ASSERT_GT(bytes.size(), 8u);
  EXPECT_EQ(bytes.substr(1, 3), "PNG");
  const std::string path = ::testing::TempDir() + "/encoded-preview.png";
  {
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }
  EXPECT_EQ(readPng(path), image);
  std::remove(path.c_str());
}

}  // namespace
}  // namespace wall
