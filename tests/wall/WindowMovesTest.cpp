// The rules of moving a running job's window (wall/service/server/WindowMoves.h).
#include <gtest/gtest.h>

#include "wall/service/server/WindowMoves.h"

namespace wall::service {
namespace {

// Two 100x80 displays with a 20-pixel bezel between them: canvas 220x80.
Layout twoDisplays() {
  Layout l;
  l.canvasWidth = 220;
  l.canvasHeight = 80;
  l.processCount = 2;
  Display left, right;
  left.name = "left";
  left.rect = {0, 0, 100, 80};
  left.process = 0;
  right.name = "right";
  right.rect = {120, 0, 220, 80};
  right.process = 1;
  l.displays = {left, right};
  return l;
}

TEST(WindowMoves, AWindowInsideTheCanvasTouchingADisplayMayBeMovedTo) {
  const Layout wall = twoDisplays();
  EXPECT_EQ(windowMoveProblem(wall, {90, 10, 130, 50}), "");  // across the bezel
  EXPECT_EQ(windowMoveProblem(wall, {0, 0, 220, 80}), "");    // the whole canvas
  EXPECT_EQ(windowMoveProblem(wall, {0, 0, 16, 16}), "");     // the smallest
}

TEST(WindowMoves, AWindowOutsideTooSmallOrOnTheBezelIsRefusedWithTheReason) {
  const Layout wall = twoDisplays();
  EXPECT_EQ(windowMoveProblem(wall, {200, 0, 240, 40}),
            "window 200,0,40,40 is not inside the wall's canvas (220x80)");
  EXPECT_EQ(windowMoveProblem(wall, {-1, 0, 40, 40}),
            "window -1,0,41,40 is not inside the wall's canvas (220x80)");
  EXPECT_NE(windowMoveProblem(wall, {10, 10, 10, 40}).find("not inside"), std::string::npos);
  EXPECT_EQ(windowMoveProblem(wall, {0, 0, 15, 40}), "window 0,0,15,40 is smaller than 16x16");
  EXPECT_EQ(windowMoveProblem(wall, {100, 0, 120, 40}),
            "window 100,0,20,40 touches no display (bezels only)");
}

TEST(WindowMoves, TheSwitchFrameIsTheFirstTheJobCannotHaveStarted) {
  // Credited 10 with 2 in flight: frames 11 and 12 may be rendering in the old shape.
  EXPECT_EQ(switchFrame(10, 2), 13u);
  EXPECT_EQ(switchFrame(0, 1), 2u);  // before the first credit: frame 1 may be on its way
  EXPECT_EQ(switchFrame(7, 16), 24u);
}

}  // namespace
}  // namespace wall::service
