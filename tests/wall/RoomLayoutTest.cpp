// Screens placed in a room (docs/rooms.md): the shipped rooms parse to the corners and eyes their
// comments promise, the generators place panels where the geometry says, and every bad room is
// one precise message (file, line, column, field).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "tests/wall/ShippedLayoutTestUtil.h"
#include "wall/layout/Layout.h"

namespace {

using test::loadShippedLayout;

void expectNear(const wall::Point3& got, const wall::Point3& want) {
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(got[i], want[i], 1e-9) << "coordinate " << i;
}

// `text` (a layout) must give exactly the problems that start with `expected`, in order.
void expectProblems(const std::string& text, const std::vector<std::string>& expected) {
  const wall::LayoutResult r = wall::readLayoutText(text, "room.toml");
  ASSERT_EQ(r.problems.size(), expected.size()) << wall::joinProblems(r.problems);
  for (size_t i = 0; i < expected.size(); ++i)
    EXPECT_EQ(r.problems[i].substr(0, expected[i].size() + 10), "room.toml:" + expected[i])
        << r.problems[i];
}

TEST(RoomLayout, FlatLayoutsHaveNoRoom) {
  for (const char* name : {"1x1.toml", "2x2.toml", "3x2-bezels.toml", "mixed.toml"}) {
    const wall::Layout l = loadShippedLayout(name);
    EXPECT_FALSE(l.inRoom()) << name;
    for (const wall::Display& d : l.displays) EXPECT_FALSE(d.screen.has_value()) << name;
  }
}

TEST(RoomLayout, CaveCorner) {
  const wall::Layout l = loadShippedLayout("cave-corner.toml");
  ASSERT_TRUE(l.inRoom());
  ASSERT_EQ(l.displays.size(), 3u);
  EXPECT_EQ(l.canvasWidth, 240);
  EXPECT_EQ(l.canvasHeight, 240);
  const wall::Display& front = l.displays[static_cast<size_t>(l.findDisplay("front"))];
  expectNear(front.screen->bottomLeft, {-1.5, -1.5, -1.5});
  expectNear(front.screen->topLeft, {-1.5, 1.5, -1.5});
  EXPECT_EQ(front.eye, wall::Eye::Centre);
  expectNear(wall::eyePosition(*l.viewer, front.eye), {0, 0, 0});
  EXPECT_DOUBLE_EQ(l.viewer->eyeSeparation, 0.065);
}

TEST(RoomLayout, CylinderColumnsFaceTheAxis) {
  const wall::Layout l = loadShippedLayout("cylinder-3x2.toml");
  ASSERT_TRUE(l.inRoom());
  ASSERT_EQ(l.displays.size(), 6u);
  // The middle column is straight ahead: its picture centred on x = 0 at z = -radius.
  const wall::Screen& top = *l.displays[1].screen;     // r0c1
  const wall::Screen& bottom = *l.displays[4].screen;  // r1c1
  expectNear(bottom.bottomLeft, {-0.6, -0.83, -3.2});
  expectNear(bottom.bottomRight, {0.6, -0.83, -3.2});
  expectNear(bottom.topLeft, {-0.6, -0.03, -3.2});
  expectNear(top.bottomLeft, {-0.6, 0.03, -3.2});  // a row pitch of 0.8 + 0.03 + 0.03 up
  // Column 2, 24 degrees to the right: its centre at the radius, its width along the tangent.
  const wall::Screen& right = *l.displays[5].screen;
  const double a = 24.0 * 3.14159265358979323846 / 180.0;
  const wall::Point3 centre{3.2 * std::sin(a), -0.83, -3.2 * std::cos(a)};
  expectNear(right.bottomLeft,
             {centre[0] - 0.6 * std::cos(a), -0.83, centre[2] - 0.6 * std::sin(a)});
  expectNear(right.bottomRight,
             {centre[0] + 0.6 * std::cos(a), -0.83, centre[2] + 0.6 * std::sin(a)});
}

TEST(RoomLayout, PassiveStereoEyes) {
  const wall::Layout l = loadShippedLayout("stereo-2x2.toml");
  ASSERT_TRUE(l.inRoom());
  ASSERT_EQ(l.displays.size(), 8u);
  EXPECT_EQ(l.processCount, 4);
  const wall::Display& left = l.displays[static_cast<size_t>(l.findDisplay("r0c0-left"))];
  const wall::Display& right = l.displays[static_cast<size_t>(l.findDisplay("r0c0-right"))];
  EXPECT_EQ(left.eye, wall::Eye::Left);
  EXPECT_EQ(right.eye, wall::Eye::Right);
  expectNear(left.screen->bottomLeft, right.screen->bottomLeft);
  expectNear(wall::eyePosition(*l.viewer, left.eye), {-0.0325, 0, 0});
  expectNear(wall::eyePosition(*l.viewer, right.eye), {0.0325, 0, 0});
}

TEST(RoomLayout, HeadOrientationTurnsTheEyeAxis) {
  wall::Viewer v;
  v.head = {1, 2, 3};
  v.orientation = {90, 0, 0};  // turned left: the eye axis points along -z... and right eye there
  expectNear(wall::eyeAxis(v), {0, 0, -1});
  expectNear(wall::eyePosition(v, wall::Eye::Right), {1, 2, 3 - 0.0325});
  v.orientation = {0, 0, 90};  // rolled: the axis points up
  expectNear(wall::eyeAxis(v), {0, 1, 0});
}

TEST(RoomLayout, PlaneGeneratorWithBezels) {
  const wall::LayoutResult r = wall::readLayoutText(R"(
[grid]
columns = 2
rows = 2
display_size = [100, 50]
bezel_px = [2, 2, 1, 1]
[grid.room]
origin = [0.0, 1.0, -2.0]
right = [0.0, 0.0, 2.0]
up = [0.0, 1.0, 0.0]
tile_size = [1.0, 0.5]
bezel = [0.01, 0.02, 0.03, 0.04]
)",
                                                    "plane.toml");
  ASSERT_TRUE(r.ok()) << wall::joinProblems(r.problems);
  // right is normalised (+z); r1c0 is the bottom-left panel at the origin; r0c1 is one column
  // pitch (1 + 0.01 + 0.02) along z and one row pitch (0.5 + 0.03 + 0.04) up.
  expectNear(r.layout.displays[2].screen->bottomLeft, {0, 1, -2});
  expectNear(r.layout.displays[2].screen->bottomRight, {0, 1, -1});
  expectNear(r.layout.displays[1].screen->bottomLeft, {0, 1.57, -2 + 1.03});
  expectNear(r.layout.displays[1].screen->topLeft, {0, 2.07, -2 + 1.03});
}

