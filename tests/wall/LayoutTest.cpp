// The shipped layouts parse to the canvas and rectangles their comments promise; the grid
// shorthand places panels so the picture continues behind the bezels.
#include <gtest/gtest.h>

#include <string>

#include "base/Error.h"
#include "tests/wall/ShippedLayoutTestUtil.h"
#include "wall/layout/Layout.h"
#include "wall/layout/Ranks.h"

namespace {

using test::loadShippedLayout;

dfb::Region rect(int x, int y, int w, int h) { return {x, y, x + w, y + h}; }

TEST(Layout, OneByOne) {
  const wall::Layout l = loadShippedLayout("1x1.toml");
  EXPECT_EQ(l.canvasWidth, 300);
  EXPECT_EQ(l.canvasHeight, 200);
  ASSERT_EQ(l.displays.size(), 1u);
  EXPECT_EQ(l.displays[0].name, "main");
  EXPECT_EQ(l.displays[0].rect, rect(0, 0, 300, 200));
  EXPECT_EQ(l.displays[0].process, 0);
  EXPECT_EQ(l.processCount, 1);
}

TEST(Layout, TwoByTwoGridWithBezels) {
  const wall::Layout l = loadShippedLayout("2x2.toml");
  // 2 * 200 + (6 right + 6 left) = 412; 2 * 150 + (5 bottom + 5 top) = 310.
  EXPECT_EQ(l.canvasWidth, 412);
  EXPECT_EQ(l.canvasHeight, 310);
  EXPECT_EQ(l.processCount, 4);
  ASSERT_EQ(l.displays.size(), 4u);
  const char* names[] = {"r0c0", "r0c1", "r1c0", "r1c1"};
  const dfb::Region rects[] = {rect(0, 0, 200, 150), rect(212, 0, 200, 150), rect(0, 160, 200, 150),
                               rect(212, 160, 200, 150)};
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(l.displays[i].name, names[i]);
    EXPECT_EQ(l.displays[i].rect, rects[i]) << names[i];
    EXPECT_EQ(l.displays[i].process, i);
  }
  EXPECT_EQ(l.findDisplay("r1c0"), 2);
  EXPECT_EQ(l.findDisplay("r2c0"), -1);
}

TEST(Layout, AsymmetricBezelsInMillimetres) {
  const wall::Layout l = loadShippedLayout("3x2-bezels.toml");
  // 0.3 mm pitch: left 15, right 30, top 10, bottom 20 px. Column pitch 160 + 45, row 120 + 30.
  EXPECT_EQ(l.canvasWidth, 570);
  EXPECT_EQ(l.canvasHeight, 270);
  ASSERT_EQ(l.displays.size(), 6u);
  for (int row = 0; row < 2; ++row) {
    for (int col = 0; col < 3; ++col) {
      const wall::Display& d = l.displays[row * 3 + col];
      EXPECT_EQ(d.name, "r" + std::to_string(row) + "c" + std::to_string(col));
      EXPECT_EQ(d.rect, rect(col * 205, row * 150, 160, 120)) << d.name;
      EXPECT_EQ(d.process, col) << "process_per = column";
      EXPECT_EQ(d.monitor, row) << "a column's panels are its host's monitors, top first";
    }
  }
  EXPECT_EQ(l.processCount, 3);
  EXPECT_EQ(l.displaysOfProcess(1), (std::vector<int>{1, 4}));
  // The gap between columns is the right bezel of one plus the left bezel of the next.
  EXPECT_EQ(l.displays[1].rect.x0 - l.displays[0].rect.x1, 30 + 15);
  EXPECT_EQ(l.displays[3].rect.y0 - l.displays[0].rect.y1, 20 + 10);
}

TEST(Layout, GridProcessPerRowAndDisplay) {
  const char* grid = "[grid]\ncolumns = 3\nrows = 2\ndisplay_size = [10, 10]\nmonitor = 1\n";
  const auto byRow =
      wall::readLayoutText(std::string(grid) + "process_per = \"row\"\n", "row.toml");
  ASSERT_TRUE(byRow.ok()) << wall::joinProblems(byRow.problems);
  EXPECT_EQ(byRow.layout.processCount, 2);
  EXPECT_EQ(byRow.layout.displays[4].process, 1);  // r1c1
  EXPECT_EQ(byRow.layout.displays[4].monitor, 2);  // base 1 + column 1
  const auto byDisplay = wall::readLayoutText(grid, "display.toml");
  ASSERT_TRUE(byDisplay.ok());
  EXPECT_EQ(byDisplay.layout.processCount, 6);
  const auto bad = wall::readLayoutText(std::string(grid) + "process_per = \"host\"\n", "bad.toml");
  ASSERT_EQ(bad.problems.size(), 1u);
  EXPECT_NE(bad.problems[0].find("bad.toml:6:15: grid.process_per: must be \"display\", \"column\" "
                                 "or \"row\", got \"host\""),
            std::string::npos)
      << bad.problems[0];
}

TEST(Layout, MixedSizesAndOneProcessDrivingTwo) {
  const wall::Layout l = loadShippedLayout("mixed.toml");
  EXPECT_EQ(l.canvasWidth, 590);
  EXPECT_EQ(l.canvasHeight, 220);
  EXPECT_EQ(l.processCount, 3);
  ASSERT_EQ(l.displays.size(), 4u);
  EXPECT_EQ(l.displays[0].rect, rect(0, 0, 240, 180));
  EXPECT_EQ(l.displays[1].rect, rect(250, 0, 180, 100));
  EXPECT_EQ(l.displays[2].rect, rect(250, 110, 180, 70));
  EXPECT_EQ(l.displays[3].rect, rect(440, 20, 150, 200));
  EXPECT_EQ(l.displaysOfProcess(1), (std::vector<int>{1, 2}));
  EXPECT_EQ(l.displaysOfProcess(0), (std::vector<int>{0}));
  EXPECT_EQ(l.displays[2].monitor, 1);
  EXPECT_FALSE(l.displays[2].fullscreen);
}

