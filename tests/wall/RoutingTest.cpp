// Cutting tiles at display borders: the pieces of all tiles cover every displayed pixel exactly
// once and no other pixel, and the per-display and per-tile views agree.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "base/Error.h"
#include "tests/wall/ShippedLayoutTestUtil.h"
#include "wall/layout/Layout.h"
#include "wall/route/PieceMessage.h"
#include "wall/route/Routing.h"

namespace {

using test::loadShippedLayout;

const char* kLayouts[] = {"1x1.toml", "2x2.toml", "3x2-bezels.toml", "mixed.toml"};
const int kTileSizes[] = {64, 50, 17, 1000};

TEST(Routing, PiecesCoverEveryDisplayedPixelOnce) {
  for (const char* name : kLayouts) {
    const wall::Layout l = loadShippedLayout(name);
    // Which display (or -1) each canvas pixel belongs to.
    std::vector<int> owner(static_cast<size_t>(l.canvasWidth) * l.canvasHeight, -1);
    for (size_t i = 0; i < l.displays.size(); ++i) {
      const dfb::Region& r = l.displays[i].rect;
      for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x)
          owner[static_cast<size_t>(y) * l.canvasWidth + x] = static_cast<int>(i);
    }
    for (int tileSize : kTileSizes) {
      SCOPED_TRACE(std::string(name) + " tile " + std::to_string(tileSize));
      const dfb::TileGrid tiles = wall::canvasTiles(l, tileSize);
      std::vector<int> covered(owner.size(), 0);
      for (int t = 0; t < tiles.tileCount(); ++t) {
        const dfb::Region tile = tiles.region(t);
        for (const wall::Piece& p : wall::piecesOf(l, tile)) {
          const dfb::Region& d = l.displays[static_cast<size_t>(p.display)].rect;
          ASSERT_FALSE(p.canvas.empty());
          // Inside the tile, and local = canvas moved to the display's origin.
          EXPECT_TRUE(p.canvas.x0 >= tile.x0 && p.canvas.x1 <= tile.x1 && p.canvas.y0 >= tile.y0 &&
                      p.canvas.y1 <= tile.y1);
          EXPECT_EQ(p.local, (dfb::Region{p.canvas.x0 - d.x0, p.canvas.y0 - d.y0,
                                          p.canvas.x1 - d.x0, p.canvas.y1 - d.y0}));
          for (int y = p.canvas.y0; y < p.canvas.y1; ++y) {
            for (int x = p.canvas.x0; x < p.canvas.x1; ++x) {
              const size_t at = static_cast<size_t>(y) * l.canvasWidth + x;
              EXPECT_EQ(owner[at], p.display) << "pixel " << x << "," << y;
              ++covered[at];
            }
          }
        }
      }
      size_t wrong = 0;
      for (size_t i = 0; i < owner.size(); ++i) wrong += covered[i] != (owner[i] >= 0 ? 1 : 0);
      EXPECT_EQ(wrong, 0u) << "pixels covered other than once-if-displayed";
    }
  }
}

TEST(Routing, TilesOfDisplayAgreeWithPiecesOf) {
  for (const char* name : kLayouts) {
    const wall::Layout l = loadShippedLayout(name);
    for (int tileSize : kTileSizes) {
      SCOPED_TRACE(std::string(name) + " tile " + std::to_string(tileSize));
      const dfb::TileGrid tiles = wall::canvasTiles(l, tileSize);
      std::vector<std::vector<wall::DisplayTile>> perDisplay;
      for (size_t i = 0; i < l.displays.size(); ++i)
        perDisplay.push_back(wall::tilesOfDisplay(l, static_cast<int>(i), tileSize));
      const std::vector<bool> shown = wall::tilesShownByAnyDisplay(l, tileSize);
      ASSERT_EQ(shown.size(), static_cast<size_t>(tiles.tileCount()));
      std::vector<size_t> next(l.displays.size(), 0);
      for (int t = 0; t < tiles.tileCount(); ++t) {
        const std::vector<wall::Piece> pieces = wall::piecesOf(l, tiles.region(t));
        EXPECT_EQ(shown[static_cast<size_t>(t)], !pieces.empty()) << "tile " << t;
        for (const wall::Piece& p : pieces) {
          auto& list = perDisplay[static_cast<size_t>(p.display)];
          size_t& k = next[static_cast<size_t>(p.display)];
          ASSERT_LT(k, list.size());
          EXPECT_EQ(list[k].tileIndex, t);
          EXPECT_EQ(list[k].tile, tiles.region(t));
          EXPECT_EQ(list[k].piece, p);
          ++k;
        }
      }
      for (size_t i = 0; i < l.displays.size(); ++i)
        EXPECT_EQ(next[i], perDisplay[i].size()) << "display " << l.displays[i].name;
    }
  }
}

