// How well tile payloads compress on the wire, and at what cost: Snappy alone against the
// plane-delta filter + Snappy, on RGBA8 and RGBA32F tiles that are smooth (a shaded surface) or
// noisy (a path-traced tile at 1 spp). Prints a table and writes JSON (argv[1], default
// bench/results/compression.json).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "messaging/Compression.h"

namespace {

using Clock = std::chrono::steady_clock;
constexpr int kTile = 64, kPixels = kTile * kTile;

std::vector<float> makeFloatTile(bool noisy, unsigned seed) {
  std::mt19937 random(seed);
  std::normal_distribution<float> noise(0.0f, 0.35f);
  std::vector<float> rgba(4 * kPixels);
  for (int y = 0; y < kTile; ++y)
    for (int x = 0; x < kTile; ++x) {
      // A lit curved surface: neighbours differ a little, byte runs rarely repeat.
      const float shade = 0.5f + 0.3f * std::sin(0.11f * static_cast<float>(x)) *
                                     std::cos(0.07f * static_cast<float>(y));
      for (int c = 0; c < 3; ++c) {
        float v = shade * (0.6f + 0.2f * static_cast<float>(c));
        if (noisy) v = std::max(0.0f, v * (1.0f + noise(random)));
        rgba[static_cast<size_t>(4 * (y * kTile + x) + c)] = v;
      }
      rgba[static_cast<size_t>(4 * (y * kTile + x) + 3)] = 1.0f;
    }
  return rgba;
}

messaging::Bytes toRgba8(const std::vector<float>& rgba) {
  messaging::Bytes out(rgba.size());
  for (size_t i = 0; i < rgba.size(); ++i)
    out[i] = static_cast<std::byte>(std::lround(std::min(1.0f, rgba[i]) * 255.0f));
  return out;
}

struct Result {
  std::string name;
  double ratio, mbPerSecond;
};

Result measure(const std::string& name, const messaging::Bytes& raw, bool filter) {
  constexpr int kRepeats = 2000;
  messaging::Bytes filtered, packed;
  size_t packedSize = raw.size();
  const auto start = Clock::now();
  for (int i = 0; i < kRepeats; ++i) {
    const messaging::Bytes* input = &raw;
    if (filter) {
      messaging::planeDeltaEncode(raw, 4, filtered);
      input = &filtered;
    }
    packedSize = messaging::compressIfSmaller(*input, packed) ? packed.size() : raw.size();
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return {name, static_cast<double>(raw.size()) / static_cast<double>(packedSize),
          static_cast<double>(raw.size()) * kRepeats / seconds / 1e6};
}

}  // namespace

int main(int argc, char** argv) {
  const std::string out = argc > 1 ? argv[1] : "bench/results/compression.json";
  std::vector<Result> results;
  for (bool noisy : {false, true}) {
    const std::string kind = noisy ? "noisy" : "smooth";
    const std::vector<float> tile = makeFloatTile(noisy, 7);
    messaging::Bytes floatBytes(tile.size() * sizeof(float));
    std::memcpy(floatBytes.data(), tile.data(), floatBytes.size());
    const messaging::Bytes rgba8 = toRgba8(tile);
    results.push_back(measure("rgba32f_" + kind + "_snappy", floatBytes, false));
    results.push_back(measure("rgba8_" + kind + "_snappy", rgba8, false));
    results.push_back(measure("rgba8_" + kind + "_planedelta_snappy", rgba8, true));
  }
  std::printf("%-32s %8s %12s\n", "64x64 tile, codec", "ratio", "MB/s in");
  std::ofstream json(out);
  json << "{\n  \"benchmark\": \"tile compression\",\n  \"results\": [\n";
  for (size_t i = 0; i < results.size(); ++i) {
    const Result& r = results[i];
    std::printf("%-32s %7.2fx %12.0f\n", r.name.c_str(), r.ratio, r.mbPerSecond);
    json << "    {\"name\": \"" << r.name << "\", \"ratio\": " << r.ratio
         << ", \"mb_per_s\": " << r.mbPerSecond << "}" << (i + 1 < results.size() ? "," : "")
         << "\n";
  }
  json << "  ]\n}\n";
  if (!json) {
    std::fprintf(stderr, "could not write %s\n", out.c_str());
    return 1;
  }
  return 0;
}
