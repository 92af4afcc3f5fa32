// The AVX2 tone-mapping kernel against the scalar one (the definition): the same bits for every
// pixel, on random values over the whole useful range, near the sRGB steps, and on the values a
// renderer can produce by mistake (negative, zero of both signs, infinite, NaN, huge).
#include "dfb/ToneMapKernel.h"

#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

namespace dfb {
namespace {

std::vector<float> randomPixels(std::size_t pixels, std::uint32_t seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> linear(-0.25f, 2.0f);
  std::uniform_int_distribution<std::uint32_t> bits(0, 0xFFFFFFFFu);
  const float special[] = {0.0f,
                           -0.0f,
                           1.0f,
                           -1.0f,
                           1e-30f,
                           1e30f,
                           std::numeric_limits<float>::denorm_min(),
                           std::numeric_limits<float>::infinity(),
                           -std::numeric_limits<float>::infinity(),
                           std::numeric_limits<float>::quiet_NaN(),
                           std::bit_cast<float>(0x3F800001u),
                           std::bit_cast<float>(0x3F7FFFFFu)};
  std::vector<float> rgba(4 * pixels);
  for (float& v : rgba) {
    switch (random() % 8) {
      case 0:
        v = special[random() % std::size(special)];
        break;
      case 1:
        v = std::bit_cast<float>(bits(random));
        break;  // any pattern, NaNs included
      case 2:
        v = std::bit_cast<float>(bits(random) % 0x3F800001u);
        break;  // [0, 1] by bits
      default:
        v = linear(random);
        break;
    }
  }
  return rgba;
}

void expectSameAsScalar(const std::vector<float>& rgba, const ToneMapSettings& settings) {
  const std::size_t n = rgba.size() / 4;
  std::vector<std::uint32_t> scalar(n), fast(n), dispatched(n);
  toneMapPixelsScalar(rgba.data(), n, scalar.data(), settings);
  toneMapPixelsAvx2(rgba.data(), n, fast.data(), settings);
  toneMapPixels(rgba.data(), n, dispatched.data(), settings);
  for (std::size_t p = 0; p < n; ++p) {
    ASSERT_EQ(fast[p], scalar[p]) << "pixel " << p << " (" << rgba[4 * p] << ", " << rgba[4 * p + 1]
                                  << ", " << rgba[4 * p + 2] << ", " << rgba[4 * p + 3]
                                  << "), exposure " << settings.exposure
                                  << (settings.filmic ? ", filmic" : "");
    ASSERT_EQ(dispatched[p], scalar[p]) << "pixel " << p;
    ASSERT_EQ(scalar[p], toneMapPixel(&rgba[4 * p], settings)) << "pixel " << p;
  }
}

TEST(ToneMapKernel, Avx2EqualsScalarOnRandomPixels) {
  if (!toneMapAvx2Available()) GTEST_SKIP() << "this CPU (or build) has no AVX2 kernel";
  std::uint32_t seed = 1;
  for (const float exposure : {1.0f, 0.37f, 2.5f, 16.0f})
    for (const bool filmic : {false, true}) {
      ToneMapSettings settings;
      settings.exposure = exposure;
      settings.filmic = filmic;
      // Odd counts exercise the scalar tail after the 8-pixel blocks.
      for (const std::size_t n :
           {std::size_t{1}, std::size_t{7}, std::size_t{8}, std::size_t{4096}, std::size_t{100003}})
        expectSameAsScalar(randomPixels(n, seed++), settings);
    }
}

// Every float of [0, 1] that starts a new sRGB step, and its neighbours, in every lane position.
TEST(ToneMapKernel, Avx2EqualsScalarAtEveryStep) {
  if (!toneMapAvx2Available()) GTEST_SKIP() << "this CPU (or build) has no AVX2 kernel";
  std::vector<float> rgba;
  std::uint32_t previous = 0;
  for (std::uint32_t b = 0; b <= 0x3F800000u; b += 97) {
    const std::uint32_t code = encodeSrgb8(std::bit_cast<float>(b));
    if (code != previous)
      for (std::uint32_t x = b - 97; x <= b + 2; ++x)
        for (int lane = 0; lane < 4; ++lane) rgba.push_back(std::bit_cast<float>(x));
    previous = code;
  }
  for (const bool filmic : {false, true}) {
    ToneMapSettings settings;
    settings.filmic = filmic;
    expectSameAsScalar(rgba, settings);
  }
}

}  // namespace
}  // namespace dfb
