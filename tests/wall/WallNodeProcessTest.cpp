// One wall process on its own (run on 1 rank): the wall node's protocol errors, stopAfter,
// keepWaiting and capture requests, through its public interface only, with a real offscreen
// (OSMesa) presenter, real MPI peers on MPI_COMM_SELF and real piece messages (packPiece into
// incoming(), or receivePiece as a service link calls it).
#include <gtest/gtest.h>
#include <mpi.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "base/Error.h"
#include "tests/Stopwatch.h"
#include "wall/display/Capture.h"
#include "wall/display/OsmesaPresenter.h"
#include "wall/display/WallNode.h"
#include "wall/image/Png.h"
#include "wall/route/PieceMessage.h"
#include "wall/route/Routing.h"

namespace wall {
namespace {

using namespace std::chrono_literals;
using testutil::Clock;
using testutil::secondsSince;
constexpr int kTile = 16;

// One 40x30 display: 3 x 2 tiles of 16, the last column 8 wide and the last row 14 high.
Layout oneDisplay() {
  Layout layout;
  layout.file = "one-display";
  Display d;
  d.name = "solo";
  d.rect = {0, 0, 40, 30};
  d.process = 0;
  layout.displays = {d};
  computeCanvas(layout);
  return layout;
}

std::uint32_t canvasPixel(int x, int y, std::uint32_t frame) {
  return static_cast<std::uint32_t>(x * 5 + y * 700 + static_cast<int>(frame) * 31) | 0xff000000u;
}

// A node with everything it needs; what it acknowledges to the renderers is recorded.
struct Wall {
  Layout layout = oneDisplay();
  std::unique_ptr<Presenter> presenter = makeOsmesaPresenter(40, 30);
  std::mutex ackMutex;
  std::vector<std::uint32_t> acknowledged;
  MpiWallPeers peers;
  std::unique_ptr<WallNode> node;

  explicit Wall(WallNodeOptions options)
      : peers(MPI_COMM_SELF, 20s, [this](std::uint32_t frameId, std::int64_t) {
          std::lock_guard lock(ackMutex);
          acknowledged.push_back(frameId);
        }) {
    options.tileSize = kTile;
    node = std::make_unique<WallNode>(layout, peers, std::vector<Presenter*>{presenter.get()},
                                      std::move(options));
  }

  std::vector<DisplayTile> pieces() const { return tilesOfDisplay(layout, 0, kTile); }

  // Piece `index` of `frame` as the routing op packs it, into incoming(). Returns its bytes.
  std::size_t send(std::uint32_t frame, size_t index, int fromRank = 3) {
    const DisplayTile t = pieces().at(index);
    std::vector<std::uint32_t> tile(static_cast<size_t>(t.tile.pixelCount()));
    for (int y = t.tile.y0; y < t.tile.y1; ++y)
      for (int x = t.tile.x0; x < t.tile.x1; ++x)
        tile[static_cast<size_t>((y - t.tile.y0) * t.tile.width() + x - t.tile.x0)] =
            canvasPixel(x, y, frame);
    messaging::Bytes bytes =
        packPiece(frame, 0, t.piece.local, tile.data(), t.tile.width(),
                  t.piece.canvas.x0 - t.tile.x0, t.piece.canvas.y0 - t.tile.y0, frame % 2 == 1);
    const std::size_t size = bytes.size();
    node->incoming(fromRank, std::move(bytes));
    return size;
  }
  std::size_t sendFrame(std::uint32_t frame) {
    std::size_t bytes = 0;
    for (size_t i = 0; i < pieces().size(); ++i) bytes += send(frame, i);
    return bytes;
  }
  // What a service link hands over: a piece `local` filled with `fill`.
  bool receive(std::uint32_t frame, int display, const dfb::Region& local, std::string* why,
               std::function<void(Image&)> fill = {}) {
    if (!fill)
      fill = [&](Image& image) {
        for (int y = local.y0; y < local.y1; ++y)
          for (int x = local.x0; x < local.x1; ++x) image.at(x, y) = canvasPixel(x, y, frame);
      };
    return node->receivePiece("link 7", frame, display, local, fill, 64, why);
  }

