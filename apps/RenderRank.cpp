// The render ranks' frame loop: pace against the wall, render through the DFB, feed the wall.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <deque>
#include <optional>

#include "apps/CameraPath.h"
#include "apps/FrameDirector.h"
#include "apps/FrameOrder.h"
#include "apps/Job.h"
#include "apps/Preview.h"
#include "apps/RunControl.h"
#include "apps/Stats.h"
#include "apps/StatusBoard.h"
#include "apps/Steering.h"
#include "base/BoundedWait.h"
#include "base/Collectives.h"
#include "base/Error.h"
#include "base/Timing.h"
#include "dfb/DistributedFrameBuffer.h"
#include "renderers/FrameDriver.h"
#include "renderers/Renderer.h"
#include "renderers/WorkDistribution.h"
#include "renderers/scivis/bricks/BrickFrameDriver.h"
#include "wall/image/Png.h"
#include "wall/route/DisplayRoutingOp.h"
#include "wall/route/FrameCredits.h"
#include "wall/route/PieceMessage.h"
#include "wall/route/Routing.h"
#include "wall/service/client/ServiceClient.h"

namespace app {
namespace {

using base::Clock;
using base::msBetween;

// Rank 0, idle: how often it looks at signals while waiting for a request.
constexpr auto kSignalPoll = std::chrono::milliseconds(100);
// The other render ranks, idle: the longest sleep between polls of the next frame order.
constexpr auto kIdlePoll = std::chrono::microseconds(10000);

// The first frame's camera and settings, from the scene and the command line.
FrameView initialView(const Options& o, const renderers::CameraDesc& sceneCamera) {
  FrameView v;
  v.camera = sceneCamera;
  v.exposure = o.exposure;
  v.spp = o.spp;
  v.maxDepth = o.maxDepth;
  return v;
}

DirectorOptions directorOptions(const Job& job, const FrameView& initial) {
  DirectorOptions d;
  d.initial = initial;
  d.orbitDegrees = job.options.orbit;
  // The pattern draws a new picture every frame (its marker moves): it never converges.
  d.maxSpp = job.options.renderer == "pattern" ? 0 : job.options.maxSpp;
  if (job.cameraPath) {
    const CameraPath path = *job.cameraPath;
    d.path = [path](std::uint32_t frameId) { return path.at(frameId); };
  }
  return d;
}

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// Gather mode's relay, as Tide-like walls do it: rank 0 has the whole image and sends each
// display its rectangle.
wall::DisplayRoutingOp::Sent relayToDisplays(const Job& job, messaging::Messenger& messenger,
                                             std::uint32_t frameId,
                                             const std::vector<std::uint32_t>& image) {
  wall::DisplayRoutingOp::Sent sent;
  const wall::Layout& layout = *job.layout;
  for (size_t d = 0; d < layout.displays.size(); ++d) {
    const dfb::Region& rect = layout.displays[d].rect;
    const int to = job.roles.rankOfProcess(layout.displays[d].process);
    messaging::Bytes piece = wall::packPiece(
        frameId, static_cast<int>(d), dfb::Region{0, 0, rect.width(), rect.height()}, image.data(),
        job.canvasWidth, rect.x0, rect.y0, messenger.compresses(to));
    sent.bytes += piece.size();
    sent.pieces++;
    if (!messenger.sameHost(to)) sent.piecesToOtherHosts++;
    messenger.send(to, wall::kWallNodeObject, std::move(piece));
  }
  return sent;
}

// One render rank's numbers of one frame, gathered to rank 0 for the statistics.
struct RankFrame {
  double renderMs, compositeMs;
  // Pieces for the wall: bytes on the wire (after compression), bytes before, how many, how
  // many to other hosts; messages this rank's messenger compressed.
  std::uint64_t wallBytes, wallBytesRaw, wallPieces, wallPiecesToOtherHosts, messagesCompressed;
  std::uint64_t wallMessages;  // MPI messages to the wall node
  std::uint64_t tileBytes, tiles, samples;
  std::int64_t lastSetTileNs;
  std::uint64_t previewBytes;
  std::uint64_t wallPiecesDropped;  // for wall processes the wall lost (--connect)
};

std::vector<RankFrame> gatherRankFrames(const RankFrame& mine, MPI_Comm comm,
                                        std::chrono::milliseconds timeout) {
  int rank = 0, size = 0;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  std::vector<RankFrame> all(rank == 0 ? static_cast<size_t>(size) : 0);
  MPI_Request request;
  base::checkMpi(MPI_Igather(&mine, sizeof mine, MPI_BYTE, all.data(), sizeof mine, MPI_BYTE, 0,
                             comm, &request),
                 "MPI_Igather");
  base::waitWithDeadline(request, Clock::now() + timeout,
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
    r.wallPiecesDropped += f.wallPiecesDropped;
    r.wallPiecesToOtherHosts += f.wallPiecesToOtherHosts;
    r.wallMessages += f.wallMessages;
    r.messagesCompressed += f.messagesCompressed;
    r.tileBytesSent += f.tileBytes;
    r.previewBytes += f.previewBytes;
    r.tilesRendered += f.tiles;
    r.samples += f.samples;
    r.lastSetTileNs = std::max(r.lastSetTileNs, f.lastSetTileNs);
  }
  return r;
}

}  // namespace

int runRenderRank(const Job& job, messaging::Messenger& messenger, MPI_Comm renderComm,
                  RunControl& control, Steering& steering, StatusBoard* status,
                  StatsStream* statsStream, RankTotals& totals) {
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
  // Without a wall the gathered image is only --image's, written once after the last frame.
  dfbOptions.gatherEveryFrame = hasWall;
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
        renderers::loadOwnBricks(*job.scene.desc, o.bricks, o.replication, renderRank, renderRanks,
                                 renderers::ghostModeFromName(o.ghost)),
        renderComm);
    brickDriver->configure(dfbOptions);
    totals.sceneBytes = static_cast<double>(brickDriver->sceneBytes());
    const renderers::SciVisScene::IsosurfaceStats iso = brickDriver->isosurfaceStats();
    totals.isosurfaceTriangles = static_cast<double>(iso.cameraTriangles);
    totals.shadingOnlyTriangles = static_cast<double>(iso.shadingTriangles);
    totals.isosurfaceSeconds = iso.seconds;
  } else {
    imageDriver = std::make_unique<renderers::FrameDriver>(*renderer, driving);
    imageDriver->configure(dfbOptions);
    if (job.scene.scivis) {
      totals.sceneBytes = static_cast<double>(job.scene.scivis->bytes());
      const renderers::SciVisScene::IsosurfaceStats& iso = job.scene.scivis->isosurfaceStats();
      totals.isosurfaceTriangles = static_cast<double>(iso.cameraTriangles);
      totals.shadingOnlyTriangles = static_cast<double>(iso.shadingTriangles);
      totals.isosurfaceSeconds = iso.seconds;
    }
  }
  auto renderFrame = [&](dfb::DistributedFrameBuffer& fb, const dfb::FrameInfo& frame,
                         const renderers::CameraDesc& camera) {
    return brickDriver ? brickDriver->renderFrame(fb, frame, camera)
                       : imageDriver->renderFrame(fb, frame, camera);
  };
  dfb::DistributedFrameBuffer dfb(messenger, renderComm, dfbOptions);
  std::shared_ptr<wall::DisplayRoutingOp> routing;
  std::shared_ptr<wall::service::ServicePieceSink> serviceSink;
  if (route && job.connected()) {
    serviceSink = std::make_shared<wall::service::ServicePieceSink>(
        *job.directory, renderRank, job.codec, static_cast<int>(o.timeoutSeconds) * 1000);
    routing = std::make_shared<wall::DisplayRoutingOp>(serviceSink, *job.layout, o.tileSize);
    dfb.addPixelOp(routing);
  } else if (route) {
    routing =
        std::make_shared<wall::DisplayRoutingOp>(messenger, *job.layout, job.roles, o.tileSize);
    dfb.addPixelOp(routing);
  }
  Preview* const preview = job.preview;
  if (preview) dfb.addPixelOp(preview->op());
  std::unique_ptr<wall::FrameCredits> credits;
  if (hasWall && job.worldRank == 0) {
    if (job.service) {
      credits = std::make_unique<wall::FrameCredits>();
      job.service->start(*credits, [&job](const std::string& why) { job.failure->fail(why); });
    } else {
      credits = std::make_unique<wall::FrameCredits>(messenger);
    }
  }

  // What every rank renders with now; each frame order may change it (steering).
  FrameView current = initialView(o, job.scene.desc->camera);
  auto applyView = [&](const FrameView& next) {
    if (next.exposure != current.exposure) {
      dfb::ToneMapSettings toneMap = dfbOptions.toneMap;
      toneMap.exposure = next.exposure;
      dfb.setToneMap(toneMap);
    }
    if (next.maxDepth != current.maxDepth || next.transferFunction != current.transferFunction ||
        next.opacityScale != current.opacityScale) {
      const renderers::LiveSettings live{next.maxDepth, next.transferFunction, next.opacityScale};
      if (brickDriver) brickDriver->setLiveSettings(live);
      if (renderer) renderer->setLiveSettings(live);
    }
    if (next.spp != current.spp) {
      if (brickDriver) brickDriver->setSamplesPerPixel(static_cast<std::uint32_t>(next.spp));
      if (imageDriver) imageDriver->setSamplesPerPixel(static_cast<std::uint32_t>(next.spp));
    }
    current = next;
  };
  // Rank 0 decides every frame; the others learn it from the broadcast.
  std::optional<FrameDirector> director;
  if (job.worldRank == 0) director.emplace(directorOptions(job, current));
  if (credits) steering.setPresentedProbe([&credits] { return credits->lastPresented(); });
  // Rank 0: what GET /api/status shows.
  auto publish = [&](std::uint32_t frame, bool idle) {
    if (!status || !director) return;
    for (std::string& e : director->takeErrors()) status->addError(std::move(e));
    RunStatus now;
    now.frame = frame;
    now.presented = credits ? credits->lastPresented() : 0;
    now.spp = director->epochSpp();
    now.epoch = director->epoch();
    now.idle = idle;
    now.view = current;
    now.lastRequest = director->lastRequest();
    now.lastRequestFrame = director->lastRequestFrame();
    status->publish(std::move(now));
  };
  publish(0, false);  // the control server may answer before the first frame
  try {
    // Every object of every rank is registered before anyone sends.
    const auto timeout = std::chrono::seconds(o.timeoutSeconds);
    base::boundedBarrier(MPI_COMM_WORLD, timeout, "start-up");
    const std::int64_t cpuAtStart = base::processCpuNs();

    // The statistics of a frame are written once its frame time (at the next frame's start) and
    // its wall acknowledgement are known: at most frames-in-flight + 1 records wait here.
    std::deque<FrameRecord> pending;
    auto writeReady = [&](bool all) {
      while (!pending.empty()) {
        FrameRecord& f = pending.front();
        if (f.frameMs <= 0 && !all) break;
        if (credits) {
          if (!all && credits->lastPresented() < f.frame) break;
          if (const auto times = credits->takeTimes(f.frame)) {
            f.displaysCompleteNs = times->completeNs;
            f.displaysPresentedNs = times->acknowledgedNs;
          }
        }
        if (statsStream) statsStream->writeFrame(f);
        pending.pop_front();
      }
    };

    auto lastProgress = Clock::now();
    const auto runStart = Clock::now();
    // What the pieces take on the wire: the messenger counts it per object, after compression.
    messaging::Messenger::ObjectTraffic wallBefore = messenger.traffic(wall::kWallNodeObject);
    std::uint64_t compressedBefore = messenger.counters().messagesCompressed;
    Clock::time_point previousStart;
    std::uint32_t lastFrame = 0;  // the last frame every render rank completed
    int exitCode = 0;
    bool stopped = false, idling = false;
    const std::uint32_t frames = static_cast<std::uint32_t>(o.frames);  // 0: until stopped
    std::uint32_t rosterVersion = 0;                                    // the directory's
    // Rank 0: the displays of wall processes the wall lost, for the status and the preview.
    const auto showLost = [&](const std::vector<wall::service::DirectoryProcess>& processes) {
      if (job.worldRank != 0) return;
      std::vector<std::string> names;
      std::vector<bool> lost;
      for (const wall::Display& d : job.layout->displays) {
        lost.push_back(!processes.at(static_cast<size_t>(d.process)).live);
        if (lost.back()) names.push_back(d.name);
      }
      if (status) status->setLostDisplays(std::move(names));
      if (preview) preview->setLostDisplays(std::move(lost));
    };
    if (job.directory) showLost(job.directory->processes);
    // While idle, rank 0 sends an order at least this often: the other ranks' waits are bounded
    // by the timeout (invariant 6), and a rank that died is still noticed.
    const auto heartbeat =
        std::min<std::chrono::milliseconds>(std::chrono::seconds(1), timeout / 4);
    for (std::uint32_t frameId = 1; frames == 0 || frameId <= frames;) {
      control.pollSignals();
      if (credits)
        credits->waitForPresented(static_cast<std::int64_t>(frameId) - o.framesInFlight, timeout);
      // Rank 0 decides whether this frame happens, with which camera and settings (a stop asked
      // for by a signal or a request on any rank ends the run before it).
      FrameOrder order;
      if (job.worldRank == 0) {
        std::vector<SteeringRequest> requests = steering.take();
        if (requests.empty() && frames == 0 && director->converged() && !control.stopRequested()) {
          // Converged: wait for a change without spinning, looking at signals now and then.
          // The last frame's time ends here, not when the wall wakes up.
          if (!pending.empty() && pending.back().frameMs <= 0)
            pending.back().frameMs = base::msBetween(previousStart, Clock::now());
          const auto until = Clock::now() + heartbeat;
          while (Clock::now() < until && !control.stopRequested()) {
            if (steering.waitForRequest(std::min(until, Clock::now() + kSignalPoll))) break;
            control.pollSignals();
          }
          requests = steering.take();
          order.idle = requests.empty() ? 1 : 0;
        }
        for (const SteeringRequest& r : requests)
          if (r.kind == SteeringRequest::kStop) control.askToStop(r.exitCode);
        if (!order.idle) order = director->next(frameId, requests);
        if (job.service) order.rosterVersion = job.service->rosterVersion();
        if (const std::optional<int> code = control.stopRequested())
          order.stop = 1, order.exitCode = *code, order.idle = 0;
      }
      // Rank 0 may first wait for the wall's credit (up to the timeout) or idle: twice that is
      // the bound. After an idle order the wait is long, so it backs off to (nearly) no CPU.
      base::boundedBcast(&order, sizeof order, renderComm, 2 * timeout,
                         "frame " + std::to_string(frameId),
                         idling ? kIdlePoll : std::chrono::microseconds(20));
      if (serviceSink && order.rosterVersion != rosterVersion) {
        // The pieces of this frame on go where the wall now is (Protocol.h, Roster).
        const wall::service::Roster roster =
            wall::service::shareRoster(renderComm, job.service.get(), timeout);
        serviceSink->setRoster(roster);
        rosterVersion = order.rosterVersion;
        showLost(roster.processes);
        if (statsStream) {
          std::vector<std::string> lost;
          for (const wall::Display& d : job.layout->displays)
            if (!roster.processes.at(static_cast<size_t>(d.process)).live) lost.push_back(d.name);
          statsStream->writeWallRoster(roster.version, frameId, roster.why, lost);
        }
      }
      if (order.stop) {
        exitCode = order.exitCode;
        stopped = true;
        break;
      }
      if (order.idle) {
        if (!idling) {
          messenger.setResting(true);
          idling = true;
        }
        // A serving wall hears the job's keepalives instead.
        if (job.worldRank == 0 && hasWall && !job.service)
          steering.tellWallsKeepWaiting(job.roles.renderRanks, job.roles.worldSize());
        writeReady(false);
        publish(lastFrame, true);
        continue;
      }
      if (idling) messenger.setResting(false);
      idling = false;
      applyView(order.view);
      if (job.worldRank == 0 && hasWall && order.captureSequence > 0) {
        if (job.service)
          job.service->capture(frameId, order.captureSequence);
        else
          steering.tellWallsCapture(frameId, order.captureSequence, job.roles.renderRanks,
                                    job.roles.worldSize());
      }
      const dfb::FrameInfo frame = order.frame;
      const auto start = Clock::now();
      if (!pending.empty() && pending.back().frameMs <= 0)
        pending.back().frameMs = base::msBetween(previousStart, start);
      previousStart = start;
      writeReady(false);

      job.failIfAsked(frameId);
      const renderers::FrameReport report = renderFrame(dfb, frame, order.view.camera);
      if (routing) routing->endFrame(frameId);
      const dfb::FrameStats stats = dfb.stats();
      wall::DisplayRoutingOp::Sent sent;
      if (routing) sent = routing->takeSent();
      const auto relayStart = Clock::now();
      if (hasWall && !route && job.worldRank == 0)
        sent = relayToDisplays(job, messenger, frameId, dfb.imageRgba8());
      messaging::Messenger::ObjectTraffic wallNow = messenger.traffic(wall::kWallNodeObject);
      if (serviceSink) {  // the pieces went through the service's sockets, not the messenger
        const auto traffic = serviceSink->takeTraffic();
        wallNow.bytesSent = wallBefore.bytesSent + traffic.bytes;
        wallNow.messagesSent = wallBefore.messagesSent + traffic.messages;
      }
      const std::uint64_t compressed = messenger.counters().messagesCompressed;
      StageTimes& t = totals.stages;
      t.gatherRelay += base::msBetween(relayStart, Clock::now());
      t.render += report.renderMs;
      t.renderCpu += report.renderCpuMs;
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
                       wallNow.bytesSent - wallBefore.bytesSent,
                       sent.bytes,
                       sent.pieces,
                       sent.piecesToOtherHosts,
                       compressed - compressedBefore,
                       wallNow.messagesSent - wallBefore.messagesSent,
                       stats.tileBytesSent,
                       static_cast<std::uint64_t>(report.tilesRendered),
                       report.samples,
                       stats.lastSetTileNs,
                       preview ? preview->op()->takeBytesSent() : 0,
                       serviceSink ? serviceSink->takeDropped() : 0};
        const std::vector<RankFrame> all = gatherRankFrames(mine, renderComm, timeout);
        if (job.worldRank == 0) {
          FrameRecord record = combine(all);
          record.frame = frameId;
          record.epoch = frame.epoch;
          record.requestId = order.requestId;
          record.requestNs = order.requestNs;
          record.presentedAtRequest = order.presentedAtRequest;
          record.rank0PixelBytes = stats.pixelBytesReceived;
          pending.push_back(record);
        }
      }
      wallBefore = wallNow;
      compressedBefore = compressed;
      publish(frameId, false);

      if (job.worldRank == 0 && !o.quiet &&
          (base::msBetween(lastProgress, Clock::now()) > 1000 || frameId == frames)) {
        lastProgress = Clock::now();
        const double seconds = base::msBetween(runStart, lastProgress) / 1000;
        std::printf("frame %u/%s  %.2f fps  %u spp accumulated\n", frameId,
                    frames ? std::to_string(frames).c_str() : "-", frameId / seconds,
                    (dfb.accumulationId() + 1) * static_cast<unsigned>(current.spp));
        std::fflush(stdout);
      }
      ++frameId;
    }
    if (idling) messenger.setResting(false);
    steering.setPresentedProbe({});  // the credits go with this function
    if (job.worldRank == 0 && stopped) {
      if (job.service)
        job.service->bye(lastFrame);
      else if (hasWall)
        control.announceLastFrame(lastFrame, exitCode, job.roles.renderRanks,
                                  job.roles.worldSize());
      if (!o.quiet) std::printf("stopped after frame %u\n", lastFrame);
    }
    // A serving wall learns the last frame here when the run ended by its count.
    if (job.service && !stopped) job.service->bye(lastFrame);
    if (credits) credits->waitForPresented(lastFrame, timeout);
    if (preview) preview->finish(lastFrame, timeout);
    totals.stages.processCpu = static_cast<double>(base::processCpuNs() - cpuAtStart) * 1e-6;
    if (!pending.empty() && pending.back().frameMs <= 0)
      pending.back().frameMs = base::msBetween(previousStart, Clock::now());
    writeReady(true);
    if (brickDriver) {
      totals.brickTiles = static_cast<double>(brickDriver->brickTilesRendered());
      totals.brickRaysSkipped = static_cast<double>(brickDriver->raysSkipped());
    }

    if (!dfbOptions.gatherEveryFrame && !o.image.empty() && lastFrame > 0) dfb.gatherImage();
    if (job.worldRank == 0 && !o.image.empty() && lastFrame > 0) {
      if (endsWith(o.image, ".png"))
        wall::writePng(o.image, dfb.imageRgba8().data(), job.canvasWidth, job.canvasHeight);
      else
        writePfm(o.image, dfb.imageRgbaF32().data(), job.canvasWidth, job.canvasHeight);
    }
    return exitCode;
  } catch (const std::exception& e) {
    job.failure->fail(e);
  }
}

}  // namespace app
