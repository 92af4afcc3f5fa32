// The data-distributed API: a program's bricks rendered by renderers::BrickFrameDriver through
// the DFB, onto a wall (route mode, wall ranks at the end of the program's communicator) or into
// an image on render rank 0. The same path as `dfbwall --bricks` (apps/RenderRank.cpp), which
// loads its bricks from a scene file instead.
#include "api/DataDistributed.h"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <exception>
#include <filesystem>
#include <mutex>
#include <optional>
#include <stdexcept>

#include "api/SceneStyle.h"
#include "api/SessionTesting.h"
#include "api/WallStop.h"
#include "base/AtomicFile.h"
#include "base/BoundedWait.h"
#include "base/Error.h"
#include "base/Parallel.h"
#include "dfb/DistributedFrameBuffer.h"
#include "messaging/Messenger.h"
#include "renderers/FrameDriver.h"
#include "renderers/scivis/bricks/BrickFrameDriver.h"
#include "wall/display/DisplayPresenters.h"
#include "wall/display/WallNode.h"
#include "wall/image/Png.h"
#include "wall/layout/Layout.h"
#include "wall/layout/Ranks.h"
#include "wall/route/DisplayRoutingOp.h"
#include "wall/route/FrameCredits.h"
#include "wall/route/PieceMessage.h"
#include "wall/route/Routing.h"
#include "wall/service/client/ServiceClient.h"

namespace dfbwall {
namespace {

using Clock = std::chrono::steady_clock;

void bounded(MPI_Request& request, std::chrono::milliseconds timeout, const std::string& what) {
  base::waitWithDeadline(
      request, Clock::now() + timeout,
      what + ": another rank did not join within " + std::to_string(timeout.count()) + " ms");
}

// What render rank 0 sends for every frame: the camera (so every rank renders the same) and the
// hash of its style, which every rank compares its own with.
struct FrameOrder {
  float camera[10];
  std::uint32_t rosterVersion;  // connect: the wall's roster this frame routes with
  std::uint64_t styleHash;
};

// The first error the messenger reported on this rank. It arrives on the messenger's threads,
// where nothing can throw to the program (a message for no object, one that does not decode, a
// handler that threw): it is kept here, and the session's next collective call on this rank
// throws it (docs/design.md, "Failures").
class FirstError {
 public:
  void record(const std::string& message) {
    std::lock_guard lock(mutex_);
    if (!failed_) message_ = message;
    failed_ = true;
  }
  bool failed() const {
    std::lock_guard lock(mutex_);
    return failed_;
  }
  [[noreturn]] void raise(const std::string& then = {}) {
    std::lock_guard lock(mutex_);
    thrown_ = true;
    throw std::runtime_error(then.empty() ? message_ : message_ + "; then: " + then);
  }
  void raiseUnlessThrown() {
    std::unique_lock lock(mutex_);
    if (!failed_ || thrown_) return;
    lock.unlock();
    raise();
  }
  // In a handler: a failure that follows the recorded one (a deadline, most likely) is thrown as
  // the recorded one, the cause, with its own message appended. Returns when there is none or it
  // was thrown already, and for a std::logic_error (the handler rethrows).
  void raiseInstead(const std::exception& e) {
    if (dynamic_cast<const std::logic_error*>(&e)) return;  // a misuse, whatever else happened
    std::unique_lock lock(mutex_);
    if (!failed_ || thrown_) return;
    lock.unlock();
    raise(e.what());
  }

 private:
  mutable std::mutex mutex_;
  std::string message_;
  bool failed_ = false, thrown_ = false;
};

}  // namespace

struct Session::Impl {
  SessionOptions options;
  std::chrono::milliseconds timeout;
  MPI_Comm own = MPI_COMM_NULL;   // the program's communicator, duplicated: our collectives
  MPI_Comm role = MPI_COMM_NULL;  // render ranks or wall ranks
  int rank = 0, size = 1;
  std::optional<wall::Layout> layout;
  wall::RankRoles roles;
  int width = 0, height = 0;
  std::unique_ptr<messaging::Messenger> messenger;
  std::unique_ptr<WallStop> wallStop;
  // Shared with the messenger's error callback: the messenger, declared before it, is destroyed
  // after it and may still report an error while it stops.
  std::shared_ptr<FirstError> error = std::make_shared<FirstError>();
  bool closed = false;

