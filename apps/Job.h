#pragma once
// What one run of dfbwall is, as every rank sees it after setup: the options, the layout (when
// there is a wall), and this rank's role.
#include <mpi.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "apps/CameraPath.h"
#include "apps/Failure.h"
#include "apps/Options.h"
#include "messaging/Messenger.h"
#include "renderers/RenderScene.h"
#include "renderers/RoomView.h"
#include "wall/layout/Layout.h"
#include "wall/layout/Ranks.h"
#include "wall/service/protocol/Codec.h"
#include "wall/service/protocol/Protocol.h"
#include "wall/service/security/Credentials.h"

namespace wall::service {
class ServiceClient;
}

namespace runtime {
class MpiWallControl;
}

namespace app {

class Preview;

struct Job {
  Options options;
  std::optional<wall::Layout> layout;  // --wall's, or the serving wall's (--connect)
  // --connect: the wall's directory (every rank) and the link to it (render rank 0).
  std::optional<wall::service::Directory> directory;
  wall::service::Credentials credentials;  // what every rank presents to the wall
  std::shared_ptr<wall::service::ServiceClient> service;
  wall::service::CodecSpec codec;
  wall::RankRoles roles;  // without a wall: every rank renders
  int worldRank = 0;
  int canvasWidth = 0, canvasHeight = 0;
  // The layout's screens in the room (null: one pinhole image over the canvas), with --wall or
  // --view; and with --view, each display's name and canvas pixels, whose picture --image gets.
  std::shared_ptr<const renderers::RoomView> room;
  struct ViewedDisplay {
    std::string name;
    dfb::Region pixels;
  };
  std::vector<ViewedDisplay> views;
  renderers::RenderScene scene;          // render ranks only
  std::optional<CameraPath> cameraPath;  // render rank 0, with --camera-path
  // Where a failure during the frames goes. The frame loops catch into it while their objects
  // still exist: unwinding first would unregister them, and a message arriving for one would
  // then be reported instead of the real cause.
  FailurePath* failure = nullptr;
  // Render ranks when previewWanted(): the preview's pixel op and (rank 0) assembler, made in
  // run() so the control server can serve it (apps/Preview.h).
  Preview* preview = nullptr;
  // Test-only: DFBWALL_FAIL_AT=RANK:FRAME makes world rank RANK throw at frame FRAME, so the
  // fault tests can check the failure path end to end (tests/apps/fault_test.sh).
  int failAtRank = -1;
  std::uint32_t failAtFrame = 0;
  void failIfAsked(std::uint32_t frame) const;
  bool gatherMode() const { return options.mode == "gather"; }
  bool connected() const { return directory.has_value(); }
  bool isWallRank() const { return roles.processOfRank(worldRank) >= 0; }
  // The whole-wall preview is assembled on rank 0 (apps/Preview.h).
  bool previewWanted() const { return !options.previewFile.empty() || !options.control.empty(); }
};

struct FrameRecord {
  std::uint32_t frame = 0;
  double frameMs = 0;                 // rank 0: from the start of this frame to the next one's
  double renderMs = 0;                // slowest render rank: begin() .. last setTile()
  double compositeMs = 0;             // slowest render rank: last setTile() .. frame complete
  std::uint64_t rank0PixelBytes = 0;  // final pixels into rank 0 (the gather)
  // Pieces sent to wall ranks by all render ranks: bytes on the wire (after compression, with
  // the messenger's envelope) and before compression; how many, how many to other hosts, and
  // how many messages the render ranks' messengers compressed. wallMessages: MPI messages to
  // the wall node, which equals wallPieces (a piece is never cut into several messages).
  std::uint64_t wallBytesSent = 0, wallBytesRaw = 0;
  std::uint64_t wallPieces = 0, wallPiecesToOtherHosts = 0, messagesCompressed = 0;
  // --connect: pieces not sent because the wall lost their display's process.
  std::uint64_t wallPiecesDropped = 0;
  std::uint64_t wallMessages = 0;
  std::uint64_t tileBytesSent = 0;  // tile inputs between render ranks
  std::uint64_t previewBytes = 0;   // shrunk tiles for rank 0's preview (apps/Preview.h)
  std::uint64_t tilesRendered = 0;
  std::uint64_t samples = 0;
  std::int64_t lastSetTileNs = 0;  // steady_clock, latest over render ranks
  // steady_clock time the last display had every piece (from the wall's acknowledgement); minus
  // lastSetTileNs it is the compositing time. One host's clock: on a cluster the difference
  // also holds the hosts' clock offset. 0: no wall.
  std::int64_t displaysCompleteNs = 0;
  // Steering: the frame's accumulation epoch; the last request it applies (0: none),
  // when the first of them reached rank 0 and the last frame every display had presented then;
  // when rank 0 learnt every display presented this frame. All on rank 0's steady_clock.
  std::uint32_t epoch = 0;
  std::uint64_t requestId = 0;
  std::int64_t requestNs = 0, presentedAtRequest = 0, displaysPresentedNs = 0;
  // A time series: the step shown (-1: none), whether this frame switched to it, and the
  // render ranks' times for it (RankFrame: the slowest rank's, the switch the fastest's).
  std::int64_t timeStep = -1;
  bool stepChanged = false;
  double stepReadMs = 0, stepBuildMs = 0, stepWaitMs = 0, stepSwitchMs = 0;
};

// Where one rank's time went over the whole run, in milliseconds summed over tiles or frames.
// Render ranks fill the first seven stages, wall ranks the next five. render, wallWait, barrier,
// present and gatherRelay are elapsed time; the per-pixel stages (tileUnpack .. send,
// pieceUnpack, assemble) are CPU time of the threads doing them (base/Timing.h). The CPU totals
// over the frames (start-up barrier .. last frame) let the bench tell the rest apart: render
// ranks: the renderer's render() calls, the whole process; wall ranks: the whole process, its
// main thread (waits, swap barrier, GL calls), the GL driver's own threads (apps/ThreadCpu.h).
// Doubles only, so the whole struct gathers as doubles.
struct StageTimes {
  double render = 0, tileUnpack = 0, tileOperation = 0, toneMap = 0, cut = 0, send = 0,
         gatherRelay = 0;
  // Wall ranks: wallWait includes upload (pieces go to the textures as they arrive); draw is
  // before the swap barrier, present (the swap) after it.
  double pieceUnpack = 0, assemble = 0, wallWait = 0, upload = 0, draw = 0, barrier = 0,
         present = 0;
  double renderCpu = 0, processCpu = 0, mainThreadCpu = 0, glThreadsCpu = 0;
};

struct RankTotals {
  StageTimes stages;
  double peakRssKiB = 0;
  double role = 0;        // 0: render, 1: wall
  double sceneBytes = 0;  // render ranks: the scene data this rank holds (its bricks, or all)
  double brickTiles = 0;  // render ranks with --bricks: brick tiles rendered over the run
  // Render ranks with --bricks: camera rays not traced, hidden behind a nearer brick's opaque
  // isosurface (renderers/scivis/bricks/BrickOcclusion.h), over the run.
  double brickRaysSkipped = 0;
  // Render ranks: isosurface triangles held (camera-visible and shading-only) and the seconds
  // making them and their BVHs at scene load.
  double isosurfaceTriangles = 0, shadingOnlyTriangles = 0, isosurfaceSeconds = 0;
  // Wall ranks: how far apart the wall processes' swaps of one frame ended (agreed, so the same
  // on every wall rank), the largest and the sum over the frames it is known for.
  double swapSpreadMaxMs = 0, swapSpreadSumMs = 0, swapSpreadFrames = 0;
};
static_assert(sizeof(RankTotals) % sizeof(double) == 0);

class RunControl;
class StatsStream;
class StatusBoard;
class Steering;

// Render ranks: renders the frames, feeds the wall (route or gather), writes --image on rank 0,
// streams the statistics there. Returns the exit code agreed with rank 0 (0, or a stop's).
// `status`: rank 0 with a control server, what it reports (else null).
int runRenderRank(const Job& job, messaging::Messenger& messenger, MPI_Comm renderComm,
                  RunControl& control, runtime::MpiWallControl& wallControl, Steering& steering,
                  StatusBoard* status, StatsStream* stats, RankTotals& totals);
// Wall ranks: assembles, swaps and presents the frames of this process's displays until the
// last frame (or the one rank 0 announces when the run stops early). Returns the exit code.
int runWallRank(const Job& job, messaging::Messenger& messenger, MPI_Comm wallComm,
                RunControl& control, runtime::MpiWallControl& wallControl, Steering& steering,
                RankTotals& totals);

// The peak resident set of this process (VmHWM), in KiB; 0 where /proc is missing.
double peakRssKiB();

// --dry-run on rank 0: canvas, displays, roles, and per display its tiles and their owners.
void printDryRun(const Job& job);
// --image on rank 0: PNG from RGBA8 or PFM from linear RGBA float, written atomically.
void writePfm(const std::string& path, const float* rgba, int width, int height);

}  // namespace app