TEST(Routing, ATileAcrossTheBezelCross) {
  const wall::Layout l = loadShippedLayout("2x2.toml");  // panels at x 0 and 212, y 0 and 160
  const dfb::TileGrid tiles = wall::canvasTiles(l, 64);
  EXPECT_EQ(tiles.tilesX(), 7);  // 412 / 64 rounded up
  EXPECT_EQ(tiles.tilesY(), 5);  // 310 / 64 rounded up
  const int t = 2 * tiles.tilesX() + 3;
  EXPECT_EQ(tiles.region(t), (dfb::Region{192, 128, 256, 192}));
  const std::vector<wall::Piece> p = wall::piecesOf(l, tiles.region(t));
  ASSERT_EQ(p.size(), 4u);
  EXPECT_EQ(p[0], (wall::Piece{0, {192, 128, 200, 150}, {192, 128, 200, 150}}));
  EXPECT_EQ(p[1], (wall::Piece{1, {212, 128, 256, 150}, {0, 128, 44, 150}}));
  EXPECT_EQ(p[2], (wall::Piece{2, {192, 160, 200, 192}, {192, 0, 200, 32}}));
  EXPECT_EQ(p[3], (wall::Piece{3, {212, 160, 256, 192}, {0, 0, 44, 32}}));
  // The last, partial tile.
  EXPECT_EQ(tiles.region(tiles.tileCount() - 1), (dfb::Region{384, 256, 412, 310}));
}

TEST(Routing, TilesBehindBezelsAreNotShown) {
  const wall::Layout l = loadShippedLayout("3x2-bezels.toml");  // 45 px between columns: x 160..205
  const dfb::TileGrid tiles = wall::canvasTiles(l, 16);
  const std::vector<bool> shown = wall::tilesShownByAnyDisplay(l, 16);
  // Column tx = 11 spans x 176..192, wholly behind the first column gap; and 30 px between rows
  // (y 120..150) leave tile row ty = 8 (y 128..144) hidden.
  int hidden = 0;
  for (int t = 0; t < tiles.tileCount(); ++t) {
    const int tx = t % tiles.tilesX(), ty = t / tiles.tilesX();
    if (tx == 11 || ty == 8) {
      EXPECT_FALSE(shown[static_cast<size_t>(t)]) << tx << "," << ty;
    }
    hidden += !shown[static_cast<size_t>(t)];
  }
  // Hidden columns: 10, 11 (x 160..192) and 23, 24 (x 368..400, in the gap 365..410); row 8.
  EXPECT_EQ(hidden, 4 * tiles.tilesY() + tiles.tilesX() - 4);
  // Every tile of a gapless single display is shown.
  const std::vector<bool> all = wall::tilesShownByAnyDisplay(loadShippedLayout("1x1.toml"), 64);
  EXPECT_EQ(all, std::vector<bool>(all.size(), true));
}

// Found by fuzz_piece: a piece rectangle whose int pixel count overflowed (UBSan) and could
// then match the message's size. Now refused before any arithmetic.
TEST(PieceMessage, RejectsARectangleWhoseSizeOverflows) {
  const std::uint32_t pixels[4] = {1, 2, 3, 4};
  messaging::Bytes bytes = wall::packPiece(1, 0, dfb::Region{0, 0, 2, 2}, pixels, 2, 0, 0, false);
  wall::PieceHeader header;
  std::memcpy(&header, bytes.data(), sizeof header);
  header.x0 = -2000000000;
  header.x1 = 2000000000;
  std::memcpy(bytes.data(), &header, sizeof header);
  EXPECT_THROW(wall::readPieceHeader(bytes), base::Error);
  // Each side within the cap, the product past an int (found on the second fuzz run).
  header.x0 = 0;
  header.x1 = 393216;
  header.y1 = 262144;
  std::memcpy(bytes.data(), &header, sizeof header);
  EXPECT_THROW(wall::readPieceHeader(bytes), base::Error);
}

}  // namespace