  // Render ranks.
  std::vector<bool> activeTiles;
  dfb::DfbOptions dfbOptions;
  std::unique_ptr<dfb::DistributedFrameBuffer> fb;
  std::shared_ptr<wall::DisplayRoutingOp> routing;
  std::unique_ptr<wall::FrameCredits> credits;
  // With SessionOptions::connect: the wall's directory, the link to it (render rank 0) and the
  // pieces' way there (every rank).
  std::optional<wall::service::Directory> directory;
  std::shared_ptr<wall::service::ServiceClient> service;
  std::shared_ptr<wall::service::ServicePieceSink> serviceSink;
  std::uint32_t rosterVersion = 0;  // of the roster serviceSink routes with (0: the directory's)
  std::unique_ptr<renderers::BrickFrameDriver> driver;
  // Where all of this rank's rendering runs: at most options.threads threads of its own, no cap
  // on the program's TBB parallelism (renderers/Parallel.h).
  std::unique_ptr<base::TaskArena> arena;
  Style style;
  std::uint64_t hashOfStyle = 0;  // styleHash(style)
  bool styleSet = false, dirty = false, replacing = false;
  std::vector<renderers::HeldBrick> pending;  // bricks added since the last frame
  Camera camera, lastCamera;
  bool haveCamera = false;
  std::uint32_t frameId = 0, epoch = 0;

  bool isWall() const { return roles.processOfRank(rank) >= 0; }
  void setUp();  // the layout, roles and canvas; throws on bad input
  void commit();
  void startRendering();
  void renderFrame();  // in the arena
};

Session::Session(MPI_Comm comm, const SessionOptions& options) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.options = options;
  m.timeout = std::chrono::seconds(std::max(1, options.timeoutSeconds));
  int level = 0;
  MPI_Query_thread(&level);
  if (level < MPI_THREAD_MULTIPLE)
    throw std::runtime_error(
        "dfbwall: MPI must be initialised with MPI_Init_thread(..., MPI_THREAD_MULTIPLE, ...)");
  base::checkMpi(MPI_Comm_dup(comm, &m.own), "MPI_Comm_dup");
  MPI_Comm_rank(m.own, &m.rank);
  MPI_Comm_size(m.own, &m.size);
  // Setup problems (a bad layout, a rank count it does not fit, a capture folder a wall rank
  // cannot write) may show on some ranks only: the ranks agree before anything else, so every
  // rank throws (the one that found it with its message) instead of some waiting forever.
  std::string problem;
  try {
    m.setUp();
  } catch (const std::exception& e) {
    problem = e.what();
  }
  int failing = problem.empty() ? m.size : m.rank, first = 0;
  MPI_Request request;
  base::checkMpi(MPI_Iallreduce(&failing, &first, 1, MPI_INT, MPI_MIN, m.own, &request),
                 "MPI_Iallreduce");
  bounded(request, m.timeout, "dfbwall session setup");
  if (first < m.size) {
    MPI_Comm_free(&m.own);
    throw std::runtime_error(problem.empty() ? "dfbwall: rank " + std::to_string(first) +
                                                   " could not set up the session (it says why)"
                                             : problem);
  }
  if (!options.connect.empty()) {
    m.directory = wall::service::shareDirectory(m.own, m.service.get(), m.timeout);
    m.layout = m.directory->layout;
    m.width = m.layout->canvasWidth;
    m.height = m.layout->canvasHeight;
  }
  base::checkMpi(MPI_Comm_split(m.own, m.isWall() ? 1 : 0, m.rank, &m.role), "MPI_Comm_split");
  messaging::MessengerOptions messaging;
  messaging.quiesceTimeout = m.timeout;
  // The session's thread budget covers the tile inputs the messenger combines too (the dfbwall
  // executable caps both with one process-wide limit, which a program embedding us must not get).
  messaging.handlerThreads = options.threads;
  m.messenger = std::make_unique<messaging::Messenger>(m.own, messaging);
  // A message that cannot be handled arrives on a messaging thread, where nothing can throw to
  // the program: it is recorded, and thrown by this rank's next renderFrame(), close() or
  // runWall() (the library never ends the job; the program decides).
  m.messenger->setErrorCallback(
      [error = m.error, where = "dfbwall: error on rank " + std::to_string(m.rank) + " (" +
                                m.messenger->hostOf(m.rank) + "): "](const std::string& message) {
        error->record(where + message);
      });
  m.wallStop = std::make_unique<WallStop>(*m.messenger);
  if (!m.isWall()) m.startRendering();
}

