// The render ranks' frame loop: pace against the wall, render through the DFB, feed the wall.
#include <chrono>
#include <cstdio>

#include "apps/Job.h"
#include "dfb/DistributedFrameBuffer.h"
#include "dfb/Timing.h"
#include "renderers/FrameDriver.h"
#include "renderers/Renderer.h"
#include "renderers/WorkDistribution.h"
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

}  // namespace

std::vector<FrameRecord> runRenderRank(const Job& job, dfb::Messenger& messenger,
                                       MPI_Comm renderComm, RankTotals& totals) {
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
  const auto renderer = renderers::makeRenderer(o.renderer, *job.scene, settings);
  renderers::FrameDriver driver(*renderer, driving);
  driver.configure(dfbOptions);
  dfb::DistributedFrameBuffer dfb(messenger, renderComm, dfbOptions);
  std::shared_ptr<wall::DisplayRoutingOp> routing;
  if (route) {
    routing =
        std::make_shared<wall::DisplayRoutingOp>(messenger, *job.layout, job.roles, o.tileSize);
    dfb.addPixelOp(routing);
  }
  std::unique_ptr<wall::FrameCredits> credits;
  if (hasWall && job.worldRank == 0) credits = std::make_unique<wall::FrameCredits>(messenger);
  // Every object of every rank is registered before anyone sends.
  MPI_Barrier(MPI_COMM_WORLD);

  std::vector<FrameRecord> records;
  const auto timeout = std::chrono::seconds(o.timeoutSeconds);
  auto lastProgress = Clock::now();
  const auto runStart = Clock::now();
  Clock::time_point previousStart;
  constexpr int kCounts = 8;
  std::uint64_t wallWireBefore = messenger.traffic(wall::kWallNodeObject).bytesSent;
  std::uint64_t compressedBefore = messenger.counters().messagesCompressed;
  for (std::uint32_t frameId = 1; frameId <= static_cast<std::uint32_t>(o.frames); ++frameId) {
    if (credits)
      credits->waitForPresented(static_cast<std::int64_t>(frameId) - o.framesInFlight, timeout);
    // A moving camera makes every frame its own accumulation epoch; the renderers compute the
    // camera from the frame id, so no rank needs more than this broadcast.
    dfb::FrameInfo frame{frameId, o.orbit != 0.0f ? frameId : 0u};
    MPI_Bcast(&frame, sizeof frame, MPI_BYTE, 0, renderComm);
    const auto start = Clock::now();
    if (!records.empty()) records.back().frameMs = msBetween(previousStart, start);
    previousStart = start;

    const renderers::FrameReport report = driver.renderFrame(dfb, frame);
    const dfb::FrameStats stats = dfb.stats();
    wall::DisplayRoutingOp::Sent sent;
    if (routing) sent = routing->takeSent();
    const auto relayStart = Clock::now();
    if (hasWall && !route && job.worldRank == 0)
      sent = relayToDisplays(job, messenger, frameId, dfb.imageRgba8());
    totals.stageMs[6] += msBetween(relayStart, Clock::now());
    // What the pieces took on the wire: the messenger counts it per object, after compression.
    const std::uint64_t wallWire = messenger.traffic(wall::kWallNodeObject).bytesSent;
    const std::uint64_t compressed = messenger.counters().messagesCompressed;
    totals.stageMs[0] += report.renderMs;
    totals.stageMs[1] += stats.unpackMs;
    totals.stageMs[2] += stats.operationMs;
    totals.stageMs[3] += stats.toneMapMs;
    if (routing) {
      const auto ns = routing->takeStageNs();
      totals.stageMs[4] += static_cast<double>(ns.cut) * 1e-6;
      totals.stageMs[5] += static_cast<double>(ns.send) * 1e-6;
    }

    // One small reduction per frame for the statistics and the progress line.
    double localMs[2] = {report.renderMs, stats.lastSetTileToCompleteMs}, maxMs[2] = {0, 0};
    std::uint64_t localCounts[kCounts] = {wallWire - wallWireBefore,
                                          sent.bytes,
                                          sent.pieces,
                                          sent.piecesToOtherHosts,
                                          compressed - compressedBefore,
                                          stats.tileBytesSent,
                                          static_cast<std::uint64_t>(report.tilesRendered),
                                          report.samples};
    wallWireBefore = wallWire;
    compressedBefore = compressed;
    std::uint64_t sums[kCounts] = {};
    MPI_Reduce(localMs, maxMs, 2, MPI_DOUBLE, MPI_MAX, 0, renderComm);
    MPI_Reduce(localCounts, sums, kCounts, MPI_UINT64_T, MPI_SUM, 0, renderComm);
    std::int64_t lastSetTile = 0;
    MPI_Reduce(&stats.lastSetTileNs, &lastSetTile, 1, MPI_INT64_T, MPI_MAX, 0, renderComm);
    FrameRecord record;
    record.frame = frameId;
    record.renderMs = maxMs[0];
    record.compositeMs = maxMs[1];
    record.rank0PixelBytes = renderRank == 0 ? stats.pixelBytesReceived : 0;
    record.wallBytesSent = sums[0];
    record.wallBytesRaw = sums[1];
    record.wallPieces = sums[2];
    record.wallPiecesToOtherHosts = sums[3];
    record.messagesCompressed = sums[4];
    record.tileBytesSent = sums[5];
    record.tilesRendered = sums[6];
    record.samples = sums[7];
    record.lastSetTileNs = lastSetTile;
    records.push_back(record);

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
  if (credits) credits->waitForPresented(o.frames, timeout);
  if (!records.empty()) records.back().frameMs = msBetween(previousStart, Clock::now());

  if (job.worldRank == 0 && !o.image.empty()) {
    if (endsWith(o.image, ".png"))
      wall::writePng(o.image, dfb.imageRgba8().data(), job.canvasWidth, job.canvasHeight);
    else
      writePfm(o.image, dfb.imageRgbaF32().data(), job.canvasWidth, job.canvasHeight);
  }
  return records;
}

}  // namespace app
