// The thumbnail's box filter (wall/image/Thumbnail.h): cells summed over any cut of the window
// into parts, added up and averaged, equal the box filter of the whole window.
#include <gtest/gtest.h>

#include "wall/image/Thumbnail.h"

namespace wall {
namespace {

Image pattern(int w, int h) {
  Image image(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      image.at(x, y) =
          rgba8(static_cast<std::uint8_t>(x * 7 + y), static_cast<std::uint8_t>(y * 13),
                static_cast<std::uint8_t>((x * y) % 251), static_cast<std::uint8_t>(200 + x % 50));
  return image;
}

TEST(Thumbnail, TheGridIsTheSmallestWholeFactorAndCutsTheLastCells) {
  EXPECT_EQ(thumbnailGrid(250, 170, 320), (ThumbnailGrid{1, 250, 170}));
  EXPECT_EQ(thumbnailGrid(250, 170, 64), (ThumbnailGrid{4, 63, 43}));
  EXPECT_EQ(thumbnailGrid(3840, 2160, 320), (ThumbnailGrid{12, 320, 180}));
  EXPECT_EQ(thumbnailGrid(100, 641, 320), (ThumbnailGrid{3, 34, 214}));
  // A canvas side of 2^20 pixels: the factor stops at 4096 (256 cells), so sums fit 32 bits.
  EXPECT_EQ(thumbnailGrid(1 << 20, 16, 16).factor, kMaxThumbnailFactor);
  EXPECT_EQ(cellsOf({4, 63, 43}, {5, 8, 9, 9}), (dfb::Region{1, 2, 3, 3}));
  EXPECT_EQ(cellArea({4, 63, 43}, 250, 170, 62, 42), 2u * 2u);
}

TEST(Thumbnail, PartsSummedApartEqualTheWholeWindowsBoxFilter) {
  const int w = 103, h = 61;
  const Image window = pattern(w, h);
  const ThumbnailGrid grid = thumbnailGrid(w, h, 20);  // factor 6: cells cut at 102 and 60
  CellSums whole = emptySums({0, 0, grid.width, grid.height});
  addPixels(whole, grid, window, 0, 0);
  // Cut at 37 and 29 (no cell border): four parts, as four displays would hold them.
  CellSums added = emptySums({0, 0, grid.width, grid.height});
  for (const dfb::Region part : {dfb::Region{0, 0, 37, 29}, dfb::Region{37, 0, w, 29},
                                 dfb::Region{0, 29, 37, h}, dfb::Region{37, 29, w, h}}) {
    CellSums mine = emptySums(cellsOf(grid, part));
    addPixels(mine, grid, crop(window, part), part.x0, part.y0);
    for (int cy = mine.cells.y0; cy < mine.cells.y1; ++cy)
      for (int cx = mine.cells.x0; cx < mine.cells.x1; ++cx)
        for (int c = 0; c < CellSums::kChannels; ++c)
          added.sums[(static_cast<std::size_t>(cy) * grid.width + cx) * CellSums::kChannels + c] +=
              mine.sums[(static_cast<std::size_t>(cy - mine.cells.y0) * mine.cells.width() +
                         (cx - mine.cells.x0)) *
                            CellSums::kChannels +
                        c];
  }
  EXPECT_EQ(added.sums, whole.sums);
  const Image thumbnail = averageCells(grid, added, nullptr);
  // Cell (17, 10): pixels 102 x 60 alone; cell (0, 0): the rounded mean of 36 pixels.
  EXPECT_EQ(thumbnail.at(17, 10), window.at(102, 60));
  std::uint32_t sum[4] = {0, 0, 0, 0};
  for (int y = 0; y < 6; ++y)
    for (int x = 0; x < 6; ++x)
      for (int c = 0; c < 4; ++c) sum[c] += (window.at(x, y) >> (8 * c)) & 0xffu;
  std::uint32_t expected = 0;
  for (int c = 0; c < 4; ++c) expected |= ((sum[c] + 18) / 36) << (8 * c);
  EXPECT_EQ(thumbnail.at(0, 0), expected);
  // Outside the cells summed: refused.
  CellSums small = emptySums({0, 0, 2, 2});
  EXPECT_THROW(addPixels(small, grid, pattern(13, 13), 0, 0), std::exception);
}

TEST(Thumbnail, CellsNobodySentKeepThePreviousThumbnailOrAreTransparent) {
  const ThumbnailGrid grid{2, 2, 1};
  CellSums sums = emptySums({0, 0, 2, 1});
  addPixels(sums, grid, Image(2, 2, rgba8(10, 20, 30)), 0, 0);
  const Image first = averageCells(grid, sums, nullptr);
  EXPECT_EQ(first.at(0, 0), rgba8(10, 20, 30));
  EXPECT_EQ(first.at(1, 0), 0u);
  const Image previous(2, 1, rgba8(1, 2, 3));
  EXPECT_EQ(averageCells(grid, sums, &previous).at(1, 0), rgba8(1, 2, 3));
  const Image otherSize(3, 1, rgba8(1, 2, 3));
  EXPECT_EQ(averageCells(grid, sums, &otherSize).at(1, 0), 0u);
}

}  // namespace
}  // namespace wall