void Session::Impl::startRendering() {
  const bool route = layout.has_value();
  dfbOptions.width = width;
  dfbOptions.height = height;
  dfbOptions.tileSize = options.tileSize;
  dfbOptions.frameTimeout = timeout;
  dfbOptions.compressGather = !messenger->sameHost(0);
  dfbOptions.toneMap.exposure = options.exposure;
  if (route) {
    // Tiles no display shows are never rendered; the rest are owned where they are rendered.
    activeTiles = wall::tilesShownByAnyDisplay(*layout, options.tileSize);
    dfbOptions.ownership = renderers::activeTileOwnership(activeTiles);
    dfbOptions.format = dfb::DisplayFormat::NONE;
  } else {
    dfbOptions.format = dfb::DisplayFormat::RGBA8;
  }
  // The driver's operation (composite, then accumulate): the same for every scene version.
  renderers::configureBrickDfb(dfbOptions, activeTiles);
  fb = std::make_unique<dfb::DistributedFrameBuffer>(*messenger, role, dfbOptions);
  arena = std::make_unique<base::TaskArena>(options.threads);
  if (route && directory) {
    serviceSink = std::make_shared<wall::service::ServicePieceSink>(
        *directory, rank, wall::service::parseCodec(options.codec),
        static_cast<int>(timeout.count()));
    routing = std::make_shared<wall::DisplayRoutingOp>(serviceSink, *layout, options.tileSize);
    fb->addPixelOp(routing);
    if (rank == 0) {
      credits = std::make_unique<wall::FrameCredits>();
      // The wall ending the job, or going silent, is this rank's next call's error.
      service->start(*credits,
                     [error = error](const std::string& why) { error->record("dfbwall: " + why); });
    }
  } else if (route) {
    routing =
        std::make_shared<wall::DisplayRoutingOp>(*messenger, *layout, roles, options.tileSize);
    fb->addPixelOp(routing);
    if (rank == 0) credits = std::make_unique<wall::FrameCredits>(*messenger);
  }
  // Pairs with runWall's: every object of every rank is registered before anyone sends.
  MPI_Request request;
  base::checkMpi(MPI_Ibarrier(own, &request), "MPI_Ibarrier");
  bounded(request, timeout, "dfbwall session start-up");
}

void Session::Impl::setUp() {
  if (!options.connect.empty()) {
    if (!options.wall.empty())
      throw std::runtime_error(
          "dfbwall: SessionOptions wall and connect: a wall you connect to has its own layout");
    const wall::service::CodecSpec codec = wall::service::parseCodec(options.codec);
    roles = wall::RankRoles{size, 0};  // every rank renders; the wall is elsewhere
    if (rank == 0)
      service = std::make_shared<wall::service::ServiceClient>(
          options.connect,
          wall::service::jobHello(size, options.tileSize, codec, options.framesInFlight,
                                  options.token, options.wait, options.captureDir,
                                  options.captureEvery),
          timeout);
  } else if (!options.wall.empty()) {
    layout = wall::loadLayout(options.wall);
    if (auto problem = wall::checkRankCount(*layout, size)) throw std::runtime_error(*problem);
    roles = wall::rankRoles(*layout, size);
    width = layout->canvasWidth;
    height = layout->canvasHeight;
  } else {
    if (options.width < 1 || options.height < 1)
      throw std::runtime_error("dfbwall: SessionOptions width and height must be positive");
    roles = wall::RankRoles{size, 0};
    width = options.width;
    height = options.height;
  }
  if (isWall() && !options.captureDir.empty())
    for (int d : layout->displaysOfProcess(roles.processOfRank(rank)))
      if (std::string problem =
              base::checkWritableFolder((std::filesystem::path(options.captureDir) /
                                         layout->displays[static_cast<std::size_t>(d)].name)
                                            .string());
          !problem.empty())
        throw std::runtime_error("dfbwall: capture folder " + problem);
}

