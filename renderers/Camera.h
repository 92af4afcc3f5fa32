#pragma once
// Pinhole camera (position, look-at, up, vertical field of view), optionally a thin lens.
// Image plane coordinates are canvas pixels, x right and y down, as the DFB's tiles are.
#include <cstddef>

#include "renderers/Math.h"

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
  Camera(const CameraDesc& desc, int width, int height);
  // The ray through canvas point (px, py); (u, v) in [0,1)^2 pick the point on the lens.
  void ray(float px, float py, float u, float v, Vec3& origin, Vec3& direction) const;
  // Without a lens every ray starts at position(): pinholeRays() then gives many at once.
  bool pinhole() const { return lensRadius_ <= 0; }
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
    if (lensRadius_ > 0) return false;
    out = {origin_, forward_, right_, up_, halfWidth_, halfHeight_, invWidth_, invHeight_};
    return true;
  }

 private:
  Vec3 origin_, forward_, right_, up_;
  float halfWidth_, halfHeight_, invWidth_, invHeight_, lensRadius_, focus_;
};

}  // namespace renderers
