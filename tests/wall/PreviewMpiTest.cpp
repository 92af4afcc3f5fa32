// The preview on real ranks (run with 1, 3 and 4): every rank renders and owns tiles through a
// real DFB, the PreviewOp sends each finished tile shrunk to rank 0, and the assembled preview
// must equal the box filter of the full image that the DFB gathers (RGBA8) for comparison.
#include <gtest/gtest.h>
#include <mpi.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <cstring>
#include <memory>

#include "base/Error.h"

#include "dfb/DistributedFrameBuffer.h"
#include "tests/MpiTestUtil.h"
#include "wall/route/PreviewAssembler.h"
#include "wall/route/PreviewOp.h"

namespace wall {
namespace {

using testutil::worldRank;
using testutil::worldSize;

float pixelValue(int x, int y, std::uint32_t frame, int channel) {
  return static_cast<float>((x * 7 + y * 13 + static_cast<int>(frame) * 5 + channel * 3) % 97) /
         80.0f;
}

dfb::Tile renderTile(const dfb::Region& region, std::uint32_t frame, std::uint32_t pass) {
  dfb::Tile tile;
  tile.reset(region);
  tile.accumulationId = pass;
  size_t i = 0;
  for (int y = region.y0; y < region.y1; ++y)
    for (int x = region.x0; x < region.x1; ++x, ++i)
      for (int c = 0; c < 4; ++c)
        tile.color[4 * i + static_cast<size_t>(c)] = pixelValue(x, y, frame, c);
  return tile;
}

struct Frames {
  int width, height, tileSize;
  dfb::DisplayFormat format;
  std::vector<bool> active;  // empty: every tile
};

// Renders `frames` frames; on rank 0 returns the last gathered image (RGBA8 format) and the
// assembler's latest preview.
struct Result {
  Image full;
  std::shared_ptr<const PreviewAssembler::Snapshot> preview;
  std::uint64_t previewBytes = 0, rank0PixelBytes = 0;
};

Result run(const Frames& s, std::uint32_t frames) {
  messaging::Messenger messenger(MPI_COMM_WORLD);
  dfb::DfbOptions o;
  o.width = s.width;
  o.height = s.height;
  o.tileSize = s.tileSize;
  o.format = s.format;
  o.operation = dfb::writeOperation();
  o.frameTimeout = std::chrono::seconds(30);
  const dfb::TileGrid tiles(s.width, s.height, s.tileSize);
  std::vector<bool> active = s.active;
  if (active.empty()) active.assign(static_cast<size_t>(tiles.tileCount()), true);
  o.expectedInputs = [active](int t) { return active[static_cast<size_t>(t)] ? 1 : 0; };
  const PreviewGrid grid{s.width, s.height, 8};
  std::unique_ptr<PreviewAssembler> assembler;
  if (worldRank() == 0)
    assembler = std::make_unique<PreviewAssembler>(messenger, grid, s.tileSize, active);
  dfb::DistributedFrameBuffer fb(messenger, MPI_COMM_WORLD, o);
  auto op = std::make_shared<PreviewOp>(messenger, grid);
  fb.addPixelOp(op);
  MPI_Barrier(MPI_COMM_WORLD);  // every handler registered before anyone sends

  Result r;
  for (std::uint32_t frame = 1; frame <= frames; ++frame) {
    fb.begin({frame, frame});
    const std::uint32_t pass = fb.accumulationId();
    tbb::parallel_for(0, tiles.tileCount(), [&](int t) {
      // Rendered by a rank other than the owner, so tiles travel before they are shrunk.
      if (active[static_cast<size_t>(t)] && (t * 3 + 1) % worldSize() == worldRank())
        fb.setTile(renderTile(tiles.region(t), frame, pass));
    });
    fb.end();
  }
  std::uint64_t mine = op->takeBytesSent();
  MPI_Reduce(&mine, &r.previewBytes, 1, MPI_UINT64_T, MPI_SUM, 0, MPI_COMM_WORLD);
  if (worldRank() == 0) {
    EXPECT_TRUE(
        assembler->waitFor(frames, std::chrono::steady_clock::now() + std::chrono::seconds(30)));
    r.preview = assembler->latest();
    r.rank0PixelBytes = fb.stats().pixelBytesReceived;
    if (s.format == dfb::DisplayFormat::RGBA8) {
      r.full = Image(s.width, s.height);
      r.full.pixels = fb.imageRgba8();
    }
  }
  messenger.stop();
  return r;
}

int maxChannelDifference(std::uint32_t a, std::uint32_t b) {
  int worst = 0;
  for (int c = 0; c < 4; ++c)
    worst = std::max(worst, std::abs(static_cast<int>(a >> (8 * c) & 0xff) -
                                     static_cast<int>(b >> (8 * c) & 0xff)));
  return worst;
}

// Tiles of 64 on a canvas whose sides are no multiple of 8 or 64: every cell lies in one tile,
// so the preview is the box filter of the full image exactly, edge cells included.
TEST(PreviewMpi, AssembledPreviewEqualsTheDownsampledFullImage) {
  const Frames s{301, 170, 64, dfb::DisplayFormat::RGBA8, {}};
  const Result r = run(s, 3);
  if (worldRank() != 0) return;
  ASSERT_EQ(r.preview->frame, 3u);
  const Image expected = downsample(PreviewGrid{s.width, s.height, 8}, r.full);
  EXPECT_EQ(r.preview->image, expected);
  // 3 frames of 38 x 22 cells with a 24-byte header per tile (5 x 3 tiles).
  EXPECT_EQ(r.previewBytes, 3u * (38u * 22u * 4u + 15u * 24u));
}

// Tiles of 20: cells straddle tiles and are assembled from the parts' averages, weighted by
// their pixels: within rounding of the box filter.
TEST(PreviewMpi, CellsAcrossTilesAreWithinRounding) {
  const Frames s{150, 100, 20, dfb::DisplayFormat::RGBA8, {}};
  const Result r = run(s, 2);
  if (worldRank() != 0) return;
  const Image expected = downsample(PreviewGrid{s.width, s.height, 8}, r.full);
  ASSERT_EQ(r.preview->image.pixels.size(), expected.pixels.size());
  int worst = 0;
  for (size_t i = 0; i < expected.pixels.size(); ++i)
    worst = std::max(worst, maxChannelDifference(r.preview->image.pixels[i], expected.pixels[i]));
  EXPECT_LE(worst, 1);
}

// Route mode: no display format (rank 0 gathers nothing) and tiles nobody shows are not
// rendered. The preview still arrives, with no full-size pixel at rank 0; the cells of the
// missing tiles stay transparent black.
TEST(PreviewMpi, WithoutAGatherRank0GetsOnlyThePreview) {
  const int w = 200, h = 96, tile = 32;
  const dfb::TileGrid tiles(w, h, tile);
  std::vector<bool> active(static_cast<size_t>(tiles.tileCount()), true);
  active[2] = active[9] = false;
  const Result r = run({w, h, tile, dfb::DisplayFormat::NONE, active}, 2);
  // The same frames gathered, to know what the tiles looked like.
  const Result reference = run({w, h, tile, dfb::DisplayFormat::RGBA8, {}}, 2);
  if (worldRank() != 0) return;
  EXPECT_EQ(r.rank0PixelBytes, 0u);
  const PreviewGrid grid{w, h, 8};
  const Image expected = downsample(grid, reference.full);
  for (int cy = 0; cy < grid.height(); ++cy)
    for (int cx = 0; cx < grid.width(); ++cx) {
      const int t = (cy * 8 / tile) * tiles.tilesX() + cx * 8 / tile;
      ASSERT_EQ(r.preview->image.at(cx, cy),
                active[static_cast<size_t>(t)] ? expected.at(cx, cy) : 0u)
          << cx << "," << cy;
    }
}

// A tile owner's preview message for `tile` of `frame`, every cell `value`.
messaging::Bytes previewMessage(const PreviewGrid& grid, const dfb::Region& tile,
                                std::uint32_t frame, std::uint32_t value) {
  const PreviewHeader h{kPreviewMagic, frame, tile.x0, tile.y0, tile.x1, tile.y1};
  const std::vector<std::uint32_t> cells(static_cast<size_t>(grid.cellsOf(tile).pixelCount()),
                                         value);
  messaging::Bytes bytes(sizeof h + 4 * cells.size());
  std::memcpy(bytes.data(), &h, sizeof h);
  std::memcpy(bytes.data() + sizeof h, cells.data(), 4 * cells.size());
  return bytes;
}

// Under load one rank's cells were seen 17 frames behind the others' (a service job's frames
// reach the wall over its own sockets, its previews rank 0 over the messenger): the job ended
// with "far ahead". Now the oldest frames are given up, the job goes on, and the preview is
// whole again once the late rank catches up.
TEST(PreviewAssembler, ALaggingRankCostsFramesOfThePreviewNotTheJob) {
  messaging::Messenger messenger(MPI_COMM_WORLD);
  const PreviewGrid grid{128, 64, 8};
  const dfb::Region left{0, 0, 64, 64}, right{64, 0, 128, 64};
  PreviewAssembler assembler(messenger, grid, 64, {true, true});
  // The left tile's owner runs 40 frames ahead of the right's.
  for (std::uint32_t f = 1; f <= 40; ++f)
    EXPECT_NO_THROW(assembler.incoming(0, previewMessage(grid, left, f, f)));
  EXPECT_EQ(assembler.latest()->frame, 0u);
  EXPECT_EQ(assembler.framesGivenUp(), 40u - PreviewAssembler::kFramesKept);
  // The right one catches up: frames given up stay so, the kept ones complete.
  for (std::uint32_t f = 1; f <= 40; ++f)
    EXPECT_NO_THROW(assembler.incoming(1, previewMessage(grid, right, f, 1000 + f)));
  const auto latest = assembler.latest();
  EXPECT_EQ(latest->frame, 40u);
  EXPECT_EQ(latest->image.at(0, 0), 40u);
  EXPECT_EQ(latest->image.at(15, 7), 1040u);
  // A message of a frame older than the latest is dropped; a broken one still fails.
  EXPECT_NO_THROW(assembler.incoming(0, previewMessage(grid, left, 3, 3)));
  EXPECT_THROW(assembler.incoming(0, previewMessage(grid, {1, 0, 65, 64}, 41, 0)), base::Error);
  messenger.stop();
}

// A service wall moved and resized the job's window at frame 5: cells of earlier frames (the old
// canvas's tiles) are dropped, the new canvas is assembled from frame 5 on.
TEST(PreviewAssembler, ARestartTakesTheNewCanvasFromItsFrame) {
  messaging::Messenger messenger(MPI_COMM_WORLD);
  const PreviewGrid before{128, 64, 8}, after{64, 128, 8};
  PreviewAssembler assembler(messenger, before, 64, {true, true});
  assembler.incoming(0, previewMessage(before, {0, 0, 64, 64}, 3, 7));
  assembler.restart(after, 64, {true, false}, 5);
  EXPECT_EQ(assembler.latest()->frame, 4u);
  EXPECT_EQ(assembler.latest()->grid.canvasHeight, 128);
  EXPECT_TRUE(assembler.waitFor(4, std::chrono::steady_clock::now()));
  // Late cells of the old canvas, whatever their tile, are not the new canvas's.
  EXPECT_NO_THROW(assembler.incoming(0, previewMessage(before, {64, 0, 128, 64}, 3, 7)));
  EXPECT_NO_THROW(assembler.incoming(0, previewMessage(before, {64, 0, 128, 64}, 4, 7)));
  assembler.incoming(0, previewMessage(after, {0, 0, 64, 64}, 5, 9));
  const auto latest = assembler.latest();
  EXPECT_EQ(latest->frame, 5u);
  EXPECT_EQ(latest->image.width, 8);
  EXPECT_EQ(latest->image.height, 16);
  EXPECT_EQ(latest->image.at(7, 7), 9u);
  EXPECT_EQ(latest->image.at(0, 8), 0u);  // the tile no display shows
  // The old canvas's right tile is no tile of the new one.
  EXPECT_THROW(assembler.incoming(0, previewMessage(before, {64, 0, 128, 64}, 6, 7)), base::Error);
  messenger.stop();
}

}  // namespace
}  // namespace wall
