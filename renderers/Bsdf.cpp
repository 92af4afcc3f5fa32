#include "renderers/Bsdf.h"

#include <cmath>

namespace renderers {
namespace {

Vec3 toWorld(Vec3 n, Vec3 local) {
  Vec3 t, b;
  basis(n, t, b);
  return t * local.x + b * local.y + n * local.z;
}

Vec3 reflect(Vec3 wo, Vec3 n) { return n * (2 * dot(wo, n)) - wo; }

Vec3 schlick(Vec3 f0, float cosTheta) {
  const float m = std::pow(1.0f - std::clamp(cosTheta, 0.0f, 1.0f), 5.0f);
  return f0 + (Vec3{1.0f} - f0) * m;
}

// Unpolarised Fresnel reflectance of a dielectric; eta = n_incident / n_transmitted.
float fresnelDielectric(float cosI, float eta) {
  const float sin2T = eta * eta * (1.0f - cosI * cosI);
  if (sin2T >= 1.0f) return 1.0f;
  const float cosT = std::sqrt(1.0f - sin2T);
  const float rs = (eta * cosI - cosT) / (eta * cosI + cosT);
  const float rp = (cosI - eta * cosT) / (cosI + eta * cosT);
  return 0.5f * (rs * rs + rp * rp);
}

// GGX (Trowbridge-Reitz) with the separable Smith shadowing term.
float ggxD(float cosH, float a2) {
  const float d = cosH * cosH * (a2 - 1.0f) + 1.0f;
  return a2 / (kPi * d * d);
}
float smithG1(float cosV, float a2) {
  return 2.0f * cosV / (cosV + std::sqrt(a2 + (1.0f - a2) * cosV * cosV));
}

Vec3 evalMetal(const Material& m, Vec3 n, Vec3 wo, Vec3 wi, float& pdf) {
  const float cosO = dot(n, wo), cosI = dot(n, wi);
  pdf = 0;
  if (cosO <= 0 || cosI <= 0) return {};
  const Vec3 h = normalize(wo + wi);
  const float a = m.roughness * m.roughness, a2 = a * a;
  const float cosH = dot(n, h), hDotO = dot(h, wo);
  const float d = ggxD(cosH, a2);
  pdf = d * cosH / (4.0f * hDotO);
  const float g = smithG1(cosO, a2) * smithG1(cosI, a2);
  return schlick(m.color, hDotO) * (d * g / (4.0f * cosO));
}

}  // namespace

Vec3 evalBsdf(const Material& m, Vec3 n, Vec3 wo, Vec3 wi, float& pdf) {
  switch (m.type) {
    case MaterialType::Diffuse: {
      const float c = dot(n, wi);
      pdf = c > 0 ? c / kPi : 0;
      return c > 0 ? m.color * (c / kPi) : Vec3{};
    }
    case MaterialType::Metal:
      if (m.roughness >= 1e-3f) return evalMetal(m, n, wo, wi, pdf);
      break;
    case MaterialType::Emissive:
    case MaterialType::Glass:
      break;
  }
  pdf = 0;
  return {};
}

bool sampleBsdf(const Material& m, Vec3 n, Vec3 wo, bool front, float u0, float u1, float u2,
                BsdfSample& out) {
  switch (m.type) {
    case MaterialType::Emissive:
      return false;
    case MaterialType::Diffuse: {
      // Cosine-weighted hemisphere: f * cos / pdf is exactly the albedo.
      const float r = std::sqrt(u0), phi = 2.0f * kPi * u1;
      const float z = std::sqrt(std::max(0.0f, 1.0f - u0));
      out.wi = toWorld(n, {r * std::cos(phi), r * std::sin(phi), z});
      out.pdf = z / kPi;
      out.weight = m.color;
      out.specular = false;
      return out.pdf > 0;
    }
    case MaterialType::Metal: {
      if (m.roughness < 1e-3f) {
        out.wi = reflect(wo, n);
        out.weight = schlick(m.color, dot(n, wo));
        out.pdf = 1;
        out.specular = true;
        return dot(out.wi, n) > 0;
      }
      const float a = m.roughness * m.roughness, a2 = a * a;
      // Sample the GGX normal distribution D(h) cos(h).
      const float cos2 = (1.0f - u0) / (1.0f + (a2 - 1.0f) * u0);
      const float cosH = std::sqrt(cos2), sinH = std::sqrt(std::max(0.0f, 1.0f - cos2));
      const float phi = 2.0f * kPi * u1;
      const Vec3 h = toWorld(n, {sinH * std::cos(phi), sinH * std::sin(phi), cosH});
      out.wi = reflect(wo, h);
      out.specular = false;
      float pdf;
      const Vec3 f = evalMetal(m, n, wo, out.wi, pdf);
      if (pdf <= 0) return false;
      out.pdf = pdf;
      out.weight = f / pdf;
      return true;
    }
    case MaterialType::Glass: {
      // `n` faces the front (outside); eta is outside over inside for a ray entering.
      const Vec3 nf = front ? n : -n;  // normal on the side of wo
      const float eta = front ? 1.0f / m.ior : m.ior;
      const float cosI = dot(nf, wo);
      const float f = fresnelDielectric(cosI, eta);
      out.pdf = 1;
      out.specular = true;
      if (u2 < f) {
        out.wi = reflect(wo, nf);
        out.weight = Vec3{1.0f};
      } else {
        const float sin2T = eta * eta * (1.0f - cosI * cosI);
        const float cosT = std::sqrt(std::max(0.0f, 1.0f - sin2T));
        out.wi = normalize(-wo * eta + nf * (eta * cosI - cosT));
        // No 1/eta^2 radiance scaling: it cancels for light that enters and leaves a closed
        // object, which is all our glass is.
        out.weight = m.color;
      }
      return true;
    }
  }
  return false;
}

}  // namespace renderers
