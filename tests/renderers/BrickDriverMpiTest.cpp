// Data- and mixed-parallel rendering through the real DFB: a scene cut into 4 bricks renders the
// same bytes on 1, 2, 3 and 4 ranks and with every replication, and matches the unbricked
// (image-parallel) render up to float summation order.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstring>

#include "dfb/DistributedFrameBuffer.h"
#include "renderers/RenderScene.h"
#include "renderers/scivis/BuiltinScenes.h"
#include "renderers/scivis/bricks/BrickFrameDriver.h"
#include "renderers/scivis/io/SciVisDesc.h"
#include "tests/MpiTestUtil.h"
#include "tests/renderers/BrickTestUtil.h"
#include "tests/renderers/RenderTestUtil.h"

namespace renderers::scivis {
namespace {

constexpr int kWidth = 80, kHeight = 56, kTile = 16, kFrames = 2;

// Everything a brick can cut: a volume with a glassy and an opaque isosurface, particles on the
// brick borders, a triangle through the middle; AO within the bricks' ghost margin, and shadows
// (the default lights: a directional one from the camera) that fall from brick to brick.
std::shared_ptr<SceneDesc> scene(int resolution = 36) {
  auto d = std::make_shared<SceneDesc>(waveletScene(resolution));
  sciVisDesc(*d).volumes[0].transfer.opacities = {{37.0f, 0.0f}, {120.0f, 0.03f}, {277.0f, 0.2f}};
  sciVisDesc(*d).settings.aoSamples = 2;
  sciVisDesc(*d).settings.aoDistance = 0.2f;
  sciVisDesc(*d).settings.shadows = true;
  sciVisDesc(*d).settings.minTransmittance = 0;
  ParticlesDesc p;
  p.name = "dots";
  p.centers = {{0, 0, 0}, {0.5f, -0.02f, 0.3f}, {-0.7f, 0.4f, -0.01f}, {0.01f, 0.8f, 0.6f}};
  p.radii = {0.12f};
  p.material = 1;
  sciVisDesc(*d).particles.push_back(p);
  Shape tri;
  tri.name = "tri";
  tri.mesh.positions = {{-1, -0.9f, -0.3f}, {1, -0.9f, 0.2f}, {0.1f, 0.9f, -0.1f}};
  tri.mesh.triangles = {{0, 1, 2}};
  d->shapes.push_back(tri);
  d->instances.push_back({0, {}, 0});
  return d;
}

RenderSettings settings() {
  RenderSettings s;
  s.width = kWidth, s.height = kHeight, s.seed = 17;
  return s;
}

// The image of kFrames accumulated frames of the bricks `held` on the ranks of `comm` (rank 0's
// copy; empty elsewhere).
std::vector<float> renderHeld(const std::shared_ptr<SceneDesc>& desc, std::vector<HeldBrick> held,
                              MPI_Comm comm) {
  return test::renderHeldBricks(desc, settings(), std::move(held), comm, kTile, kFrames,
                                std::chrono::milliseconds(30000));
}

// The image of kFrames accumulated frames with `bricks` bricks on the first `ranks` ranks of the
// world (rank 0's copy; empty elsewhere).
std::vector<float> renderBricks(const std::shared_ptr<SceneDesc>& desc, int ranks, int bricks,
                                int replication, GhostMode ghosts = GhostMode::Reach) {
  MPI_Comm comm;
  const int rank = testutil::worldRank();
  MPI_Comm_split(MPI_COMM_WORLD, rank < ranks ? 0 : 1, rank, &comm);
  std::vector<float> image;
  if (rank < ranks)
    image = renderHeld(desc, loadOwnBricks(*desc, bricks, replication, rank, ranks, ghosts), comm);
  MPI_Comm_free(&comm);
  MPI_Barrier(MPI_COMM_WORLD);
  return image;
}

// 4 bricks on 1 .. world size ranks, every replication, give the bytes of 1 rank.
void checkEveryRankCountAndReplication(const std::shared_ptr<SceneDesc>& desc, GhostMode ghosts) {
  const int size = testutil::worldSize();
  const std::vector<float> reference = renderBricks(desc, 1, 4, 1, ghosts);
  for (int ranks = 1; ranks <= size; ++ranks)
    for (int replication : {1, 2, 4}) {
      if (replication > ranks || (ranks == 1 && replication > 1)) continue;
      const std::vector<float> image = renderBricks(desc, ranks, 4, replication, ghosts);
      if (testutil::worldRank() != 0) continue;
      ASSERT_EQ(image.size(), reference.size());
      EXPECT_EQ(0, std::memcmp(image.data(), reference.data(), image.size() * sizeof(float)))
          << ranks << " ranks, replication " << replication << ", ghost " << ghostModeName(ghosts);
    }
}

TEST(BrickDriverMpi, EveryRankCountAndReplicationGivesTheSameBytes) {
  checkEveryRankCountAndReplication(scene(), GhostMode::Reach);
}

// One ghost layer: what a brick's AO rays see depends on the brick plan only, so the image is
// still a function of the plan, whoever renders which brick.
TEST(BrickDriverMpi, LayerGhostsGiveTheSameBytesOnEveryRankCountAndReplication) {
  checkEveryRankCountAndReplication(scene(), GhostMode::Layer);
}

// Without AO and shadows no shading ray leaves a brick, so both ghost modes load the same data
// and render the same bytes.
TEST(BrickDriverMpi, LayerGhostsEqualReachWithoutAoAndShadows) {
  const auto desc = scene();
  sciVisDesc(*desc).settings.aoSamples = 0;
  sciVisDesc(*desc).settings.shadows = false;
  const int ranks = testutil::worldSize();
  const std::vector<float> reach = renderBricks(desc, ranks, 4, 1, GhostMode::Reach);
  const std::vector<float> layer = renderBricks(desc, ranks, 4, 1, GhostMode::Layer);
  if (testutil::worldRank() != 0) return;
  ASSERT_EQ(reach.size(), layer.size());
  EXPECT_EQ(0, std::memcmp(reach.data(), layer.data(), reach.size() * sizeof(float)));
}

// With AO on, one ghost layer holds less than the AO reach, and the AO of points near brick
// faces no longer sees the neighbour's data: the image differs from the unbricked one there.
TEST(BrickDriverMpi, LayerGhostsHoldLessAndChangeAoNearBrickFaces) {
  const auto desc = scene();
  ASSERT_GT(sciVisDesc(*desc).settings.aoSamples, 0);
  std::size_t reachBytes = 0, layerBytes = 0;
  for (const HeldBrick& b : loadOwnBricks(*desc, 4, 1, 0, 1, GhostMode::Reach))
    reachBytes += b.content.bytes();
  for (const HeldBrick& b : loadOwnBricks(*desc, 4, 1, 0, 1, GhostMode::Layer))
    layerBytes += b.content.bytes();
  EXPECT_LT(layerBytes, reachBytes);
  const int ranks = testutil::worldSize();
  const std::vector<float> whole = renderBricks(desc, ranks, 1, 1, GhostMode::Layer);
  const std::vector<float> layer = renderBricks(desc, ranks, 4, 1, GhostMode::Layer);
  if (testutil::worldRank() != 0) return;
  ASSERT_EQ(whole.size(), layer.size());
  float worst = 0;
  std::size_t differing = 0;
  for (std::size_t i = 0; i < whole.size(); ++i) {
    worst = std::max(worst, std::abs(whole[i] - layer[i]));
    differing += std::abs(whole[i] - layer[i]) > 1e-4f;
  }
  EXPECT_GT(worst, 1e-4f) << "AO rays near brick faces should miss the neighbours' data";
  std::printf(
      "4 bricks, ghost layer: %zu vs %zu bytes (reach); %zu of %zu channels differ from "
      "the unbricked render by more than 1e-4, at most %.3g\n",
      layerBytes, reachBytes, differing, whole.size(), worst);
}

// Every rank count gives rank 1's bytes, and 4 bricks match the image-parallel render of `desc`.
void checkAgainstUnbricked(const std::shared_ptr<SceneDesc>& desc);

TEST(BrickDriverMpi, FourBricksMatchTheUnbrickedRender) { checkAgainstUnbricked(scene()); }

// Shadows towards a point light inside the domain and a directional light along an axis (the
// bricks swept towards them: the hull of brick and light, a column to the domain's face).
TEST(BrickDriverMpi, FourBricksMatchTheUnbrickedRenderWithPointAndAxisLights) {
  const auto desc = scene();
  sciVisDesc(*desc).settings.aoSamples = 0;
  LightDesc point;
  point.kind = LightDesc::Kind::Point;
  point.position = {0.6f, 0.9f, -0.5f};
  point.intensity = 0.6f;
  LightDesc axis;
  axis.direction = {1, 0, 0};
  axis.intensity = 0.5f;
  LightDesc ambient;
  ambient.kind = LightDesc::Kind::Ambient;
  ambient.intensity = 0.2f;
  sciVisDesc(*desc).lights = {point, axis, ambient};
  checkAgainstUnbricked(desc);
}

// The camera inside a brick: its rays leave that brick (counted: they exit it) and enter others.
TEST(BrickDriverMpi, CameraInsideABrick) {
  const auto desc = scene();
  desc->camera.position = {0.45f, 0.35f, -0.4f};
  desc->camera.lookAt = {-0.5f, -0.2f, 0.6f};
  desc->camera.fovY = 70;
  int inside = 0;
  for (const BrickPlan& b : splitScene(*desc, 4))
    inside += b.bounds.contains(desc->camera.position);
  ASSERT_EQ(inside, 1);
  {
    // The screen projection cannot place a brick with a corner behind the camera (it is a
    // candidate for every tile); the tiles' rays can: each tile needs the brick around the
    // camera, and fewer tile-bricks are needed than the projections suggest.
    const BrickFrameDriver driver(desc, settings(), {}, loadOwnBricks(*desc, 4, 1, 0, 1),
                                  MPI_COMM_SELF);
    std::size_t candidates = 0, needed = 0;
    for (int y = 0; y < kHeight; y += kTile)
      for (int x = 0; x < kWidth; x += kTile) {
        const dfb::Region r{x, y, std::min(x + kTile, kWidth), std::min(y + kTile, kHeight)};
        const auto tileNeeds = driver.bricksOfTile(desc->camera, r, 0);
        candidates += driver.candidateBricks(desc->camera, r).size();
        needed += tileNeeds.size();
        EXPECT_GE(tileNeeds.size(), 1u);
      }
    EXPECT_LT(needed, candidates);
  }
  const std::vector<float> one = renderBricks(desc, 1, 4, 1);
  const std::vector<float> all = renderBricks(desc, testutil::worldSize(), 4, 2);
  if (testutil::worldRank() == 0) {
    ASSERT_EQ(one.size(), all.size());
    EXPECT_EQ(0, std::memcmp(one.data(), all.data(), one.size() * sizeof(float)));
  }
  checkAgainstUnbricked(desc);
}

void checkAgainstUnbricked(const std::shared_ptr<SceneDesc>& desc) {
  const std::vector<float> bricked = renderBricks(desc, testutil::worldSize(), 4, 1);
  const std::vector<float> one = renderBricks(desc, testutil::worldSize(), 1, 1);
  if (testutil::worldRank() != 0) return;
  // The image-parallel render: the frames' mean, as the accumulate operation makes it.
  const RenderScene whole = buildRenderScene("scivis", *desc);
  const auto renderer = makeRenderer("scivis", whole, settings());
  // As the frame driver does (and with it, camera rays' first hits as the bricks find them).
  renderer->beginFrame(dfb::FrameInfo{}, desc->camera);
  std::vector<float> expected(bricked.size(), 0.0f);
  for (int f = 0; f < kFrames; ++f) {
    const auto frame =
        test::renderImage(*renderer, kWidth, kHeight, kTile, 2, 1, static_cast<std::uint32_t>(f));
    for (std::size_t i = 0; i < frame.size(); ++i) expected[i] += frame[i] / kFrames;
  }
  ASSERT_EQ(bricked.size(), expected.size());
  float worst = 0, worstOne = 0;
  int visible = 0;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    worst = std::max(worst, std::abs(bricked[i] - expected[i]));
    worstOne = std::max(worstOne, std::abs(one[i] - expected[i]));
    if (i % 4 != 3 && std::abs(expected[i] - bricked[0]) > 0.05f) ++visible;
  }
  EXPECT_LE(worst, 1e-4f) << "4 bricks vs the unbricked render";
  EXPECT_LE(worstOne, 1e-4f) << "1 brick vs the unbricked render";
  EXPECT_GT(visible, 500) << "the scene should cover much of the image";
  std::printf("largest difference per channel: 4 bricks %.3g, 1 brick %.3g\n", worst, worstOne);
}

// --ghost reach on a field large enough for sparse ghost shells (ShadingShell: beyond one
// ghost layer only the macrocells whose range holds an isovalue): shading rays see the bits
// they see with the whole reach held densely (so the image is the dense reach's, which the
// tests above hold to the unbricked render), and the bricks hold less.
TEST(BrickDriverMpi, SparseShellsShadeAsTheDenseReach) {
  const auto desc = scene(160);
  sciVisDesc(*desc).settings.aoDistance = 0.4f;  // 32 voxels: a shell of several macrocells
  std::vector<HeldBrick> sparse = loadOwnBricks(*desc, 4, 1, 0, 1, GhostMode::Reach);
  std::vector<HeldBrick> dense = sparse, unshelled = sparse;
  for (HeldBrick& b : unshelled) b.content.shells.clear();
  std::size_t sparseBytes = 0, denseBytes = 0, shells = 0;
  for (HeldBrick& b : dense) {
    sparseBytes += b.content.bytes();
    for (std::size_t v = 0; v < b.content.shells.size(); ++v) {
      const ShadingShell& shell = b.content.shells[v];
      if (shell.empty()) continue;
      ++shells;
      b.content.volumes[v] = loadVolume(sciVisDesc(*desc).volumes[v].source, shell.box());
      b.content.shells[v] = ShadingShell();
    }
    denseBytes += b.content.bytes();
  }
  // (Where isosurfaces fill most macrocells of a shell, a brick keeps it dense: here 2 of 4.)
  ASSERT_GE(shells, 1u) << "a brick should hold its reach beyond the ghost layer sparsely";
  EXPECT_LT(sparseBytes, denseBytes);
  if (testutil::worldRank() == 0) {
    const std::vector<float> a = renderHeld(desc, std::move(sparse), MPI_COMM_SELF);
    const std::vector<float> b = renderHeld(desc, std::move(dense), MPI_COMM_SELF);
    // Without the sparse shells (their bricks keep one ghost layer) AO near those bricks' faces
    // differs: the shells are what the shading rays saw.
    const std::vector<float> c = renderHeld(desc, std::move(unshelled), MPI_COMM_SELF);
    ASSERT_EQ(a.size(), b.size());
    ASSERT_EQ(a.size(), c.size());
    EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(float)));
    EXPECT_NE(0, std::memcmp(a.data(), c.data(), a.size() * sizeof(float)));
    std::printf(
        "4 bricks of a 160^3 field, ghost reach: %zu bytes with %zu sparse shells, %zu "
        "dense\n",
        sparseBytes, shells, denseBytes);
  }
  MPI_Barrier(MPI_COMM_WORLD);
}

