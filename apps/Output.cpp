// The --image PFM (written atomically, see base/AtomicFile.h) and the peak-memory probe.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "apps/Job.h"
#include "base/AtomicFile.h"

namespace app {

void Job::failIfAsked(std::uint32_t frame) const {
  if (worldRank == failAtRank && frame == failAtFrame)
    throw std::runtime_error("injected failure at frame " + std::to_string(frame) +
                             " (DFBWALL_FAIL_AT)");
}

double peakRssKiB() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::atof(line.c_str() + 6);
  return 0;
}

void writePfm(const std::string& path, const float* rgba, int width, int height) {
  base::AtomicFile file(path);
  FILE* out = file.stream();
  std::fprintf(out, "PF\n%d %d\n-1.0\n", width, height);  // negative scale: little-endian
  std::vector<float> row(3 * static_cast<size_t>(width));
  for (int y = height - 1; y >= 0; --y) {  // PFM rows go bottom to top
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < 3; ++c)
        row[3 * static_cast<size_t>(x) + static_cast<size_t>(c)] =
            rgba[4 * (static_cast<size_t>(y) * static_cast<size_t>(width) +
                      static_cast<size_t>(x)) +
                 static_cast<size_t>(c)];
    std::fwrite(row.data(), sizeof(float), row.size(), out);
  }
  file.commit();  // reports a short write (full disk) with the path
}

}  // namespace app
