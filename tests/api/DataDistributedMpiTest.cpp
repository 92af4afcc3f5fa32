// The data-distributed API on real ranks: a program's own bricks (a wavelet field cut by the
// program into 4 sub-boxes with ghost layers, particles, a triangle) render the same bytes on any
// number of ranks, match the whole field given as one brick up to float summation order, keep a
// rank's bricks when only another rank changes its data, and bad input fails on every rank.
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include "api/DataDistributed.h"
#include "tests/MpiTestUtil.h"
#include "tests/api/ApiTestScene.h"

namespace {

using namespace apitest;

// The image rendered on the first `ranks` ranks, bricks b = rank, rank + ranks, ... of `count`.
// Frames: `frames` with one scene version; with `touchOne`, a second version where only rank 0
// gives its bricks again.
std::vector<std::uint8_t> render(int ranks, int count, int frames, bool touchOne = false) {
  const int rank = testutil::worldRank();
  MPI_Comm comm;
  MPI_Comm_split(MPI_COMM_WORLD, rank < ranks ? 0 : 1, rank, &comm);
  std::vector<std::uint8_t> image;
  if (rank < ranks) {
    dfbwall::SessionOptions o;
    o.width = 96, o.height = 72, o.tileSize = 16, o.threads = 2, o.timeoutSeconds = 60;
    dfbwall::Session session(comm, o);
    EXPECT_FALSE(session.isWallRank());
    session.setStyle(style());
    session.setCamera(camera());
    std::vector<float> storage;
    for (int b = rank; b < count; b += ranks) session.addBrick(brick(b, count, storage));
    for (int f = 0; f < frames; ++f) session.renderFrame();
    if (touchOne) {
      if (rank == 0) {
        session.clearBricks();
        for (int b = rank; b < count; b += ranks) session.addBrick(brick(b, count, storage));
      }
      for (int f = 0; f < frames; ++f) session.renderFrame();
    }
    image = session.image();
    if (rank == 0) {
      EXPECT_EQ(image.size(), 96u * 72u * 4u);
    }
    session.close();
  }
  MPI_Comm_free(&comm);
  return image;
}

TEST(DataDistributedApi, AnyRankCountGivesTheSameBytes) {
  const std::vector<std::uint8_t> one = render(1, 4, 2);
  for (int ranks = 2; ranks <= testutil::worldSize(); ++ranks) {
    const std::vector<std::uint8_t> image = render(ranks, 4, 2);
    if (testutil::worldRank() == 0) {
      EXPECT_EQ(image, one) << ranks << " ranks";
    }
  }
  if (testutil::worldRank() != 0) return;
  int lit = 0;  // a picture, not the background
  for (std::size_t p = 0; p < one.size(); p += 4)
    if (std::abs(int(one[p]) - int(one[0])) > 20 || std::abs(int(one[p + 2]) - int(one[2])) > 20)
      ++lit;
  EXPECT_GT(lit, 96 * 72 / 5);
}

TEST(DataDistributedApi, FourBricksMatchTheWholeFieldAsOneBrick) {
  const std::vector<std::uint8_t> four = render(testutil::worldSize(), 4, 1);
  const std::vector<std::uint8_t> whole = render(1, 1, 1);
  if (testutil::worldRank() != 0) return;
  ASSERT_EQ(four.size(), whole.size());
  int worst = 0;
  for (std::size_t i = 0; i < four.size(); ++i)
    worst = std::max(worst, std::abs(int(four[i]) - int(whole[i])));
  // Float summation order only: at most one 8-bit step.
  EXPECT_LE(worst, 1);
}

TEST(DataDistributedApi, ARankThatAddsNothingKeepsItsBricks) {
  // The second scene version starts the average afresh with the same samples: the same image,
  // only if every other rank still holds its bricks.
  const std::vector<std::uint8_t> once = render(testutil::worldSize(), 4, 1);
  const std::vector<std::uint8_t> twice = render(testutil::worldSize(), 4, 1, true);
  if (testutil::worldRank() == 0) {
    EXPECT_EQ(once, twice);
  }
}

TEST(DataDistributedApi, BricksThatDisagreeFailOnEveryRank) {
  ASSERT_GE(testutil::worldSize(), 2) << "run with 3 ranks (tests/api/CMakeLists.txt)";
  dfbwall::SessionOptions o;
  o.width = 32, o.height = 32, o.timeoutSeconds = 20;
  dfbwall::Session session(MPI_COMM_WORLD, o);
  session.setStyle(style());
  std::vector<float> storage;
  dfbwall::Brick b = brick(0, 2, storage);
  if (testutil::worldRank() == 1) b.boundsHi[0] += 0.1f;  // "the same brick", other bounds
  session.addBrick(b);
  try {
    session.renderFrame();
    ADD_FAILURE() << "no error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("brick 0: render rank 1 gives it other bounds"),
              std::string::npos)
        << e.what();
  }
  session.close();
}