TEST(RoomLayout, BadRooms) {
  const std::string display = "[[display]]\nname = \"a\"\norigin = [0, 0]\nsize = [10, 10]\n";
  expectProblems(display + "bottom_left = [0, 0, -1]\nbottom_right = [1, 0, -1]\n",
                 {"1:1: display 'a'.top_left: missing"});
  expectProblems(display +
                     "bottom_left = [0, 0, -1]\nbottom_right = [1, 0, -1]\n"
                     "top_left = [1, 1, -1]\n",
                 {"5:15: display 'a'.top_left: the screen must be a rectangle"});
  expectProblems(display +
                     "bottom_left = [0, 0, -1]\nbottom_right = [0, 0, -1]\n"
                     "top_left = [0, 1, -1]\n",
                 {"5:15: display 'a'.bottom_right: the corners must span a screen"});
  expectProblems(display + "eye = \"left\"\n",
                 {"5:7: display 'a'.eye: only a display placed in the room"});
  expectProblems(display +
                     "bottom_left = [0, 0, -1]\nbottom_right = [1, 0, -1]\n"
                     "top_left = [0, 1, -1]\neye = \"centre\"\n",
                 {"8:7: display 'a'.eye: must be \"left\" or \"right\""});
  expectProblems(display + "[viewer]\nhead = [0, 0, 0]\n",
                 {"5:1: viewer: a viewer needs displays placed in the room"});
  expectProblems(display +
                     "bottom_left = [0, 0, -1]\nbottom_right = [1, 0, -1]\n"
                     "top_left = [0, 1, -1]\n[viewer]\neye_separation = -0.1\nhed = [0, 0, 0]\n",
                 {"10:1: viewer: unknown field 'hed'", "9:18: viewer.eye_separation: must be 0"});
  expectProblems(display +
                     "bottom_left = [0, 0, -1]\nbottom_right = [1, 0, -1]\n"
                     "top_left = [0, 1, -1]\n"
                     "[[display]]\nname = \"b\"\norigin = [10, 0]\nsize = [10, 10]\n",
                 {"8:1: display 'b': not placed in the room, while display 'a' is"});
  const std::string grid = "[grid]\ncolumns = 2\nrows = 1\ndisplay_size = [10, 10]\n[grid.room]\n";
  expectProblems(grid +
                     "shape = \"cylinder\"\nradius = 3\nfirst_angle = 0\n"
                     "tile_size = [1, 1]\norigin = [0, 0, 0]\n",
                 {"10:10: grid.room.origin: is not a field of a cylinder",
                  "5:1: grid.room.angle_per_column: missing"});
  expectProblems(grid +
                     "shape = \"cylinder\"\nradius = 3\nfirst_angle = 0\n"
                     "angle_per_column = 200\ntile_size = [1, 1]\n",
                 {"9:20: grid.room.angle_per_column: must be non-zero, the columns spanning"});
  expectProblems(
      grid + "origin = [0, 0, 0]\nright = [1, 0, 0]\nup = [1, 1, 0]\ntile_size = [1, 1]\n",
      {"8:6: grid.room.up: must be at right angles"});
  expectProblems(grid + "shape = \"dome\"\n", {"6:9: grid.room.shape: must be \"plane\" or"});
}

}  // namespace
