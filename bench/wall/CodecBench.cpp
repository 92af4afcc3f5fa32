// The wall service's pixel codecs (wall/service/protocol/Codec.h) on the pieces a render job sends:
// 64x64 RGBA8 tiles of a 512x512 image that is smooth (a rendered-looking scene) or noisy (the same
// at low sample counts: every channel off by a normal factor, sigma 0.35). Per codec: the ratio
// (raw bytes / encoded bytes), encode and decode speed in MB/s of raw pixels on one thread, and
// the PSNR of what decodes. Prints a table and writes JSON (argv[1], default
// bench/results/codec.json).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "wall/image/Image.h"
#include "wall/service/protocol/Codec.h"

namespace {

using Clock = std::chrono::steady_clock;
using Pixels = std::vector<std::uint32_t>;
constexpr int kSide = 512, kTile = 64, kTiles = (kSide / kTile) * (kSide / kTile);

float smoothstep(float edge0, float edge1, float x) {
  const float t = std::clamp((x - edge0) / (edge1 - edge0), 0.0f, 1.0f);
  return t * t * (3 - 2 * t);
}

// Sky over a floor, a shaded sphere with a soft shadow, a glow (as tests/wall/CodecTest.cpp).
Pixels makeImage(bool noisy) {
  std::mt19937 random(7);
  std::normal_distribution<float> noise(0.0f, 0.35f);
  Pixels pixels(static_cast<std::size_t>(kSide) * kSide);
  const float n = static_cast<float>(kSide);
  for (int y = 0; y < kSide; ++y)
    for (int x = 0; x < kSide; ++x) {
      const float u = (static_cast<float>(x) + 0.5f) / n, v = (static_cast<float>(y) + 0.5f) / n;
      const float floor = smoothstep(0.60f, 0.64f, v);
      float rgb[3] = {(1 - floor) * (0.35f + 0.3f * v) + floor * (0.55f - 0.2f * (v - 0.6f)),
                      (1 - floor) * (0.55f + 0.25f * v) + floor * (0.45f - 0.15f * (v - 0.6f)),
                      (1 - floor) * (0.90f - 0.2f * v) + floor * (0.35f - 0.1f * (v - 0.6f))};
      const float sx = (u - 0.45f) / 0.30f, sy = (v - 0.78f) / 0.07f;
      const float shadow = 1 - 0.45f * std::exp(-(sx * sx + sy * sy));
      const float dx = (u - 0.42f) / 0.22f, dy = (v - 0.45f) / 0.22f;
      const float d2 = dx * dx + dy * dy;
      const float coverage = 1 - smoothstep(1 - 2.0f / (0.22f * n), 1, std::sqrt(d2));
      const float nz = std::sqrt(std::max(0.0f, 1 - std::min(d2, 1.0f)));
      const float shade = 0.08f + 0.85f * std::max(0.0f, -0.5f * dx - 0.6f * dy + 0.62f * nz);
      const float albedo[3] = {0.85f, 0.30f, 0.25f}, glowColour[3] = {0.4f, 0.4f, 0.2f};
      const float gx = (u - 0.78f) / 0.1f, gy = (v - 0.25f) / 0.1f;
      const float glow = std::exp(-(gx * gx + gy * gy));
      std::uint8_t bytes[3];
      for (int c = 0; c < 3; ++c) {
        float value = (1 - coverage) * rgb[c] * shadow + coverage * shade * albedo[c];
        value += glowColour[c] * glow;
        if (noisy) value *= 1 + noise(random);
        bytes[c] = static_cast<std::uint8_t>(std::lround(std::clamp(value, 0.0f, 1.0f) * 255));
      }
      pixels[static_cast<std::size_t>(y) * kSide + static_cast<std::size_t>(x)] =
          wall::rgba8(bytes[0], bytes[1], bytes[2]);
    }
  return pixels;
}

// The image's 64x64 tiles, each in its own buffer as a tile owner holds them.
std::vector<Pixels> cutTiles(const Pixels& image) {
  std::vector<Pixels> tiles;
  for (int ty = 0; ty < kSide; ty += kTile)
    for (int tx = 0; tx < kSide; tx += kTile) {
      Pixels tile(kTile * kTile);
      for (int y = 0; y < kTile; ++y)
        std::copy_n(image.begin() + (ty + y) * kSide + tx, kTile, tile.begin() + y * kTile);
      tiles.push_back(std::move(tile));
    }
  return tiles;
}

double psnr(const std::vector<Pixels>& a, const std::vector<Pixels>& b) {
  double squared = 0, count = 0;
  for (std::size_t t = 0; t < a.size(); ++t)
    for (std::size_t i = 0; i < a[t].size(); ++i)
      for (int c = 0; c < 3; ++c) {
        const double d = static_cast<double>((a[t][i] >> (8 * c)) & 0xFF) -
                         static_cast<double>((b[t][i] >> (8 * c)) & 0xFF);
        squared += d * d;
        count += 1;
      }
  return squared == 0 ? INFINITY : 10 * std::log10(255.0 * 255.0 * count / squared);
}

struct Result {
  std::string image, codec;
  double ratio, encodeMbPerSecond, decodeMbPerSecond, psnrDb;
};

// Runs `pass` (one pass over every tile) until a quarter second has gone; MB/s of raw pixels.
template <typename Pass>
double rate(Pass pass) {
  constexpr double kRawBytes = 4.0 * kTile * kTile * kTiles;
  int passes = 0;
  const auto start = Clock::now();
  double seconds = 0;
  do {
    pass();
    ++passes;
    seconds = std::chrono::duration<double>(Clock::now() - start).count();
  } while (seconds < 0.25);
  return kRawBytes * passes / seconds / 1e6;
}

Result measure(const std::string& image, const std::vector<Pixels>& tiles,
               const std::string& codecText) {
  const wall::service::CodecSpec spec = wall::service::parseCodec(codecText);
  std::vector<messaging::Bytes> encoded(tiles.size());
  const double encodeRate = rate([&] {
    for (std::size_t t = 0; t < tiles.size(); ++t) {
      encoded[t].clear();
      wall::service::encodePixels(spec, tiles[t].data(), kTile, kTile, kTile, encoded[t]);
    }
  });
  std::vector<Pixels> decoded(tiles.size(), Pixels(kTile * kTile));
  const double decodeRate = rate([&] {
    for (std::size_t t = 0; t < tiles.size(); ++t)
      wall::service::decodePixels(spec.codec, encoded[t].data(), encoded[t].size(), kTile, kTile,
                                  decoded[t].data(), kTile);
  });
  double encodedBytes = 0;
  for (const messaging::Bytes& e : encoded) encodedBytes += static_cast<double>(e.size());
  return {image,
          wall::service::codecName(spec),
          4.0 * kTile * kTile * kTiles / encodedBytes,
          encodeRate,
          decodeRate,
          psnr(tiles, decoded)};
}

}  // namespace

