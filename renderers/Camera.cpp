#include "renderers/Camera.h"

#include <cmath>
#include <utility>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "base/Error.h"

namespace renderers {

CameraDesc orbitCamera(const CameraDesc& desc, float degrees) {
  if (degrees == 0.0f) return desc;
  CameraDesc out = desc;
  // Rotation() builds an orthonormal rotation from the normalised axis; lookAt is the pivot.
  out.position = desc.lookAt + rotation(desc.up, degrees).vector(desc.position - desc.lookAt);
  return out;
}

Camera::Camera(const CameraDesc& d, int width, int height, std::shared_ptr<const RoomView> room)
    : origin_(d.position), room_(std::move(room)) {
  if (width <= 0 || height <= 0) throw base::Error("camera: image size must be positive");
  const Vec3 view = d.lookAt - d.position;
  if (length(view) <= 0 || length(cross(view, d.up)) <= 0)
    throw base::Error("camera: look_at must differ from position and not lie along up");
  forward_ = normalize(view);
  // forward x up points to image right for a right-handed world: the classic Cornell box camera
  // (looking down +z, up +y) then shows the red wall (x = 556) on the left, as published.
  right_ = normalize(cross(forward_, d.up));
  up_ = cross(right_, forward_);
  halfHeight_ = std::tan(0.5f * d.fovY * kPi / 180.0f);
  halfWidth_ = halfHeight_ * static_cast<float>(width) / static_cast<float>(height);
  invWidth_ = 1.0f / static_cast<float>(width);
  invHeight_ = 1.0f / static_cast<float>(height);
  lensRadius_ = d.lensRadius;
  focus_ = d.focusDistance > 0 ? d.focusDistance : length(view);
}

bool Camera::ray(float px, float py, float u, float v, Vec3& origin, Vec3& direction) const {
  if (room_) {
    const int s =
        room_->screenAt(static_cast<int>(std::floor(px)), static_cast<int>(std::floor(py)));
    if (s < 0) {
      origin = origin_;
      direction = forward_;
      return false;
    }
    const Vec3 eye = room_->screens[static_cast<std::size_t>(s)].eye;
    origin = origin_ + toWorld(eye);
    direction = normalize(toWorld(room_->pointOn(s, px, py) - eye));
    return true;
  }
  const float sx = (2.0f * px * invWidth_ - 1.0f) * halfWidth_;
  const float sy = (1.0f - 2.0f * py * invHeight_) * halfHeight_;
  const Vec3 d = forward_ + right_ * sx + up_ * sy;
  if (lensRadius_ <= 0) {
    origin = origin_;
    direction = normalize(d);
    return true;
  }
  // Concentric-free polar lens sample is enough here: uniform over the disk.
  const float r = lensRadius_ * std::sqrt(u), phi = 2.0f * kPi * v;
  const Vec3 lens = right_ * (r * std::cos(phi)) + up_ * (r * std::sin(phi));
  const Vec3 focusPoint = origin_ + d * focus_;
  origin = origin_ + lens;
  direction = normalize(focusPoint - origin);
  return true;
}

void Camera::pinholeRays(std::size_t n, const float* px, const float* py, Vec3* dirs,
                         Vec3* invDirs) const {
  // ray()'s arithmetic, operation for operation (no fused multiply-adds in this file), so every
  // lane rounds as the scalar code does.
  std::size_t i = 0;
#if defined(__SSE2__)
  const __m128 two = _mm_set1_ps(2.0f), one = _mm_set1_ps(1.0f);
  const __m128 invW = _mm_set1_ps(invWidth_), invH = _mm_set1_ps(invHeight_);
  const __m128 halfW = _mm_set1_ps(halfWidth_), halfH = _mm_set1_ps(halfHeight_);
  const __m128 f[3] = {_mm_set1_ps(forward_.x), _mm_set1_ps(forward_.y), _mm_set1_ps(forward_.z)};
  const __m128 r[3] = {_mm_set1_ps(right_.x), _mm_set1_ps(right_.y), _mm_set1_ps(right_.z)};
  const __m128 u[3] = {_mm_set1_ps(up_.x), _mm_set1_ps(up_.y), _mm_set1_ps(up_.z)};
  for (; i + 4 <= n; i += 4) {
    const __m128 sx =
        _mm_mul_ps(_mm_sub_ps(_mm_mul_ps(_mm_mul_ps(two, _mm_loadu_ps(px + i)), invW), one), halfW);
    const __m128 sy =
        _mm_mul_ps(_mm_sub_ps(one, _mm_mul_ps(_mm_mul_ps(two, _mm_loadu_ps(py + i)), invH)), halfH);
    __m128 d[3];
    for (int a = 0; a < 3; ++a)
      d[a] = _mm_add_ps(_mm_add_ps(f[a], _mm_mul_ps(r[a], sx)), _mm_mul_ps(u[a], sy));
    const __m128 len = _mm_sqrt_ps(_mm_add_ps(
        _mm_add_ps(_mm_mul_ps(d[0], d[0]), _mm_mul_ps(d[1], d[1])), _mm_mul_ps(d[2], d[2])));
    const __m128 scale = _mm_div_ps(one, len);
    alignas(16) float out[6][4];
    for (int a = 0; a < 3; ++a) {
      const __m128 dir = _mm_mul_ps(d[a], scale);
      _mm_store_ps(out[a], dir);
      _mm_store_ps(out[3 + a], _mm_div_ps(one, dir));
    }
    for (int k = 0; k < 4; ++k) {
      dirs[i + k] = {out[0][k], out[1][k], out[2][k]};
      invDirs[i + k] = {out[3][k], out[4][k], out[5][k]};
    }
  }
#endif
  for (; i < n; ++i) {
    Vec3 origin;
    ray(px[i], py[i], 0.5f, 0.5f, origin, dirs[i]);
    invDirs[i] = {1.0f / dirs[i].x, 1.0f / dirs[i].y, 1.0f / dirs[i].z};
  }
}

}  // namespace renderers
