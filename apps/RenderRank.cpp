// The render ranks' frame loop: pace against the wall, render through the DFB, feed the wall.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <deque>
#include <optional>
#include <thread>

#include "apps/CameraPath.h"
#include "apps/FrameDirector.h"
#include "apps/FrameOrder.h"
#include "apps/Job.h"
#include "apps/Preview.h"
#include "apps/RankFrames.h"
#include "apps/RunControl.h"
#include "apps/Stats.h"
#include "apps/StatusBoard.h"
#include "apps/Steering.h"
#include "apps/StepPrefetch.h"
#include "base/Collectives.h"
#include "base/Timing.h"
#include "dfb/DistributedFrameBuffer.h"
#include "renderers/FrameDriver.h"
#include "renderers/Renderer.h"
#include "renderers/WorkDistribution.h"
#include "renderers/picture/PictureSequence.h"
#include "renderers/scivis/Registration.h"
#include "renderers/scivis/bricks/BrickFrameDriver.h"
#include "renderers/scivis/io/SciVisDesc.h"
#include "renderers/scivis/scene/SciVisScene.h"
#include "runtime/FrameBuffer.h"
#include "runtime/RenderWall.h"
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

// The tiles of `grid` that hold a pixel of `region`.
std::vector<bool> tilesMeeting(const dfb::TileGrid& grid, const dfb::Region& region) {
  std::vector<bool> out(static_cast<std::size_t>(grid.tileCount()), false);
  for (int t = 0; t < grid.tileCount(); ++t)
    out[static_cast<std::size_t>(t)] = !dfb::intersect(grid.region(t), region).empty();
  return out;
}

// --view: `image` with each kViewedDisplay replaced by the display's name.
std::string viewImagePath(std::string image, const std::string& display) {
  const std::string key = kViewedDisplay;
  for (std::size_t at = image.find(key); at != std::string::npos; at = image.find(key, at))
    image.replace(at, key.size(), display), at += display.size();
  return image;
}

// --view: the display's pixels of the gathered canvas (`width` pixels a row), as a PNG.
void writeView(const std::string& path, const std::uint32_t* canvas, int width,
               const dfb::Region& view) {
  std::vector<std::uint32_t> pixels;
  pixels.reserve(static_cast<std::size_t>(view.pixelCount()));
  for (int y = view.y0; y < view.y1; ++y) {
    const std::uint32_t* row =
        canvas + static_cast<std::size_t>(y) * static_cast<std::size_t>(width);
    pixels.insert(pixels.end(), row + view.x0, row + view.x1);
  }
  wall::writePng(path, pixels.data(), view.width(), view.height());
}

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
  // The pattern draws a new picture every frame (its marker moves): it never converges. A
  // picture is drawn whole in one sample: converged while the next frame shows the same one.
  d.maxSpp = job.options.renderer == "pattern" ? 0 : job.options.show ? 1 : job.options.maxSpp;
  if (job.options.show) {
    const std::size_t count = job.options.pictures.files.size();
    const bool loop = job.options.pictures.loop;
    d.content = [count, loop](std::uint32_t frameId) {
      return renderers::picture::pictureOfFrame(frameId, count, loop);
    };
  }
  if (job.cameraPath) {
    const CameraPath path = *job.cameraPath;
    d.path = [path](std::uint32_t frameId) { return path.at(frameId); };
    d.pathStep = [path](std::uint32_t frameId) { return path.stepAt(frameId); };
  }
  d.timeSteps = renderers::scivis::timeSteps(*job.scene.desc);
  d.fps = renderers::scivis::playbackFps(*job.scene.desc);
  return d;
}

// Renderers that draw display pixels straight away, a new picture each frame, nothing to average.
bool drawsDisplayPixels(const Options& o) { return o.renderer == "pattern" || o.show; }

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// One render rank's run, as a sequence of named steps: set up the renderers, the DFB and the
// wall; then per frame take rank 0's order, follow the wall, render, count; then end the job.
class RenderRank {
 public:
  RenderRank(const Job& job, messaging::Messenger& messenger, MPI_Comm renderComm,
             RunControl& control, runtime::MpiWallControl& wallControl, Steering& steering,
             StatusBoard* status, StatsStream* stats, RankTotals& totals);
  int run();

