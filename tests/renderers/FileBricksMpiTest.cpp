// Real data cut into bricks: configs/scenes/brain.toml (gzipped NIfTI: a volume and an
// isosurface of another) and ocean.toml (NetCDF with missing values) render with 4 bricks the
// same bytes on 1 and on 3 ranks, and within 1e-4 of the same scene in 1 brick.
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "renderers/SceneToml.h"
#include "renderers/scivis/bricks/BrickFrameDriver.h"
#include "tests/MpiTestUtil.h"
#include "tests/renderers/BrickTestUtil.h"

namespace renderers::scivis {
namespace {

constexpr int kWidth = 64, kHeight = 48, kTile = 16;

// `bricks` bricks on the first `ranks` ranks of the world (rank 0's image; empty elsewhere).
std::vector<float> renderBricks(const std::shared_ptr<SceneDesc>& desc, int ranks, int bricks) {
  return test::onFirstRanks(ranks, [&](MPI_Comm comm, int rank) {
    RenderSettings settings;
    settings.width = kWidth, settings.height = kHeight, settings.seed = 11;
    return test::renderHeldBricks(desc, settings, loadOwnBricks(*desc, bricks, 1, rank, ranks),
                                  comm, kTile, 1, std::chrono::milliseconds(60000));
  });
}

void checkScene(const std::string& name) {
  const auto desc =
      std::make_shared<SceneDesc>(readSceneToml(std::string(DFBWALL_SCENES) + "/" + name));
  const std::vector<float> one = renderBricks(desc, 1, 4);
  const std::vector<float> many = renderBricks(desc, testutil::worldSize(), 4);
  const std::vector<float> whole = renderBricks(desc, 1, 1);
  if (testutil::worldRank() != 0) return;
  ASSERT_EQ(one.size(), 4u * kWidth * kHeight);
  ASSERT_EQ(many.size(), one.size());
  ASSERT_EQ(whole.size(), one.size());
  EXPECT_EQ(0, std::memcmp(one.data(), many.data(), one.size() * sizeof(float)))
      << name << ": 4 bricks on " << testutil::worldSize() << " ranks differ from 1 rank";
  float worst = 0;
  int lit = 0;
  for (std::size_t i = 0; i < one.size(); ++i) {
    worst = std::max(worst, std::abs(one[i] - whole[i]));
    if (i % 4 == 0 && std::abs(whole[i] - whole[0]) > 0.05f) ++lit;
  }
  EXPECT_LE(worst, 1e-4f) << name << ": 4 bricks vs 1 brick";
  EXPECT_GT(lit, kWidth * kHeight / 8) << name << ": the data should cover much of the image";
  std::printf("%s: 4 bricks on 1 and %d ranks: same bytes; largest difference to 1 brick %.3g\n",
              name.c_str(), testutil::worldSize(), worst);
}

TEST(FileBricksMpi, BrainRendersTheSameBytesOnEveryRankCountAndMatchesOneBrick) {
  checkScene("brain.toml");
}

TEST(FileBricksMpi, OceanRendersTheSameBytesOnEveryRankCountAndMatchesOneBrick) {
  checkScene("ocean.toml");
}

}  // namespace
}  // namespace renderers::scivis
