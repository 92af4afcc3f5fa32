#pragma once
// Axis-aligned world boxes and the ray interval inside one: how camera rays are clipped to a
// brick, and how volumes and their macrocells are entered and left.
#include <algorithm>
#include <limits>

#include "renderers/Math.h"

namespace renderers::scivis {

struct Box3 {
  static constexpr float kInf = std::numeric_limits<float>::infinity();
  Vec3 lo{-kInf}, hi{kInf};  // default: all of space
  bool empty() const { return !(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z); }
  bool contains(Vec3 p) const {
    return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
  }
  bool operator==(const Box3&) const = default;
};

// `b` widened to hold [lo, hi].
inline void grow(Box3& b, Vec3 lo, Vec3 hi) {
  b.lo = {std::min(b.lo.x, lo.x), std::min(b.lo.y, lo.y), std::min(b.lo.z, lo.z)};
  b.hi = {std::max(b.hi.x, hi.x), std::max(b.hi.y, hi.y), std::max(b.hi.z, hi.z)};
}

inline Vec3 reciprocal(Vec3 d) { return {1.0f / d.x, 1.0f / d.y, 1.0f / d.z}; }

// One axis of clipToBox(): [t0, t1] narrowed to the slab lo <= origin + t dir <= hi along it
// (o: the origin's coordinate, inv: 1 / the direction's).
inline void clipToSlab(float lo, float hi, float o, float inv, float& t0, float& t1) {
  float near = (lo - o) * inv, far = (hi - o) * inv;
  if (near > far) std::swap(near, far);
  // A ray parallel to a slab and inside it gives (-inf, inf); on its plane, NaN: keep it in.
  if (near == near) t0 = std::max(t0, near);
  if (far == far) t1 = std::min(t1, far);
}

// Narrows [t0, t1] to the part of origin + t * dir inside `box` (invDir = 1 / dir per axis, inf
// for a zero component). False when nothing is left. Infinite boxes give back [t0, t1].
inline bool clipToBox(const Box3& box, Vec3 origin, Vec3 invDir, float& t0, float& t1) {
  for (int a = 0; a < 3; ++a) clipToSlab(box.lo[a], box.hi[a], origin[a], invDir[a], t0, t1);
  return t0 <= t1;
}

}  // namespace renderers::scivis