 private:
  void chooseFormat();
  void makeDrivers();
  renderers::scivis::BrickDriverOptions brickOptions() const;
  StepData loadStep(std::uint32_t step) const;
  void showStep(std::uint32_t step);
  void reapplyView();
  void connectWall(runtime::MpiWallControl& wallControl);
  FrameOrder orderFrame(std::uint32_t frameId);
  std::vector<SteeringRequest> waitWhileConverged();
  void waitForFrameTime(std::uint32_t frameId);
  void followWall(const FrameOrder& order, std::uint32_t frameId);
  void replan(const wall::service::Reshape& moved, std::uint32_t frameId);
  void idle();
  void renderFrame(const FrameOrder& order, std::uint32_t frameId);
  void countFrame(const FrameOrder& order, const renderers::FrameReport& report,
                  const wall::DisplayRoutingOp::Sent& sent, double relayMs, bool stepChanged);
  void applyView(const FrameView& next);
  void showLost(const std::vector<wall::service::DirectoryProcess>& processes);
  void publish(std::uint32_t frame, bool idle);
  void writeReady(bool all);
  void printProgress(std::uint32_t frameId);
  void endJob();

  const Job& job_;
  const Options& o_;
  messaging::Messenger& messenger_;
  MPI_Comm renderComm_;
  RunControl& control_;
  Steering& steering_;
  StatusBoard* status_;
  StatsStream* stats_;
  RankTotals& totals_;
  const std::chrono::milliseconds timeout_;
  // While idle, rank 0 sends an order at least this often: the other ranks' waits are bounded
  // by the timeout (invariant 6), and a rank that died is still noticed.
  const std::chrono::milliseconds heartbeat_;
  const bool hasWall_, route_;
  int renderRank_ = 0, renderRanks_ = 1;
  // What the frames are rendered for: the job's wall or window, until the wall moves the window.
  const wall::Layout* layout_ = nullptr;

  renderers::RenderSettings settings_;
  renderers::FrameDriverOptions driving_;
  dfb::DfbOptions dfbOptions_;
  std::unique_ptr<renderers::Renderer> renderer_;
  std::unique_ptr<renderers::FrameDriver> imageDriver_;
  std::unique_ptr<renderers::scivis::BrickFrameDriver> brickDriver_;
  std::unique_ptr<dfb::DistributedFrameBuffer> dfb_;
  std::optional<runtime::RenderWall> wall_;
  Preview* preview_ = nullptr;
  std::optional<FrameDirector> director_;  // rank 0 decides every frame
  FrameView current_;                      // what every rank renders with now
  // The scene as the step shown (a time series: each step's, docs/scivis.md "Time series"), the
  // whole scene of that step when rendering image-parallel, and the next step's data on its way.
  std::shared_ptr<const renderers::SceneDesc> desc_;
  std::optional<renderers::RenderScene> stepScene_;
  const std::uint32_t timeSteps_;
  std::unique_ptr<StepPrefetch> prefetch_;
  RankFrame stepTimes_{};  // of the step switched to this frame (its step fields only)

  // The statistics of a frame are written once its frame time (at the next frame's start) and
  // its wall acknowledgement are known: at most frames-in-flight + 1 records wait here.
  std::deque<FrameRecord> pending_;
  Clock::time_point runStart_, lastProgress_, previousStart_;
  messaging::Messenger::ObjectTraffic wallBefore_;
  std::uint64_t compressedBefore_ = 0;
  std::int64_t cpuAtStart_ = 0;
  std::uint32_t frames_ = 0;     // 0: until stopped
  std::uint32_t lastFrame_ = 0;  // the last frame every render rank completed
  int exitCode_ = 0;
  bool stopped_ = false, idling_ = false;
};

RenderRank::RenderRank(const Job& job, messaging::Messenger& messenger, MPI_Comm renderComm,
                       RunControl& control, runtime::MpiWallControl& wallControl,
                       Steering& steering, StatusBoard* status, StatsStream* stats,
                       RankTotals& totals)
    : job_(job),
      o_(job.options),
      messenger_(messenger),
      renderComm_(renderComm),
      control_(control),
      steering_(steering),
      status_(status),
      stats_(stats),
      totals_(totals),
      timeout_(std::chrono::seconds(job.options.timeoutSeconds)),
      heartbeat_(std::min<std::chrono::milliseconds>(std::chrono::seconds(1), timeout_ / 4)),
      hasWall_(job.layout.has_value()),
      route_(hasWall_ && !job.gatherMode()),
      desc_(job.scene.desc),
      timeSteps_(renderers::scivis::timeSteps(*job.scene.desc)),
      frames_(static_cast<std::uint32_t>(job.options.frames)) {
  MPI_Comm_rank(renderComm, &renderRank_);
  MPI_Comm_size(renderComm, &renderRanks_);
  if (job.layout) layout_ = &*job.layout;
  settings_.width = job.canvasWidth;
  settings_.height = job.canvasHeight;
  settings_.seed = o_.seed;
  settings_.maxDepth = o_.maxDepth;
  settings_.room = job.room;
  chooseFormat();
  makeDrivers();
  dfb_ = std::make_unique<dfb::DistributedFrameBuffer>(messenger, renderComm, dfbOptions_);
  connectWall(wallControl);
  preview_ = job.preview;
  if (preview_) dfb_->addPixelOp(preview_->op());
  current_ = initialView(o_, job.scene.desc->camera);
  if (job.worldRank == 0) director_.emplace(directorOptions(job, current_));
  if (timeSteps_ > 1) {
    // Step 0 is what makeDrivers loaded (the scene's sources are its); step 1 is read meanwhile.
    prefetch_ =
        std::make_unique<StepPrefetch>([this](std::uint32_t step) { return loadStep(step); });
    prefetch_->start(1);
  }
  if (wall::FrameCredits* credits = wall_ ? wall_->credits() : nullptr)
    steering_.setPresentedProbe([credits] { return credits->lastPresented(); });
}

