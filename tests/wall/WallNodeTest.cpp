// The wall node on real ranks (run with 3: rank 0 sends pieces, ranks 1 and 2 are wall
// processes 0 and 1, each driving one offscreen display), fed by hand or by the display-routing
// op through the job's messenger.
#include "wall/display/WallNode.h"

#include <gtest/gtest.h>
#include <mpi.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <thread>

#include "base/Error.h"
#include "dfb/PixelOp.h"
#include "wall/display/Capture.h"
#include "wall/display/OsmesaPresenter.h"
#include "wall/image/Png.h"
#include "wall/layout/Ranks.h"
#include "wall/route/DisplayRoutingOp.h"
#include "wall/route/FrameCredits.h"
#include "wall/route/PieceMessage.h"
#include "wall/route/Routing.h"

namespace wall {
namespace {

using messaging::Messenger;
constexpr int kTileSize = 16;

Layout twoDisplays() {
  Layout layout;
  layout.file = "two-displays";
  Display a, b;
  a.name = "a";
  a.rect = {0, 0, 40, 30};
  a.process = 0;
  b.name = "b";
  b.rect = {46, 0, 86, 30};  // a 6-pixel bezel between them
  b.process = 1;
  layout.displays = {a, b};
  computeCanvas(layout);
  return layout;
}

std::uint32_t canvasPixel(int x, int y, std::uint32_t frame) {
  return static_cast<std::uint32_t>(x * 3 + y * 1000 + static_cast<int>(frame) * 77) | 0xff000000u;
}

// Sends every piece of display `d` for `frame`, cut from the canvas tiles as the routing op does.
void sendDisplay(Messenger& messenger, const Layout& layout, const RankRoles& roles, int d,
                 std::uint32_t frame) {
  for (const DisplayTile& t : tilesOfDisplay(layout, d, kTileSize)) {
    std::vector<std::uint32_t> tile(static_cast<size_t>(t.tile.pixelCount()));
    for (int y = t.tile.y0; y < t.tile.y1; ++y)
      for (int x = t.tile.x0; x < t.tile.x1; ++x)
        tile[static_cast<size_t>((y - t.tile.y0) * t.tile.width() + x - t.tile.x0)] =
            canvasPixel(x, y, frame);
    messenger.send(
        roles.rankOfProcess(layout.displays[static_cast<size_t>(d)].process), kWallNodeObject,
        packPiece(frame, d, t.piece.local, tile.data(), t.tile.width(),
                  t.piece.canvas.x0 - t.tile.x0, t.piece.canvas.y0 - t.tile.y0, frame % 2 == 0));
  }
}

using Clock = std::chrono::steady_clock;

// `shown` (what a display shows, or its capture) is its part of the canvas of `frame`, pixel for
// pixel.
void expectCanvas(const Image& shown, const Display& display, std::uint32_t frame) {
  ASSERT_EQ(shown.width, display.rect.width());
  for (int y = 0; y < display.rect.height(); ++y)
    for (int x = 0; x < display.rect.width(); ++x)
      ASSERT_EQ(shown.at(x, y), canvasPixel(display.rect.x0 + x, display.rect.y0 + y, frame))
          << "display " << display.name << " frame " << frame;
}

TEST(WallNode, PresentsOnlyWhenEveryDisplayHasTheFrameAndAcknowledgesIt) {
  int rank = 0, size = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  ASSERT_EQ(size, 3) << "run with 3 ranks";
  const Layout layout = twoDisplays();
  const RankRoles roles = rankRoles(layout, size);
  Messenger messenger(MPI_COMM_WORLD);
  MPI_Comm roleComm;
  MPI_Comm_split(MPI_COMM_WORLD, rank == 0 ? 0 : 1, rank, &roleComm);
  constexpr auto kDelay = std::chrono::milliseconds(300);
  constexpr std::uint32_t kFrames = 3;

  double slowDisplaySentAt[kFrames + 1] = {};
  double presentedAt[kFrames + 1] = {};
  if (rank == 0) {
    FrameCredits credits(messenger);
    MPI_Barrier(MPI_COMM_WORLD);
    for (std::uint32_t frame = 1; frame <= kFrames; ++frame) {
      // Display a gets its frame at once, display b only after a delay.
      sendDisplay(messenger, layout, roles, 0, frame);
      std::this_thread::sleep_for(kDelay);
      slowDisplaySentAt[frame] =
          std::chrono::duration<double>(Clock::now().time_since_epoch()).count();
      sendDisplay(messenger, layout, roles, 1, frame);
    }
    credits.waitForPresented(kFrames, std::chrono::seconds(20));
    EXPECT_EQ(credits.lastPresented(), static_cast<std::int64_t>(kFrames));
  } else {
    const int process = roles.processOfRank(rank);
    const dfb::Region rect = layout.displays[static_cast<size_t>(process)].rect;
    std::vector<std::unique_ptr<Presenter>> presenters;
    presenters.push_back(makeOsmesaPresenter(rect.width(), rect.height()));
    Presenter* presenter = presenters.back().get();
    WallNodeOptions options;
    options.tileSize = kTileSize;
    options.lastFrame = kFrames;
    options.timeout = std::chrono::seconds(20);
    MpiWallPeers peers(messenger, roleComm, options.timeout);
    WallNode node(layout, peers, {presenter}, options);
    const messaging::Registration registration(messenger, kWallNodeObject, &node);
    MPI_Barrier(MPI_COMM_WORLD);
    for (std::uint32_t frame = 1; frame <= kFrames; ++frame) {
      node.presentFrame(frame);
      presentedAt[frame] = std::chrono::duration<double>(Clock::now().time_since_epoch()).count();
      expectCanvas(presenter->readBack(), layout.displays[static_cast<size_t>(process)], frame);
    }
  }
  // Steady clocks are system-wide on Linux, so times from different ranks compare.
  double sent[kFrames + 1], presented[kFrames + 1];
  MPI_Allreduce(slowDisplaySentAt, sent, kFrames + 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  MPI_Allreduce(presentedAt, presented, kFrames + 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  if (rank == 1) {  // display a: complete early, but must wait for b in the swap barrier
    for (std::uint32_t frame = 1; frame <= kFrames; ++frame)
      EXPECT_GE(presentedAt[frame], sent[frame])
          << "display a presented frame " << frame << " before display b's pieces were even sent";
  }
  MPI_Comm_free(&roleComm);
  messenger.stop();
}

// Rank 0's side of a frame as the DFB runs it: every canvas tile finished, through the routing op.
void routeFrame(DisplayRoutingOp& op, const Layout& layout, std::uint32_t frame) {
  const dfb::TileGrid tiles = canvasTiles(layout, kTileSize);
  for (int t = 0; t < tiles.tileCount(); ++t) {
    const dfb::Region r = tiles.region(t);
    std::vector<std::uint32_t> pixels(static_cast<size_t>(r.pixelCount()));
    for (int y = r.y0; y < r.y1; ++y)
      for (int x = r.x0; x < r.x1; ++x)
        pixels[static_cast<size_t>((y - r.y0) * r.width() + x - r.x0)] = canvasPixel(x, y, frame);
    dfb::FinishedTile tile;
    tile.tileIndex = t;
    tile.region = r;
    tile.frameId = frame;
    tile.rgba8 = &pixels;
    op.process(tile);
  }
  op.endFrame(frame);
}

// What the routing op and the wall share: a job of one render rank and two wall processes,
// each wall process presenting `frames` frames and checking it shows the canvas.
struct RoutedJob {
  int rank = 0;
  Layout layout = twoDisplays();
  RankRoles roles;
  std::unique_ptr<Messenger> messenger;
  MPI_Comm roleComm = MPI_COMM_NULL;

  RoutedJob() {
    int size = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    roles = rankRoles(layout, size);
    messenger = std::make_unique<Messenger>(MPI_COMM_WORLD);
    MPI_Comm_split(MPI_COMM_WORLD, rank == 0 ? 0 : 1, rank, &roleComm);
  }
  ~RoutedJob() {
    MPI_Comm_free(&roleComm);
    messenger->stop();
  }
  // A wall rank: presents frames 1..frames (before each, `beforeFrame(node, frame)`), checking
  // every pixel of its display.
  void wall(std::uint32_t frames, WallNodeOptions options,
            const std::function<void(WallNode&, std::uint32_t)>& beforeFrame) {
    const int process = roles.processOfRank(rank);
    const dfb::Region rect = layout.displays[static_cast<size_t>(process)].rect;
    std::unique_ptr<Presenter> presenter = makeOsmesaPresenter(rect.width(), rect.height());
    options.tileSize = kTileSize;
    options.lastFrame = frames;
    options.timeout = std::chrono::seconds(20);
    MpiWallPeers peers(*messenger, roleComm, options.timeout);
    WallNode node(layout, peers, {presenter.get()}, options);
    const messaging::Registration registration(*messenger, kWallNodeObject, &node);
    MPI_Barrier(MPI_COMM_WORLD);
    for (std::uint32_t frame = 1; frame <= frames; ++frame) {
      if (beforeFrame) beforeFrame(node, frame);
      node.presentFrame(frame);
      expectCanvas(presenter->readBack(), layout.displays[static_cast<size_t>(process)], frame);
    }
    node.finish();
  }
};

// The routing op cuts each finished tile at the display borders, drops what the bezel hides,
// and sends each piece to its display's wall rank, which shows exactly the canvas.
TEST(DisplayRoutingOp, CutsTilesAtDisplayBordersAndTheDisplaysShowTheCanvas) {
  RoutedJob job;
  constexpr std::uint32_t kFrames = 2;
  if (job.rank == 0) {
    FrameCredits credits(*job.messenger);
    DisplayRoutingOp op(*job.messenger, job.layout, job.roles, kTileSize);
    MPI_Barrier(MPI_COMM_WORLD);
    for (std::uint32_t frame = 1; frame <= kFrames; ++frame) {
      routeFrame(op, job.layout, frame);
      // Canvas 86 x 30 in tiles of 16: 6 x 2 tiles; the tile [32, 48) holds a's right edge and
      // b's left edge, two pieces; every other tile one. The 6-pixel bezel is dropped: 2 x 40 x
      // 30 pixels travel, each piece with its 32-byte header.
      const DisplayRoutingOp::Sent sent = op.takeSent();
      EXPECT_EQ(sent.pieces, 14u);
      EXPECT_EQ(sent.bytes, 14u * sizeof(PieceHeader) + 2u * 40u * 30u * 4u);
      EXPECT_EQ(sent.piecesToOtherHosts, 0u);  // one host
      EXPECT_EQ(op.takeSent().pieces, 0u) << "taken once";
    }
    credits.waitForPresented(kFrames, std::chrono::seconds(20));
    // A DFB of another tile size: refused by name, nothing sent.
    std::vector<std::uint32_t> pixels(32 * 30);
    dfb::FinishedTile wrong;
    wrong.region = {0, 0, 32, 30};
    wrong.frameId = kFrames + 1;
    wrong.rgba8 = &pixels;
    for (int index : {0, 12, -1}) {
      wrong.tileIndex = index;
      try {
        op.process(wrong);
        ADD_FAILURE() << "tile " << index << " routed";
      } catch (const base::Error& e) {
        EXPECT_EQ(std::string(e.what()),
                  "display routing: finished tile " + std::to_string(index) +
                      " [0, 32) x [0, 30) is not a tile of the wall's 86x30 canvas in tiles of 16 "
                      "(the DFB's tile size must be the op's)");
      }
    }
    EXPECT_EQ(op.takeSent().pieces, 0u);
  } else {
    job.wall(kFrames, {}, {});
  }
}

// A capture asked of one wall process only is taken by every wall process, of the same frame:
// the swap barrier agrees on it. Process 0 also writes the whole-wall capture.
TEST(WallNode, ACaptureAskedOfOneProcessIsTakenByEveryProcess) {
  RoutedJob job;
  constexpr std::uint32_t kFrames = 4;
  const std::string dir = ::testing::TempDir() + "/wallnode-3ranks-capture";
  if (job.rank == 0) std::filesystem::remove_all(dir);
  MPI_Barrier(MPI_COMM_WORLD);
  if (job.rank == 0) {
    FrameCredits credits(*job.messenger);
    DisplayRoutingOp op(*job.messenger, job.layout, job.roles, kTileSize);
    MPI_Barrier(MPI_COMM_WORLD);
    for (std::uint32_t frame = 1; frame <= kFrames; ++frame) {
      credits.waitForPresented(static_cast<std::int64_t>(frame) - 1, std::chrono::seconds(20));
      routeFrame(op, job.layout, frame);
    }
    credits.waitForPresented(kFrames, std::chrono::seconds(20));
  } else {
    WallNodeOptions options;
    options.captureDir = dir;
    const bool asked = job.roles.processOfRank(job.rank) == 1;
    job.wall(kFrames, options, [asked](WallNode& node, std::uint32_t frame) {
      if (asked && frame == 2) node.requestCapture(2, 1);
    });
  }
  MPI_Barrier(MPI_COMM_WORLD);
  if (job.rank == 0) {
    for (const Display& d : job.layout.displays) {
      std::vector<std::uint32_t> captured;
      for (std::uint32_t frame = 1; frame <= kFrames; ++frame) {
        if (!std::filesystem::exists(displayCapturePath(dir, d.name, frame))) continue;
        captured.push_back(frame);
        expectCanvas(readPng(displayCapturePath(dir, d.name, frame)), d, frame);
      }
      // Frame 2 asked for (of process 1 only), frame 4 the last.
      EXPECT_EQ(captured, (std::vector<std::uint32_t>{2, 4})) << "display " << d.name;
    }
    const Image wallCapture = readPng(wallPreviewPath(dir, 2));
    EXPECT_EQ(wallCapture.width, 86);
    EXPECT_EQ(wallCapture.at(50, 10), canvasPixel(50, 10, 2));  // display b
    EXPECT_EQ(wallCapture.at(43, 10), kBezelColor);
    std::filesystem::remove_all(dir);
  }
}

}  // namespace
}  // namespace wall
