#pragma once
// Screens placed in a room and the viewer who looks at them (docs/rooms.md): what a layout says
// about an immersive wall. Room coordinates are metres, x right, y up, z towards the viewer.
#include <array>
#include <optional>

namespace wall {

using Point3 = std::array<double, 3>;

// A display's picture in the room: its bottom-left, bottom-right and top-left corners.
struct Screen {
  Point3 bottomLeft{}, bottomRight{}, topLeft{};
};

// Which eye a display shows (passive stereo: two displays with the same corners, one per eye).
enum class Eye { Centre, Left, Right };

struct Viewer {
  Point3 head{0, 0, 0};
  // Degrees: yaw about y (positive turns to the left, towards -x), then pitch about x, then roll
  // about z. Only the eye axis (the head's x) depends on it: a frustum is fixed by its eye point.
  std::array<double, 3> orientation{0, 0, 0};
  double eyeSeparation = 0.065;  // metres
};

// The head's x axis (from the left eye to the right one), in the room.
Point3 eyeAxis(const Viewer& viewer);
// Where `eye` of `viewer` is in the room: the head moved by half the separation along the axis.
Point3 eyePosition(const Viewer& viewer, Eye eye);

}  // namespace wall