// What the DFB finishes tiles into: pieces for the displays, a gathered image for the wall's
// gather mode or --image, or nothing.
void RenderRank::chooseFormat() {
  runtime::FrameBufferSettings fb;
  fb.width = settings_.width;
  fb.height = settings_.height;
  fb.tileSize = o_.tileSize;
  fb.timeout = timeout_;
  fb.exposure = o_.exposure;
  fb.filmic = o_.filmic;
  fb.compress = o_.compress;
  // Without a wall the gathered image is only --image's, written once after the last frame.
  fb.gatherEveryFrame = hasWall_;
  dfbOptions_ = runtime::frameBufferOptions(fb, messenger_);
  // The pattern is a new picture every frame (its marker moves), and so is a shown picture:
  // nothing to average.
  dfbOptions_.operation =
      drawsDisplayPixels(o_) ? dfb::writeOperation() : dfb::accumulateOperation();
  if (route_) {
    driving_.activeTiles = runtime::routeToDisplays(dfbOptions_, *layout_, o_.tileSize);
  } else if (hasWall_ || endsWith(o_.image, ".png")) {
    dfbOptions_.format = dfb::DisplayFormat::RGBA8;
  } else if (endsWith(o_.image, ".pfm")) {
    dfbOptions_.format = dfb::DisplayFormat::RGBAF32;
  } else {
    dfbOptions_.format = dfb::DisplayFormat::NONE;
  }
  // --view: only the tiles of those displays, as their wall would have them rendered.
  if (!job_.views.empty()) {
    const dfb::TileGrid grid(fb.width, fb.height, fb.tileSize);
    driving_.activeTiles.assign(static_cast<std::size_t>(grid.tileCount()), false);
    for (const Job::ViewedDisplay& v : job_.views) {
      const std::vector<bool> tiles = tilesMeeting(grid, v.pixels);
      for (std::size_t t = 0; t < tiles.size(); ++t)
        if (tiles[t]) driving_.activeTiles[t] = true;
    }
    dfbOptions_.ownership = renderers::activeTileOwnership(driving_.activeTiles);
  }
  // The pattern writes display pixels straight away, unless linear output is asked for.
  if (drawsDisplayPixels(o_) && dfbOptions_.format != dfb::DisplayFormat::RGBAF32)
    settings_.displayPixels = dfbOptions_.toneMap;
}

// Image-parallel: one renderer over the whole scene, tiles planned by the frame driver.
// Data-parallel (--bricks): this rank's bricks, tiles planned per brick.
renderers::scivis::BrickDriverOptions RenderRank::brickOptions() const {
  renderers::scivis::BrickDriverOptions bricks;
  bricks.samplesPerPixel = static_cast<std::uint32_t>(o_.spp);
  bricks.threads = o_.threads;
  bricks.activeTiles = driving_.activeTiles;
  bricks.timeout = timeout_;
  return bricks;
}

