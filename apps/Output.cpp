// Files rank 0 writes: the --image PFM and the --stats JSON. Both are written to a temporary
// name and renamed, so nobody reads half a file.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "apps/Job.h"

namespace app {
namespace {

void replace(const std::string& temporary, const std::string& path) {
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) {
    std::filesystem::remove(temporary);
    throw std::runtime_error("cannot write " + path + ": " + error.message());
  }
}

double median(std::vector<double> values) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

}  // namespace

void writePfm(const std::string& path, const float* rgba, int width, int height) {
  const std::string temporary = path + ".partial";
  {
    std::ofstream out(temporary, std::ios::binary);
    if (!out) throw std::runtime_error("cannot create " + temporary);
    out << "PF\n" << width << " " << height << "\n-1.0\n";  // negative scale: little-endian
    std::vector<float> row(static_cast<size_t>(3 * width));
    for (int y = height - 1; y >= 0; --y) {  // PFM rows go bottom to top
      for (int x = 0; x < width; ++x)
        for (int c = 0; c < 3; ++c)
          row[static_cast<size_t>(3 * x + c)] =
              rgba[4 * (static_cast<size_t>(y) * static_cast<size_t>(width) +
                        static_cast<size_t>(x)) +
                   static_cast<size_t>(c)];
      out.write(reinterpret_cast<const char*>(row.data()),
                static_cast<std::streamsize>(row.size() * sizeof(float)));
    }
    if (!out) throw std::runtime_error("cannot write " + temporary);
  }
  replace(temporary, path);
}

void writeStats(const Job& job, const std::vector<FrameRecord>& frames) {
  const Options& o = job.options;
  const std::string temporary = o.statsFile + ".partial";
  std::vector<double> frameMs;
  {
    std::ofstream out(temporary);
    if (!out) throw std::runtime_error("cannot create " + temporary);
    out << "{\n  \"canvas\": [" << job.canvasWidth << ", " << job.canvasHeight << "],\n"
        << "  \"mode\": \"" << (job.layout ? o.mode : "image") << "\",\n"
        << "  \"renderer\": \"" << o.renderer << "\",\n"
        << "  \"render_ranks\": " << job.roles.renderRanks << ",\n"
        << "  \"wall_ranks\": " << job.roles.wallRanks << ",\n"
        << "  \"spp\": " << o.spp << ",\n  \"frames\": [\n";
    for (size_t i = 0; i < frames.size(); ++i) {
      const FrameRecord& f = frames[i];
      frameMs.push_back(f.frameMs);
      out << "    {\"frame\": " << f.frame << ", \"frame_ms\": " << f.frameMs
          << ", \"render_ms\": " << f.renderMs << ", \"composite_ms\": " << f.compositeMs
          << ", \"rank0_pixel_bytes_received\": " << f.rank0PixelBytes
          << ", \"wall_bytes_sent\": " << f.wallBytesSent
          << ", \"tile_bytes_sent\": " << f.tileBytesSent
          << ", \"tiles_rendered\": " << f.tilesRendered << ", \"samples\": " << f.samples << "}"
          << (i + 1 < frames.size() ? "," : "") << "\n";
    }
    const double medianMs = median(frameMs);
    out << "  ],\n  \"summary\": {\"frames\": " << frames.size()
        << ", \"median_frame_ms\": " << medianMs
        << ", \"fps\": " << (medianMs > 0 ? 1000.0 / medianMs : 0.0) << "}\n}\n";
    if (!out) throw std::runtime_error("cannot write " + temporary);
  }
  replace(temporary, o.statsFile);
}

}  // namespace app