TEST(Layout, ShippedSizesAreNotTileMultiples) {
  for (const char* name : {"1x1.toml", "2x2.toml", "3x2-bezels.toml", "mixed.toml"}) {
    const wall::Layout l = loadShippedLayout(name);
    EXPECT_TRUE(l.canvasWidth % 64 != 0 || l.canvasHeight % 64 != 0) << name;
    for (const wall::Display& d : l.displays)
      EXPECT_TRUE(d.rect.width() % 64 != 0 || d.rect.height() % 64 != 0) << name << " " << d.name;
  }
}

TEST(Layout, CanvasIsMovedToStartAtZero) {
  const wall::LayoutResult r = wall::readLayoutText(R"(
[[display]]
name = "a"
origin = [100, -40]
size = [50, 60]
[[display]]
name = "b"
origin = [160, -30]
size = [70, 20]
)",
                                                    "inline.toml");
  ASSERT_TRUE(r.ok()) << wall::joinProblems(r.problems);
  EXPECT_EQ(r.layout.displays[0].rect, rect(0, 0, 50, 60));
  EXPECT_EQ(r.layout.displays[1].rect, rect(60, 10, 70, 20));
  EXPECT_EQ(r.layout.canvasWidth, 130);
  EXPECT_EQ(r.layout.canvasHeight, 60);
  EXPECT_EQ(r.layout.processCount, 2);
  EXPECT_EQ(r.layout.displays[1].lines.table, 6);
  EXPECT_EQ(r.layout.displays[1].lines.size, 9);
  EXPECT_EQ(r.layout.displays[1].columns.table, 1);
  EXPECT_EQ(r.layout.displays[1].columns.size, 8);
}

TEST(Layout, LoadLayoutThrowsWithEveryProblem) {
  try {
    wall::loadLayout(std::string(DFBWALL_SOURCE_DIR) + "/tests/wall/bad/overlap.toml");
    FAIL() << "no exception";
  } catch (const base::Error& e) {
    EXPECT_NE(std::string(e.what()).find("overlap.toml:"), std::string::npos) << e.what();
  }
  try {
    wall::loadLayout(test::shippedLayoutPath("does-not-exist.toml"));
    FAIL() << "no exception";
  } catch (const base::Error& e) {
    EXPECT_NE(std::string(e.what()).find("does-not-exist.toml: cannot read"), std::string::npos)
        << e.what();
  }
}

TEST(Ranks, RenderRanksAreTheRest) {
  const wall::Layout l = loadShippedLayout("2x2.toml");  // 4 wall processes
  EXPECT_FALSE(wall::checkRankCount(l, 5));
  EXPECT_FALSE(wall::checkRankCount(l, 9));
  const wall::RankRoles roles = wall::rankRoles(l, 6);
  EXPECT_EQ(roles.renderRanks, 2);
  EXPECT_EQ(roles.wallRanks, 4);
  EXPECT_EQ(roles.rankOfProcess(0), 2);
  EXPECT_EQ(roles.rankOfProcess(3), 5);
  EXPECT_EQ(roles.processOfRank(1), -1);
  EXPECT_EQ(roles.processOfRank(4), 2);
}

TEST(Ranks, TooFewRanksIsAClearError) {
  const wall::Layout l = loadShippedLayout("2x2.toml");
  const auto message = wall::checkRankCount(l, 4);
  ASSERT_TRUE(message);
  EXPECT_NE(message->find("2x2.toml"), std::string::npos) << *message;
  EXPECT_NE(message->find("4 wall processes"), std::string::npos) << *message;
  EXPECT_NE(message->find("at least 5"), std::string::npos) << *message;
  EXPECT_NE(message->find("but it is 4"), std::string::npos) << *message;
  EXPECT_THROW(wall::rankRoles(l, 4), base::Error);
}

TEST(Ranks, ExplicitRenderRanksMustAddUp) {
  const wall::Layout l = loadShippedLayout("mixed.toml");  // 3 wall processes
  EXPECT_FALSE(wall::checkRankCount(l, 5, 2));
  const auto message = wall::checkRankCount(l, 6, 2);
  ASSERT_TRUE(message);
  EXPECT_NE(message->find("must be 2 render ranks + 3 = 5, but it is 6"), std::string::npos)
      << *message;
  EXPECT_TRUE(wall::checkRankCount(l, 3, 0));
}

TEST(Ranks, HostMismatchIsAWarningNamingTheDisplay) {
  const wall::LayoutResult r = wall::readLayoutText(R"([[display]]
name = "a"
origin = [0, 0]
size = [10, 10]
host = "node07"
[[display]]
name = "b"
origin = [10, 0]
size = [10, 10]
)",
                                                    "hosts.toml");
  ASSERT_TRUE(r.ok()) << wall::joinProblems(r.problems);
  EXPECT_EQ(r.layout.displays[0].host, "node07");
  EXPECT_TRUE(wall::hostWarnings(r.layout, 0, "node07").empty());
  EXPECT_TRUE(wall::hostWarnings(r.layout, 1, "anything").empty());  // 'b' names no host
  const auto w = wall::hostWarnings(r.layout, 0, "laptop");
  ASSERT_EQ(w.size(), 1u);
  EXPECT_EQ(w[0].rfind("hosts.toml:1: warning: display 'a' expects host 'node07', but wall "
                       "process 0 runs on 'laptop'",
                       0),
            0u)
      << w[0];
}

}  // namespace
