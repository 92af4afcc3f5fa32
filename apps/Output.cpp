// Files rank 0 writes: the --image PFM and the --stats JSON. Both are written to a temporary
// name and renamed, so nobody reads half a file.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
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

// Median absolute deviation: the spread the paper reports next to the median.
double mad(const std::vector<double>& values) {
  const double m = median(values);
  std::vector<double> deviations;
  for (double v : values) deviations.push_back(std::abs(v - m));
  return median(deviations);
}

}  // namespace

double peakRssKiB() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::atof(line.c_str() + 6);
  return 0;
}

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

void writeStats(const Job& job, const std::vector<FrameRecord>& frames,
                const std::vector<RankTotals>& ranks) {
  const Options& o = job.options;
  const std::string temporary = o.statsFile + ".partial";
  std::vector<double> frameMs, compositeShare;
  {
    std::ofstream out(temporary);
    if (!out) throw std::runtime_error("cannot create " + temporary);
    out << "{\n  \"canvas\": [" << job.canvasWidth << ", " << job.canvasHeight << "],\n"
        << "  \"mode\": \"" << (job.layout ? o.mode : "image") << "\",\n"
        << "  \"renderer\": \"" << o.renderer << "\",\n"
        << "  \"render_ranks\": " << job.roles.renderRanks << ",\n"
        << "  \"wall_ranks\": " << job.roles.wallRanks << ",\n"
        << "  \"threads\": " << o.threads << ",\n"
        << "  \"orbit_degrees_per_frame\": " << o.orbit << ",\n"
        << "  \"spp\": " << o.spp << ",\n  \"frames\": [\n";
    for (size_t i = 0; i < frames.size(); ++i) {
      const FrameRecord& f = frames[i];
      frameMs.push_back(f.frameMs);
      out << "    {\"frame\": " << f.frame << ", \"frame_ms\": " << f.frameMs
          << ", \"render_ms\": " << f.renderMs << ", \"composite_ms\": " << f.compositeMs;
      // Last setTile on any rank to the last display holding every piece of the frame.
      if (f.displaysCompleteNs > 0 && f.lastSetTileNs > 0) {
        const double ms = static_cast<double>(f.displaysCompleteNs - f.lastSetTileNs) * 1e-6;
        out << ", \"composite_to_displays_ms\": " << ms;
        if (f.frameMs > 0) compositeShare.push_back(std::max(0.0, ms) / f.frameMs);
      }
      out << ", \"rank0_pixel_bytes_received\": " << f.rank0PixelBytes
          << ", \"wall_bytes_sent\": " << f.wallBytesSent
          << ", \"wall_bytes_raw\": " << f.wallBytesRaw << ", \"wall_pieces\": " << f.wallPieces
          << ", \"wall_pieces_to_other_hosts\": " << f.wallPiecesToOtherHosts
          << ", \"messages_compressed\": " << f.messagesCompressed
          << ", \"tile_bytes_sent\": " << f.tileBytesSent
          << ", \"tiles_rendered\": " << f.tilesRendered << ", \"samples\": " << f.samples << "}"
          << (i + 1 < frames.size() ? "," : "") << "\n";
    }
    out << "  ],\n  \"ranks\": [\n";
    double peak[2] = {0, 0};
    for (size_t r = 0; r < ranks.size(); ++r) {
      const RankTotals& t = ranks[r];
      const int role = t.role > 0.5 ? 1 : 0;
      peak[role] = std::max(peak[role], t.peakRssKiB);
      out << "    {\"rank\": " << r << ", \"role\": \"" << (role ? "wall" : "render")
          << "\", \"peak_rss_kib\": " << t.peakRssKiB << ", \"stages_ms\": {";
      // Each role reports its own stages only.
      const int first = role ? 7 : 0, last = role ? RankTotals::kStages : 7;
      for (int s = first; s < last; ++s)
        out << (s > first ? ", " : "") << "\"" << RankTotals::kStageNames[s]
            << "\": " << t.stageMs[s];
      out << "}}" << (r + 1 < ranks.size() ? "," : "") << "\n";
    }
    const double medianMs = median(frameMs);
    out << "  ],\n  \"summary\": {\"frames\": " << frames.size()
        << ", \"median_frame_ms\": " << medianMs << ", \"mad_frame_ms\": " << mad(frameMs)
        << ", \"fps\": " << (medianMs > 0 ? 1000.0 / medianMs : 0.0)
        << ", \"peak_rss_kib\": {\"render\": " << peak[0] << ", \"wall\": " << peak[1] << "}";
    if (!compositeShare.empty())
      out << ", \"median_composite_share\": " << median(compositeShare)
          << ", \"mad_composite_share\": " << mad(compositeShare);
    out << "}\n}\n";
    if (!out) throw std::runtime_error("cannot write " + temporary);
  }
  replace(temporary, o.statsFile);
}

}  // namespace app
