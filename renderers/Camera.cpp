#include "renderers/Camera.h"

#include <cmath>

#include "renderers/Error.h"

namespace renderers {

CameraDesc orbitCamera(const CameraDesc& desc, float degrees) {
  if (degrees == 0.0f) return desc;
  CameraDesc out = desc;
  // Rotation() builds an orthonormal rotation from the normalised axis; lookAt is the pivot.
  out.position = desc.lookAt + rotation(desc.up, degrees).vector(desc.position - desc.lookAt);
  return out;
}

Camera::Camera(const CameraDesc& d, int width, int height) : origin_(d.position) {
  if (width <= 0 || height <= 0) throw Error("camera: image size must be positive");
  const Vec3 view = d.lookAt - d.position;
  if (length(view) <= 0 || length(cross(view, d.up)) <= 0)
    throw Error("camera: look_at must differ from position and not lie along up");
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

void Camera::ray(float px, float py, float u, float v, Vec3& origin, Vec3& direction) const {
  const float sx = (2.0f * px * invWidth_ - 1.0f) * halfWidth_;
  const float sy = (1.0f - 2.0f * py * invHeight_) * halfHeight_;
  const Vec3 d = forward_ + right_ * sx + up_ * sy;
  if (lensRadius_ <= 0) {
    origin = origin_;
    direction = normalize(d);
    return;
  }
  // Concentric-free polar lens sample is enough here: uniform over the disk.
  const float r = lensRadius_ * std::sqrt(u), phi = 2.0f * kPi * v;
  const Vec3 lens = right_ * (r * std::cos(phi)) + up_ * (r * std::sin(phi));
  const Vec3 focusPoint = origin_ + d * focus_;
  origin = origin_ + lens;
  direction = normalize(focusPoint - origin);
}

}  // namespace renderers
