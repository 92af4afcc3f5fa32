#pragma once
// Screens placed in a room and the eye that looks at each: the off-axis camera model of an
// immersive wall (docs/rooms.md). Each screen shows a rectangle of canvas pixels; a pixel's
// primary ray goes from its screen's eye through the pixel's point on the screen's rectangle.
//
// Room coordinates are metres, x right, y up, z towards the viewer (the front wall of a CAVE
// lies at negative z). The scene's camera places the room in the world: the room's origin at
// the camera's position, x along the camera's right, y along its up, -z along its view.
#include <vector>

#include "dfb/Tile.h"
#include "renderers/Math.h"

namespace renderers {

struct ScreenView {
  dfb::Region pixels;  // the canvas pixels this screen shows
  // The screen's rectangle in the room: the picture's bottom-left, bottom-right and top-left
  // corners (the top-right one completes the parallelogram).
  Vec3 bottomLeft, bottomRight, topLeft;
  Vec3 eye;  // the eye that looks at it, in the room (the head moved by half the eye separation)
};

struct RoomView {
  std::vector<ScreenView> screens;

  // The screen that shows canvas pixel (x, y), or -1 (a pixel under a bezel or in a gap).
  int screenAt(int x, int y) const;
  // The point of screen `s` at canvas point (px, py) (pixel centres at + 0.5), in the room.
  Vec3 pointOn(int s, float px, float py) const;
};

}  // namespace renderers