Session::~Session() {
  if (!impl_ || impl_->closed) return;
  if (std::uncaught_exceptions() > 0) return;  // a failing job: MPI_Abort ends it, not us
  try {
    if (impl_->isWall()) return;  // runWall() closes on wall ranks
    close();
  } catch (const std::exception&) {
    // A destructor must not throw; the program's own error path reports what went wrong.
  }
}

bool Session::isWallRank() const { return impl_->isWall(); }
MPI_Comm Session::renderComm() const { return impl_->isWall() ? MPI_COMM_NULL : impl_->role; }
int Session::canvasWidth() const { return impl_->width; }
int Session::canvasHeight() const { return impl_->height; }

void Session::runWall() try {
  Impl& m = *impl_;
  if (!m.isWall()) throw std::logic_error("dfbwall: runWall() on a render rank");
  const int process = m.roles.processOfRank(m.rank);
  base::FloatModeGuard callersMode;  // a GL implementation may change it (llvmpipe)
  const auto presenters = wall::makeDisplayPresenters(*m.layout, process, m.options.offscreen);
  wall::WallNodeOptions options;
  options.tileSize = m.options.tileSize;
  options.captureDir = m.options.captureDir;
  options.captureEvery = m.options.captureEvery;
  options.lastFrame = 0;  // unknown: the render ranks announce it when they close
  options.timeout = m.timeout;
  options.framesAhead = static_cast<std::uint32_t>(m.options.framesInFlight) + 2;
  {
    wall::MpiWallPeers peers(*m.messenger, m.role, options.timeout);
    wall::WallNode node(*m.layout, peers, presenters->list(), options);
    const messaging::Registration pieces(*m.messenger, wall::kWallNodeObject, &node);
    m.wallStop->onLastFrame([&node](std::uint32_t last) { node.stopAfter(last); });
    // However the block is left (a throw too), the stop no longer reaches the node it leaves.
    const std::unique_ptr<WallStop, void (*)(WallStop*)> forget(
        m.wallStop.get(), [](WallStop* stop) { stop->onLastFrame({}); });
    MPI_Request request;
    base::checkMpi(MPI_Ibarrier(m.own, &request), "MPI_Ibarrier");
    bounded(request, m.timeout, "dfbwall session start-up");
    for (std::uint32_t frameId = 1;; ++frameId) {
      if (node.presentFrame(frameId).stopped) break;
      if (m.error->failed()) m.error->raise();  // the render ranks fail at their deadline
    }
    node.finish();  // captures the last frame
  }
  m.wallStop.reset();
  m.messenger->stop();
  MPI_Comm_free(&m.role);
  MPI_Comm_free(&m.own);
  m.closed = true;
  m.error->raiseUnlessThrown();
} catch (const std::exception& e) {
  impl_->error->raiseInstead(e);
  throw;
}

void Session::setStyle(const Style& style) {
  impl_->style = style;
  impl_->hashOfStyle = styleHash(style);
  impl_->styleSet = true;
  impl_->dirty = true;
}

void Session::addBrick(const Brick& brick) {
  Impl& m = *impl_;
  if (!m.styleSet) throw std::logic_error("dfbwall: addBrick() before setStyle()");
  if (!m.replacing) m.pending.clear();
  m.replacing = true;
  m.dirty = true;
  m.pending.push_back({brick.id, brickContent(m.style, brick)});
}