int main(int argc, char** argv) {
  const std::string out = argc > 1 ? argv[1] : "bench/results/codec.json";
  std::vector<Result> results;
  for (const bool noisy : {false, true}) {
    const std::vector<Pixels> tiles = cutTiles(makeImage(noisy));
    for (const char* codec : {"raw", "snappy", "jpeg:90:420", "jpeg:75:420", "jpeg:90:444"})
      results.push_back(measure(noisy ? "noisy" : "smooth", tiles, codec));
  }
  std::printf("%-7s %-12s %8s %12s %12s %9s\n", "64x64", "codec", "ratio", "encode MB/s",
              "decode MB/s", "PSNR dB");
  std::ofstream json(out);
  json << "{\n  \"benchmark\": \"wall service pixel codecs, 64x64 RGBA8 tiles, one thread\",\n"
       << "  \"results\": [\n";
  for (std::size_t i = 0; i < results.size(); ++i) {
    const Result& r = results[i];
    std::printf("%-7s %-12s %7.2fx %12.0f %12.0f %9.2f\n", r.image.c_str(), r.codec.c_str(),
                r.ratio, r.encodeMbPerSecond, r.decodeMbPerSecond, r.psnrDb);
    json << "    {\"image\": \"" << r.image << "\", \"codec\": \"" << r.codec
         << "\", \"ratio\": " << r.ratio << ", \"encode_mb_per_s\": " << r.encodeMbPerSecond
         << ", \"decode_mb_per_s\": " << r.decodeMbPerSecond << ", \"psnr_db\": "
         << (std::isinf(r.psnrDb) ? std::string("null") : std::to_string(r.psnrDb)) << "}"
         << (i + 1 < results.size() ? "," : "") << "\n";
  }
  json << "  ]\n}\n";
  if (!json) {
    std::fprintf(stderr, "could not write %s\n", out.c_str());
    return 1;
  }
  return 0;
}
