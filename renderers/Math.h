#pragma once
// Small vector and affine-transform types for the renderers; header-only so the hot loops inline.
#include <algorithm>
#include <cmath>

namespace renderers {

constexpr float kPi = 3.14159265358979323846f;

struct Vec3 {
  float x = 0, y = 0, z = 0;
  constexpr Vec3() = default;
  constexpr Vec3(float a, float b, float c) : x(a), y(b), z(c) {}
  constexpr explicit Vec3(float s) : x(s), y(s), z(s) {}
  constexpr float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr bool operator==(const Vec3&) const = default;
};

constexpr Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
constexpr Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
constexpr Vec3 operator-(Vec3 a) { return {-a.x, -a.y, -a.z}; }
constexpr Vec3 operator*(Vec3 a, Vec3 b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
constexpr Vec3 operator*(Vec3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
constexpr Vec3 operator*(float s, Vec3 a) { return a * s; }
constexpr Vec3 operator/(Vec3 a, float s) { return a * (1.0f / s); }
constexpr Vec3& operator+=(Vec3& a, Vec3 b) { return a = a + b; }
constexpr Vec3& operator*=(Vec3& a, Vec3 b) { return a = a * b; }
constexpr Vec3& operator*=(Vec3& a, float s) { return a = a * s; }

constexpr float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length(Vec3 a) { return std::sqrt(dot(a, a)); }
inline Vec3 normalize(Vec3 a) { return a / length(a); }
constexpr float maxComponent(Vec3 a) { return std::max(a.x, std::max(a.y, a.z)); }
constexpr float minComponent(Vec3 a) { return std::min(a.x, std::min(a.y, a.z)); }
inline float maxAbs(Vec3 a) { return std::max({std::fabs(a.x), std::fabs(a.y), std::fabs(a.z)}); }
inline bool isFinite(Vec3 a) {
  return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}
// The gap between |x| and the next float above it: the finest detail a coordinate near x keeps.
inline float floatStep(float x) {
  const float a = std::fabs(x);
  return std::nextafter(a, INFINITY) - a;
}
constexpr float luminance(Vec3 c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }
constexpr bool isBlack(Vec3 c) { return c.x <= 0 && c.y <= 0 && c.z <= 0; }

// Orthonormal basis around a unit normal (Duff et al. 2017, branchless).
inline void basis(Vec3 n, Vec3& t, Vec3& b) {
  const float s = std::copysign(1.0f, n.z);
  const float a = -1.0f / (s + n.z);
  const float c = n.x * n.y * a;
  t = {1.0f + s * n.x * n.x * a, s * c, -s * n.x};
  b = {c, s + n.y * n.y * a, -n.y};
}

// x' = vx * x.x + vy * x.y + vz * x.z + p: column-major 3x4, the layout Embree takes.
struct Affine {
  Vec3 vx{1, 0, 0}, vy{0, 1, 0}, vz{0, 0, 1}, p{};
  constexpr Vec3 vector(Vec3 v) const { return vx * v.x + vy * v.y + vz * v.z; }
  constexpr Vec3 point(Vec3 v) const { return vector(v) + p; }
};

constexpr Affine operator*(const Affine& a, const Affine& b) {
  return {a.vector(b.vx), a.vector(b.vy), a.vector(b.vz), a.point(b.p)};
}
inline Affine inverse(const Affine& m) {
  const Vec3 r0 = cross(m.vy, m.vz), r1 = cross(m.vz, m.vx), r2 = cross(m.vx, m.vy);
  const float inv = 1.0f / dot(m.vx, r0);
  Affine out{Vec3{r0.x, r1.x, r2.x} * inv, Vec3{r0.y, r1.y, r2.y} * inv,
             Vec3{r0.z, r1.z, r2.z} * inv, Vec3{}};
  out.p = -out.vector(m.p);
  return out;
}
// Normals transform with the inverse transpose; `inv` is the inverse of the object's transform.
constexpr Vec3 transformNormal(const Affine& inv, Vec3 n) {
  return {dot(inv.vx, n), dot(inv.vy, n), dot(inv.vz, n)};
}
constexpr Affine translation(Vec3 t) { return {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, t}; }
constexpr Affine scaling(Vec3 s) { return {{s.x, 0, 0}, {0, s.y, 0}, {0, 0, s.z}, {}}; }
// Rotation by `degrees` about `axis` (right-handed).
inline Affine rotation(Vec3 axis, float degrees) {
  const Vec3 a = normalize(axis);
  const float r = degrees * kPi / 180.0f, c = std::cos(r), s = std::sin(r), t = 1 - c;
  return {{t * a.x * a.x + c, t * a.x * a.y + s * a.z, t * a.x * a.z - s * a.y},
          {t * a.x * a.y - s * a.z, t * a.y * a.y + c, t * a.y * a.z + s * a.x},
          {t * a.x * a.z + s * a.y, t * a.y * a.z - s * a.x, t * a.z * a.z + c},
          {}};
}

}  // namespace renderers