void Session::clearBricks() {
  impl_->pending.clear();
  impl_->replacing = true;
  impl_->dirty = true;
}

void Session::setCamera(const Camera& camera) {
  impl_->camera = camera;
  impl_->haveCamera = true;
}

void Session::Impl::commit() {
  // This rank's bricks: the ones added since the last frame, or the ones it had.
  std::vector<renderers::HeldBrick> bricks =
      replacing ? std::move(pending)
                : (driver ? driver->releaseBricks() : std::vector<renderers::HeldBrick>{});
  pending.clear();
  replacing = false;
  driver.reset();
  renderers::RenderSettings settings;
  settings.width = width;
  settings.height = height;
  settings.seed = style.seed;
  auto desc = std::make_shared<renderers::SceneDesc>(sceneDesc(style, bricks, role, timeout));
  renderers::BrickDriverOptions driving;
  driving.samplesPerPixel = static_cast<std::uint32_t>(std::max(1, style.samplesPerPixel));
  driving.threads = 0;  // no process-wide cap: the arena renderFrame runs in has the threads
  driving.activeTiles = activeTiles;
  driving.timeout = timeout;
  driver = std::make_unique<renderers::BrickFrameDriver>(std::move(desc), settings, driving,
                                                         std::move(bricks), role);
}

void Session::renderFrame() {
  Impl& m = *impl_;
  if (m.isWall()) throw std::logic_error("dfbwall: renderFrame() on a wall rank");
  if (m.closed) throw std::logic_error("dfbwall: renderFrame() after close()");
  // Render tasks set flush-to-zero and denormals-are-zero on the threads that run them, this one
  // included: the program gets its own mode back, also when the frame throws.
  base::FloatModeGuard callersMode;
  try {
    m.arena->execute([&m] { m.renderFrame(); });
  } catch (const std::exception& e) {
    m.error->raiseInstead(e);
    throw;
  }
}

void Session::Impl::renderFrame() {
  const std::uint32_t next = frameId + 1;
  // Frames in flight: rank 0 starts frame F once the wall presented F - K.
  if (credits)
    credits->waitForPresented(static_cast<std::int64_t>(next) - options.framesInFlight, timeout);
  FrameOrder order{};
  const Camera& c = camera;
  const float floats[10] = {c.position[0], c.position[1], c.position[2], c.lookAt[0], c.lookAt[1],
                            c.lookAt[2],   c.up[0],       c.up[1],       c.up[2],     c.fovY};
  std::memcpy(order.camera, floats, sizeof floats);
  order.styleHash = hashOfStyle;
  if (service) order.rosterVersion = service->rosterVersion();
  MPI_Request request;
  base::checkMpi(MPI_Ibcast(&order, sizeof order, MPI_BYTE, 0, role, &request), "MPI_Ibcast");
  bounded(request, 2 * timeout, "frame " + std::to_string(next));  // rank 0 may wait for the wall
  if (serviceSink && order.rosterVersion != rosterVersion) {
    // The wall lost a process or got one back: its pieces stop, or go to its new endpoint.
    serviceSink->setRoster(wall::service::shareRoster(role, service.get(), timeout));
    rosterVersion = order.rosterVersion;
  }
  // What the ranks must agree on, each the lowest rank it concerns as renderRanks - rank (MPI_MAX;
  // 0: none): whether any rank changed its bricks or style (a new scene version), a rank without
  // a style, a rank whose style is not render rank 0's, a rank that failed (its messenger
  // reported an error): then every rank throws here, together, instead of the others waiting
  // for it until their deadline.
  const int renderRanks = roles.renderRanks, mark = renderRanks - rank;
  const bool failed = error->failed();
  int mine[4] = {dirty || !driver ? 1 : 0, styleSet ? 0 : mark,
                 styleSet && hashOfStyle != order.styleHash ? mark : 0, failed ? mark : 0};
  int agreed[4] = {0, 0, 0, 0};
  base::checkMpi(MPI_Iallreduce(mine, agreed, 4, MPI_INT, MPI_MAX, role, &request),
                 "MPI_Iallreduce");
  bounded(request, timeout, "frame " + std::to_string(next));
  if (failed) error->raise();
  if (agreed[3])
    throw std::runtime_error("dfbwall: render rank " + std::to_string(renderRanks - agreed[3]) +
                             " failed (its error says why); the session is unusable");
  const bool anyChanged = agreed[0] != 0;
  if (anyChanged) {
    // Thrown on every rank alike, before anything changed: the session stays in step.
    if (agreed[1])
      throw std::logic_error("dfbwall: renderFrame() before setStyle() on render rank " +
                             std::to_string(renderRanks - agreed[1]));
    if (agreed[2])
      throw std::runtime_error(
          "dfbwall: the render ranks passed different styles to setStyle() (render rank " +
          std::to_string(renderRanks - agreed[2]) + " differs from render rank 0)");
    commit();
    dirty = false;
    ++epoch;
  }
  Camera used;
  std::memcpy(used.position.data(), order.camera, 3 * sizeof(float));
  std::memcpy(used.lookAt.data(), order.camera + 3, 3 * sizeof(float));
  std::memcpy(used.up.data(), order.camera + 6, 3 * sizeof(float));
  used.fovY = order.camera[9];
  if (!anyChanged && std::memcmp(&used, &lastCamera, sizeof used) != 0) ++epoch;
  lastCamera = used;
  renderers::CameraDesc cd;
  cd.position = {used.position[0], used.position[1], used.position[2]};
  cd.lookAt = {used.lookAt[0], used.lookAt[1], used.lookAt[2]};
  cd.up = {used.up[0], used.up[1], used.up[2]};
  cd.fovY = used.fovY;
  driver->renderFrame(*fb, {next, epoch}, cd);
  if (routing) routing->endFrame(next);
  frameId = next;
  if (error->failed()) error->raise();  // during this frame: the others learn at the next one
}

