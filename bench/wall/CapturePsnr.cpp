// capture_psnr A.png B.png [A.png B.png ...]: the PSNR in dB of the RGB channels of A against B,
// pooled over every pair given (one mean squared error over all their pixels), e.g. every
// display's capture of one frame from a JPEG job against the same frame from a raw job
// (scripts/bench service). Prints the dB ("inf" when identical) and the largest channel error.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>

#include "wall/image/Image.h"
#include "wall/image/Png.h"

int main(int argc, char** argv) {
  if (argc < 3 || (argc - 1) % 2 != 0) {
    std::fprintf(stderr, "usage: capture_psnr A.png B.png [A.png B.png ...]\n");
    return 2;
  }
  try {
    double squared = 0;
    std::uint64_t samples = 0;
    int worst = 0;
    for (int i = 1; i + 1 < argc; i += 2) {
      const wall::Image a = wall::readPng(argv[i]), b = wall::readPng(argv[i + 1]);
      if (a.width != b.width || a.height != b.height) {
        std::fprintf(stderr, "%s is %dx%d, %s is %dx%d\n", argv[i], a.width, a.height, argv[i + 1],
                     b.width, b.height);
        return 1;
      }
      for (std::size_t p = 0; p < a.pixels.size(); ++p)
        for (int c = 0; c < 3; ++c) {
          const int d = static_cast<int>((a.pixels[p] >> (8 * c)) & 0xff) -
                        static_cast<int>((b.pixels[p] >> (8 * c)) & 0xff);
          squared += static_cast<double>(d) * d;
          worst = std::max(worst, std::abs(d));
        }
      samples += 3 * a.pixels.size();
    }
    const double mse = samples > 0 ? squared / static_cast<double>(samples) : 0;
    if (mse == 0)
      std::printf("inf %d\n", worst);
    else
      std::printf("%.3f %d\n", 10 * std::log10(255.0 * 255.0 / mse), worst);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "capture_psnr: %s\n", e.what());
    return 1;
  }
  return 0;
}
