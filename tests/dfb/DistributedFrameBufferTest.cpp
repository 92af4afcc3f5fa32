// The DFB on real ranks: run under mpiexec with 1, 2 and 4 ranks.
#include "dfb/DistributedFrameBuffer.h"

#include <gtest/gtest.h>
#include <mpi.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <thread>

#include "base/Error.h"
#include "dfb/TileMessage.h"

#include "tests/MpiTestUtil.h"

namespace dfb {
namespace {

using testutil::worldRank;
using testutil::worldSize;

constexpr int kWidth = 150, kHeight = 100, kTileSize = 32;  // edge tiles are partial

float pixelValue(int x, int y, std::uint32_t frame, int channel) {
  return static_cast<float>((x * 7 + y * 13 + static_cast<int>(frame) * 5 + channel * 3) % 97) /
         40.0f;
}

Tile renderTile(const Region& region, std::uint32_t frame, std::uint32_t accumulationId) {
  Tile tile;
  tile.reset(region);
  tile.accumulationId = accumulationId;
  size_t i = 0;
  for (int y = region.y0; y < region.y1; ++y)
    for (int x = region.x0; x < region.x1; ++x, ++i)
      for (int c = 0; c < 4; ++c)
        tile.color[4 * i + static_cast<size_t>(c)] = pixelValue(x, y, frame, c);
  return tile;
}

// Work distribution deliberately unlike the round-robin ownership, so tiles travel.
bool renders(int tile) { return (tile * 3 + 1) % worldSize() == worldRank(); }

void renderFrame(DistributedFrameBuffer& dfb, std::uint32_t frame, std::uint32_t epoch = 0) {
  dfb.begin({frame, epoch});
  const std::uint32_t pass = dfb.accumulationId();
  tbb::parallel_for(0, dfb.grid().tileCount(), [&](int t) {
    if (renders(t)) dfb.setTile(renderTile(dfb.grid().region(t), frame, pass));
  });
  dfb.end();
}

DfbOptions options(DisplayFormat format, TileOperationFactory operation = writeOperation()) {
  DfbOptions o;
  o.width = kWidth;
  o.height = kHeight;
  o.tileSize = kTileSize;
  o.format = format;
  o.operation = std::move(operation);
  o.frameTimeout = std::chrono::milliseconds(20000);
  return o;
}

// The gathered RGBAF32 image is every pixel's pixelValue() of `frame`.
void expectImageOfFrame(const std::vector<float>& image, std::uint32_t frame) {
  ASSERT_EQ(image.size(), static_cast<size_t>(4 * kWidth * kHeight));
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x)
      for (int c = 0; c < 4; ++c)
        ASSERT_EQ(image[static_cast<size_t>(4 * (y * kWidth + x) + c)], pixelValue(x, y, frame, c))
            << x << "," << y << " channel " << c << " frame " << frame;
}

TEST(Dfb, GatheredRgbaF32EqualsTheReference) {
  messaging::Messenger messenger(MPI_COMM_WORLD);
  DistributedFrameBuffer dfb(messenger, MPI_COMM_WORLD, options(DisplayFormat::RGBAF32));
  // Several frames: the gather keeps its buffers from one frame to the next.
  for (std::uint32_t frame = 1; frame <= 3; ++frame) {
    renderFrame(dfb, frame);
    if (worldRank() != 0) continue;
    expectImageOfFrame(dfb.imageRgbaF32(), frame);
    if (HasFatalFailure()) return;
    EXPECT_EQ(dfb.stats().pixelBytesReceived, static_cast<std::uint64_t>(16 * kWidth * kHeight));
    EXPECT_EQ(dfb.stats().gatherBytesSent, 0u) << "rank 0 places its own tiles, sends none";
  }
  std::uint64_t completed = dfb.stats().tilesCompleted, total = 0;
  MPI_Allreduce(&completed, &total, 1, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_EQ(total, static_cast<std::uint64_t>(dfb.grid().tileCount()));
}

// A run that wants only its last frame (dfbwall --image without a wall) gathers it once, after
// the last end(): frames before gather nothing, and gatherImage() gives that frame's image.
TEST(Dfb, GatheringOnlyTheLastFrameGivesItsImage) {
  messaging::Messenger messenger(MPI_COMM_WORLD);
  DfbOptions o = options(DisplayFormat::RGBAF32);
  o.gatherEveryFrame = false;
  DistributedFrameBuffer dfb(messenger, MPI_COMM_WORLD, o);
  for (std::uint32_t frame = 1; frame <= 3; ++frame) {
    renderFrame(dfb, frame);
    EXPECT_EQ(dfb.stats().pixelBytesReceived, 0u) << "frame " << frame;
    EXPECT_TRUE(dfb.imageRgbaF32().empty()) << "frame " << frame;
  }
  dfb.gatherImage();
  if (worldRank() != 0) return;
  expectImageOfFrame(dfb.imageRgbaF32(), 3);
}

class GatherRgba8 : public ::testing::TestWithParam<bool> {};

TEST_P(GatherRgba8, EqualsTheToneMappedReference) {
  messaging::Messenger messenger(MPI_COMM_WORLD);
  DfbOptions o = options(DisplayFormat::RGBA8);
  o.compressGather = GetParam();
  o.toneMap.exposure = 0.7f;
  o.toneMap.filmic = true;
  DistributedFrameBuffer dfb(messenger, MPI_COMM_WORLD, o);
  for (std::uint32_t frame = 1; frame <= 3; ++frame) {
    renderFrame(dfb, frame);
    if (worldRank() != 0) {
      EXPECT_TRUE(dfb.imageRgba8().empty());
      continue;
    }
    const auto& image = dfb.imageRgba8();
    ASSERT_EQ(image.size(), static_cast<size_t>(kWidth * kHeight));
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x) {
        float rgba[4];
        for (int c = 0; c < 4; ++c) rgba[c] = pixelValue(x, y, frame, c);
        ASSERT_EQ(image[static_cast<size_t>(y * kWidth + x)], toneMapPixel(rgba, o.toneMap))
            << x << "," << y;
      }
    EXPECT_EQ(dfb.stats().pixelBytesReceived, static_cast<std::uint64_t>(4 * kWidth * kHeight));
    if (worldSize() > 1 && GetParam()) {
      EXPECT_LT(dfb.stats().gatherBytesReceived, dfb.stats().pixelBytesReceived)
          << "the plane-delta filter makes smooth RGBA8 compressible";
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Compression, GatherRgba8, ::testing::Bool());

// Tiles that come as display pixels (Tile::rgba8, no color) travel to their owners and reach
// the RGBA8 image exactly as given: nothing tone-maps them.
TEST(Dfb, DisplayPixelTilesReachTheImageUntouched) {
  messaging::Messenger messenger(MPI_COMM_WORLD);
  DistributedFrameBuffer dfb(messenger, MPI_COMM_WORLD, options(DisplayFormat::RGBA8));
  const auto value = [](int x, int y) {
    return 0x80000000u | (static_cast<std::uint32_t>(x * 131 + y * 7) & 0xffffffu);
  };
  for (std::uint32_t frame = 1; frame <= 2; ++frame) {
    dfb.begin({frame, 0});
    tbb::parallel_for(0, dfb.grid().tileCount(), [&](int t) {
      if (!renders(t)) return;
      Tile tile;
      tile.region = dfb.grid().region(t);
      for (int y = tile.region.y0; y < tile.region.y1; ++y)
        for (int x = tile.region.x0; x < tile.region.x1; ++x) tile.rgba8.push_back(value(x, y));
      dfb.setTile(std::move(tile));
    });
    dfb.end();
    if (worldRank() != 0) continue;
    const auto& image = dfb.imageRgba8();
    ASSERT_EQ(image.size(), static_cast<size_t>(kWidth * kHeight));
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x)
        ASSERT_EQ(image[static_cast<size_t>(y * kWidth + x)], value(x, y)) << x << "," << y;
  }
}

TEST(Dfb, FormatNoneGathersNoPixelsToRankZero) {
  messaging::Messenger messenger(MPI_COMM_WORLD);
  DistributedFrameBuffer dfb(messenger, MPI_COMM_WORLD, options(DisplayFormat::NONE));
  for (std::uint32_t frame = 1; frame <= 2; ++frame) {
    renderFrame(dfb, frame);
    const FrameStats s = dfb.stats();
    EXPECT_EQ(s.pixelBytesReceived, 0u);
    EXPECT_EQ(s.gatherBytesReceived, 0u);
    EXPECT_EQ(s.gatherBytesSent, 0u);
    EXPECT_TRUE(dfb.imageRgba8().empty());
    EXPECT_TRUE(dfb.imageRgbaF32().empty());
    std::uint64_t completed = s.tilesCompleted, total = 0;
    MPI_Allreduce(&completed, &total, 1, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
    EXPECT_EQ(total, static_cast<std::uint64_t>(dfb.grid().tileCount()));
    if (worldSize() > 1) {
      EXPECT_GT(s.tileBytesSent + s.tileBytesReceived, 0u);
    }
  }
}

TEST(Dfb, TilesWithNoExpectedInputsAreLeftOutOfTheFrame) {
  messaging::Messenger messenger(MPI_COMM_WORLD);
  DfbOptions o = options(DisplayFormat::RGBAF32);
  o.expectedInputs = [](int t) { return t % 3 == 0 ? 0 : 1; };
  DistributedFrameBuffer dfb(messenger, MPI_COMM_WORLD, o);
  dfb.begin({1, 0});
  tbb::parallel_for(0, dfb.grid().tileCount(), [&](int t) {
    if (t % 3 != 0 && renders(t)) dfb.setTile(renderTile(dfb.grid().region(t), 1, 0));
  });
  dfb.end();
  if (worldRank() != 0) return;
  for (int t = 0; t < dfb.grid().tileCount(); ++t) {
    const Region r = dfb.grid().region(t);
    const float got = dfb.imageRgbaF32()[static_cast<size_t>(4 * (r.y0 * kWidth + r.x0) + 1)];
    EXPECT_EQ(got, t % 3 == 0 ? 0.0f : pixelValue(r.x0, r.y0, 1, 1)) << "tile " << t;
  }
}

TEST(Dfb, AccumulationOverFramesIsTheRunningMean) {
  messaging::Messenger messenger(MPI_COMM_WORLD);
  DistributedFrameBuffer dfb(messenger, MPI_COMM_WORLD,
                             options(DisplayFormat::RGBAF32, accumulateOperation()));
  for (std::uint32_t frame = 1; frame <= 4; ++frame) {
    renderFrame(dfb, frame);
    EXPECT_EQ(dfb.accumulationId(), frame - 1);
    if (worldRank() != 0) continue;
    const auto& image = dfb.imageRgbaF32();
    for (int y = 0; y < kHeight; y += 7)
      for (int x = 0; x < kWidth; x += 5) {
        float mean = 0;
        for (std::uint32_t f = 1; f <= frame; ++f) mean += pixelValue(x, y, f, 1);
        mean /= static_cast<float>(frame);
        ASSERT_NEAR(image[static_cast<size_t>(4 * (y * kWidth + x) + 1)], mean, 1e-5f)
            << "frame " << frame;
      }
  }
  // Every rank knows every tile's error estimate, and a varying image has one.
  EXPECT_GT(*std::min_element(dfb.tileErrors().begin(), dfb.tileErrors().end()), 0.0f);
  // A new epoch restarts accumulation.
  renderFrame(dfb, 5, /*epoch=*/1);
  EXPECT_EQ(dfb.accumulationId(), 0u);
  if (worldRank() == 0) {
    EXPECT_EQ(dfb.imageRgbaF32()[4], pixelValue(1, 0, 5, 0));
  }
}

// Renders one frame where tile t gets `inputs` redundant inputs, input k from rank (t + k) % size
// with sequence k and weight k + 1, sent after random delays.
std::vector<float> renderRedundant(unsigned delaySeed, int inputs) {
  messaging::Messenger messenger(MPI_COMM_WORLD);
  DfbOptions o = options(DisplayFormat::RGBAF32, accumulateOperation());
  o.expectedInputs = [inputs](int) { return inputs; };
  DistributedFrameBuffer dfb(messenger, MPI_COMM_WORLD, o);
  dfb.begin({1, 0});
  std::vector<std::pair<int, int>> work;
  for (int t = 0; t < dfb.grid().tileCount(); ++t)
    for (int k = 0; k < inputs; ++k)
      if ((t + k) % worldSize() == worldRank()) work.emplace_back(t, k);
  std::mt19937 random(delaySeed * 31 + static_cast<unsigned>(worldRank()));
  std::shuffle(work.begin(), work.end(), random);
  for (auto [t, k] : work) {
    Tile tile = renderTile(dfb.grid().region(t), static_cast<std::uint32_t>(10 + k), 0);
    tile.sequence = static_cast<std::uint32_t>(k);
    tile.weight = static_cast<std::uint32_t>(k + 1);
    if (random() % 4 == 0) std::this_thread::sleep_for(std::chrono::microseconds(random() % 300));
    dfb.setTile(tile);
  }
  dfb.end();
  return dfb.imageRgbaF32();
}

TEST(Dfb, RedundantInputsGiveTheSameBytesInAnyArrivalOrder) {
  const std::vector<float> first = renderRedundant(1, 3);
  for (unsigned seed = 2; seed <= 4; ++seed) {
    const std::vector<float> again = renderRedundant(seed, 3);
    if (worldRank() == 0) {
      ASSERT_EQ(first, again) << "delay seed " << seed;
    }
  }
  if (worldRank() == 0) {
    const float expected =
        (1 * pixelValue(3, 4, 10, 2) + 2 * pixelValue(3, 4, 11, 2) + 3 * pixelValue(3, 4, 12, 2)) /
        6;
    EXPECT_NEAR(first[static_cast<size_t>(4 * (4 * kWidth + 3) + 2)], expected, 1e-5f);
  }
}

// --- alpha blending over random dependency trees --------------------------------------------

struct TreeNode {
  int generation, children;
  std::uint32_t sequence;
};

// The same tree on every rank: a function of (seed, tile) only.
std::vector<TreeNode> randomTree(unsigned seed, int tile) {
  std::mt19937 random(seed * 7919u + static_cast<unsigned>(tile));
  std::vector<TreeNode> nodes{{0, static_cast<int>(random() % 4), 0}};
  std::uint32_t sequence = 1;
  for (size_t i = 0; i < nodes.size(); ++i) {
    const TreeNode parent = nodes[i];
    for (int c = 0; c < parent.children; ++c) {
      const int children = parent.generation < 2 ? static_cast<int>(random() % 3) : 0;
      nodes.push_back({parent.generation + 1, children, sequence++});
    }
  }
  return nodes;
}

Tile fragmentTile(const Region& region, unsigned seed, int tile, const TreeNode& node) {
  Tile t;
  t.reset(region, true);
  t.generation = node.generation;
  t.children = node.children;
  t.sequence = node.sequence;
  std::mt19937 random(seed * 104729u + static_cast<unsigned>(tile) * 131u + node.sequence);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (size_t p = 0; p < t.depth.size(); ++p) {
    t.depth[p] = 1.0f + 100.0f * unit(random);
    const float alpha = unit(random);
    for (int c = 0; c < 3; ++c) t.color[4 * p + static_cast<size_t>(c)] = alpha * unit(random);
    t.color[4 * p + 3] = alpha;
  }
  return t;
}

TEST(Dfb, AlphaBlendOfRandomTreesInRandomOrderEqualsSerialComposite) {
  messaging::Messenger messenger(MPI_COMM_WORLD);
  DfbOptions o = options(DisplayFormat::RGBAF32, alphaBlendOperation());
  DistributedFrameBuffer dfb(messenger, MPI_COMM_WORLD, o);
  const TileGrid& grid = dfb.grid();
  for (unsigned seed = 1; seed <= 12; ++seed) {
    dfb.begin({seed, 0});
    std::vector<std::pair<int, TreeNode>> mine;
    for (int t = 0; t < grid.tileCount(); ++t)
      for (const TreeNode& node : randomTree(seed, t))
        if ((node.sequence * 5 + static_cast<unsigned>(t) + seed) %
                static_cast<unsigned>(worldSize()) ==
            static_cast<unsigned>(worldRank()))
          mine.emplace_back(t, node);
    std::mt19937 random(seed + 1000u * static_cast<unsigned>(worldRank()));
    std::shuffle(mine.begin(), mine.end(), random);  // children often before parents
    for (auto& [t, node] : mine) {
      if (random() % 8 == 0) std::this_thread::sleep_for(std::chrono::microseconds(random() % 200));
      dfb.setTile(fragmentTile(grid.region(t), seed, t, node));
    }
    dfb.end();
    if (worldRank() != 0) continue;

    // Serial reference: every fragment of a pixel, sorted by depth, blended front to back.
    const auto& image = dfb.imageRgbaF32();
    for (int t = 0; t < grid.tileCount(); ++t) {
      const Region region = grid.region(t);
      std::vector<Tile> fragments;
      for (const TreeNode& node : randomTree(seed, t))
        fragments.push_back(fragmentTile(region, seed, t, node));
      for (int p = 0; p < region.pixelCount(); p += 3) {
        std::vector<std::pair<float, const float*>> order;
        for (const Tile& f : fragments)
          order.emplace_back(f.depth[static_cast<size_t>(p)], &f.color[4 * static_cast<size_t>(p)]);
        std::sort(order.begin(), order.end(), [](auto& a, auto& b) { return a.first < b.first; });
        float out[4] = {0, 0, 0, 0};
        for (auto& [depth, c] : order)
          for (int k = 0; k < 4; ++k) out[k] += (1.0f - out[3]) * c[k];
        const int x = region.x0 + p % region.width(), y = region.y0 + p / region.width();
        for (int k = 0; k < 4; ++k)
          ASSERT_NEAR(image[static_cast<size_t>(4 * (y * kWidth + x) + k)], out[k], 1e-6f)
              << "seed " << seed << " tile " << t << " pixel " << p;
      }
    }
  }
}

TEST(Dfb, TilesForTheNextFrameArrivingEarlyAreHeldAndApplied) {
  messaging::Messenger messenger(MPI_COMM_WORLD);
  const DfbOptions o = options(DisplayFormat::RGBAF32);
  DistributedFrameBuffer dfb(messenger, MPI_COMM_WORLD, o);
  renderFrame(dfb, 1);
  // Rank 0 starts frame 2 late, so the other ranks' tiles for it arrive before its begin(): it
  // waits until it holds every tile others send it (a fixed sleep was too short on a loaded
  // machine), at most 10 s. (Counting the messages received since frame 1 raced: a fast rank's
  // frame-2 tiles could come before the count was first read, and rank 0 then waited out its
  // whole wait while the other rank's frame timed out.)
  if (worldRank() == 0) {
    std::size_t fromOthers = 0;
    for (int t = 0; t < dfb.grid().tileCount(); ++t)
      if (dfb.ownerOf(t) == 0 && !renders(t)) ++fromOthers;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (dfb.heldInputs() < fromOthers && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    EXPECT_EQ(dfb.heldInputs(), fromOthers);
  }
  renderFrame(dfb, 2);
  std::uint64_t early = dfb.stats().earlyInputs, total = 0;
  MPI_Allreduce(&early, &total, 1, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
  if (worldSize() > 1) {
    EXPECT_GT(total, 0u);
  }
  if (worldRank() == 0) {
    for (int i = 0; i < kWidth * kHeight; i += 11) {
      ASSERT_EQ(dfb.imageRgbaF32()[4 * static_cast<size_t>(i)],
                pixelValue(i % kWidth, i / kWidth, 2, 0));
    }
  }
}

TEST(Dfb, StaleInputsAreRejectedAndCounted) {
  messaging::Messenger messenger(MPI_COMM_WORLD);
  DfbOptions o = options(DisplayFormat::RGBAF32);
  DistributedFrameBuffer dfb(messenger, MPI_COMM_WORLD, o);
  renderFrame(dfb, 1);
  dfb.begin({5, 0});
  // An input for frame 3, which this DFB never runs again: stale on arrival.
  const int next = (worldRank() + 1) % worldSize();
  int target = 0;
  while (dfb.ownerOf(target) != next) ++target;
  messenger.send(next, o.objectId,
                 packTile(renderTile(dfb.grid().region(target), 3, 0), target, 3, 0));
  messenger.quiesce();
  tbb::parallel_for(0, dfb.grid().tileCount(), [&](int t) {
    if (renders(t)) dfb.setTile(renderTile(dfb.grid().region(t), 5, 0));
  });
  dfb.end();
  EXPECT_EQ(dfb.stats().staleInputs, 1u);
}

TEST(Dfb, AMissingTileFailsTheFrameOnEveryRankWithinTheTimeout) {
  messaging::Messenger messenger(MPI_COMM_WORLD);
  DfbOptions o = options(DisplayFormat::NONE);
  o.frameTimeout = std::chrono::milliseconds(400);
  DistributedFrameBuffer dfb(messenger, MPI_COMM_WORLD, o);
  dfb.begin({1, 0});
  for (int t = 1; t < dfb.grid().tileCount(); ++t)  // tile 0 never comes
    if (renders(t)) dfb.setTile(renderTile(dfb.grid().region(t), 1, 0));
  const auto start = std::chrono::steady_clock::now();
  std::string message;
  try {
    dfb.end();
  } catch (const base::Error& e) {
    message = e.what();
  }
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(3));
  ASSERT_FALSE(message.empty()) << "end() must fail";
  if (dfb.ownerOf(0) == worldRank()) {
    EXPECT_NE(message.find("tiles 0"), std::string::npos) << message;
  } else {
    EXPECT_NE(message.find("another rank"), std::string::npos) << message;
  }
}

TEST(Dfb, SetTileRejectsARegionThatIsNoTile) {
  messaging::Messenger messenger(MPI_COMM_WORLD);
  DistributedFrameBuffer dfb(messenger, MPI_COMM_WORLD, options(DisplayFormat::NONE));
  dfb.begin({1, 0});
  Tile bad;
  bad.reset(Region{3, 0, 35, 32});
  EXPECT_THROW(dfb.setTile(bad), base::Error);
  tbb::parallel_for(0, dfb.grid().tileCount(), [&](int t) {
    if (renders(t)) dfb.setTile(renderTile(dfb.grid().region(t), 1, 0));
  });
  dfb.end();
}

TEST(Dfb, SetTileOutsideAFrameIsRefused) {
  messaging::Messenger messenger(MPI_COMM_WORLD);
  DistributedFrameBuffer dfb(messenger, MPI_COMM_WORLD, options(DisplayFormat::NONE));
  const Tile tile = renderTile(dfb.grid().region(0), 1, 0);
  auto refusal = [&] {
    try {
      dfb.setTile(tile);
    } catch (const base::Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(refusal().find("setTile outside a frame"), std::string::npos);
  renderFrame(dfb, 1);
  EXPECT_NE(refusal().find("setTile outside a frame"), std::string::npos);
}

// A message that is no tile, arriving between frames, is not lost at the next begin(): that
// begin() throws it, naming the sender.
TEST(Dfb, AMalformedMessageBetweenFramesFailsTheNextBegin) {
  messaging::Messenger messenger(MPI_COMM_WORLD);
  DfbOptions o = options(DisplayFormat::NONE);
  DistributedFrameBuffer dfb(messenger, MPI_COMM_WORLD, o);
  renderFrame(dfb, 1);
  const int sender = worldSize() - 1;
  if (worldRank() == sender) messenger.send(0, o.objectId, messaging::Bytes(10));
  messenger.quiesce();
  if (worldRank() != 0) return;  // the others would wait for rank 0's tiles in frame 2
  try {
    dfb.begin({2, 0});
    ADD_FAILURE() << "begin() must throw the error that came between frames";
  } catch (const base::Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("a tile message from rank " + std::to_string(sender)), std::string::npos)
        << message;
    EXPECT_NE(message.find("shorter than its header"), std::string::npos) << message;
  }
}

// One malformed input for tile 0 (owned by rank 0), from the last rank, in frame 1: rank 0's
// end() throws the door's error naming the tile, the frame, the sender and what is wrong; the
// other ranks fail at their deadline (rank 0 ends the job in a real run).
struct BadInput {
  const char* name;
  TileOperationFactory operation;
  DisplayFormat format;
  std::function<Tile(const Region& tile, std::uint32_t pass)> make;
  std::uint32_t epoch;  // the message's; the frame is epoch 0
  bool viaSetTile;      // set on the last rank rather than sent as a raw message
  const char* expected;
};

Tile withoutColor(const Region& region, std::uint32_t pass) {
  Tile t = renderTile(region, 1, pass);
  t.color.clear();  // a kNoColor | kHasRgba8 message
  t.rgba8.assign(static_cast<size_t>(region.pixelCount()), 0xff0000ffu);
  return t;
}

const BadInput kBadInputs[] = {
    {"accumulate_without_color", accumulateOperation(), DisplayFormat::NONE, withoutColor, 0, false,
     "color has 0 floats"},
    {"alpha_blend_without_color", alphaBlendOperation(), DisplayFormat::NONE, withoutColor, 0,
     false, "color has 0 floats"},
    {"composite_accumulate_without_color", compositeAccumulateOperation(), DisplayFormat::NONE,
     withoutColor, 0, false, "color has 0 floats"},
    // The float gather reads color: display pixels do not stand in for it there.
    {"float_gather_of_display_pixels", writeOperation(), DisplayFormat::RGBAF32, withoutColor, 0,
     true, "color has 0 floats"},
    {"another_epoch", accumulateOperation(), DisplayFormat::NONE,
     [](const Region& r, std::uint32_t pass) { return renderTile(r, 1, pass); }, 9, false,
     "epoch 9, but frame 1 is epoch 0"},
    {"another_pass", accumulateOperation(), DisplayFormat::NONE,
     [](const Region& r, std::uint32_t pass) { return renderTile(r, 1, pass + 4); }, 0, false,
     "accumulation pass 4"},
    {"a_huge_tree", alphaBlendOperation(), DisplayFormat::NONE,
     [](const Region& r, std::uint32_t pass) {
       Tile t = renderTile(r, 1, pass);
       t.children = 1 << 30;
       return t;
     },
     0, false, "children count 1073741824"},
    {"a_tree_where_none_is_taken", writeOperation(), DisplayFormat::NONE,
     [](const Region& r, std::uint32_t pass) {
       Tile t = renderTile(r, 1, pass);
       t.generation = 2;
       return t;
     },
     0, false, "takes no dependency tree"},
    {"the_region_of_another_tile", accumulateOperation(), DisplayFormat::NONE,
     [](const Region& r, std::uint32_t pass) {
       return renderTile(Region{r.x0 + kTileSize, r.y0, r.x1 + kTileSize, r.y1}, 1, pass);
     },
     0, false, "is not the tile's"},
};

class DfbDoor : public ::testing::TestWithParam<BadInput> {};

TEST_P(DfbDoor, RefusesAMalformedInputByName) {
  const BadInput& bad = GetParam();
  messaging::Messenger messenger(MPI_COMM_WORLD);
  DfbOptions o = options(bad.format, bad.operation);
  o.frameTimeout = std::chrono::milliseconds(400);
  DistributedFrameBuffer dfb(messenger, MPI_COMM_WORLD, o);
  ASSERT_EQ(dfb.ownerOf(0), 0);
  const int sender = worldSize() - 1;
  dfb.begin({1, 0});
  const std::uint32_t pass = dfb.accumulationId();
  if (worldRank() == sender) {
    Tile tile = bad.make(dfb.grid().region(0), pass);
    if (bad.viaSetTile)
      dfb.setTile(std::move(tile));
    else
      messenger.send(0, o.objectId, packTile(tile, 0, 1, bad.epoch));
  }
  for (int t = 1; t < dfb.grid().tileCount(); ++t)
    if (renders(t)) dfb.setTile(renderTile(dfb.grid().region(t), 1, pass));
  std::string message;
  try {
    dfb.end();
  } catch (const base::Error& e) {
    message = e.what();
  }
  ASSERT_FALSE(message.empty()) << "end() must fail";
  if (worldRank() != 0) return;
  EXPECT_NE(message.find("tile 0 of frame 1, input "), std::string::npos) << message;
  EXPECT_NE(message.find(bad.viaSetTile && sender == 0 ? "set on this rank"
                                                       : "from rank " + std::to_string(sender)),
            std::string::npos)
      << message;
  EXPECT_NE(message.find(bad.expected), std::string::npos) << message;
}

INSTANTIATE_TEST_SUITE_P(EveryKind, DfbDoor, ::testing::ValuesIn(kBadInputs),
                         [](const auto& p) { return std::string(p.param.name); });

long residentKiB() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  return 0;
}

// Label 'stress': 1,000 small frames, no hang, no growth in memory.
TEST(DfbStress, ThousandSmallFrames) {
  messaging::Messenger messenger(MPI_COMM_WORLD);
  DfbOptions o = options(DisplayFormat::RGBA8, accumulateOperation());
  o.width = 96;
  o.height = 64;
  o.tileSize = 16;
  DistributedFrameBuffer dfb(messenger, MPI_COMM_WORLD, o);
  long afterWarmup = 0;
  for (std::uint32_t frame = 1; frame <= 1000; ++frame) {
    renderFrame(dfb, frame, frame / 50);
    if (frame == 100) afterWarmup = residentKiB();
  }
  EXPECT_EQ(dfb.stats().frameId, 1000u);
#if defined(__SANITIZE_ADDRESS__)
  // AddressSanitizer's quarantine keeps freed memory resident on purpose; growth means nothing.
  (void)afterWarmup;
#else
  const long growth = residentKiB() - afterWarmup;
  EXPECT_LT(growth, 4096) << "resident memory grew by " << growth << " KiB over 900 frames";
#endif
}

}  // namespace
}  // namespace dfb
