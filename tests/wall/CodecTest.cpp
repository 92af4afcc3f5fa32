// The wall service's pixel codecs (wall/service/protocol/Codec.h): --codec parsing, bit-exact raw
// and Snappy round trips (strided rectangles, odd sizes), JPEG quality and size on a
// rendered-looking image, and hostile input: every malformed piece is a base::Error, never a crash
// (this suite also runs under ASan+UBSan).
#include <gtest/gtest.h>
#include <turbojpeg.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "base/Error.h"
#include "wall/image/Image.h"
#include "wall/service/protocol/Codec.h"

namespace wall::service {
namespace {

using Pixels = std::vector<std::uint32_t>;

Pixels randomPixels(int width, int height, unsigned seed) {
  std::mt19937 random(seed);
  Pixels pixels(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  for (std::uint32_t& p : pixels) p = random();
  return pixels;
}

Pixels noisyOpaquePixels(int width, int height, unsigned seed) {
  Pixels pixels = randomPixels(width, height, seed);
  for (std::uint32_t& p : pixels) p |= 0xFF00'0000u;
  return pixels;
}

// A horizontal and vertical gradient across the whole image, opaque: what a smooth shaded
// surface gives.
Pixels gradientPixels(int width, int height) {
  Pixels pixels(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      pixels[static_cast<std::size_t>(y * width + x)] =
          rgba8(static_cast<std::uint8_t>(40 + 180 * x / width),
                static_cast<std::uint8_t>(60 + 120 * y / height),
                static_cast<std::uint8_t>(200 - 100 * x / width), 255);
  return pixels;
}

float smoothstep(float edge0, float edge1, float x) {
  const float t = std::clamp((x - edge0) / (edge1 - edge0), 0.0f, 1.0f);
  return t * t * (3 - 2 * t);
}

// What a render looks like: a sky gradient over a floor, a shaded sphere with an anti-aliased
// silhouette and a soft shadow, a soft glowing disc. Opaque.
Pixels renderedLookingPixels(int width, int height) {
  Pixels pixels(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  const float w = static_cast<float>(width), h = static_cast<float>(height);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const float u = (static_cast<float>(x) + 0.5f) / w, v = (static_cast<float>(y) + 0.5f) / h;
      // Sky to floor, with a soft horizon.
      const float floor = smoothstep(0.60f, 0.64f, v);
      float r = (1 - floor) * (0.35f + 0.3f * v) + floor * (0.55f - 0.2f * (v - 0.6f));
      float g = (1 - floor) * (0.55f + 0.25f * v) + floor * (0.45f - 0.15f * (v - 0.6f));
      float b = (1 - floor) * (0.90f - 0.2f * v) + floor * (0.35f - 0.1f * (v - 0.6f));
      // The sphere's soft shadow on the floor.
      const float sx = (u - 0.45f) / 0.30f, sy = (v - 0.78f) / 0.07f;
      const float shadow = 1 - 0.45f * std::exp(-(sx * sx + sy * sy));
      r *= shadow, g *= shadow, b *= shadow;
      // A Lambert-shaded sphere, the light from the top left, an anti-aliased edge.
      const float dx = (u - 0.42f) / 0.22f, dy = (v - 0.45f) / 0.22f;
      const float d2 = dx * dx + dy * dy;
      const float coverage = 1 - smoothstep(1 - 2.0f / (0.22f * w), 1, std::sqrt(d2));
      if (coverage > 0) {
        const float nz = std::sqrt(std::max(0.0f, 1 - std::min(d2, 1.0f)));
        const float light = std::max(0.0f, -0.5f * dx - 0.6f * dy + 0.62f * nz);
        const float shade = 0.08f + 0.85f * light;
        r = (1 - coverage) * r + coverage * shade * 0.85f;
        g = (1 - coverage) * g + coverage * shade * 0.30f;
        b = (1 - coverage) * b + coverage * shade * 0.25f;
      }
      // A soft glowing disc.
      const float gx = (u - 0.78f) / 0.1f, gy = (v - 0.25f) / 0.1f;
      const float glow = std::exp(-(gx * gx + gy * gy));
      r += 0.4f * glow, g += 0.4f * glow, b += 0.2f * glow;
      const auto byte = [](float c) {
        return static_cast<std::uint8_t>(std::lround(std::clamp(c, 0.0f, 1.0f) * 255.0f));
      };
      pixels[static_cast<std::size_t>(y * width + x)] = rgba8(byte(r), byte(g), byte(b), 255);
    }
  return pixels;
}

double psnrRgb(const Pixels& a, const Pixels& b) {
  double squared = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      const double d = static_cast<double>((a[i] >> (8 * c)) & 0xFF) -
                       static_cast<double>((b[i] >> (8 * c)) & 0xFF);
      squared += d * d;
    }
  const double mse = squared / (3.0 * static_cast<double>(a.size()));
  return mse == 0 ? 99.0 : 10 * std::log10(255.0 * 255.0 / mse);
}

messaging::Bytes encode(const CodecSpec& spec, const Pixels& pixels, int width, int height) {
  messaging::Bytes out;
  encodePixels(spec, pixels.data(), width, height, width, out);
  return out;
}

Pixels decode(Codec codec, const messaging::Bytes& bytes, int width, int height) {
  Pixels out(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  decodePixels(codec, bytes.data(), bytes.size(), width, height, out.data(), width);
  return out;
}

// ---- --codec ----

TEST(Codec, ParsesEachForm) {
  EXPECT_EQ(parseCodec("raw"), CodecSpec{Codec::Raw});
  EXPECT_EQ(parseCodec("snappy"), CodecSpec{Codec::Snappy});
  EXPECT_EQ(parseCodec("jpeg"), (CodecSpec{Codec::Jpeg, 90, ChromaSubsampling::S420}));
  EXPECT_EQ(parseCodec("jpeg:75"), (CodecSpec{Codec::Jpeg, 75, ChromaSubsampling::S420}));
  EXPECT_EQ(parseCodec("jpeg:1:444"), (CodecSpec{Codec::Jpeg, 1, ChromaSubsampling::S444}));
  EXPECT_EQ(parseCodec("jpeg:100:422"), (CodecSpec{Codec::Jpeg, 100, ChromaSubsampling::S422}));
  EXPECT_EQ(parseCodec("jpeg:95:420"), (CodecSpec{Codec::Jpeg, 95, ChromaSubsampling::S420}));
}

TEST(Codec, NamesRoundTrip) {
  for (const char* text : {"raw", "snappy", "jpeg", "jpeg:1", "jpeg:50:444", "jpeg:100:422",
                           "jpeg:90:420", "jpeg:007"}) {
    const CodecSpec spec = parseCodec(text);
    EXPECT_EQ(parseCodec(codecName(spec)), spec) << text;
  }
  EXPECT_EQ(codecName(parseCodec("raw")), "raw");
  EXPECT_EQ(codecName(parseCodec("snappy")), "snappy");
  EXPECT_EQ(codecName(parseCodec("jpeg")), "jpeg:90:420");
  EXPECT_EQ(codecName(parseCodec("jpeg:75:444")), "jpeg:75:444");
}

TEST(Codec, RefusesBadStringsNamingTheOptionAndWhatIsAllowed) {
  for (const char* text : {"",
                           "png",
                           "RAW",
                           "Jpeg",
                           " raw",
                           "raw ",
                           "raw:1",
                           "snappy:2",
                           "jpeg:",
                           "jpeg:0",
                           "jpeg:101",
                           "jpeg:1000",
                           "jpeg:-5",
                           "jpeg:+5",
                           "jpeg:9x",
                           "jpeg:90:",
                           "jpeg:90:411",
                           "jpeg:90:440",
                           "jpeg:90:420:",
                           "jpeg:90:420:1",
                           "jpeg::420",
                           "jpeg 90",
                           ":"}) {
    try {
      parseCodec(text);
      ADD_FAILURE() << "accepted '" << text << "'";
    } catch (const base::Error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("--codec"), std::string::npos) << message;
      EXPECT_NE(message.find("'" + std::string(text) + "'"), std::string::npos) << message;
      EXPECT_NE(message.find("raw, snappy, jpeg, jpeg:QUALITY or jpeg:QUALITY:444|422|420"),
                std::string::npos)
          << message;
      EXPECT_NE(message.find("1 to 100"), std::string::npos) << message;
    }
  }
  try {
    parseCodec("jpeg:0");
  } catch (const base::Error& e) {
    EXPECT_NE(std::string(e.what()).find("quality"), std::string::npos) << e.what();
  }
}

TEST(Codec, CodecFromByte) {
  EXPECT_EQ(codecFromByte(0), Codec::Raw);
  EXPECT_EQ(codecFromByte(1), Codec::Snappy);
  EXPECT_EQ(codecFromByte(2), Codec::Jpeg);
  EXPECT_THROW(codecFromByte(3), base::Error);
  EXPECT_THROW(codecFromByte(255), base::Error);
}

// ---- lossless round trips ----

struct Size {
  int width, height;
};
constexpr Size kSizes[] = {{1, 1}, {17, 5}, {64, 64}, {1920, 8}};

// Encodes the rectangle at (5, 2) of a wider, taller random image (rows `stride` apart) and
// decodes it into the middle of another buffer with padded rows; the padding stays untouched.
void expectStridedRoundTrip(Codec codec, const Pixels& source, int stride, int width, int height) {
  const int x0 = 5, y0 = 2;
  messaging::Bytes bytes{std::byte{0xAB}};  // appended after what is there
  encodePixels(CodecSpec{codec}, source.data() + y0 * stride + x0, width, height, stride, bytes);
  ASSERT_EQ(bytes[0], std::byte{0xAB});
  const int destStride = width + 7;
  constexpr std::uint32_t kSentinel = 0xDEADBEEF;
  Pixels dest(static_cast<std::size_t>(destStride) * static_cast<std::size_t>(height + 2),
              kSentinel);
  decodePixels(codec, bytes.data() + 1, bytes.size() - 1, width, height, dest.data() + destStride,
               destStride);
  for (int y = 0; y < height + 2; ++y)
    for (int x = 0; x < destStride; ++x) {
      const std::uint32_t got = dest[static_cast<std::size_t>(y * destStride + x)];
      if (y >= 1 && y <= height && x < width)
        ASSERT_EQ(got, source[static_cast<std::size_t>((y0 + y - 1) * stride + x0 + x)])
            << width << "x" << height << " at " << x << "," << y - 1;
      else
        ASSERT_EQ(got, kSentinel) << "padding written at " << x << "," << y;
    }
}

TEST(Codec, RawAndSnappyRoundTripBitExactly) {
  for (const Codec codec : {Codec::Raw, Codec::Snappy})
    for (const auto [width, height] : kSizes) {
      SCOPED_TRACE(std::to_string(static_cast<int>(codec)) + ": " + std::to_string(width) + "x" +
                   std::to_string(height));
      for (const Pixels& pixels : {randomPixels(width, height, 11), gradientPixels(width, height)})
        EXPECT_EQ(decode(codec, encode(CodecSpec{codec}, pixels, width, height), width, height),
                  pixels);
      const int stride = width + 13;
      expectStridedRoundTrip(codec, randomPixels(stride, height + 5, 12), stride, width, height);
      expectStridedRoundTrip(codec, gradientPixels(stride, height + 5), stride, width, height);
    }
}

TEST(Codec, RawIsThePixelsAsTheyAre) {
  const Pixels pixels = randomPixels(17, 5, 3);
  const messaging::Bytes bytes = encode(CodecSpec{Codec::Raw}, pixels, 17, 5);
  ASSERT_EQ(bytes.size(), pixels.size() * 4);
  EXPECT_EQ(std::memcmp(bytes.data(), pixels.data(), bytes.size()), 0);
  // Memory order R, G, B, A.
  const Pixels one{rgba8(1, 2, 3, 4)};
  const messaging::Bytes b = encode(CodecSpec{Codec::Raw}, one, 1, 1);
  EXPECT_EQ(b, (messaging::Bytes{std::byte{1}, std::byte{2}, std::byte{3}, std::byte{4}}));
}

TEST(Codec, SnappyShrinksASmoothGradientAndStoresNoise) {
  const Pixels smooth = gradientPixels(64, 64);
  const messaging::Bytes packed = encode(CodecSpec{Codec::Snappy}, smooth, 64, 64);
  EXPECT_EQ(packed[0], std::byte{kSnappyCompressed});
  EXPECT_LT(packed.size() * 4, smooth.size() * 4 / 2) << packed.size() << " bytes";
  std::printf("snappy, 64x64 gradient: %zu bytes of %zu (%.1fx)\n", packed.size(),
              smooth.size() * 4,
              static_cast<double>(smooth.size() * 4) / static_cast<double>(packed.size()));
  // Noise does not shrink: the filtered bytes are stored, one flag byte more than raw.
  const Pixels noise = randomPixels(64, 64, 5);
  const messaging::Bytes stored = encode(CodecSpec{Codec::Snappy}, noise, 64, 64);
  EXPECT_EQ(stored[0], std::byte{kSnappyStored});
  EXPECT_EQ(stored.size(), noise.size() * 4 + 1);
  EXPECT_EQ(decode(Codec::Snappy, stored, 64, 64), noise);
}

// ---- JPEG ----

TEST(Codec, JpegOfARenderedLookingImageIsCloseAndSmall) {
  constexpr int kSide = 256;
  const Pixels image = renderedLookingPixels(kSide, kSide);
  const messaging::Bytes jpeg = encode(parseCodec("jpeg:90:420"), image, kSide, kSide);
  const Pixels back = decode(Codec::Jpeg, jpeg, kSide, kSide);
  const double psnr = psnrRgb(image, back);
  const std::size_t raw = image.size() * 4;
  std::printf("jpeg:90:420, 256x256 rendered-looking: %zu bytes of %zu (%.1fx), PSNR %.2f dB\n",
              jpeg.size(), raw, static_cast<double>(raw) / static_cast<double>(jpeg.size()), psnr);
  EXPECT_GE(psnr, 40.0);
  EXPECT_LE(jpeg.size() * 4, raw);
  for (const std::uint32_t p : back) ASSERT_EQ(p >> 24, 255u);
  // Finer chroma costs bytes, not quality.
  for (const char* text : {"jpeg:90:444", "jpeg:90:422", "jpeg:75"}) {
    const messaging::Bytes other = encode(parseCodec(text), image, kSide, kSide);
    const double p = psnrRgb(image, decode(Codec::Jpeg, other, kSide, kSide));
    std::printf("%s, 256x256 rendered-looking: %zu bytes, PSNR %.2f dB\n", text, other.size(), p);
    EXPECT_GE(p, 35.0) << text;
  }
}

TEST(Codec, JpegOfNoiseDecodes) {
  const Pixels noise = noisyOpaquePixels(64, 64, 9);
  const messaging::Bytes jpeg = encode(parseCodec("jpeg:90"), noise, 64, 64);
  const Pixels back = decode(Codec::Jpeg, jpeg, 64, 64);
  std::printf("jpeg:90:420, 64x64 noise: %zu bytes of %zu, PSNR %.2f dB\n", jpeg.size(),
              noise.size() * 4, psnrRgb(noise, back));
  for (const std::uint32_t p : back) ASSERT_EQ(p >> 24, 255u);
}

TEST(Codec, JpegDropsAlphaAndTakesStridedOddRectangles) {
  for (const char* text : {"jpeg:90:444", "jpeg:90:422", "jpeg:90:420"})
    for (const auto [width, height] : kSizes) {
      SCOPED_TRACE(std::string(text) + " " + std::to_string(width) + "x" + std::to_string(height));
      const int stride = width + 13;
      Pixels source = gradientPixels(stride, height + 5);
      // Random alpha: the encoder ignores it.
      std::mt19937 random(4);
      for (std::uint32_t& p : source) p = (p & 0x00FF'FFFFu) | (random() << 24);
      messaging::Bytes jpeg;
      encodePixels(parseCodec(text), source.data() + 2 * stride + 5, width, height, stride, jpeg);
      const int destStride = width + 3;
      Pixels dest(static_cast<std::size_t>(destStride) * static_cast<std::size_t>(height), 7u);
      decodePixels(Codec::Jpeg, jpeg.data(), jpeg.size(), width, height, dest.data(), destStride);
      for (int y = 0; y < height; ++y)
        for (int x = 0; x < destStride; ++x) {
          const std::uint32_t got = dest[static_cast<std::size_t>(y * destStride + x)];
          if (x >= width) {
            ASSERT_EQ(got, 7u) << "padding written";
            continue;
          }
          const std::uint32_t want = source[static_cast<std::size_t>((y + 2) * stride + x + 5)];
          ASSERT_EQ(got >> 24, 255u);
          for (int c = 0; c < 3; ++c)
            ASSERT_NEAR(static_cast<int>((got >> (8 * c)) & 0xFF),
                        static_cast<int>((want >> (8 * c)) & 0xFF), 12)
                << x << "," << y << " channel " << c;
        }
    }
}

TEST(Codec, EncodeAppendsAndChecksItsArguments) {
  const Pixels pixels = gradientPixels(8, 8);
  for (const CodecSpec spec :
       {CodecSpec{Codec::Raw}, CodecSpec{Codec::Snappy}, CodecSpec{Codec::Jpeg}}) {
    messaging::Bytes out{std::byte{1}, std::byte{2}};
    encodePixels(spec, pixels.data(), 8, 8, 8, out);
    const messaging::Bytes alone = encode(spec, pixels, 8, 8);
    EXPECT_EQ(messaging::Bytes(out.begin() + 2, out.end()), alone);
    EXPECT_THROW(encodePixels(spec, pixels.data(), 0, 8, 8, out), base::Error);
    EXPECT_THROW(encodePixels(spec, pixels.data(), 8, -1, 8, out), base::Error);
    EXPECT_THROW(encodePixels(spec, pixels.data(), 8, 8, 7, out), base::Error);
    EXPECT_THROW(encodePixels(spec, pixels.data(), 70000, 1, 70000, out), base::Error);
  }
  messaging::Bytes out;
  EXPECT_THROW(encodePixels(CodecSpec{Codec::Jpeg, 0}, pixels.data(), 8, 8, 8, out), base::Error);
  EXPECT_THROW(encodePixels(CodecSpec{Codec::Jpeg, 101}, pixels.data(), 8, 8, 8, out), base::Error);
  EXPECT_THROW(encodePixels(CodecSpec{static_cast<Codec>(7)}, pixels.data(), 8, 8, 8, out),
               base::Error);
}

TEST(Codec, ThreadsEncodeAndDecodeAtOnce) {
  const Pixels image = renderedLookingPixels(64, 64);
  std::vector<messaging::Bytes> expected;
  const CodecSpec specs[] = {parseCodec("snappy"), parseCodec("jpeg:80:444"), parseCodec("jpeg")};
  for (const CodecSpec& spec : specs) expected.push_back(encode(spec, image, 64, 64));
  std::vector<int> failures(4, 0);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      for (int i = 0; i < 50; ++i)
        for (std::size_t s = 0; s < std::size(specs); ++s) {
          const messaging::Bytes bytes = encode(specs[s], image, 64, 64);
          if (bytes != expected[s]) ++failures[static_cast<std::size_t>(t)];
          const Pixels back = decode(specs[s].codec, bytes, 64, 64);
          if (specs[s].codec == Codec::Snappy && back != image)
            ++failures[static_cast<std::size_t>(t)];
        }
    });
  for (std::thread& thread : threads) thread.join();
  for (const int f : failures) EXPECT_EQ(f, 0);
}

// ---- hostile input ----

void expectRefused(Codec codec, const messaging::Bytes& bytes, int width, int height,
                   const std::string& what) {
  Pixels dest(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  EXPECT_THROW(decodePixels(codec, bytes.data(), bytes.size(), width, height, dest.data(), width),
               base::Error)
      << what << " (" << bytes.size() << " bytes)";
}

// Decodes, or throws base::Error; anything else (a crash, a sanitizer report) fails the test.
void decodeOrRefuse(Codec codec, const messaging::Bytes& bytes, int width, int height) {
  Pixels dest(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  try {
    decodePixels(codec, bytes.data(), bytes.size(), width, height, dest.data(), width);
  } catch (const base::Error&) {
  }
}

TEST(CodecHostile, EmptyData) {
  for (const Codec codec : {Codec::Raw, Codec::Snappy, Codec::Jpeg}) {
    std::uint32_t pixel = 0;
    EXPECT_THROW(decodePixels(codec, nullptr, 0, 1, 1, &pixel, 1), base::Error);
    expectRefused(codec, {}, 16, 16, "empty");
  }
  EXPECT_THROW(decodePixels(static_cast<Codec>(9), nullptr, 0, 1, 1, nullptr, 1), base::Error);
}

TEST(CodecHostile, EveryTruncation) {
  const Pixels image = renderedLookingPixels(24, 16);
  for (const char* text : {"raw", "snappy", "jpeg", "jpeg:100:444"}) {
    const CodecSpec spec = parseCodec(text);
    const messaging::Bytes whole = encode(spec, image, 24, 16);
    for (std::size_t n = 0; n < whole.size(); ++n)
      expectRefused(spec.codec, messaging::Bytes(whole.begin(), whole.begin() + n), 24, 16,
                    std::string(text) + " truncated");
  }
  // Stored Snappy (noise) too.
  const messaging::Bytes stored = encode(CodecSpec{Codec::Snappy}, randomPixels(8, 8, 1), 8, 8);
  for (std::size_t n = 0; n < stored.size(); ++n)
    expectRefused(Codec::Snappy, messaging::Bytes(stored.begin(), stored.begin() + n), 8, 8,
                  "stored snappy truncated");
}

TEST(CodecHostile, WrongSizesAndTrailingBytes) {
  const Pixels image = gradientPixels(16, 16);
  for (const Codec codec : {Codec::Raw, Codec::Snappy}) {
    messaging::Bytes bytes = encode(CodecSpec{codec}, image, 16, 16);
    expectRefused(codec, bytes, 16, 15, "another height");
    expectRefused(codec, bytes, 15, 16, "another width");
    bytes.push_back(std::byte{0});
    expectRefused(codec, bytes, 16, 16, "a trailing byte");
  }
  messaging::Bytes stored = encode(CodecSpec{Codec::Snappy}, randomPixels(8, 8, 1), 8, 8);
  stored.push_back(std::byte{0});
  expectRefused(Codec::Snappy, stored, 8, 8, "stored snappy with a trailing byte");
  for (const std::uint8_t flag : {2, 255}) {
    messaging::Bytes bytes = encode(CodecSpec{Codec::Snappy}, image, 16, 16);
    bytes[0] = std::byte{flag};
    expectRefused(Codec::Snappy, bytes, 16, 16, "an unknown flag");
  }
}

TEST(CodecHostile, JpegOfAnotherSize) {
  const Pixels image = renderedLookingPixels(32, 32);
  const messaging::Bytes jpeg = encode(CodecSpec{Codec::Jpeg}, image, 32, 32);
  expectRefused(Codec::Jpeg, jpeg, 64, 64, "a 32x32 JPEG asked for as 64x64");
  expectRefused(Codec::Jpeg, jpeg, 16, 16, "a 32x32 JPEG asked for as 16x16 (scaled)");
  expectRefused(Codec::Jpeg, jpeg, 32, 31, "a 32x32 JPEG asked for as 32x31");
  try {
    Pixels dest(64 * 64);
    decodePixels(Codec::Jpeg, jpeg.data(), jpeg.size(), 64, 64, dest.data(), 64);
  } catch (const base::Error& e) {
    EXPECT_NE(std::string(e.what()).find("32x32"), std::string::npos) << e.what();
  }
}

// JPEGs TurboJPEG writes but the codec does not: greyscale (another colour space), and
// progressive (decoded through a whole-image buffer).
TEST(CodecHostile, JpegOfAnotherKind) {
  const Pixels image = renderedLookingPixels(32, 32);
  tjhandle handle = tjInitCompress();
  ASSERT_NE(handle, nullptr);
  const auto compress = [&](int subsampling, int flags) {
    unsigned char* jpeg = nullptr;
    unsigned long size = 0;
    EXPECT_EQ(tjCompress2(handle, reinterpret_cast<const unsigned char*>(image.data()), 32, 0, 32,
                          TJPF_RGBA, &jpeg, &size, subsampling, 90, flags),
              0);
    messaging::Bytes bytes(reinterpret_cast<std::byte*>(jpeg),
                           reinterpret_cast<std::byte*>(jpeg) + size);
    tjFree(jpeg);
    return bytes;
  };
  const messaging::Bytes baseline = compress(TJSAMP_420, 0);
  EXPECT_EQ(decode(Codec::Jpeg, baseline, 32, 32).size(), 32u * 32u);
  expectRefused(Codec::Jpeg, compress(TJSAMP_GRAY, 0), 32, 32, "greyscale");
  expectRefused(Codec::Jpeg, compress(TJSAMP_420, TJFLAG_PROGRESSIVE), 32, 32, "progressive");
  // The baseline JPEG with its frame marker made arithmetic-coded (SOF9), and with its first scan
  // announcing one component of three (a non-interleaved, multi-scan layout).
  const auto markerAt = [&](std::uint8_t marker) {
    for (std::size_t i = 2; i + 1 < baseline.size(); ++i)
      if (baseline[i] == std::byte{0xFF} && baseline[i + 1] == std::byte{marker}) return i;
    ADD_FAILURE() << "no marker " << int{marker};
    return std::size_t{0};
  };
  messaging::Bytes arithmetic = baseline;
  arithmetic[markerAt(0xC0) + 1] = std::byte{0xC9};
  expectRefused(Codec::Jpeg, arithmetic, 32, 32, "arithmetic-coded");
  messaging::Bytes multiScan = baseline;
  multiScan[markerAt(0xDA) + 4] = std::byte{1};
  expectRefused(Codec::Jpeg, multiScan, 32, 32, "a first scan of one component");
  tjDestroy(handle);
}

TEST(CodecHostile, SnappyClaimingAHugeSize) {
  // Flag, then a Snappy length varint of 2^32 - 1, then a few literal bytes.
  const messaging::Bytes huge{std::byte{kSnappyCompressed},
                              std::byte{0xFF},
                              std::byte{0xFF},
                              std::byte{0xFF},
                              std::byte{0xFF},
                              std::byte{0x0F},
                              std::byte{0x0C},
                              std::byte{1},
                              std::byte{2},
                              std::byte{3},
                              std::byte{4}};
  expectRefused(Codec::Snappy, huge, 64, 64, "a Snappy stream announcing 4 GiB");
  // Announcing exactly the rectangle's 4 MiB but holding 16 bytes: refused before the 4 MiB are
  // allocated (no Snappy element expands more than 64 bytes from 3).
  messaging::Bytes claims{std::byte{kSnappyCompressed}, std::byte{0x80}, std::byte{0x80},
                          std::byte{0x80}, std::byte{0x02}};  // 2^22
  claims.resize(claims.size() + 16, std::byte{0});
  expectRefused(Codec::Snappy, claims, 1024, 1024, "a Snappy stream announcing 4 MiB");
}

TEST(CodecHostile, Garbage) {
  std::mt19937 random(17);
  for (const Codec codec : {Codec::Raw, Codec::Snappy, Codec::Jpeg})
    for (const std::size_t size : {1u, 2u, 3u, 4u, 17u, 100u, 1023u, 5000u}) {
      messaging::Bytes garbage(size);
      for (std::byte& b : garbage) b = static_cast<std::byte>(random());
      expectRefused(codec, garbage, 32, 32, "garbage");
      if (size >= 2 && codec == Codec::Jpeg) {  // garbage after a JPEG's start marker
        garbage[0] = std::byte{0xFF}, garbage[1] = std::byte{0xD8};
        expectRefused(codec, garbage, 32, 32, "garbage after SOI");
      }
    }
}

// Every single-byte corruption of a small piece of each codec decodes or is refused, never
// crashes, and leaves the thread able to decode the intact piece (the fuzz target,
// tests/fuzz/FuzzCodec.cpp, goes further).
TEST(CodecHostile, EverySingleByteCorruption) {
  const Pixels image = renderedLookingPixels(16, 16);
  for (const char* text : {"snappy", "jpeg:90:420", "jpeg:90:444"}) {
    const CodecSpec spec = parseCodec(text);
    const messaging::Bytes whole = encode(spec, image, 16, 16);
    const Pixels intact = decode(spec.codec, whole, 16, 16);
    for (std::size_t i = 0; i < whole.size(); ++i)
      for (const std::uint8_t x : {0x01, 0x80, 0xFF}) {
        messaging::Bytes corrupt = whole;
        corrupt[i] ^= std::byte{x};
        decodeOrRefuse(spec.codec, corrupt, 16, 16);
        ASSERT_EQ(decode(spec.codec, whole, 16, 16), intact)
            << text << ": byte " << i << " ^ " << int{x} << " broke the next decode";
      }
  }
}

// Regression: libjpeg-turbo 2.1's tjDecompressHeader3 leaves its instance mid-header after an
// error, and every later decode on it failed; the codec now replaces the thread's instance.
TEST(CodecHostile, JpegDecodingRecoversFromABadHeader) {
  const Pixels image = renderedLookingPixels(32, 32);
  const messaging::Bytes jpeg = encode(CodecSpec{Codec::Jpeg}, image, 32, 32);
  messaging::Bytes bad = jpeg;  // the frame header's height set to 0 ("Empty JPEG image")
  bool found = false;
  for (std::size_t i = 2; i + 6 < bad.size() && !found; ++i)
    if (bad[i] == std::byte{0xFF} && bad[i + 1] == std::byte{0xC0}) {
      bad[i + 5] = bad[i + 6] = std::byte{0};
      found = true;
    }
  ASSERT_TRUE(found);
  for (int round = 0; round < 3; ++round) {
    expectRefused(Codec::Jpeg, bad, 32, 32, "a frame header of height 0");
    EXPECT_NO_THROW(decode(Codec::Jpeg, jpeg, 32, 32)) << "round " << round;
  }
}

}  // namespace
}  // namespace wall::service
