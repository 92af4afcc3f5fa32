#pragma once
// Counter-based random numbers: every value is a pure function of (seed, canvas pixel,
// accumulation id, sample index, dimension). Nothing depends on thread, rank, tile or the order
// work is done in, which is what makes a wall render equal a single-process render bit for bit
// (docs/design.md, invariant 2).
#include <cstdint>

namespace renderers {

// A 64-bit finalizer (splitmix64 / Stafford variant 13): good avalanche, a handful of cycles.
constexpr std::uint64_t mix64(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

// The random stream of one sample of one pixel. Cheap to make; holds only its key.
class Sampler {
 public:
  constexpr Sampler() = default;  // a placeholder, to be assigned a real one
  constexpr Sampler(std::uint64_t seed, int x, int y, std::uint32_t accumulationId,
                    std::uint32_t sampleIndex)
      : key_(mix64(pixelKey(x, y) ^ sampleKey(seed, accumulationId, sampleIndex))) {}

  // The constructor's key is mix64(pixelKey(x, y) ^ sampleKey(...)): SIMD code derives many
  // pixels' keys at once from these parts, and makes their streams with fromKey().
  static constexpr std::uint64_t pixelKey(int x, int y) {
    return mix64((static_cast<std::uint64_t>(static_cast<std::uint32_t>(y)) << 32) |
                 static_cast<std::uint32_t>(x));
  }
  static constexpr std::uint64_t sampleKey(std::uint64_t seed, std::uint32_t accumulationId,
                                           std::uint32_t sampleIndex) {
    return mix64(seed ^ kDimensionStep) ^
           mix64((static_cast<std::uint64_t>(accumulationId) << 32 | sampleIndex) +
                 0x632be59bd9b4e019ull);
  }
  static constexpr Sampler fromKey(std::uint64_t key) {
    Sampler s;
    s.key_ = key;
    return s;
  }
  constexpr std::uint64_t key() const { return key_; }

  // A further stream of this sample, named by `salt`: e.g. the random numbers for shading one
  // surface hit, keyed by what was hit rather than by how many hits came before it, so a ray cut
  // into pieces (data-parallel bricks) shades each hit with the numbers the whole ray uses.
  constexpr Sampler fork(std::uint64_t salt) const {
    Sampler s;
    s.key_ = mix64(key_ ^ mix64(salt + 0xd1b54a32d192ed03ull));
    return s;
  }

  // Uniform in [0, 1) for dimension `d`; the same (key, d) always gives the same value.
  constexpr float get(std::uint32_t d) const {
    return static_cast<float>(mix64(key_ + (d + 1) * kDimensionStep) >> 40) * (1.0f / 16777216.0f);
  }

  // get(d) hashes key() + (d + 1) kDimensionStep.
  static constexpr std::uint64_t kDimensionStep = 0x9e3779b97f4a7c15ull;

 private:
  std::uint64_t key_ = 0;
};

}  // namespace renderers