void RenderRank::makeDrivers() {
  driving_.distribution = renderers::distributionFromName(o_.distribution);
  driving_.samplesPerPixel = static_cast<std::uint32_t>(o_.spp);
  driving_.threads = o_.threads;
  renderers::scivis::SciVisScene::IsosurfaceStats iso;
  if (o_.bricks > 0) {
    int renderRanks = 1;
    MPI_Comm_size(renderComm_, &renderRanks);
    const renderers::scivis::BrickDriverOptions bricks = brickOptions();
    // Each rank loads only its own bricks; the ranks then exchange their bounds, as programs
    // that bring their own data do (api/DataDistributed.h).
    brickDriver_ = std::make_unique<renderers::scivis::BrickFrameDriver>(
        desc_, settings_, bricks,
        renderers::scivis::loadOwnBricks(*desc_, o_.bricks, o_.replication, renderRank_,
                                         renderRanks,
                                         renderers::scivis::ghostModeFromName(o_.ghost)),
        renderComm_);
    brickDriver_->configure(dfbOptions_);
    totals_.sceneBytes = static_cast<double>(brickDriver_->sceneBytes());
    iso = brickDriver_->isosurfaceStats();
  } else {
    const renderers::RenderScene& scene = stepScene_ ? *stepScene_ : job_.scene;
    renderer_ = renderers::makeRenderer(o_.renderer, scene, settings_);
    imageDriver_ = std::make_unique<renderers::FrameDriver>(*renderer_, driving_);
    imageDriver_->configure(dfbOptions_);
    const renderers::scivis::SciVisScene* scivis = renderers::scivis::findSciVisScene(scene);
    if (!scivis) return;
    totals_.sceneBytes = static_cast<double>(scivis->bytes());
    iso = scivis->isosurfaceStats();
  }
  totals_.isosurfaceTriangles = static_cast<double>(iso.cameraTriangles);
  totals_.shadingOnlyTriangles = static_cast<double>(iso.shadingTriangles);
  totals_.isosurfaceSeconds = iso.seconds;
}

// A time step's data on this rank, on the prefetch thread: its own bricks read and built
// (--bricks), else the whole scene of that step.
StepData RenderRank::loadStep(std::uint32_t step) const {
  const auto start = Clock::now();
  StepData data;
  data.step = step;
  data.desc = renderers::scivis::sceneAtStep(*job_.scene.desc, step);
  if (o_.bricks > 0) {
    std::vector<renderers::scivis::HeldBrick> held = renderers::scivis::loadOwnBricks(
        *data.desc, o_.bricks, o_.replication, renderRank_, renderRanks_,
        renderers::scivis::ghostModeFromName(o_.ghost));
    const auto read = Clock::now();
    data.bricks = renderers::scivis::buildBricks(data.desc, std::move(held));
    data.readMs = msBetween(start, read);
    data.buildMs = msBetween(read, Clock::now());
  } else {
    data.scene = renderers::buildRenderScene(o_.renderer, *data.desc);
    data.readMs = msBetween(start, Clock::now());
  }
  return data;
}

// Every render rank, at the same frame (the order says so): the drivers render step `step` from
// now on, and the step after it is read meanwhile.
void RenderRank::showStep(std::uint32_t step) {
  stepTimes_ = RankFrame{};
  StepData data = prefetch_->take(step, stepTimes_.stepWaitMs);
  stepTimes_.stepReadMs = data.readMs;
  stepTimes_.stepBuildMs = data.buildMs;
  const auto start = Clock::now();
  desc_ = data.desc;
  if (brickDriver_) {
    brickDriver_.reset();
    const renderers::scivis::BrickDriverOptions bricks = brickOptions();
    brickDriver_ = std::make_unique<renderers::scivis::BrickFrameDriver>(
        desc_, settings_, bricks, std::move(data.bricks), renderComm_);
  } else {
    imageDriver_.reset();
    renderer_.reset();  // before the scene it draws
    stepScene_ = std::move(data.scene);
    renderer_ = renderers::makeRenderer(o_.renderer, *stepScene_, settings_);
    imageDriver_ = std::make_unique<renderers::FrameDriver>(*renderer_, driving_);
  }
  reapplyView();
  stepTimes_.stepSwitchMs = msBetween(start, Clock::now());
  prefetch_->start((step + 1) % timeSteps_);
}

// What the frames were steered to holds on in new drivers or a new frame buffer.
void RenderRank::reapplyView() {
  dfb::ToneMapSettings toneMap = dfbOptions_.toneMap;
  toneMap.exposure = current_.exposure;
  dfb_->setToneMap(toneMap);
  const renderers::LiveSettings live{current_.maxDepth, current_.transferFunction,
                                     current_.opacityScale};
  if (brickDriver_) brickDriver_->setLiveSettings(live);
  if (renderer_) renderer_->setLiveSettings(live);
  if (brickDriver_) brickDriver_->setSamplesPerPixel(static_cast<std::uint32_t>(current_.spp));
  if (imageDriver_) imageDriver_->setSamplesPerPixel(static_cast<std::uint32_t>(current_.spp));
}

