#pragma once
// Scattering at a surface point for the materials of Material.h. Directions point away from the
// surface; `n` is the unit geometric normal already turned to the side `wo` is on, except for
// glass, which takes the front-side normal and whether the ray arrives from the front.
#include "renderers/Material.h"
#include "renderers/Math.h"

namespace renderers {

struct BsdfSample {
  Vec3 wi;
  Vec3 weight;    // f * |cos| / pdf
  float pdf = 0;  // solid angle; meaningless when `specular`
  bool specular = false;
};

// Returns false when the sample is absorbed (or falls below the surface).
bool sampleBsdf(const Material& m, Vec3 n, Vec3 wo, bool front, float u0, float u1, float u2,
                BsdfSample& out);
// f * |cos(wi)| for a non-specular material, and the pdf sampleBsdf would have given wi.
Vec3 evalBsdf(const Material& m, Vec3 n, Vec3 wo, Vec3 wi, float& pdf);

}  // namespace renderers
