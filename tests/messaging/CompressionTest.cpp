#include "messaging/Compression.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace messaging {
namespace {

Bytes smoothRgba8(int width, int height) {
  Bytes pixels(static_cast<size_t>(width * height * 4));
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      std::byte* p = &pixels[static_cast<size_t>((y * width + x) * 4)];
      p[0] = static_cast<std::byte>(x * 255 / width);
      p[1] = static_cast<std::byte>(y * 255 / height);
      p[2] = static_cast<std::byte>(128 + 100 * std::sin((x + y) * 0.05));
      p[3] = std::byte{255};
    }
  return pixels;
}

TEST(Compression, RoundTripsAndShrinksRepetitiveData) {
  Bytes raw(10000, std::byte{42});
  Bytes packed, unpacked;
  ASSERT_TRUE(compressIfSmaller(raw, packed));
  EXPECT_LT(packed.size(), raw.size() / 10);
  decompress(packed, raw.size(), unpacked);
  EXPECT_EQ(unpacked, raw);
}

TEST(Compression, RefusesWhenNotSmaller) {
  std::mt19937 random(1);
  Bytes noise(4096);
  for (auto& b : noise) b = static_cast<std::byte>(random());
  Bytes packed;
  EXPECT_FALSE(compressIfSmaller(noise, packed));
  EXPECT_TRUE(packed.empty());
}

TEST(Compression, CorruptInputIsAnError) {
  Bytes garbage(64, std::byte{0xff});
  Bytes out;
  EXPECT_ANY_THROW(decompress(garbage, 100, out));
}

// The filter's definition, byte by byte: each plane holds each pixel's channel minus the one
// before it. The library's kernels (SSSE3 for 4 channels, 16 pixels at a time) must give these
// bytes for every size, the tails after the 16-pixel blocks included, and decode them back.
Bytes planeDeltaDefinition(const Bytes& pixels, int channels) {
  const size_t n = static_cast<size_t>(channels), count = pixels.size() / n;
  Bytes out(pixels.size());
  for (size_t c = 0; c < n; ++c)
    for (size_t i = 0; i < count; ++i) {
      const auto value = static_cast<unsigned char>(pixels[i * n + c]);
      const auto before = i > 0 ? static_cast<unsigned char>(pixels[(i - 1) * n + c]) : 0;
      out[c * count + i] = static_cast<std::byte>(static_cast<unsigned char>(value - before));
    }
  return out;
}

TEST(PlaneDelta, KernelsEqualTheDefinitionForEverySize) {
  std::mt19937 random(11);
  for (const int channels : {4, 3, 1})
    for (size_t count : {0, 1, 15, 16, 17, 31, 32, 33, 100, 4096, 4099}) {
      Bytes pixels(count * static_cast<size_t>(channels));
      for (std::byte& b : pixels) b = static_cast<std::byte>(random() % 7 == 0 ? random() : 128);
      Bytes encoded, decoded;
      planeDeltaEncode(pixels, channels, encoded);
      ASSERT_EQ(encoded, planeDeltaDefinition(pixels, channels))
          << count << " pixels of " << channels << " channels";
      planeDeltaDecode(encoded, channels, decoded);
      ASSERT_EQ(decoded, pixels) << count << " pixels of " << channels << " channels";
    }
}

TEST(PlaneDelta, IsLosslessAndMakesSmoothPixelsCompressible) {
  const Bytes pixels = smoothRgba8(64, 64);
  Bytes encoded, decoded, plain, filtered;
  planeDeltaEncode(pixels, 4, encoded);
  ASSERT_EQ(encoded.size(), pixels.size());
  planeDeltaDecode(encoded, 4, decoded);
  EXPECT_EQ(decoded, pixels);

  const bool plainShrank = compressIfSmaller(pixels, plain);
  ASSERT_TRUE(compressIfSmaller(encoded, filtered));
  const size_t plainSize = plainShrank ? plain.size() : pixels.size();
  EXPECT_LT(filtered.size() * 3, plainSize) << "the filter should win by a wide margin";
}

}  // namespace
}  // namespace messaging