  void expectShows(std::uint32_t frame) {
    const Image shown = presenter->readBack();
    ASSERT_EQ(shown.width, 40);
    for (int y = 0; y < 30; ++y)
      for (int x = 0; x < 40; ++x)
        ASSERT_EQ(shown.at(x, y), canvasPixel(x, y, frame)) << x << "," << y << " frame " << frame;
  }
  std::vector<std::uint32_t> acks() {
    std::lock_guard lock(ackMutex);
    return acknowledged;
  }
};

WallNodeOptions withTimeout(std::chrono::milliseconds timeout) {
  WallNodeOptions o;
  o.timeout = timeout;
  return o;
}

TEST(WallNodeProcess, PresentsThePiecesItGetsAndAcknowledgesEachFrameInOrder) {
  Wall wall(withTimeout(20s));
  ASSERT_EQ(wall.pieces().size(), 6u);
  for (std::uint32_t frame = 1; frame <= 3; ++frame) {
    // Pieces of the next frame may come first (the renderers run ahead).
    std::size_t bytes = 0;
    if (frame != 2) bytes += wall.sendFrame(frame);
    if (frame == 1) bytes += wall.sendFrame(2);
    const PresentReport r = wall.node->presentFrame(frame);
    EXPECT_FALSE(r.stopped);
    EXPECT_TRUE(r.failure.empty());
    // Bytes received since the previous frame: frame 2's came with frame 1's.
    EXPECT_EQ(r.bytesReceived, bytes) << "frame " << frame;
    EXPECT_GT(r.completeNs, 0);
    EXPECT_EQ(r.wallCompleteNs, r.completeNs);  // the only process
    wall.expectShows(frame);
  }
  EXPECT_EQ(wall.acks(), (std::vector<std::uint32_t>{1, 2, 3}));
}

// Every kind of piece the node does not expect is refused with a message naming the sender and
// what is wrong; presentFrame then throws it at once (not at its deadline), and no pixel of the
// refused piece reaches the display's buffer.
struct BadPiece {
  const char* what;
  std::function<bool(Wall&, std::string*)> send;
  std::string expected;
};

TEST(WallNodeProcess, ProtocolErrorsAreNamedAndThrownByPresentFrameAtOnce) {
  const std::vector<BadPiece> cases = {
      {"a display of another process",
       [](Wall& w, std::string* why) {
         return w.receive(2, 1, {0, 0, 16, 16}, why);
       },
       "link 7 sent a piece of display 1, which wall process 0 does not drive"},
      {"a negative display",
       [](Wall& w, std::string* why) {
         return w.receive(2, -1, {0, 0, 16, 16}, why);
       },
       "link 7 sent a piece of display -1, which wall process 0 does not drive"},
      {"a frame already presented",
       [](Wall& w, std::string* why) {
         return w.receive(1, 0, {0, 0, 16, 16}, why);
       },
       "link 7 sent a piece for frame 1, already presented"},
      {"a frame too far ahead",
       [](Wall& w, std::string* why) {
         return w.receive(10, 0, {0, 0, 16, 16}, why);
       },
       "link 7 sent a piece for frame 10, more than 8 frames past the last presented (1)"},
      {"a rectangle cut short",
       [](Wall& w, std::string* why) {
         return w.receive(2, 0, {0, 0, 16, 15}, why);
       },
       "link 7 sent display 'solo' a piece [0, 16) x [0, 15) that is none of its expected "
       "pieces"},
      {"a rectangle off the tile grid",
       [](Wall& w, std::string* why) {
         return w.receive(2, 0, {8, 0, 24, 16}, why);
       },
       "a piece [8, 24) x [0, 16) that is none of its expected pieces"},
      {"a rectangle outside the display",
       [](Wall& w, std::string* why) {
         return w.receive(2, 0, {40, 0, 56, 16}, why);
       },
       "a piece [40, 56) x [0, 16) that is none of its expected pieces"},
      {"a rectangle left of the display",
       [](Wall& w, std::string* why) {
         return w.receive(2, 0, {-16, 0, 0, 16}, why);
       },
       "a piece [-16, 0) x [0, 16) that is none of its expected pieces"},
      {"the same piece twice",
       [](Wall& w, std::string* why) {
         return w.receive(2, 0, {16, 16, 32, 30}, why) && w.receive(2, 0, {16, 16, 32, 30}, why);
       },
       "display 'solo' got piece [16, 32) x [16, 30) of frame 2 twice"},
      {"pixels that cannot be decoded",
       [](Wall& w, std::string* why) {
         return w.receive(2, 0, {0, 0, 16, 16}, why,
                          [](Image&) { throw base::Error("piece of 12 bytes: not a JPEG"); });
       },
       "piece of 12 bytes: not a JPEG"},
  };
  for (const BadPiece& c : cases) {
    SCOPED_TRACE(c.what);
    Wall wall(withTimeout(20s));
    wall.sendFrame(1);
    wall.node->presentFrame(1);
    std::string why;
    EXPECT_FALSE(c.send(wall, &why));
    EXPECT_NE(why.find(c.expected), std::string::npos) << why;
    wall.sendFrame(2);  // the frame is complete, and still refused
    const auto start = Clock::now();
    try {
      wall.node->presentFrame(2);
      ADD_FAILURE() << "presentFrame did not throw";
    } catch (const base::Error& e) {
      EXPECT_EQ(std::string(e.what()), "wall process 0: " + why);
    }
    EXPECT_LT(secondsSince(start), 5.0) << "thrown at the deadline, not at once";
    EXPECT_EQ(wall.acks(), std::vector<std::uint32_t>{1});
  }
}

TEST(WallNodeProcess, MalformedMessagesAreNamedToo) {
  const std::vector<std::pair<messaging::Bytes, std::string>> cases = {
      {messaging::Bytes(5), "piece message shorter than its header"},
      {messaging::Bytes(32), "malformed piece message (bad magic, or an empty or oversized"},
  };
  for (const auto& [payload, expected] : cases) {
    Wall wall(withTimeout(20s));
    messaging::Bytes copy = payload;
    wall.node->incoming(4, std::move(copy));
    try {
      wall.node->presentFrame(1);
      ADD_FAILURE() << "presentFrame did not throw";
    } catch (const base::Error& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  }
  // reportError: a sender's error found outside the node (a malformed batch).
  Wall wall(withTimeout(20s));
  wall.node->reportError("link 7: batch of 3 pieces says 4");
  EXPECT_THROW(
      {
        try {
          wall.node->presentFrame(1);
        } catch (const base::Error& e) {
          EXPECT_STREQ(e.what(), "wall process 0: link 7: batch of 3 pieces says 4");
          throw;
        }
      },
      base::Error);
}

// A service wall gives a broken frame up instead of throwing: onAbandon hears why first, the
// frame is not presented nor acknowledged, and the display still shows the last good frame.
TEST(WallNodeProcess, WithAbandonOnFailureABrokenFrameIsGivenUp) {
  std::vector<std::string> heard;
  WallNodeOptions o = withTimeout(20s);
  o.abandonOnFailure = true;
  o.onAbandon = [&](const std::string& why) { heard.push_back(why); };
  Wall wall(o);
  wall.sendFrame(1);
  wall.node->presentFrame(1);
  std::string why;
  wall.sendFrame(2);
  EXPECT_FALSE(wall.receive(2, 0, {0, 0, 16, 16}, &why));
  const PresentReport r = wall.node->presentFrame(2);
  EXPECT_TRUE(r.abandoned);
  EXPECT_TRUE(r.stopped);
  EXPECT_EQ(r.failure, why);
  EXPECT_EQ(heard, std::vector<std::string>{why});
  EXPECT_EQ(wall.acks(), std::vector<std::uint32_t>{1});
  wall.node->showLastPresented();
  wall.expectShows(1);

  // abort(): the job is gone; the frame waited for is given up with its reason.
  Wall aborted(o);
  std::thread later([&] {
    std::this_thread::sleep_for(100ms);
    aborted.node->abort("the render job disconnected");
  });
  const auto start = Clock::now();
  const PresentReport a = aborted.node->presentFrame(1);
  later.join();
  EXPECT_LT(secondsSince(start), 5.0);
  EXPECT_TRUE(a.abandoned);
  EXPECT_EQ(a.failure, "the render job disconnected");
}

TEST(WallNodeProcess, AnIncompleteFrameTimesOutNamingTheMissingPieces) {
  Wall wall(withTimeout(300ms));
  for (size_t i = 0; i < 4; ++i) wall.send(1, i);
  const auto start = Clock::now();
  try {
    wall.node->presentFrame(1);
    ADD_FAILURE() << "presentFrame did not throw";
  } catch (const base::DeadlineError& e) {
    EXPECT_STREQ(e.what(),
                 "frame 1 not complete on wall process 0 after 300 ms: 'solo' has 4/6 pieces;");
  }
  EXPECT_GE(secondsSince(start), 0.29);
}

// stopAfter: a frame past the last one returns `stopped` without waiting, also when it is
// already waiting; the last frame itself is presented (and captured: the run's last).
TEST(WallNodeProcess, StopAfterEndsTheRunAtThatFrame) {
  const std::string dir = ::testing::TempDir() + "/wallnode-stop";
  std::filesystem::remove_all(dir);
  WallNodeOptions o = withTimeout(20s);
  o.captureDir = dir;
  Wall wall(o);  // no last frame: runs until stopped
  wall.sendFrame(1);
  EXPECT_FALSE(wall.node->presentFrame(1).stopped);
  wall.node->stopAfter(2);
  wall.sendFrame(2);
  EXPECT_FALSE(wall.node->presentFrame(2).stopped);  // the last frame is still presented
  auto start = Clock::now();
  const PresentReport r = wall.node->presentFrame(3);
  EXPECT_TRUE(r.stopped);
  EXPECT_FALSE(r.abandoned);
  EXPECT_LT(secondsSince(start), 1.0);
  EXPECT_EQ(wall.acks(), (std::vector<std::uint32_t>{1, 2}));
  // Frame 2 was the last: captured, and only it.
  EXPECT_FALSE(std::filesystem::exists(displayCapturePath(dir, "solo", 1)));
  EXPECT_EQ(readPng(displayCapturePath(dir, "solo", 2)), wall.presenter->readBack());
  EXPECT_TRUE(std::filesystem::exists(wallPreviewPath(dir, 2)));
  std::filesystem::remove_all(dir);

  // Told while it waits for a frame that will not come: it wakes at once.
  Wall waiting(withTimeout(20s));
  waiting.sendFrame(1);
  waiting.node->presentFrame(1);
  std::thread stopper([&] {
    std::this_thread::sleep_for(200ms);
    waiting.node->stopAfter(1);
  });
  start = Clock::now();
  EXPECT_TRUE(waiting.node->presentFrame(2).stopped);
  stopper.join();
  EXPECT_LT(secondsSince(start), 5.0);

  // stopAfter(0): stops before the first frame.
  Wall early(withTimeout(20s));
  early.node->stopAfter(0);
  start = Clock::now();
  EXPECT_TRUE(early.node->presentFrame(1).stopped);
  EXPECT_LT(secondsSince(start), 1.0);
  EXPECT_TRUE(early.acks().empty());
}

// keepWaiting: while the renderers idle, the wait for the next frame starts over each time, so
// a frame that comes well after the timeout is still presented; without it the wait ends.
TEST(WallNodeProcess, KeepWaitingMovesTheDeadline) {
  Wall wall(withTimeout(1000ms));
  std::thread renderers([&] {
    for (int i = 0; i < 12; ++i) {  // 3 s of idling, three timeouts
      std::this_thread::sleep_for(250ms);
      wall.node->keepWaiting();
    }
    wall.sendFrame(1);
  });
  const auto start = Clock::now();
  const PresentReport r = wall.node->presentFrame(1);
  renderers.join();
  EXPECT_GE(secondsSince(start), 3.0);
  EXPECT_FALSE(r.stopped);
  wall.expectShows(1);
  // The idling ended: the next wait has the plain timeout again.
  const auto again = Clock::now();
  EXPECT_THROW(wall.node->presentFrame(2), base::DeadlineError);
  EXPECT_LT(secondsSince(again), 3.0);
}

// Capture requests: frame F, or the first frame after it when F is presented already; each
// request once, and every request honoured even when a later one comes before its frame.
TEST(WallNodeProcess, CaptureRequestsCaptureTheirFrameOnce) {
  const std::string dir = ::testing::TempDir() + "/wallnode-capture";
  std::filesystem::remove_all(dir);
  WallNodeOptions o = withTimeout(20s);
  o.captureDir = dir;
  o.lastFrame = 8;
  Wall wall(o);
  wall.node->requestCapture(2, 1);  // two requests before either frame: both are captured
  wall.node->requestCapture(3, 2);
  std::vector<std::uint32_t> captured;
  for (std::uint32_t frame = 1; frame <= 8; ++frame) {
    if (frame == 5) wall.node->requestCapture(4, 3);  // frame 4 is presented: frame 5 then
    if (frame == 6) wall.node->requestCapture(6, 3);  // sequence 3 again: nothing new
    wall.sendFrame(frame);
    wall.node->presentFrame(frame);
    if (std::filesystem::exists(displayCapturePath(dir, "solo", frame))) {
      captured.push_back(frame);
      EXPECT_EQ(readPng(displayCapturePath(dir, "solo", frame)), wall.presenter->readBack());
      EXPECT_TRUE(std::filesystem::exists(wallPreviewPath(dir, frame)));
    }
  }
  EXPECT_EQ(captured, (std::vector<std::uint32_t>{2, 3, 5, 8}));  // 8: the last frame
  std::filesystem::remove_all(dir);
}

// finish(): a run stopped early captures its last presented frame when it was not captured.
TEST(WallNodeProcess, FinishCapturesTheLastPresentedFrame) {
  const std::string dir = ::testing::TempDir() + "/wallnode-finish";
  std::filesystem::remove_all(dir);
  WallNodeOptions o = withTimeout(20s);
  o.captureDir = dir;
  o.lastFrame = 10;
  Wall wall(o);
  for (std::uint32_t frame = 1; frame <= 2; ++frame) {
    wall.sendFrame(frame);
    wall.node->presentFrame(frame);
  }
  EXPECT_FALSE(std::filesystem::exists(displayCapturePath(dir, "solo", 2)));
  wall.node->finish();
  EXPECT_EQ(readPng(displayCapturePath(dir, "solo", 2)), wall.presenter->readBack());
  EXPECT_FALSE(std::filesystem::exists(displayCapturePath(dir, "solo", 1)));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace wall