std::uint32_t Session::framesRendered() const { return impl_->frameId; }

std::vector<std::uint8_t> Session::image() const {
  const Impl& m = *impl_;
  if (m.isWall() || m.layout || m.rank != 0 || m.frameId == 0) return {};
  const std::vector<std::uint32_t>& pixels = m.fb->imageRgba8();
  std::vector<std::uint8_t> out(pixels.size() * 4);
  std::memcpy(out.data(), pixels.data(), out.size());
  return out;
}

void Session::writeImage(const std::string& path) const {
  const Impl& m = *impl_;
  if (m.isWall() || m.layout || m.rank != 0 || m.frameId == 0) return;
  wall::writePng(path, m.fb->imageRgba8().data(), m.width, m.height);
}

std::size_t Session::sceneBytes() const { return impl_->driver ? impl_->driver->sceneBytes() : 0; }

void Session::close() try {
  Impl& m = *impl_;
  if (m.closed) return;
  if (m.isWall()) throw std::logic_error("dfbwall: close() on a wall rank (runWall() returns)");
  if (m.rank == 0 && m.layout) {
    if (m.service)
      m.service->bye(m.frameId);
    else
      m.wallStop->announceLastFrame(m.frameId, m.roles.renderRanks, m.roles.worldSize());
    if (m.credits) m.credits->waitForPresented(m.frameId, m.timeout);
  }
  m.driver.reset();
  m.service.reset();  // after the goodbye and the last credit: its thread holds the credits
  m.credits.reset();
  m.serviceSink.reset();
  m.fb.reset();
  m.routing.reset();
  m.wallStop.reset();
  m.messenger->stop();
  MPI_Comm_free(&m.role);
  MPI_Comm_free(&m.own);
  m.closed = true;
  m.error->raiseUnlessThrown();  // one that came after the last frame
} catch (const std::exception& e) {
  impl_->error->raiseInstead(e);
  throw;
}

void SessionTesting::send(Session& session, int toRank, std::uint64_t object) {
  session.impl_->messenger->send(toRank, object, messaging::Bytes{});
}

void SessionTesting::quiesce(Session& session) { session.impl_->messenger->quiesce(); }

}  // namespace dfbwall
