// No work behind a nearer brick's opaque surface (renderers/scivis/bricks/BrickOcclusion.h): the
// rays it skips change no byte of the image, on any rank count and replication, it does skip some,
// and it never applies where a fragment may be translucent.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstring>

#include "renderers/RenderScene.h"
#include "renderers/scivis/BuiltinScenes.h"
#include "renderers/scivis/bricks/BrickFrameDriver.h"
#include "renderers/scivis/bricks/BrickOcclusion.h"
#include "renderers/scivis/io/SciVisDesc.h"
#include "renderers/scivis/render/SciVisRenderer.h"
#include "tests/MpiTestUtil.h"
#include "tests/renderers/BrickTestUtil.h"
#include "tests/renderers/RenderTestUtil.h"

namespace renderers::scivis {
namespace {

constexpr int kWidth = 96, kHeight = 72, kTile = 16, kFrames = 2;

// The wavelet's two isosurfaces, both opaque, the volume not drawn, with AO and shadows (shading
// does not matter to the cut, only alpha does); the builtin camera looks at the field from a
// corner, so nearer bricks hide farther ones.
std::shared_ptr<SceneDesc> opaqueScene() {
  auto d = std::make_shared<SceneDesc>(waveletScene(40));
  sciVisDesc(*d).volumes[0].visible = false;
  for (Material& m : d->materials) m.opacity = 1.0f;
  sciVisDesc(*d).settings.aoSamples = 2;
  sciVisDesc(*d).settings.aoDistance = 0.2f;
  sciVisDesc(*d).settings.shadows = true;
  return d;
}

RenderSettings settings() {
  RenderSettings s;
  s.width = kWidth, s.height = kHeight, s.seed = 23;
  return s;
}

// The image of kFrames frames of `bricks` bricks on the first `ranks` ranks (rank 0's copy) and
// the rays the ranks skipped, summed (on rank 0).
std::vector<float> renderBricks(const std::shared_ptr<SceneDesc>& desc, int ranks, int bricks,
                                int replication, bool cut, std::uint64_t& skipped,
                                FirstHits firstHits = FirstHits::Auto) {
  MPI_Comm comm;
  const int rank = testutil::worldRank();
  MPI_Comm_split(MPI_COMM_WORLD, rank < ranks ? 0 : 1, rank, &comm);
  std::vector<float> image;
  std::uint64_t mine = 0;
  if (rank < ranks)
    image = test::renderHeldBricks(
        desc, settings(), loadOwnBricks(*desc, bricks, replication, rank, ranks), comm, kTile,
        kFrames, std::chrono::milliseconds(30000), cut, &mine, firstHits);
  MPI_Comm_free(&comm);
  skipped = 0;
  MPI_Reduce(&mine, &skipped, 1, MPI_UINT64_T, MPI_SUM, 0, MPI_COMM_WORLD);
  return image;
}

bool sameBytes(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

// With first hits from Embree (Auto at this size) and from the raster (FirstHitRaster.h: its hit
// distances key the AO and shadow rays' random numbers as Embree's do, so the unbricked render
// must find its first hits the same way).
TEST(BrickOcclusionMpi, SkippedRaysChangeNoByteOnAnyRankCountOrReplication) {
  const auto desc = opaqueScene();
  ASSERT_TRUE(BrickOcclusion::exactFor(*desc));
  const int size = testutil::worldSize();
  for (const FirstHits firstHits : {FirstHits::Auto, FirstHits::Raster}) {
    const char* how = firstHits == FirstHits::Raster ? "raster" : "Embree";
    std::uint64_t skippedOff = 0, skippedOn = 0, skippedOne = 0, skippedReplicated = 0;
    const std::vector<float> off = renderBricks(desc, size, 4, 1, false, skippedOff, firstHits);
    const std::vector<float> on = renderBricks(desc, size, 4, 1, true, skippedOn, firstHits);
    const std::vector<float> one = renderBricks(desc, 1, 4, 1, true, skippedOne, firstHits);
    const std::vector<float> replicated =
        renderBricks(desc, size, 4, std::min(size, 2), true, skippedReplicated, firstHits);
    if (testutil::worldRank() != 0) continue;
    EXPECT_EQ(skippedOff, 0u) << how;
    // Every frame's tiles are cut the same whoever renders them: the same rays on every layout.
    EXPECT_GT(skippedOn, 0u) << how << ": the nearer bricks' isosurfaces should hide some rays";
    EXPECT_EQ(skippedOne, skippedOn) << how;
    EXPECT_EQ(skippedReplicated, skippedOn) << how;
    EXPECT_TRUE(sameBytes(on, off)) << how << ": skipping hidden rays changed the image";
    EXPECT_TRUE(sameBytes(one, off)) << how << ": 1 rank";
    EXPECT_TRUE(sameBytes(replicated, off)) << how << ": replication " << std::min(size, 2);

    // And the unbricked render, within float summation order.
    const SciVisScene whole(desc, wholeScene(*desc));
    SciVisOptions options;
    options.firstHits = firstHits;
    SciVisRenderer renderer(whole, settings(), options);
    // As the frame driver does (and with it, the raster's binning for this camera).
    renderer.beginFrame(dfb::FrameInfo{}, desc->camera);
    EXPECT_EQ(renderer.firstHitsRasterised(1), firstHits == FirstHits::Raster) << how;
    std::vector<float> expected(on.size(), 0.0f);
    for (int f = 0; f < kFrames; ++f) {
      const auto frame =
          test::renderImage(renderer, kWidth, kHeight, kTile, 2, 1, static_cast<std::uint32_t>(f));
      for (std::size_t i = 0; i < frame.size(); ++i) expected[i] += frame[i] / kFrames;
    }
    ASSERT_EQ(on.size(), expected.size());
    float worst = 0;
    for (std::size_t i = 0; i < on.size(); ++i)
      worst = std::max(worst, std::abs(on[i] - expected[i]));
    EXPECT_LE(worst, 1e-4f) << how;
    std::printf(
        "4 bricks on %d rank(s), first hits by %s: %llu of %d camera rays skipped over %d "
        "frames; %.3g from the unbricked render\n",
        size, how, static_cast<unsigned long long>(skippedOn), kWidth * kHeight * kFrames, kFrames,
        worst);
  }
}

// Where a fragment's alpha may lie between 0 and 1, an opaque crossing does not make the
// composited alpha exactly 1 (or early termination stops short of it): nothing is skipped.
TEST(BrickOcclusionMpi, NothingIsSkippedWhereFragmentsMayBeTranslucent) {
  auto glassy = opaqueScene();
  glassy->materials[0].opacity = 0.5f;
  auto volume = opaqueScene();
  sciVisDesc(*volume).volumes[0].visible = true;
  auto bare = opaqueScene();
  sciVisDesc(*bare).isosurfaces.clear();
  EXPECT_FALSE(BrickOcclusion::exactFor(*glassy));
  EXPECT_FALSE(BrickOcclusion::exactFor(*volume));
  EXPECT_FALSE(BrickOcclusion::exactFor(*bare));
  std::uint64_t skipped = 0;
  renderBricks(glassy, testutil::worldSize(), 4, 1, true, skipped);
  if (testutil::worldRank() == 0) {
    EXPECT_EQ(skipped, 0u);
  }
}

// The summary's known answers on two bricks of the wavelet (about 37 at the domain's faces, 255
// in its middle): a ray entering a brick at the domain's face (below 160) and leaving it by the
// face the bricks share, through the middle (above 160), certainly crosses the isosurface
// there, and so does the same ray in the other brick (in above, out below); one near the
// domain's edge enters and leaves below: nothing is certain.
TEST(BrickOcclusionMpi, ACrossingIsCertainOnlyBetweenCellsOnBothSides) {
  const auto desc = opaqueScene();
  std::vector<HeldBrick> held = loadOwnBricks(*desc, 2, 1, 0, 1);
  std::vector<BrickPlan> plans;
  std::vector<std::pair<int, const BrickContent*>> contents;
  for (const HeldBrick& b : held) {
    plans.push_back({b.id, b.content.bounds});
    contents.emplace_back(b.id, &b.content);
  }
  ASSERT_EQ(plans.size(), 2u);
  const BrickOcclusion occlusion = BrickOcclusion::exchange(*desc, plans, contents, MPI_COMM_SELF,
                                                            std::chrono::milliseconds(10000));
  EXPECT_GT(occlusion.bytes(), 0u);
  // The brick whose high face (along the split axis) is the shared one.
  const Box3 a = plans[0].bounds, b = plans[1].bounds;
  int axis = -1;
  for (int k = 0; k < 3; ++k)
    if (a.hi[k] == b.lo[k]) axis = k;
  ASSERT_GE(axis, 0) << "brick 0 should be the low half";
  auto ray = [&](float offset, Vec3& origin, Vec3& dir) {
    origin = Vec3{0.02f + offset, 0.03f + offset, 0.01f + offset};
    float* o = &origin.x;
    o[axis] = -3.0f;
    dir = Vec3{0.0f};
    float* d = &dir.x;
    d[axis] = 1.0f;
  };
  auto certain = [&](int brick, float offset) {
    Vec3 origin, dir;
    ray(offset, origin, dir);
    const Vec3 inv = reciprocal(dir);
    float t0 = 0, t1 = Box3::kInf;
    EXPECT_TRUE(clipToBox(plans[static_cast<std::size_t>(brick)].bounds, origin, inv, t0, t1));
    // Nothing nearer (before = inf), or the ray's own entry with the tie won: the same answer.
    const bool any = occlusion.hides(brick, origin, dir, inv, Box3::kInf, false);
    EXPECT_EQ(any, occlusion.hides(brick, origin, dir, inv, t0, true));
    EXPECT_FALSE(occlusion.hides(brick, origin, dir, inv, t0, false))
        << "entering at t0 is no earlier";
    return any;
  };
  EXPECT_TRUE(certain(0, 0.0f)) << "through the middle, out by the shared face";
  EXPECT_FALSE(certain(0, 0.85f)) << "near the domain's edge: below 160 all along";
  EXPECT_TRUE(certain(1, 0.0f)) << "in by the shared face above 160, out below";
  EXPECT_FALSE(certain(1, 0.85f)) << "near the domain's edge: below 160 all along";
}

}  // namespace
}  // namespace renderers::scivis
