// The render ranks' frame loop: pace against the wall, render through the DFB, feed the wall.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <deque>
#include <optional>

#include "apps/Collectives.h"
#include "apps/Job.h"
#include "apps/RunControl.h"
#include "apps/Stats.h"
#include "dfb/BoundedWait.h"
#include "dfb/DistributedFrameBuffer.h"
#include "dfb/Error.h"
#include "dfb/Timing.h"
#include "renderers/FrameDriver.h"
#include "renderers/Renderer.h"
#include "renderers/WorkDistribution.h"
#include "renderers/scivis/BrickFrameDriver.h"
#include "wall/DisplayRoutingOp.h"
#include "wall/FrameCredits.h"
#include "wall/PieceMessage.h"
#include "wall/Png.h"
#include "wall/Routing.h"

namespace app {
namespace {

using dfb::Clock;
using dfb::msBetween;

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// Gather mode's relay, as Tide-like walls do it: rank 0 has the whole image and sends each
// display its rectangle.
wall::DisplayRoutingOp::Sent relayToDisplays(const Job& job, dfb::Messenger& messenger,
                                             std::uint32_t frameId,
                                             const std::vector<std::uint32_t>& image) {
  wall::DisplayRoutingOp::Sent sent;
  const wall::Layout& layout = *job.layout;
  for (size_t d = 0; d < layout.displays.size(); ++d) {
    const dfb::Region& rect = layout.displays[d].rect;
    const int to = job.roles.rankOfProcess(layout.displays[d].process);
    dfb::Bytes piece = wall::packPiece(frameId, static_cast<int>(d),
                                       dfb::Region{0, 0, rect.width(), rect.height()}, image.data(),
                                       job.canvasWidth, rect.x0, rect.y0, messenger.compresses(to));
    sent.bytes += piece.size();
    sent.pieces++;
    if (!messenger.sameHost(to)) sent.piecesToOtherHosts++;
    messenger.send(to, wall::kWallNodeObject, std::move(piece));
  }
  return sent;
}

// What rank 0 broadcasts before each frame: the frame, or the end of the run.
struct FrameOrder {
  dfb::FrameInfo frame;
  std::int32_t stop;      // 1: no more frames (a graceful stop)
  std::int32_t exitCode;  // of the stop
};

// One render rank's numbers of one frame, gathered to rank 0 for the statistics.
struct RankFrame {
  double renderMs, compositeMs;
  // Pieces for the wall: bytes on the wire (after compression), bytes before, how many, how
  // many to other hosts; messages this rank's messenger compressed.
  std::uint64_t wallBytes, wallBytesRaw, wallPieces, wallPiecesToOtherHosts, messagesCompressed;
  std::uint64_t tileBytes, tiles, samples;
  std::int64_t lastSetTileNs;
};

std::vector<RankFrame> gatherRankFrames(const RankFrame& mine, MPI_Comm comm,
                                        std::chrono::milliseconds timeout) {
  int rank = 0, size = 0;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  std::vector<RankFrame> all(rank == 0 ? static_cast<size_t>(size) : 0);
  MPI_Request request;
  dfb::checkMpi(MPI_Igather(&mine, sizeof mine, MPI_BYTE, all.data(), sizeof mine, MPI_BYTE, 0,
                            comm, &request),
                "MPI_Igather");
  dfb::waitWithDeadline(request, Clock::now() + timeout,
                        "frame statistics: another render rank did not send them in time");
  return all;
}

// The slowest rank's times, the sums of the counts, the latest setTile.
FrameRecord combine(const std::vector<RankFrame>& all) {
  FrameRecord r;
  for (const RankFrame& f : all) {
    r.renderMs = std::max(r.renderMs, f.renderMs);
    // The paper's compositing overhead: from the slowest rank's last tile to the finished
    // frame, i.e. that rank's own last setTile -> complete. (The maximum over ranks would be the
    // time the fastest rank waited for the others.)
    if (f.lastSetTileNs >= r.lastSetTileNs) r.compositeMs = f.compositeMs;
    r.wallBytesSent += f.wallBytes;
    r.wallBytesRaw += f.wallBytesRaw;
    r.wallPieces += f.wallPieces;
    r.wallPiecesToOtherHosts += f.wallPiecesToOtherHosts;
    r.messagesCompressed += f.messagesCompressed;
    r.tileBytesSent += f.tileBytes;
    r.tilesRendered += f.tiles;
    r.samples += f.samples;
    r.lastSetTileNs = std::max(r.lastSetTileNs, f.lastSetTileNs);
  }
  return r;
}

}  // namespace

int runRenderRank(const Job& job, dfb::Messenger& messenger, MPI_Comm renderComm,
                  RunControl& control, StatsStream* statsStream, RankTotals& totals) {
  const Options& o = job.options;
  int renderRank = 0;
  MPI_Comm_rank(renderComm, &renderRank);
  const bool hasWall = job.layout.has_value();
  const bool route = hasWall && !job.gatherMode();

  renderers::RenderSettings settings;
  settings.width = job.canvasWidth;
  settings.height = job.canvasHeight;
  settings.seed = o.seed;
  settings.maxDepth = o.maxDepth;
  settings.orbitDegreesPerFrame = o.orbit;
  // Image-parallel: one renderer over the whole scene, tiles planned by the frame driver.
  // Data-parallel (--bricks): this rank's bricks, tiles planned per brick.
  const bool bricked = o.bricks > 0;

  renderers::FrameDriverOptions driving;
  driving.distribution = renderers::distributionFromName(o.distribution);
  driving.samplesPerPixel = static_cast<std::uint32_t>(o.spp);
  driving.threads = o.threads;
  dfb::DfbOptions dfbOptions;
  dfbOptions.width = job.canvasWidth;
  dfbOptions.height = job.canvasHeight;
  dfbOptions.tileSize = o.tileSize;
  // The pattern is a new picture every frame (its marker moves): nothing to average.
  dfbOptions.operation =
      o.renderer == "pattern" ? dfb::writeOperation() : dfb::accumulateOperation();
  // Like the messenger: compress the gather only where it crosses hosts.
  dfbOptions.compressGather = o.compress && !messenger.sameHost(0);
  dfbOptions.toneMap.exposure = o.exposure;
  dfbOptions.toneMap.filmic = o.filmic;
  dfbOptions.frameTimeout = std::chrono::seconds(o.timeoutSeconds);
  if (route) {
    // Tiles no display shows are never rendered; the rest are owned where they are rendered.
    driving.activeTiles = wall::tilesShownByAnyDisplay(*job.layout, o.tileSize);
    dfbOptions.ownership = renderers::activeTileOwnership(driving.activeTiles);
    dfbOptions.format = dfb::DisplayFormat::NONE;
  } else if (hasWall || endsWith(o.image, ".png")) {
    dfbOptions.format = dfb::DisplayFormat::RGBA8;
  } else if (endsWith(o.image, ".pfm")) {
    dfbOptions.format = dfb::DisplayFormat::RGBAF32;
  } else {
    dfbOptions.format = dfb::DisplayFormat::NONE;
  }
  // The pattern writes display pixels straight away, unless linear output is asked for.
  if (o.renderer == "pattern" && dfbOptions.format != dfb::DisplayFormat::RGBAF32)
    settings.displayPixels = dfbOptions.toneMap;
  const auto renderer =
      bricked ? nullptr : renderers::makeRenderer(o.renderer, job.scene, settings);
  std::unique_ptr<renderers::FrameDriver> imageDriver;
  std::unique_ptr<renderers::BrickFrameDriver> brickDriver;
  if (bricked) {
    int renderRanks = 1;
    MPI_Comm_size(renderComm, &renderRanks);
    renderers::BrickDriverOptions bricks;
    bricks.samplesPerPixel = static_cast<std::uint32_t>(o.spp);
    bricks.threads = o.threads;
    bricks.activeTiles = driving.activeTiles;
    bricks.timeout = std::chrono::seconds(o.timeoutSeconds);
    // Each rank loads only its own bricks; the ranks then exchange their bounds, as programs
    // that bring their own data do (api/DataDistributed.h).
    brickDriver = std::make_unique<renderers::BrickFrameDriver>(
        job.scene.desc, settings, bricks,
        renderers::loadOwnBricks(*job.scene.desc, o.bricks, o.replication, renderRank, renderRanks),
        renderComm);
    brickDriver->configure(dfbOptions);
    totals.sceneBytes = static_cast<double>(brickDriver->sceneBytes());
  } else {
    imageDriver = std::make_unique<renderers::FrameDriver>(*renderer, driving);
    imageDriver->configure(dfbOptions);
    if (job.scene.scivis)
      totals.sceneBytes = static_cast<double>(job.scene.scivis->content().bytes());
  }
  auto renderFrame = [&](dfb::DistributedFrameBuffer& fb, const dfb::FrameInfo& frame) {
    return brickDriver ? brickDriver->renderFrame(fb, frame) : imageDriver->renderFrame(fb, frame);
  };
  dfb::DistributedFrameBuffer dfb(messenger, renderComm, dfbOptions);
  std::shared_ptr<wall::DisplayRoutingOp> routing;
  if (route) {
    routing =
        std::make_shared<wall::DisplayRoutingOp>(messenger, *job.layout, job.roles, o.tileSize);
    dfb.addPixelOp(routing);
  }
  std::unique_ptr<wall::FrameCredits> credits;
  if (hasWall && job.worldRank == 0) credits = std::make_unique<wall::FrameCredits>(messenger);
  try {
    // Every object of every rank is registered before anyone sends.
    const auto timeout = std::chrono::seconds(o.timeoutSeconds);
    boundedBarrier(MPI_COMM_WORLD, timeout, "start-up");

    // The statistics of a frame are written once its frame time (at the next frame's start) and
    // its wall acknowledgement are known: at most frames-in-flight + 1 records wait here.
    std::deque<FrameRecord> pending;
    auto writeReady = [&](bool all) {
      while (!pending.empty()) {
        FrameRecord& f = pending.front();
        if (f.frameMs <= 0 && !all) break;
        if (credits) {
          if (!all && credits->lastPresented() < f.frame) break;
          f.displaysCompleteNs = credits->takeCompleteNs(f.frame).value_or(0);
        }
        if (statsStream) statsStream->writeFrame(f);
        pending.pop_front();
      }
    };

    auto lastProgress = Clock::now();
    const auto runStart = Clock::now();
    // What the pieces take on the wire: the messenger counts it per object, after compression.
    std::uint64_t wallWireBefore = messenger.traffic(wall::kWallNodeObject).bytesSent;
    std::uint64_t compressedBefore = messenger.counters().messagesCompressed;
    Clock::time_point previousStart;
    std::uint32_t lastFrame = 0;  // the last frame every render rank completed
    int exitCode = 0;
    for (std::uint32_t frameId = 1; frameId <= static_cast<std::uint32_t>(o.frames); ++frameId) {
      control.pollSignals();
      if (credits)
        credits->waitForPresented(static_cast<std::int64_t>(frameId) - o.framesInFlight, timeout);
      // Rank 0 decides whether this frame happens (a stop asked for by a signal on any rank ends
      // the run before it). A moving camera makes every frame its own accumulation epoch; the
      // renderers compute the camera from the frame id, so no rank needs more than this.
      FrameOrder order{{frameId, o.orbit != 0.0f ? frameId : 0u}, 0, 0};
      if (job.worldRank == 0)
        if (const std::optional<int> code = control.stopRequested())
          order.stop = 1, order.exitCode = *code;
      // Rank 0 may first wait for the wall's credit (up to the timeout): twice that is the bound.
      boundedBcast(&order, sizeof order, renderComm, 2 * timeout,
                   "frame " + std::to_string(frameId));
      if (order.stop) {
        exitCode = order.exitCode;
        break;
      }
      const dfb::FrameInfo frame = order.frame;
      const auto start = Clock::now();
      if (!pending.empty()) pending.back().frameMs = msBetween(previousStart, start);
      previousStart = start;
      writeReady(false);

      job.failIfAsked(frameId);
      const renderers::FrameReport report = renderFrame(dfb, frame);
      const dfb::FrameStats stats = dfb.stats();
      wall::DisplayRoutingOp::Sent sent;
      if (routing) sent = routing->takeSent();
      const auto relayStart = Clock::now();
      if (hasWall && !route && job.worldRank == 0)
        sent = relayToDisplays(job, messenger, frameId, dfb.imageRgba8());
      const std::uint64_t wallWire = messenger.traffic(wall::kWallNodeObject).bytesSent;
      const std::uint64_t compressed = messenger.counters().messagesCompressed;
      StageTimes& t = totals.stages;
      t.gatherRelay += msBetween(relayStart, Clock::now());
      t.render += report.renderMs;
      t.tileUnpack += stats.unpackMs;
      t.tileOperation += stats.operationMs;
      t.toneMap += stats.toneMapMs;
      if (routing) {
        const auto ns = routing->takeStageNs();
        t.cut += static_cast<double>(ns.cut) * 1e-6;
        t.send += static_cast<double>(ns.send) * 1e-6;
      }
      lastFrame = frameId;

      if (!o.statsFile.empty()) {
        // One small gather per frame, only when statistics are asked for.
        RankFrame mine{report.renderMs,
                       stats.lastSetTileToCompleteMs,
                       wallWire - wallWireBefore,
                       sent.bytes,
                       sent.pieces,
                       sent.piecesToOtherHosts,
                       compressed - compressedBefore,
                       stats.tileBytesSent,
                       static_cast<std::uint64_t>(report.tilesRendered),
                       report.samples,
                       stats.lastSetTileNs};
        const std::vector<RankFrame> all = gatherRankFrames(mine, renderComm, timeout);
        if (job.worldRank == 0) {
          FrameRecord record = combine(all);
          record.frame = frameId;
          record.rank0PixelBytes = stats.pixelBytesReceived;
          pending.push_back(record);
        }
      }
      wallWireBefore = wallWire;
      compressedBefore = compressed;

      if (job.worldRank == 0 && !o.quiet &&
          (msBetween(lastProgress, Clock::now()) > 1000 ||
           frameId == static_cast<std::uint32_t>(o.frames))) {
        lastProgress = Clock::now();
        const double seconds = msBetween(runStart, lastProgress) / 1000;
        std::printf("frame %u/%d  %.2f fps  %u spp accumulated\n", frameId, o.frames,
                    frameId / seconds, (dfb.accumulationId() + 1) * static_cast<unsigned>(o.spp));
        std::fflush(stdout);
      }
    }
    if (job.worldRank == 0 && lastFrame < static_cast<std::uint32_t>(o.frames)) {
      if (hasWall)
        control.announceLastFrame(lastFrame, exitCode, job.roles.renderRanks,
                                  job.roles.worldSize());
      if (!o.quiet) std::printf("stopped after frame %u (signal)\n", lastFrame);
    }
    if (credits) credits->waitForPresented(lastFrame, timeout);
    if (!pending.empty()) pending.back().frameMs = msBetween(previousStart, Clock::now());
    writeReady(true);
    if (brickDriver) totals.brickTiles = static_cast<double>(brickDriver->brickTilesRendered());

    if (job.worldRank == 0 && !o.image.empty() && lastFrame > 0) {
      if (endsWith(o.image, ".png"))
        wall::writePng(o.image, dfb.imageRgba8().data(), job.canvasWidth, job.canvasHeight);
      else
        writePfm(o.image, dfb.imageRgbaF32().data(), job.canvasWidth, job.canvasHeight);
    }
    return exitCode;
  } catch (const std::exception& e) {
    job.failure->fail(e.what());
  }
}

}  // namespace app
