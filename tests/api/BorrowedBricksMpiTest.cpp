// Borrowed voxels (VolumePart::borrowed) on real ranks: the same bytes as copied ones, no copy in
// the session's memory (scene bytes and peak RSS), and values the program changed in place shown
// by the frame after dataChanged(), as a fresh copied render of them.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include "api/DataDistributed.h"
#include "tests/MpiTestUtil.h"
#include "tests/api/ApiTestScene.h"

namespace {

using namespace apitest;

constexpr int kBricks = 4;

// This rank's bricks b = rank, rank + ranks, ... of kBricks, each over its own storage (borrowed
// voxels must stay where they are while the session holds them).
struct RankBricks {
  std::vector<std::vector<float>> storage;
  std::vector<dfbwall::Brick> bricks;
  std::size_t voxelBytes = 0;
  RankBricks() {
    const int rank = testutil::worldRank(), ranks = testutil::worldSize();
    storage.resize(kBricks);
    for (int b = rank; b < kBricks; b += ranks) {
      bricks.push_back(brick(b, kBricks, storage[static_cast<std::size_t>(b)]));
      voxelBytes += storage[static_cast<std::size_t>(b)].size() * sizeof(float);
    }
  }
  void add(dfbwall::Session& session, bool borrowed) {
    session.clearBricks();
    for (dfbwall::Brick b : bricks) {
      b.volumes[0].borrowed = borrowed;
      session.addBrick(b);
    }
  }
};

dfbwall::SessionOptions options() {
  dfbwall::SessionOptions o;
  o.width = 96, o.height = 72, o.tileSize = 16, o.threads = 2, o.timeoutSeconds = 60;
  return o;
}

struct Frame {
  std::vector<std::uint8_t> image;
  std::size_t sceneBytes = 0, borrowedBytes = 0;
};

Frame renderOnce(RankBricks& bricks, bool borrowed) {
  dfbwall::Session session(MPI_COMM_WORLD, options());
  session.setStyle(style());
  session.setCamera(camera());
  bricks.add(session, borrowed);
  session.renderFrame();
  Frame f{session.image(), session.sceneBytes(), session.borrowedBytes()};
  session.close();
  return f;
}

TEST(BorrowedBricks, RenderTheCopiedBytesWithoutHoldingTheVoxels) {
  RankBricks bricks;
  const Frame copied = renderOnce(bricks, false);
  const Frame borrowed = renderOnce(bricks, true);
  EXPECT_EQ(copied.borrowedBytes, 0u);
  EXPECT_EQ(borrowed.borrowedBytes, bricks.voxelBytes);
  // The copy's voxels (padded slices: at least their bytes) are all the difference.
  EXPECT_GE(copied.sceneBytes, borrowed.sceneBytes + bricks.voxelBytes)
      << copied.sceneBytes << " copied, " << borrowed.sceneBytes << " borrowed";
  if (testutil::worldRank() == 0) {
    ASSERT_EQ(copied.image.size(), 96u * 72u * 4u);
    EXPECT_EQ(borrowed.image, copied.image);
  }
}

TEST(BorrowedBricks, ChangedValuesShowInTheFrameAfterDataChanged) {
  RankBricks bricks;
  dfbwall::Session session(MPI_COMM_WORLD, options());
  session.setStyle(style());
  session.setCamera(camera());
  bricks.add(session, true);
  session.renderFrame();
  const std::vector<std::uint8_t> before = session.image();
  // The simulation steps in place: the isosurfaces move and the value range changes.
  for (std::vector<float>& s : bricks.storage)
    for (float& v : s) v = 0.8f * v + 40.0f * std::sin(v * 0.05f);
  session.dataChanged();
  session.renderFrame();
  const std::vector<std::uint8_t> after = session.image();
  session.close();
  const Frame fresh = renderOnce(bricks, false);
  if (testutil::worldRank() == 0) {
    EXPECT_NE(after, before);
    EXPECT_EQ(after, fresh.image) << "the changed values, not what was built from the old ones";
  }
}

// kB of a /proc/self/status line ("VmRSS", "VmHWM").
std::size_t statusKb(const std::string& key) {
  std::ifstream in("/proc/self/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind(key + ":", 0) == 0) return std::stoul(line.substr(key.size() + 1));
  return 0;
}

// The peak RSS a step adds over the RSS before it (the peak reset first: clear_refs 5).
template <class Step>
std::size_t peakGrowthBytes(Step&& step) {
  std::ofstream("/proc/self/clear_refs") << "5";
  const std::size_t before = statusKb("VmRSS");
  step();
  const std::size_t peak = statusKb("VmHWM");
  return peak > before ? (peak - before) * 1024 : 0;
}

// A 64 MiB brick per rank: borrowing it adds under a tenth of it to the rank's peak memory;
// copying it adds all of it (so the measure sees a copy where there is one).
TEST(BorrowedBricks, ABigBrickAddsNoCopyToPeakMemory) {
  constexpr int n = 256;
  const int rank = testutil::worldRank(), ranks = testutil::worldSize();
  dfbwall::SessionOptions o = options();
  o.width = 32, o.height = 24;
  dfbwall::Session session(MPI_COMM_WORLD, o);
  dfbwall::Style st;
  dfbwall::VolumeStyle v;
  v.grid.dims = {n, n, n * ranks};
  st.volumes.push_back(v);
  session.setStyle(st);
  dfbwall::Camera c;
  c.position = {-300, 200, -300};
  c.lookAt = {n / 2.0f, n / 2.0f, n * ranks / 2.0f};
  session.setCamera(c);
  const std::size_t count = std::size_t{n} * n * n, bytes = count * sizeof(float);
  std::vector<float> field(count);
  for (std::size_t i = 0; i < count; ++i) field[i] = static_cast<float>((i * 2654435761u) % 1000);
  dfbwall::Brick b;
  b.id = rank;
  b.boundsLo = {0, 0, static_cast<float>(n * rank)};
  b.boundsHi = {n - 1, n - 1, static_cast<float>(n * (rank + 1) - 1)};
  dfbwall::VolumePart part;
  part.lo = {0, 0, n * rank};
  part.hi = {n, n, n * (rank + 1)};
  part.voxels = field.data();
  part.borrowed = true;
  b.volumes.push_back(part);
  const std::size_t borrowing = peakGrowthBytes([&] {
    session.addBrick(b);
    session.renderFrame();
  });
  EXPECT_LT(borrowing, bytes / 10) << "rank " << rank;
  EXPECT_LT(session.sceneBytes(), bytes / 10);
  EXPECT_EQ(session.borrowedBytes(), bytes);
  b.volumes[0].borrowed = false;
  const std::size_t copying = peakGrowthBytes([&] {
    session.clearBricks();
    session.addBrick(b);
    session.renderFrame();
  });
  EXPECT_GT(copying, bytes * 9 / 10) << "rank " << rank;
  EXPECT_GE(session.sceneBytes(), bytes);
  session.close();
}

}  // namespace