void RenderRank::connectWall(runtime::MpiWallControl& wallControl) {
  if (!hasWall_) return;
  runtime::RenderWallSettings w;
  w.layout = &*job_.layout;
  w.roles = job_.roles;
  w.gather = !route_;
  w.tileSize = o_.tileSize;
  w.framesInFlight = o_.framesInFlight;
  w.timeout = timeout_;
  if (job_.directory) w.directory = &*job_.directory;
  w.credentials = job_.credentials;
  w.service = job_.service;
  w.codec = job_.codec;
  w.mpiControl = &wallControl;
  const Job& job = job_;
  wall_.emplace(messenger_, renderRank_, w,
                [&job](const std::string& why) { job.failure->fail(why); });
  wall_->attach(*dfb_);
}

int RenderRank::run() {
  publish(0, false);  // the control server may answer before the first frame
  try {
    // Every object of every rank is registered before anyone sends.
    base::barrier(MPI_COMM_WORLD, base::Bound::joinWithin(timeout_, "start-up"));
    cpuAtStart_ = base::processCpuNs();
    runStart_ = lastProgress_ = Clock::now();
    // What the pieces take on the wire: the messenger counts it per object, after compression.
    wallBefore_ = messenger_.traffic(wall::kWallNodeObject);
    compressedBefore_ = messenger_.counters().messagesCompressed;
    if (job_.directory) showLost(job_.directory->processes);
    for (std::uint32_t frameId = 1; frames_ == 0 || frameId <= frames_;) {
      control_.pollSignals();
      if (wall_) wall_->waitForCredit(frameId);
      const FrameOrder order = orderFrame(frameId);
      followWall(order, frameId);
      if (order.stop) {
        exitCode_ = order.exitCode;
        stopped_ = true;
        break;
      }
      if (order.idle) {
        idle();
        continue;
      }
      renderFrame(order, frameId);
      ++frameId;
    }
    endJob();
    return exitCode_;
  } catch (const std::exception& e) {
    job_.failure->fail(e);
  }
}

// Rank 0 decides whether frame `frameId` happens, with which camera and settings (a stop asked
// for by a signal or a request on any rank ends the run before it); every rank learns it.
FrameOrder RenderRank::orderFrame(std::uint32_t frameId) {
  FrameOrder order;
  if (job_.worldRank == 0) {
    std::vector<SteeringRequest> requests = steering_.take();
    // A move of the window the wall sent is rendered even when the picture has converged.
    const bool moveAhead = wall_ && wall_->reshapeAhead(wall_->reshapeVersion());
    if (requests.empty() && frames_ == 0 && director_->converged() && !control_.stopRequested() &&
        !moveAhead) {
      requests = waitWhileConverged();
      order.idle = requests.empty() ? 1 : 0;
    }
    for (const SteeringRequest& r : requests)
      if (r.kind == SteeringRequest::kStop) control_.askToStop(r.exitCode);
    const std::uint32_t reshapeVersion =
        wall_ ? wall_->reshapeVersionFor(frameId, wall_->reshapeVersion()) : 0;
    if (wall_ && reshapeVersion != wall_->reshapeVersion()) director_->restartAccumulation();
    if (!order.idle) waitForFrameTime(frameId);
    if (!order.idle) order = director_->next(frameId, requests);
    if (wall_) {
      order.rosterVersion = wall_->rosterVersion();
      order.reshapeVersion = reshapeVersion;
    }
    if (const std::optional<int> code = control_.stopRequested())
      order.stop = 1, order.exitCode = *code, order.idle = 0;
  }
  // Rank 0 may first wait for the wall's credit (up to the timeout) or idle: twice that is
  // the bound. After an idle order the wait is long, so it backs off to (nearly) no CPU.
  base::Bound bound = base::Bound::joinWithin(2 * timeout_, "frame " + std::to_string(frameId));
  if (idling_) bound.maxSleep = kIdlePoll;
  base::bcast(&order, sizeof order, 0, renderComm_, bound);
  return order;
}

// Rank 0, converged: waits for a change without spinning, looking at signals now and then, up
// to a heartbeat. The last frame's time ends here, not when the wall wakes up.
std::vector<SteeringRequest> RenderRank::waitWhileConverged() {
  if (!pending_.empty() && pending_.back().frameMs <= 0)
    pending_.back().frameMs = base::msBetween(previousStart_, Clock::now());
  const auto until = Clock::now() + heartbeat_;
  while (Clock::now() < until && !control_.stopRequested()) {
    if (steering_.waitForRequest(std::min(until, Clock::now() + kSignalPoll))) break;
    control_.pollSignals();
  }
  return steering_.take();
}

// Rank 0, `dfbwall show` with several pictures: frame F (picture F-1) starts (F-1)/fps seconds
// after the first, looking at signals meanwhile.
void RenderRank::waitForFrameTime(std::uint32_t frameId) {
  if (!o_.show || o_.pictures.files.size() < 2) return;
  const auto due =
      runStart_ + std::chrono::duration_cast<Clock::duration>(
                      std::chrono::duration<double>(double(frameId - 1) / o_.pictures.fps));
  while (Clock::now() < due && !control_.stopRequested()) {
    std::this_thread::sleep_for(std::min<Clock::duration>(due - Clock::now(), kSignalPoll));
    control_.pollSignals();
  }
}

