// Ghosts the session exchanges itself (Ghosts::Exchange) on real ranks: bricks given with only
// the voxels they own render byte for byte as bricks given with the ghosts their renderer reads
// (shadows and ambient occlusion on, so those reach past the gradient layer), on 1 and 3 ranks,
// for slabs and for an uneven decomposition with edges and corners; boxes that overlap or leave
// a gap are an InputError on every rank naming them, and the session renders after it.
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <string>
#include <vector>

#include "api/DataDistributed.h"
#include "api/SceneStyle.h"
#include "renderers/scivis/bricks/BrickLoad.h"
#include "tests/MpiTestUtil.h"
#include "tests/api/ApiTestScene.h"

namespace {

using namespace apitest;
using Box = std::array<std::array<int, 3>, 2>;  // owned voxels [lo, hi)

// The wavelet's isosurfaces, AO, and shadows from a slanted light: shading rays leave a brick
// well past its 2 + 3 voxel layer.
dfbwall::Style shadowStyle() {
  dfbwall::Style st = style();
  st.shadows = true;
  dfbwall::Light sun;
  sun.direction = {-0.4f, -1, 0.3f};
  dfbwall::Light sky;
  sky.kind = dfbwall::Light::Kind::Ambient;
  sky.intensity = 0.3f;
  st.lights = {sun, sky};
  return st;
}

// Slabs along x (4 bricks: uneven over 3 ranks), and 5 boxes of unequal sizes cut along all
// three axes, meeting at edges and corners.
const std::vector<Box> kSlabs = {
    {{{0, 0, 0}, {8, kN, kN}}},
    {{{8, 0, 0}, {16, kN, kN}}},
    {{{16, 0, 0}, {24, kN, kN}}},
    {{{24, 0, 0}, {kN, kN, kN}}},
};
const std::vector<Box> kUneven = {
    {{{0, 0, 0}, {10, 20, kN}}},  {{{0, 20, 0}, {10, kN, kN}}},  {{{10, 0, 0}, {kN, kN, 7}}},
    {{{10, 0, 7}, {kN, 15, kN}}}, {{{10, 15, 7}, {kN, kN, kN}}},
};

enum class Held { Exchanged, Needed, Layer, Whole };

// The brick owning `owned`: clipped to its cells (up to the next brick's first voxel), holding
// what `held` says.
dfbwall::Brick brickOf(int id, const Box& owned, Held held, const dfbwall::Style& st,
                       std::vector<float>& storage) {
  const float h = 2.0f / (kN - 1);
  dfbwall::Brick b;
  b.id = id;
  for (int a = 0; a < 3; ++a) {
    b.boundsLo[a] = -1 + h * owned[0][a];
    b.boundsHi[a] = -1 + h * std::min(owned[1][a], kN - 1);
  }
  Box box = owned;
  if (held == Held::Whole) box = {{{0, 0, 0}, {kN, kN, kN}}};
  if (held == Held::Needed || held == Held::Layer) {
    // What the renderer reads (or only its gradient layer), by the rule the exchange uses.
    dfbwall::Style fixed = st;
    fixed.volumes[0].autoRange = false;
    const renderers::SceneDesc desc = dfbwall::sceneDesc(fixed, {}, MPI_COMM_NULL, {});
    const renderers::scivis::GhostReach reach =
        held == Held::Layer ? renderers::scivis::GhostReach{} : renderers::scivis::ghostReach(desc);
    const renderers::scivis::Box3 bounds{{b.boundsLo[0], b.boundsLo[1], b.boundsLo[2]},
                                         {b.boundsHi[0], b.boundsHi[1], b.boundsHi[2]}};
    const renderers::VoxelBox v = renderers::scivis::neededVoxels(desc, 0, bounds, reach);
    box = {{{v.lo.x, v.lo.y, v.lo.z}, {v.hi.x, v.hi.y, v.hi.z}}};
  }
  storage.clear();
  for (int z = box[0][2]; z < box[1][2]; ++z)
    for (int y = box[0][1]; y < box[1][1]; ++y)
      for (int x = box[0][0]; x < box[1][0]; ++x) storage.push_back(field().at(x, y, z));
  dfbwall::VolumePart part;
  part.lo = box[0];
  part.hi = box[1];
  part.voxels = storage.data();
  part.ghosts = held == Held::Exchanged ? dfbwall::Ghosts::Exchange : dfbwall::Ghosts::Given;
  b.volumes.push_back(part);
  return b;
}

struct Rendered {
  std::vector<std::uint8_t> image;  // on rank 0
  std::size_t ghostBytes = 0;       // received by this rank
};

// The image of `boxes` on the first `ranks` ranks (brick b on rank b % ranks).
Rendered render(int ranks, const std::vector<Box>& boxes, Held held) {
  const int rank = testutil::worldRank();
  MPI_Comm comm;
  MPI_Comm_split(MPI_COMM_WORLD, rank < ranks ? 0 : 1, rank, &comm);
  Rendered out;
  if (rank < ranks) {
    dfbwall::SessionOptions o;
    o.width = 96, o.height = 72, o.tileSize = 16, o.threads = 2, o.timeoutSeconds = 60;
    dfbwall::Session session(comm, o);
    const dfbwall::Style st = shadowStyle();
    session.setStyle(st);
    session.setCamera(camera());
    std::vector<std::vector<float>> storage(boxes.size());
    for (int b = rank; b < static_cast<int>(boxes.size()); b += ranks)
      session.addBrick(brickOf(b, boxes[static_cast<std::size_t>(b)], held, st,
                               storage[static_cast<std::size_t>(b)]));
    session.renderFrame();
    out.image = session.image();
    out.ghostBytes = session.ghostBytesReceived();
    session.close();
  }
  MPI_Comm_free(&comm);
  return out;
}

void expectExchangedEqualsNeeded(const std::vector<Box>& boxes) {
  const int ranks = testutil::worldSize();
  const Rendered needed = render(ranks, boxes, Held::Needed);
  const Rendered exchanged = render(ranks, boxes, Held::Exchanged);
  const Rendered alone = render(1, boxes, Held::Exchanged);
  const Rendered layer = render(ranks, boxes, Held::Layer);
  // Every rank but the last of a split receives ghosts from another rank; alone, none.
  if (testutil::worldRank() < ranks) {
    EXPECT_GT(exchanged.ghostBytes, 0u);
  }
  if (testutil::worldRank() == 0) {
    EXPECT_EQ(alone.ghostBytes, 0u);
    ASSERT_EQ(needed.image.size(), 96u * 72u * 4u);
    EXPECT_EQ(exchanged.image, needed.image) << "exchanged ghosts on " << ranks << " ranks";
    EXPECT_EQ(alone.image, needed.image) << "exchanged ghosts on 1 rank";
    // The scene is one where ghosts beyond the gradient layer matter (shadows, AO).
    EXPECT_NE(layer.image, needed.image);
  }
}

TEST(GhostExchange, SlabsOnUnevenRanksRenderAsGivenGhosts) { expectExchangedEqualsNeeded(kSlabs); }

TEST(GhostExchange, BoxesMeetingAtEdgesAndCornersRenderAsGivenGhosts) {
  expectExchangedEqualsNeeded(kUneven);
}

// Every brick holding the whole field: nothing the exchange left out changes the image.
TEST(GhostExchange, ExchangedGhostsRenderAsTheWholeField) {
  const Rendered whole = render(testutil::worldSize(), kUneven, Held::Whole);
  const Rendered exchanged = render(testutil::worldSize(), kUneven, Held::Exchanged);
  if (testutil::worldRank() == 0) {
    EXPECT_EQ(exchanged.image, whole.image);
  }
}

// A new style with the same bricks: the session exchanges again, from the owned voxels the
// bricks kept, what the new style's rays reach (the first style has no shadows: a thin layer).
TEST(GhostExchange, ANewStyleWithTheSameBricksExchangesWhatItReaches) {
  const int rank = testutil::worldRank(), ranks = testutil::worldSize();
  dfbwall::SessionOptions o;
  o.width = 96, o.height = 72, o.tileSize = 16, o.threads = 2, o.timeoutSeconds = 60;
  dfbwall::Session session(MPI_COMM_WORLD, o);
  dfbwall::Style plain = style();
  plain.aoSamples = 0;
  session.setStyle(plain);
  session.setCamera(camera());
  std::vector<float> storage;
  for (int b = rank; b < static_cast<int>(kUneven.size()); b += ranks)
    session.addBrick(
        brickOf(b, kUneven[static_cast<std::size_t>(b)], Held::Exchanged, plain, storage));
  session.renderFrame();
  const std::size_t thin = session.ghostBytesReceived();
  session.setStyle(shadowStyle());
  session.renderFrame();
  EXPECT_GT(session.ghostBytesReceived(), thin);
  const std::vector<std::uint8_t> image = session.image();
  session.close();
  const Rendered fresh = render(ranks, kUneven, Held::Needed);
  if (rank == 0) {
    EXPECT_EQ(image, fresh.image);
  }
}

// `boxes` on every rank (brick b on rank b % ranks): the error every rank throws.
void expectRefusedOnEveryRank(const std::vector<Box>& boxes,
                              const std::vector<std::string>& named) {
  const int rank = testutil::worldRank(), ranks = testutil::worldSize();
  dfbwall::SessionOptions o;
  o.width = 32, o.height = 24, o.tileSize = 16, o.threads = 1, o.timeoutSeconds = 30;
  dfbwall::Session session(MPI_COMM_WORLD, o);
  const dfbwall::Style st = shadowStyle();
  session.setStyle(st);
  session.setCamera(camera());
  std::vector<std::vector<float>> storage(boxes.size());
  for (int b = rank; b < static_cast<int>(boxes.size()); b += ranks)
    session.addBrick(brickOf(b, boxes[static_cast<std::size_t>(b)], Held::Exchanged, st,
                             storage[static_cast<std::size_t>(b)]));
  const auto start = std::chrono::steady_clock::now();
  try {
    session.renderFrame();
    ADD_FAILURE() << "no error on rank " << rank;
  } catch (const dfbwall::InputError& e) {
    for (const std::string& text : named)
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
  }
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
  // Given again, right: the session renders.
  session.clearBricks();
  for (int b = rank; b < static_cast<int>(kSlabs.size()); b += ranks)
    session.addBrick(brickOf(b, kSlabs[static_cast<std::size_t>(b)], Held::Exchanged, st,
                             storage[static_cast<std::size_t>(b) % storage.size()]));
  session.renderFrame();
  EXPECT_EQ(session.framesRendered(), 1u);
  session.close();
}

// The session holds an exchanged part's owned voxels and ghosts as one copy: borrowing it is
// refused (on every rank, at the next frame), and the session renders after it.
TEST(GhostExchange, BorrowedVoxelsWithExchangedGhostsAreRefused) {
  const int rank = testutil::worldRank(), ranks = testutil::worldSize();
  dfbwall::SessionOptions o;
  o.width = 32, o.height = 24, o.tileSize = 16, o.threads = 1, o.timeoutSeconds = 30;
  dfbwall::Session session(MPI_COMM_WORLD, o);
  session.setStyle(style());
  session.setCamera(camera());
  std::vector<std::vector<float>> storage(kSlabs.size());
  auto add = [&](bool borrow) {
    session.clearBricks();
    for (int b = rank; b < static_cast<int>(kSlabs.size()); b += ranks) {
      dfbwall::Brick brick = brickOf(b, kSlabs[static_cast<std::size_t>(b)], Held::Exchanged,
                                     style(), storage[static_cast<std::size_t>(b)]);
      brick.volumes[0].borrowed = borrow && b == 1;
      session.addBrick(brick);
    }
  };
  add(true);
  try {
    session.renderFrame();
    ADD_FAILURE() << "no error on rank " << rank;
  } catch (const dfbwall::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("brick 1: volume 'volume': borrowed voxels with "
                                         "Ghosts::Exchange"),
              std::string::npos)
        << e.what();
  }
  add(false);
  session.renderFrame();
  EXPECT_EQ(session.framesRendered(), 1u);
  session.close();
}

TEST(GhostExchange, OverlappingBoxesFailOnEveryRankNamingBoth) {
  std::vector<Box> boxes = kSlabs;
  boxes[2][0][0] = 14;  // brick 2 (rank 2) reaches into brick 1 (rank 1)
  expectRefusedOnEveryRank(boxes,
                           {"overlap", "brick 1 on render rank 1, voxels [(8, 0, 0), (16, 33, 33))",
                            "brick 2 on render rank 2, voxels [(14, 0, 0), (24, 33, 33))"});
}

TEST(GhostExchange, ABoxThatLeavesAGapFailsOnEveryRankNamingItsNeighbours) {
  std::vector<Box> boxes = kUneven;
  boxes[3][1][1] = 12;  // brick 3 stops short of brick 4: y 12..14 is nobody's
  expectRefusedOnEveryRank(boxes, {"voxels [(10, 12, 7), (33, 15, 33)) are in no brick's owned box",
                                   "brick 3 on render rank 0, voxels [(10, 0, 7), (33, 12, 33))",
                                   "brick 4 on render rank 1"});
}

}  // namespace
