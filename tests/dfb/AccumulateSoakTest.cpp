// Soak (label 'stress'): a still view accumulated for 10^7 frames stays within 0.1% of a
// double-precision reference. With float running sums the mean drifted by percents once a sum
// passed 2^24 increments. Every pixel keeps its own sums, so a 4x4 tile tests exactly what a
// 16x16 one would, at a sixteenth of the time (16x16: 67 s on the CI machine, too long).
#include <gtest/gtest.h>

#include <cmath>

#include "dfb/TileOperation.h"

namespace dfb {
namespace {

TEST(AccumulateSoak, TenMillionStillFramesStayWithinAThousandthOfTheDoubleMean) {
  const Region region{0, 0, 4, 4};
  auto op = accumulateOperation()(region);
  Tile input;
  input.reset(region);
  constexpr std::uint32_t kFrames = 10'000'000;
  double reference[3] = {0, 0, 0};
  for (std::uint32_t f = 0; f < kFrames; ++f) {
    // A noisy still view: three values per pixel cycling, like samples of one pixel.
    const float v = 0.1f + 0.7f * static_cast<float>(f % 3) / 2.0f;
    for (size_t i = 0; i < input.color.size(); ++i) input.color[i] = v;
    reference[f % 3] += 1;
    input.accumulationId = f;
    op->newFrame({f + 1, 0}, f, 1);
    ASSERT_TRUE(op->process(Tile(input)));
  }
  double mean = 0;
  for (int k = 0; k < 3; ++k)
    mean += reference[k] * static_cast<double>(0.1f + 0.7f * static_cast<float>(k) / 2.0f);
  mean /= kFrames;
  const Tile& out = op->finished();
  double worst = 0;
  for (float c : out.color) worst = std::max(worst, std::abs(c - mean) / mean);
  EXPECT_LT(worst, 1e-3) << "mean " << mean << ", first pixel " << out.color[0];
}

}  // namespace
}  // namespace dfb
