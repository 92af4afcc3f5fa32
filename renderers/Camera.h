#pragma once
// Pinhole camera (position, look-at, up, vertical field of view), optionally a thin lens; or,
// given a room (RoomView.h), an off-axis view per screen from its eye, the camera placing the
// room in the world. Image plane coordinates are canvas pixels, x right and y down, as the DFB's
// tiles are.
#include <cstddef>
#include <memory>

#include "renderers/Math.h"
#include "renderers/RoomView.h"

namespace renderers {

struct CameraDesc {
  Vec3 position{0, 0, -5};
  Vec3 lookAt{0, 0, 0};
  Vec3 up{0, 1, 0};
  float fovY = 45.0f;          // degrees
  float lensRadius = 0.0f;     // 0: pinhole
  float focusDistance = 0.0f;  // 0: the distance to lookAt
  bool operator==(const CameraDesc&) const = default;
};

// Whether the point at offset `v` from a camera looking along unit `forward` lies in front of
// the camera's plane by more than rounding (its screen position is then finite and meaningful).
inline bool inFrontOfCamera(Vec3 v, Vec3 forward) {
  return dot(v, forward) > 1e-6f * (1.0f + length(v));  // false for inf and NaN too
}

// `desc` with its position turned about lookAt around the up axis by `degrees` (right-handed
// about up). Pure arithmetic on the description, so every rank that asks for the same angle gets
// the same camera bit for bit, with no communication.
CameraDesc orbitCamera(const CameraDesc& desc, float degrees);

class Camera {
 public:
  // With `room`, the screens' frusta replace fovY and the lens (they are ignored).
  Camera(const CameraDesc& desc, int width, int height,
         std::shared_ptr<const RoomView> room = nullptr);
  // The ray through canvas point (px, py); (u, v) in [0,1)^2 pick the point on the lens. False
  // for a point no screen of the room shows (under a bezel): not to be traced (the ray given is
  // then the view direction, finite).
  bool ray(float px, float py, float u, float v, Vec3& origin, Vec3& direction) const;
  // Without a lens or a room every ray starts at position(): pinholeRays() gives many at once.
  bool pinhole() const { return lensRadius_ <= 0 && !room_; }
  // Whether the camera is the room's per-screen frusta.
  bool inRoom() const { return room_ != nullptr; }
  Vec3 position() const { return origin_; }
  // Pinhole only: for i < n the direction ray() gives through canvas point (px[i], py[i]) and
  // its per-axis reciprocal (1 / component, as clipToBox wants), the same bits, 4 rays at a time
  // in SSE where the CPU has it (the per-ray set-up of a tile is latency-bound one at a time).
  void pinholeRays(std::size_t n, const float* px, const float* py, Vec3* dirs,
                   Vec3* invDirs) const;

  // What ray() computes a pinhole camera's rays from, for SIMD versions of it that give the
  // same bits: direction = normalize((forward + right * sx) + up * sy) with
  // sx = (2 px invWidth - 1) halfWidth and sy = (1 - 2 py invHeight) halfHeight. False (and
  // nothing) for a thin lens.
  struct Pinhole {
    Vec3 origin, forward, right, up;
    float halfWidth, halfHeight, invWidth, invHeight;
  };
  bool pinhole(Pinhole& out) const {
    if (!pinhole()) return false;
    out = {origin_, forward_, right_, up_, halfWidth_, halfHeight_, invWidth_, invHeight_};
    return true;
  }

 private:
  Vec3 origin_, forward_, right_, up_;
  float halfWidth_, halfHeight_, invWidth_, invHeight_, lensRadius_, focus_;
  std::shared_ptr<const RoomView> room_;
  // A vector given in the room's axes, in the world's (the room turns with the camera).
  Vec3 toWorld(Vec3 v) const { return right_ * v.x + up_ * v.y - forward_ * v.z; }
};

}  // namespace renderers
