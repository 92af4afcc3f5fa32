// The wall node on real ranks (run with 3: rank 0 sends pieces, ranks 1 and 2 are wall
// processes 0 and 1, each driving one offscreen display).
#include "wall/WallNode.h"

#include <gtest/gtest.h>
#include <mpi.h>

#include <chrono>
#include <thread>

#include "wall/FrameCredits.h"
#include "wall/OsmesaPresenter.h"
#include "wall/PieceMessage.h"
#include "wall/Ranks.h"
#include "wall/Routing.h"

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
      const Image shown = presenter->readBack();
      for (int y = 0; y < rect.height(); ++y)
        for (int x = 0; x < rect.width(); ++x)
          ASSERT_EQ(shown.at(x, y), canvasPixel(rect.x0 + x, rect.y0 + y, frame))
              << "display " << layout.displays[static_cast<size_t>(process)].name << " frame "
              << frame;
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

}  // namespace
}  // namespace wall