// The pieces of this frame on go where the wall now is (Protocol.h, Roster).
void RenderRank::followWall(const FrameOrder& order, std::uint32_t frameId) {
  if (!wall_) return;
  if (!order.idle && !order.stop)
    if (const std::optional<wall::service::Reshape> moved =
            wall_->followReshape(order.reshapeVersion, renderComm_))
      replan(*moved, frameId);
  const std::optional<wall::service::Roster> changed =
      wall_->followRoster(order.rosterVersion, renderComm_);
  if (!changed) return;
  showLost(changed->processes);
  if (!stats_) return;
  std::vector<std::string> lost;
  for (const wall::Display& d : layout_->displays)
    if (!changed->processes.at(static_cast<size_t>(d.process)).live) lost.push_back(d.name);
  stats_->writeWallRoster(changed->version, frameId, changed->why, lost);
}

// The wall moved or resized the job's window from this frame on (Protocol.h, Reshape): every rank
// makes its frame buffer, renderers, routing and preview anew for the new window (its canvas), as
// at the start; accumulation starts over (rank 0's director restarted it when it ordered the
// frame).
void RenderRank::replan(const wall::service::Reshape& moved, std::uint32_t frameId) {
  const base::Bound bound = base::Bound::joinWithin(timeout_, "moving the window");
  // No tile of an earlier frame is still on its way to a frame buffer about to go.
  base::barrier(renderComm_, bound);
  dfb_.reset();
  imageDriver_.reset();
  renderer_.reset();
  brickDriver_.reset();
  layout_ = &wall_->layout();
  settings_.width = layout_->canvasWidth;
  settings_.height = layout_->canvasHeight;
  chooseFormat();
  makeDrivers();
  dfb_ = std::make_unique<dfb::DistributedFrameBuffer>(messenger_, renderComm_, dfbOptions_);
  wall_->attach(*dfb_);
  // The job's page and --preview show the new window from this frame on.
  if (preview_) {
    preview_->replan(*layout_, frameId);
    dfb_->addPixelOp(preview_->op());
  }
  reapplyView();
  // Every rank's new frame buffer is registered before any sends to it.
  base::barrier(renderComm_, bound);
  if (job_.worldRank == 0) {
    // Rank 0's page: the new window's displays, and which of them the wall lost.
    if (status_) {
      std::vector<std::string> names;
      for (const wall::Display& d : layout_->displays) names.push_back(d.name);
      status_->setDisplays(std::move(names));
    }
    showLost(moved.directory.processes);
    const dfb::Region& w = moved.directory.window;
    std::printf("dfbwall: the wall moved the window to %d,%d,%d,%d from frame %u\n", w.x0, w.y0,
                w.width(), w.height(), frameId);
    std::fflush(stdout);
  }
}

void RenderRank::idle() {
  if (!idling_) {
    messenger_.setResting(true);
    idling_ = true;
  }
  if (wall_ && wall_->control()) wall_->control()->keepWaiting();
  writeReady(false);
  publish(lastFrame_, true);
}

void RenderRank::renderFrame(const FrameOrder& order, std::uint32_t frameId) {
  if (idling_) messenger_.setResting(false);
  idling_ = false;
  const bool stepChanged = order.view.timeStep != current_.timeStep;
  if (stepChanged) showStep(order.view.timeStep);
  applyView(order.view);
  if (wall_ && wall_->control() && order.captureSequence > 0)
    wall_->control()->capture(frameId, order.captureSequence);
  const auto start = Clock::now();
  if (!pending_.empty() && pending_.back().frameMs <= 0)
    pending_.back().frameMs = base::msBetween(previousStart_, start);
  previousStart_ = start;
  writeReady(false);

  job_.failIfAsked(frameId);
  const renderers::FrameReport report =
      brickDriver_ ? brickDriver_->renderFrame(*dfb_, order.frame, order.view.camera)
                   : imageDriver_->renderFrame(*dfb_, order.frame, order.view.camera);
  wall::DisplayRoutingOp::Sent sent;
  if (wall_) {
    wall_->endFrame(frameId);
    if (wall_->routing()) sent = wall_->routing()->takeSent();
  }
  const auto relayStart = Clock::now();
  if (hasWall_ && !route_ && job_.worldRank == 0)
    sent = wall_->relayGathered(frameId, dfb_->imageRgba8());
  lastFrame_ = frameId;
  countFrame(order, report, sent, base::msBetween(relayStart, Clock::now()), stepChanged);
  publish(frameId, false);
  printProgress(frameId);
}

