#include "renderers/scivis/io/Particles.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "base/Error.h"
#include "base/Parallel.h"
#include "renderers/Rng.h"

namespace renderers::scivis {
namespace {

float unitFloat(std::uint64_t key) {
  return static_cast<float>(mix64(key) >> 40) * (1.0f / 16777216.0f);
}

// A point in the unit ball from a key (rejection-free: direction and cube-root radius).
Vec3 inUnitBall(std::uint64_t key) {
  const float z = 2.0f * unitFloat(key + 1) - 1.0f, phi = 2.0f * kPi * unitFloat(key + 2);
  const float s = std::sqrt(std::max(0.0f, 1.0f - z * z)), r = std::cbrt(unitFloat(key + 3));
  return Vec3{s * std::cos(phi), s * std::sin(phi), z} * r;
}

}  // namespace

ParticlesDesc clusteredParticles(std::size_t count, std::uint64_t seed, Vec3 center, float size,
                                 float radius) {
  // Soneira-Peebles: kTop halos, each splits into kBranch clumps kLevels deep, every level
  // 1/kShrink the size of the one above. A particle walks down a random path and stops at a
  // random depth, so deep (dense) clumps hold the most particles per volume.
  constexpr int kTop = 12, kBranch = 4, kLevels = 6;
  constexpr float kShrink = 2.2f, kBackground = 0.02f;
  const std::uint64_t base = mix64(seed ^ 0x5ca1ab1e0ddba11ull);
  ParticlesDesc p;
  p.name = "clusters";
  p.centers.resize(count);
  p.attribute.resize(count);
  p.radii = {radius};
  const float half = 0.5f * size;
  base::parallelFor((count + 4095) / 4096, [&](std::size_t block) {
    for (std::size_t i = block * 4096; i < std::min(count, (block + 1) * 4096); ++i) {
      const std::uint64_t key = mix64(base + i * 0x9e3779b97f4a7c15ull);
      if (unitFloat(key) < kBackground) {
        p.centers[i] = center + Vec3{unitFloat(key + 11) - 0.5f, unitFloat(key + 12) - 0.5f,
                                     unitFloat(key + 13) - 0.5f} *
                                    size;
        p.attribute[i] = 0.0f;
        continue;
      }
      // The clump tree is a function of the seed alone: its node keys hash the path taken.
      std::uint64_t node =
          mix64(base ^ (1 + static_cast<std::uint64_t>(unitFloat(key + 20) * kTop)));
      Vec3 c = center + inUnitBall(node) * (0.6f * half);
      float r = 0.35f * half;
      const int depth = 1 + static_cast<int>(unitFloat(key + 21) * kLevels);
      for (int level = 1; level < depth; ++level) {
        const std::uint64_t branch =
            1 + static_cast<std::uint64_t>(unitFloat(key + 30 + level) * kBranch);
        node = mix64(node * 31 + branch);
        c = c + inUnitBall(node) * r;
        r /= kShrink;
      }
      Vec3 q = c + inUnitBall(key + 40) * r;
      // Keep every particle inside the cube.
      q = {std::clamp(q.x, center.x - half, center.x + half),
           std::clamp(q.y, center.y - half, center.y + half),
           std::clamp(q.z, center.z - half, center.z + half)};
      p.centers[i] = q;
      p.attribute[i] = (static_cast<float>(depth) - unitFloat(key + 41)) / kLevels;
    }
  });
  return p;
}

void readParticleFile(const std::string& path, const std::string& layout, ParticlesDesc& out) {
  int x = -1, y = -1, z = -1, r = -1, a = -1;
  for (std::size_t i = 0; i < layout.size(); ++i) {
    int* slot = layout[i] == 'x'   ? &x
                : layout[i] == 'y' ? &y
                : layout[i] == 'z' ? &z
                : layout[i] == 'r' ? &r
                : layout[i] == 'a' ? &a
                                   : nullptr;
    if (!slot || *slot >= 0)
      throw base::Error("layout '" + layout +
                        "': use each of x, y, z, r, a at most once, and no other letter");
    *slot = static_cast<int>(i);
  }
  if (x < 0 || y < 0 || z < 0) throw base::Error("layout '" + layout + "' needs x, y and z");
  const std::size_t fields = layout.size(), recordBytes = fields * sizeof(float);
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) throw base::Error(path + ": cannot read (" + ec.message() + ")");
  if (size == 0 || size % recordBytes != 0)
    throw base::Error(path + ": " + std::to_string(size) + " bytes is not a whole number of " +
                      std::to_string(recordBytes) + "-byte records (layout '" + layout + "')");
  const std::size_t n = size / recordBytes;
  std::vector<float> data(n * fields);
  std::ifstream in(path, std::ios::binary);
  if (!in.read(reinterpret_cast<char*>(data.data()), static_cast<std::streamsize>(size)))
    throw base::Error(path + ": read failed");
  out.centers.resize(n);
  if (r >= 0) out.radii.resize(n);
  if (a >= 0) out.attribute.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const float* rec = &data[i * fields];
    out.centers[i] = {rec[x], rec[y], rec[z]};
    if (!std::isfinite(rec[x] + rec[y] + rec[z]))
      throw base::Error(path + ": particle " + std::to_string(i) + " has a non-finite position");
    if (r >= 0) out.radii[i] = rec[r];
    if (a >= 0) out.attribute[i] = rec[a];
  }
}

}  // namespace renderers::scivis