// The wavelet as a volume alone: every brick's rays take the one-volume march, in SIMD packets
// where the CPU runs them (VolumeMarch.h), with empty macrocells to jump.
TEST(BrickDriverMpi, AVolumeAloneGivesTheSameBytesOnEveryRankCountAndMatchesTheUnbricked) {
  auto desc = scene();
  sciVisDesc(*desc).isosurfaces.clear(), sciVisDesc(*desc).particles.clear(), desc->shapes.clear();
  desc->instances.clear();
  sciVisDesc(*desc).volumes[0].transfer.opacities = {{37.0f, 0.0f}, {140.0f, 0.0f}, {277.0f, 0.5f}};
  sciVisDesc(*desc).settings.aoSamples = 0;
  checkEveryRankCountAndReplication(desc, GhostMode::Reach);
  checkAgainstUnbricked(desc);
}

TEST(BrickDriverMpi, EachRankHoldsOnlyItsBricks) {
  const auto desc = scene();
  // No shading ray leaves a brick: it holds its data and ghost layers only (what AO and shadow
  // rays reach costs whole macrocells, a large part of this small field).
  sciVisDesc(*desc).settings.aoSamples = 0;
  sciVisDesc(*desc).settings.shadows = false;
  const int size = testutil::worldSize(), rank = testutil::worldRank();
  BrickFrameDriver split(desc, settings(), {}, loadOwnBricks(*desc, 4, 1, rank, size),
                         MPI_COMM_WORLD);
  BrickFrameDriver whole(desc, settings(), {}, loadOwnBricks(*desc, 1, 1, 0, 1), MPI_COMM_SELF);
  EXPECT_EQ(split.bricks().size(), 4u);
  EXPECT_EQ(split.heldBricks().size(), static_cast<std::size_t>((4 + size - 1 - rank) / size));
  if (size == 4) {
    // One brick of four: with AO and shadows off it holds no ghost reach, only its voxels, its
    // isosurface triangles and their BVH (counted in scene bytes).
    EXPECT_LT(split.sceneBytes(), whole.sceneBytes() / 2)
        << split.sceneBytes() << " of " << whole.sceneBytes() << " bytes";
  }
}

}  // namespace
}  // namespace renderers::scivis