void RenderRank::countFrame(const FrameOrder& order, const renderers::FrameReport& report,
                            const wall::DisplayRoutingOp::Sent& sent, double relayMs,
                            bool stepChanged) {
  const dfb::FrameStats stats = dfb_->stats();
  wall::service::ServicePieceSink* const serviceSink = wall_ ? wall_->serviceSink() : nullptr;
  messaging::Messenger::ObjectTraffic wallNow = messenger_.traffic(wall::kWallNodeObject);
  if (serviceSink) {  // the pieces went through the service's sockets, not the messenger
    const auto traffic = serviceSink->takeTraffic();
    wallNow.bytesSent = wallBefore_.bytesSent + traffic.bytes;
    wallNow.messagesSent = wallBefore_.messagesSent + traffic.messages;
  }
  const std::uint64_t compressed = messenger_.counters().messagesCompressed;
  StageTimes& t = totals_.stages;
  t.gatherRelay += relayMs;
  t.render += report.renderMs;
  t.renderCpu += report.renderCpuMs;
  t.tileUnpack += stats.unpackMs;
  t.tileOperation += stats.operationMs;
  t.toneMap += stats.toneMapMs;
  if (wall::DisplayRoutingOp* routing = wall_ ? wall_->routing() : nullptr) {
    const auto ns = routing->takeStageNs();
    t.cut += static_cast<double>(ns.cut) * 1e-6;
    t.send += static_cast<double>(ns.send) * 1e-6;
  }
  if (!o_.statsFile.empty()) {
    // One small gather per frame, only when statistics are asked for.
    const RankFrame mine{report.renderMs,
                         stats.lastSetTileToCompleteMs,
                         wallNow.bytesSent - wallBefore_.bytesSent,
                         sent.bytes,
                         sent.pieces,
                         sent.piecesToOtherHosts,
                         compressed - compressedBefore_,
                         wallNow.messagesSent - wallBefore_.messagesSent,
                         stats.tileBytesSent,
                         static_cast<std::uint64_t>(report.tilesRendered),
                         report.samples,
                         stats.lastSetTileNs,
                         preview_ ? preview_->op()->takeBytesSent() : 0,
                         serviceSink ? serviceSink->takeDropped() : 0,
                         stepChanged ? stepTimes_.stepReadMs : 0,
                         stepChanged ? stepTimes_.stepBuildMs : 0,
                         stepChanged ? stepTimes_.stepWaitMs : 0,
                         stepChanged ? stepTimes_.stepSwitchMs : 0};
    const std::vector<RankFrame> all = gatherRankFrames(mine, renderComm_, timeout_);
    if (job_.worldRank == 0) {
      FrameRecord record = combine(all);
      record.frame = lastFrame_;
      record.epoch = order.frame.epoch;
      record.requestId = order.requestId;
      record.requestNs = order.requestNs;
      record.presentedAtRequest = order.presentedAtRequest;
      record.rank0PixelBytes = stats.pixelBytesReceived;
      if (timeSteps_ > 1) record.timeStep = order.view.timeStep;
      record.stepChanged = stepChanged;
      pending_.push_back(record);
    }
  }
  wallBefore_ = wallNow;
  compressedBefore_ = compressed;
}

void RenderRank::applyView(const FrameView& next) {
  if (next.exposure != current_.exposure) {
    dfb::ToneMapSettings toneMap = dfbOptions_.toneMap;
    toneMap.exposure = next.exposure;
    dfb_->setToneMap(toneMap);
  }
  if (next.maxDepth != current_.maxDepth || next.transferFunction != current_.transferFunction ||
      next.opacityScale != current_.opacityScale) {
    const renderers::LiveSettings live{next.maxDepth, next.transferFunction, next.opacityScale};
    if (brickDriver_) brickDriver_->setLiveSettings(live);
    if (renderer_) renderer_->setLiveSettings(live);
  }
  if (next.spp != current_.spp) {
    if (brickDriver_) brickDriver_->setSamplesPerPixel(static_cast<std::uint32_t>(next.spp));
    if (imageDriver_) imageDriver_->setSamplesPerPixel(static_cast<std::uint32_t>(next.spp));
  }
  current_ = next;
}

