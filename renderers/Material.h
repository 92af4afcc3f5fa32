#pragma once
// Surface materials. An emissive surface emits `emission` (radiance) from its front side and
// reflects nothing; every emissive triangle is an area light sampled for next-event estimation.
#include <string>

#include "renderers/Math.h"

namespace renderers {

enum class MaterialType { Diffuse, Emissive, Metal, Glass };

struct Material {
  std::string name;
  MaterialType type = MaterialType::Diffuse;
  Vec3 color{0.8f};  // diffuse albedo, metal reflectance at normal incidence, glass tint
  Vec3 emission{};
  float roughness = 0.0f;  // metal: GGX alpha = roughness^2; 0 is a perfect mirror
  float ior = 1.5f;        // glass
  // The scivis renderer's local shading: 1 - opacity of the light passes through the surface,
  // and a Phong highlight of `specular` strength and exponent `shininess`.
  float opacity = 1.0f;
  float specular = 0.0f;
  float shininess = 32.0f;
};

// True when the BSDF is a delta distribution (no next-event estimation through it).
inline bool isSpecular(const Material& m) {
  return m.type == MaterialType::Glass || (m.type == MaterialType::Metal && m.roughness < 1e-3f);
}

}  // namespace renderers