// A window is a part of a serving wall: without `connect` every rank refuses the session.
TEST(DataDistributedApi, AWindowNeedsAServingWall) {
  dfbwall::SessionOptions o;
  o.width = 32, o.height = 32, o.timeoutSeconds = 20;
  o.window = "0,0,8,8";
  try {
    dfbwall::Session session(MPI_COMM_WORLD, o);
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("window is for connect"), std::string::npos) << e.what();
  }
}

// Voxels given as float64, int16 or int32 render as the same values given as float32 (the field
// rounded to integers, which all three hold exactly).
TEST(DataDistributedApi, OtherVoxelTypesRenderAsTheirFloat32Values) {
  auto image = [](dfbwall::VoxelType type) {
    dfbwall::SessionOptions o;
    o.width = 48, o.height = 36, o.tileSize = 16, o.threads = 2;
    dfbwall::Session session(MPI_COMM_SELF, o);
    session.setStyle(style());
    session.setCamera(camera());
    std::vector<float> storage;
    dfbwall::Brick b = brick(0, 1, storage);
    for (float& v : storage) v = std::round(v);
    std::vector<double> f64(storage.begin(), storage.end());
    std::vector<std::int16_t> i16(storage.begin(), storage.end());
    std::vector<std::int32_t> i32(storage.begin(), storage.end());
    b.volumes[0].type = type;
    b.volumes[0].voxels = type == dfbwall::VoxelType::Float64 ? static_cast<const void*>(f64.data())
                          : type == dfbwall::VoxelType::Int16 ? static_cast<const void*>(i16.data())
                          : type == dfbwall::VoxelType::Int32 ? static_cast<const void*>(i32.data())
                                                              : storage.data();
    session.addBrick(b);
    session.renderFrame();
    std::vector<std::uint8_t> out = session.image();
    session.close();
    return out;
  };
  const auto f32 = image(dfbwall::VoxelType::Float32);
  EXPECT_EQ(image(dfbwall::VoxelType::Float64), f32);
  EXPECT_EQ(image(dfbwall::VoxelType::Int16), f32);
  EXPECT_EQ(image(dfbwall::VoxelType::Int32), f32);
}

TEST(DataDistributedApi, BadBrickDataIsRefusedNamingTheBrick) {
  dfbwall::SessionOptions o;
  o.width = 32, o.height = 32;
  dfbwall::Session session(MPI_COMM_SELF, o);
  session.setStyle(style());
  session.setCamera(camera());
  std::vector<float> storage;
  // Refused at the next frame (on every rank, tests/api/LeavingMpiTest.cpp), naming the field.
  auto refusal = [&](const dfbwall::Brick& b) -> std::string {
    session.clearBricks();
    session.addBrick(b);
    try {
      session.renderFrame();
    } catch (const dfbwall::InputError& e) {
      return e.what();
    }
    return "no error";
  };
  dfbwall::Brick b = brick(0, 1, storage);
  b.id = 7;
  b.volumes[0].hi[2] = kN + 1;
  EXPECT_NE(refusal(b).find("brick 7: volume 'volume'"), std::string::npos) << refusal(b);
  b = brick(0, 1, storage);
  b.particles.radii = {0.1f, 0.2f};
  EXPECT_NE(refusal(b).find("brick 0: particles"), std::string::npos) << refusal(b);
  EXPECT_EQ(session.framesRendered(), 0u);
  session.close();
}

}  // namespace