// Rank 0: the displays of wall processes the wall lost, for the status and the preview.
void RenderRank::showLost(const std::vector<wall::service::DirectoryProcess>& processes) {
  if (job_.worldRank != 0) return;
  std::vector<std::string> names;
  std::vector<bool> lost;
  for (const wall::Display& d : layout_->displays) {
    lost.push_back(!processes.at(static_cast<size_t>(d.process)).live);
    if (lost.back()) names.push_back(d.name);
  }
  if (status_) status_->setLostDisplays(std::move(names));
  if (preview_) preview_->setLostDisplays(std::move(lost));
}

// Rank 0: what GET /api/status shows.
void RenderRank::publish(std::uint32_t frame, bool idle) {
  if (!status_ || !director_) return;
  for (std::string& e : director_->takeErrors()) status_->addError(std::move(e));
  wall::FrameCredits* const credits = wall_ ? wall_->credits() : nullptr;
  RunStatus now;
  now.frame = frame;
  now.presented = credits ? credits->lastPresented() : 0;
  now.spp = director_->epochSpp();
  now.epoch = director_->epoch();
  now.idle = idle;
  now.view = current_;
  now.lastRequest = director_->lastRequest();
  now.lastRequestFrame = director_->lastRequestFrame();
  now.timeSteps = timeSteps_;
  now.playing = director_->playing();
  status_->publish(std::move(now));
}

void RenderRank::writeReady(bool all) {
  wall::FrameCredits* const credits = wall_ ? wall_->credits() : nullptr;
  while (!pending_.empty()) {
    FrameRecord& f = pending_.front();
    if (f.frameMs <= 0 && !all) break;
    if (credits) {
      if (!all && credits->lastPresented() < f.frame) break;
      if (const auto times = credits->takeTimes(f.frame)) {
        f.displaysCompleteNs = times->completeNs;
        f.displaysPresentedNs = times->acknowledgedNs;
      }
    }
    if (stats_) stats_->writeFrame(f);
    pending_.pop_front();
  }
}

void RenderRank::printProgress(std::uint32_t frameId) {
  if (job_.worldRank != 0 || o_.quiet) return;
  if (base::msBetween(lastProgress_, Clock::now()) <= 1000 && frameId != frames_) return;
  lastProgress_ = Clock::now();
  const double seconds = base::msBetween(runStart_, lastProgress_) / 1000;
  std::printf("frame %u/%s  %.2f fps  %u spp accumulated\n", frameId,
              frames_ ? std::to_string(frames_).c_str() : "-", frameId / seconds,
              (dfb_->accumulationId() + 1) * static_cast<unsigned>(current_.spp));
  std::fflush(stdout);
}

// The wall learns the last frame (when it cannot know it) and presents it; the statistics and
// --image are written.
void RenderRank::endJob() {
  if (idling_) messenger_.setResting(false);
  steering_.setPresentedProbe({});  // the credits go with this rank's wall
  if (wall_) wall_->finish(lastFrame_, exitCode_, !stopped_);
  if (job_.worldRank == 0 && stopped_ && !o_.quiet)
    std::printf("stopped after frame %u\n", lastFrame_);
  if (preview_) preview_->finish(lastFrame_, timeout_);
  totals_.stages.processCpu = static_cast<double>(base::processCpuNs() - cpuAtStart_) * 1e-6;
  if (!pending_.empty() && pending_.back().frameMs <= 0)
    pending_.back().frameMs = base::msBetween(previousStart_, Clock::now());
  writeReady(true);
  if (brickDriver_) {
    totals_.brickTiles = static_cast<double>(brickDriver_->brickTilesRendered());
    totals_.brickRaysSkipped = static_cast<double>(brickDriver_->raysSkipped());
  }
  if (!dfbOptions_.gatherEveryFrame && !o_.image.empty() && lastFrame_ > 0) dfb_->gatherImage();
  if (job_.worldRank == 0 && !o_.image.empty() && lastFrame_ > 0) {
    if (!job_.views.empty())
      for (const Job::ViewedDisplay& v : job_.views)
        writeView(viewImagePath(o_.image, v.name), dfb_->imageRgba8().data(), job_.canvasWidth,
                  v.pixels);
    else if (endsWith(o_.image, ".png"))
      wall::writePng(o_.image, dfb_->imageRgba8().data(), job_.canvasWidth, job_.canvasHeight);
    else
      writePfm(o_.image, dfb_->imageRgbaF32().data(), job_.canvasWidth, job_.canvasHeight);
  }
}

}  // namespace

int runRenderRank(const Job& job, messaging::Messenger& messenger, MPI_Comm renderComm,
                  RunControl& control, runtime::MpiWallControl& wallControl, Steering& steering,
                  StatusBoard* status, StatsStream* stats, RankTotals& totals) {
  return RenderRank(job, messenger, renderComm, control, wallControl, steering, status, stats,
                    totals)
      .run();
}

}  // namespace app
