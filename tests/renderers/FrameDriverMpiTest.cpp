// A frame through the real DFB on 1..3 ranks equals the single-process render bit for bit.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>

#include "dfb/DistributedFrameBuffer.h"
#include "renderers/BuiltinScenes.h"
#include "renderers/FrameDriver.h"
#include "renderers/PathTracer.h"
#include "renderers/Scene.h"
#include "tests/renderers/RenderTestUtil.h"

namespace renderers {
namespace {

constexpr int kWidth = 72, kHeight = 40, kTile = 16;
constexpr std::uint32_t kSpp = 2;

struct DfbRun {
  std::vector<float> image;  // rank 0 only
  WorkPlan lastPlan;
};

DfbRun renderThroughDfb(const Scene& scene, Distribution distribution, int frames, int threads) {
  PathTracer pt(scene, {kWidth, kHeight, 9, 6});
  FrameDriverOptions fo;
  fo.distribution = distribution;
  fo.samplesPerPixel = kSpp;
  fo.threads = threads;
  FrameDriver driver(pt, fo);
  messaging::Messenger messenger(MPI_COMM_WORLD);
  dfb::DfbOptions options;
  options.width = kWidth, options.height = kHeight, options.tileSize = kTile;
  options.format = dfb::DisplayFormat::RGBAF32;
  options.operation = dfb::accumulateOperation();
  options.frameTimeout = std::chrono::milliseconds(20000);
  driver.configure(options);
  DfbRun run;
  {
    dfb::DistributedFrameBuffer fb(messenger, MPI_COMM_WORLD, options);
    for (int f = 0; f < frames; ++f) {
      const FrameReport report =
          driver.renderFrame(fb, {static_cast<std::uint32_t>(f), 0}, scene.desc().camera);
      EXPECT_EQ(report.tilesRendered,
                static_cast<int>(driver.lastPlan().perRank[fb.rank()].size()));
    }
    run.image = fb.imageRgbaF32();
    run.lastPlan = driver.lastPlan();
  }
  messenger.stop();
  return run;
}

class FrameDriverMpi : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { scene_ = new Scene(cornellBox()); }
  static void TearDownTestSuite() { delete scene_; }
  static Scene* scene_;
  int rank() const {
    int r;
    MPI_Comm_rank(MPI_COMM_WORLD, &r);
    return r;
  }
};
Scene* FrameDriverMpi::scene_ = nullptr;

TEST_F(FrameDriverMpi, OneFrameEqualsTheSingleProcessRenderForEveryDistribution) {
  PathTracer pt(*scene_, {kWidth, kHeight, 9, 6});
  const auto reference = test::renderImage(pt, kWidth, kHeight, 64, 1, kSpp);
  for (auto d : {Distribution::Static, Distribution::RoundRobin, Distribution::Dynamic}) {
    const DfbRun run = renderThroughDfb(*scene_, d, 1, 2);
    if (rank() != 0) continue;
    ASSERT_EQ(run.image.size(), reference.size());
    EXPECT_EQ(0, std::memcmp(run.image.data(), reference.data(), reference.size() * 4))
        << "distribution " << static_cast<int>(d);
  }
}

TEST_F(FrameDriverMpi, DynamicAddsInputsAfterTheFirstFrameAndStillConverges) {
  const DfbRun dynamic = renderThroughDfb(*scene_, Distribution::Dynamic, 3, 1);
  const DfbRun roundRobin = renderThroughDfb(*scene_, Distribution::RoundRobin, 3, 1);
  int ranks;
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  int extra = 0;
  for (int n : dynamic.lastPlan.inputsPerTile) extra += n - 1;
  if (ranks > 1) {
    EXPECT_GT(extra, 0) << "no tile got a redundant input";
  }
  if (rank() != 0) return;
  double a = 0, b = 0;
  for (std::size_t i = 0; i < dynamic.image.size(); i += 4) {
    ASSERT_TRUE(std::isfinite(dynamic.image[i]));
    a += dynamic.image[i], b += roundRobin.image[i];
  }
  // Both estimate the same image; at this sample count the means agree within a few percent.
  EXPECT_NEAR(a / b, 1.0, 0.05);
}

}  // namespace
}  // namespace renderers
