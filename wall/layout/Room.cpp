#include "wall/layout/Room.h"

#include <cmath>

namespace wall {

Point3 eyeAxis(const Viewer& viewer) {
  constexpr double kDegrees = 3.14159265358979323846 / 180.0;
  const double yaw = viewer.orientation[0] * kDegrees, pitch = viewer.orientation[1] * kDegrees,
               roll = viewer.orientation[2] * kDegrees;
  // R = Ry(yaw) Rx(pitch) Rz(roll) applied to (1, 0, 0).
  const double x = std::cos(roll), y = std::sin(roll);              // Rz
  const double y2 = y * std::cos(pitch), z2 = y * std::sin(pitch);  // Rx
  return {x * std::cos(yaw) + z2 * std::sin(yaw), y2, -x * std::sin(yaw) + z2 * std::cos(yaw)};
}

Point3 eyePosition(const Viewer& viewer, Eye eye) {
  if (eye == Eye::Centre) return viewer.head;
  const double half = 0.5 * viewer.eyeSeparation * (eye == Eye::Left ? -1.0 : 1.0);
  const Point3 axis = eyeAxis(viewer);
  return {viewer.head[0] + half * axis[0], viewer.head[1] + half * axis[1],
          viewer.head[2] + half * axis[2]};
}

}  // namespace wall
