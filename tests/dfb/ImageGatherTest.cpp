// The display-format gather (dfb/ImageGather.h) on real ranks (run with 1, 2 and 4): every
// rank's tiles land at their place in rank 0's image, byte for byte, raw or compressed, RGBA8 or
// RGBAF32, with the counts it reports; a peer whose block does not match its tiles is named.
#include "dfb/ImageGather.h"

#include <gtest/gtest.h>
#include <mpi.h>

#include <chrono>
#include <cstring>
#include <span>
#include <string>
#include <vector>

#include "base/Collectives.h"
#include "base/Error.h"
#include "tests/MpiTestUtil.h"

namespace dfb {
namespace {

using Clock = std::chrono::steady_clock;

// A 50 x 37 image in tiles of 16: 4 x 3 tiles, the last column 2 wide, the last row 5 high.
const TileGrid kGrid(50, 37, 16);

// Owners not in blocks: tile t on rank (7 t + 1) mod size.
int ownerOf(int tile, int size) { return (7 * tile + 1) % size; }
std::vector<int> tilesOfRank(int rank, int size) {
  std::vector<int> tiles;
  for (int t = 0; t < kGrid.tileCount(); ++t)
    if (ownerOf(t, size) == rank) tiles.push_back(t);
  return tiles;
}

// The pixel bytes of (x, y) in frame `frame`: smooth (compressible), different per frame.
void pixelBytes(int x, int y, int frame, int bytesPerPixel, std::byte* out) {
  if (bytesPerPixel == 4) {
    const std::uint32_t p = static_cast<std::uint32_t>(x * 2 + frame) |
                            static_cast<std::uint32_t>(y * 3) << 8 | 0x40u << 16 | 0xffu << 24;
    std::memcpy(out, &p, 4);
  } else {
    const float p[4] = {static_cast<float>(x) * 0.5f + static_cast<float>(frame), 0.25f * y,
                        1.0f / static_cast<float>(1 + x + y), 1.0f};
    std::memcpy(out, p, 16);
  }
}

// Each owned tile's pixels, packed row by row, as the DFB holds them.
std::vector<std::vector<std::byte>> tilePixels(const std::vector<int>& owned, int frame,
                                               int bytesPerPixel) {
  std::vector<std::vector<std::byte>> pixels(static_cast<size_t>(kGrid.tileCount()));
  for (int t : owned) {
    const Region r = kGrid.region(t);
    auto& p = pixels[static_cast<size_t>(t)];
    p.resize(static_cast<size_t>(r.pixelCount() * bytesPerPixel));
    std::byte* at = p.data();
    for (int y = r.y0; y < r.y1; ++y)
      for (int x = r.x0; x < r.x1; ++x, at += bytesPerPixel)
        pixelBytes(x, y, frame, bytesPerPixel, at);
  }
  return pixels;
}

std::vector<std::byte> expectedImage(int frame, int bytesPerPixel) {
  std::vector<std::byte> image(static_cast<size_t>(50 * 37 * bytesPerPixel));
  for (int y = 0; y < 37; ++y)
    for (int x = 0; x < 50; ++x)
      pixelBytes(x, y, frame, bytesPerPixel,
                 image.data() + static_cast<size_t>((y * 50 + x) * bytesPerPixel));
  return image;
}

TEST(ImageGather, EveryTileLandsAtItsPlaceOnRankZeroWithTheCounts) {
  const int rank = testutil::worldRank(), size = testutil::worldSize();
  const std::vector<int> owned = tilesOfRank(rank, size);
  for (int bytesPerPixel : {4, 16})
    for (bool compress : {false, true}) {
      SCOPED_TRACE((bytesPerPixel == 4 ? "RGBA8" : "RGBAF32") +
                   std::string(compress ? " compressed" : " raw"));
      GatherBuffers buffers;  // kept from one frame to the next, as the DFB does
      for (int frame = 1; frame <= 2; ++frame) {
        const auto pixels = tilePixels(owned, frame, bytesPerPixel);
        std::vector<std::byte> image(rank == 0 ? 50 * 37 * bytesPerPixel : 0, std::byte{0x5a});
        const GatherCounts counts = gatherImage(
            MPI_COMM_WORLD, kGrid, bytesPerPixel, compress, owned,
            [size](int r) { return tilesOfRank(r, size); },
            [&pixels](int t) { return pixels[static_cast<size_t>(t)].data(); }, image.data(),
            Clock::now() + std::chrono::seconds(20), buffers);
        std::uint64_t rawBytes = 0;
        for (int t : owned)
          rawBytes += static_cast<std::uint64_t>(kGrid.region(t).pixelCount() * bytesPerPixel);
        std::uint64_t sentByAll = 0, rawByOthers = rank == 0 ? 0 : rawBytes, allRawByOthers = 0;
        MPI_Reduce(&counts.bytesSent, &sentByAll, 1, MPI_UINT64_T, MPI_SUM, 0, MPI_COMM_WORLD);
        MPI_Reduce(&rawByOthers, &allRawByOthers, 1, MPI_UINT64_T, MPI_SUM, 0, MPI_COMM_WORLD);
        if (rank != 0) {
          EXPECT_GT(counts.bytesSent, 0u);
          EXPECT_EQ(counts.bytesReceived, 0u);
          EXPECT_EQ(counts.pixelBytesReceived, 0u);
          if (!compress) {
            EXPECT_EQ(counts.bytesSent, 16u + rawBytes);  // a 16-byte header
          }
          continue;
        }
        EXPECT_EQ(image, expectedImage(frame, bytesPerPixel)) << "frame " << frame;
        EXPECT_EQ(counts.bytesSent, 0u);  // the root places its own tiles
        EXPECT_EQ(counts.bytesReceived, sentByAll);
        EXPECT_EQ(counts.pixelBytesReceived, static_cast<std::uint64_t>(50 * 37 * bytesPerPixel));
        if (compress && size > 1) {
          EXPECT_LT(counts.bytesReceived, allRawByOthers);
        }
      }
    }
}

// What a broken or hostile peer could send: rank 1 speaks the gather's protocol by hand (the
// block's size, then the block: a 16-byte header {raw bytes, encoding, 0} and the pixels) with a
// block that does not match its tiles; rank 0 refuses it naming the rank, and every rank leaves
// the gather (no collective is left pending).
struct BadBlock {
  const char* what;
  std::vector<std::byte> block;
  std::string expected;
};

std::vector<std::byte> block(std::uint64_t rawBytes, std::uint32_t encoding, size_t bodyBytes) {
  struct {
    std::uint64_t rawBytes;
    std::uint32_t encoding, reserved;
  } header{rawBytes, encoding, 0};
  static_assert(sizeof header == 16);
  const auto* at = reinterpret_cast<const std::byte*>(&header);
  std::vector<std::byte> b(at, at + sizeof header);
  b.resize(16 + bodyBytes, std::byte{1});
  return b;
}

TEST(ImageGather, ABlockThatDoesNotMatchItsTilesIsRefusedNamingTheRank) {
  const int rank = testutil::worldRank(), size = testutil::worldSize();
  if (size < 2) GTEST_SKIP() << "needs a second rank to send the bad block";
  const std::vector<int> owned1 = tilesOfRank(1, size);
  std::uint64_t need = 0;
  for (int t : owned1) need += static_cast<std::uint64_t>(kGrid.region(t).pixelCount() * 4);
  const std::vector<BadBlock> cases = {
      {"shorter than its header", std::vector<std::byte>(8),
       "gather: rank 1 sent a block shorter than its header"},
      {"raw, shorter than it says", block(need, 0, 10),
       "gather: rank 1 sent 10 raw bytes, its header says " + std::to_string(need)},
      {"raw, too few for its tiles", block(8, 0, 8),
       "gather: rank 1 sent fewer pixel bytes (8) than its tiles need"},
      {"raw, too many for its tiles", block(need + 4, 0, need + 4),
       "gather: rank 1 sent " + std::to_string(need + 4) + " pixel bytes for tiles that need " +
           std::to_string(need)},
      {"compressed, not Snappy", block(need, 1, 40), "gather: rank 1: corrupt compressed message"},
      {"an unknown encoding", block(need, 7, need),
       "gather: rank 1 sent a block of unknown encoding 7"},
  };
  for (const BadBlock& c : cases) {
    SCOPED_TRACE(c.what);
    if (rank == 1) {
      // The same collective as gatherImage's, with a block it would never send.
      const base::Bound bound{.until = std::chrono::seconds(20), .late = "never said"};
      base::Gathered<std::byte> gathered;
      base::startGatherv(std::span<const std::byte>(c.block), 0, MPI_COMM_WORLD, bound, gathered)
          .finish(bound);
      continue;
    }
    const std::vector<int> owned = tilesOfRank(rank, size);
    const auto pixels = tilePixels(owned, 1, 4);
    std::vector<std::byte> image(rank == 0 ? 50 * 37 * 4 : 0);
    GatherBuffers buffers;
    const auto gather = [&] {
      gatherImage(
          MPI_COMM_WORLD, kGrid, 4, false, owned, [size](int r) { return tilesOfRank(r, size); },
          [&pixels](int t) { return pixels[static_cast<size_t>(t)].data(); }, image.data(),
          Clock::now() + std::chrono::seconds(20), buffers);
    };
    if (rank != 0) {
      gather();
      continue;
    }
    try {
      gather();
      ADD_FAILURE() << "rank 0 accepted the block";
    } catch (const base::Error& e) {
      EXPECT_EQ(std::string(e.what()).rfind(c.expected, 0), 0u) << e.what();
    }
  }
}

}  // namespace
}  // namespace dfb
