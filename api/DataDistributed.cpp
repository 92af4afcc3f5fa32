// The data-distributed API: a program's bricks rendered by renderers::scivis::BrickFrameDriver
// through the DFB, onto a wall (route mode, wall ranks at the end of the program's communicator) or
// into an image on render rank 0. The same path as `dfbwall --bricks` (apps/RenderRank.cpp), which
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

#include "api/GhostExchange.h"
#include "api/SceneStyle.h"
#include "api/SessionTesting.h"
#include "base/AtomicFile.h"
#include "base/Collectives.h"
#include "base/Error.h"
#include "base/Parallel.h"
#include "dfb/DistributedFrameBuffer.h"
#include "messaging/Messenger.h"
#include "renderers/FrameDriver.h"
#include "renderers/scivis/bricks/BrickFrameDriver.h"
#include "runtime/MpiWallProcess.h"
#include "runtime/RenderWall.h"
#include "runtime/RoomView.h"
#include "runtime/SetupAgreement.h"
#include "runtime/WallControl.h"
#include "wall/display/Capture.h"
#include "wall/image/Png.h"
#include "wall/layout/Layout.h"
#include "wall/layout/Ranks.h"
#include "wall/layout/Window.h"
#include "wall/service/client/ServiceClient.h"

namespace dfbwall {
namespace {

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
  std::unique_ptr<runtime::MpiWallControl> wallControl;
  // Shared with the messenger's error callback: the messenger, declared before it, is destroyed
  // after it and may still report an error while it stops.
  std::shared_ptr<FirstError> error = std::make_shared<FirstError>();
  bool closed = false;

  // Render ranks.
  std::vector<bool> activeTiles;
  dfb::DfbOptions dfbOptions;
  std::unique_ptr<dfb::DistributedFrameBuffer> fb;
  // With SessionOptions::connect: the wall's directory and the link to it (render rank 0, until
  // the wall side takes it).
  std::optional<wall::service::Directory> directory;
  wall::service::Credentials credentials;  // what every rank presents to the wall
  std::shared_ptr<wall::service::ServiceClient> service;
  std::unique_ptr<runtime::RenderWall> wallSide;  // with a layout or a connected wall
  std::unique_ptr<renderers::scivis::BrickFrameDriver> driver;
  // Where all of this rank's rendering runs: at most options.threads threads of its own, no cap
  // on the program's TBB parallelism (base/Parallel.h).
  std::unique_ptr<base::TaskArena> arena;
  Style style;
  std::uint64_t hashOfStyle = 0;  // styleHash(style)
  bool styleSet = false, dirty = false, replacing = false;
  std::vector<renderers::scivis::HeldBrick> pending;  // bricks added since the last frame
  std::string refused;  // the first brick refused since then (the next frame's InputError)
  // The volume parts whose ghosts the session exchanges (Ghosts::Exchange): of the bricks added
  // since the last frame, and of the bricks held.
  std::vector<OwnedPart> pendingOwned, owned;
  std::size_t ghostBytes = 0;  // received at the last scene version
  Camera camera, lastCamera;
  bool haveCamera = false;
  std::uint32_t frameId = 0, epoch = 0;
  std::size_t borrowedBytes = 0;  // of the bricks the driver holds

  bool isWall() const { return roles.processOfRank(rank) >= 0; }
  // The bound of the session's own collectives: also given up at once when a rank left.
  base::Bound bound(std::chrono::milliseconds within, const std::string& what) const {
    base::Bound b = base::Bound::joinWithin(within, what);
    b.unless = [messenger = messenger.get(), what] {
      return messenger && !messenger->departed().empty() ? what + ": given up" : std::string();
    };
    return b;
  }
  void setUp();  // the layout, roles and canvas; throws on bad input
  void commit();
  void startRendering();
  void renderFrame();  // in the arena
  [[noreturn]] void throwRefusal(int refusing, std::uint32_t next);
};

Session::Session(MPI_Comm comm, const SessionOptions& options) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  if (comm == MPI_COMM_NULL)
    throw InputError("dfbwall: Session needs the program's communicator; MPI_COMM_NULL given");
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
  // Every rank throws a setup problem (the one that found it with its message).
  std::string problem;
  try {
    m.setUp();
  } catch (const std::exception& e) {
    problem = e.what();
  }
  if (const std::optional<int> first =
          runtime::firstRankWithProblem(problem, m.own, m.timeout, "dfbwall session setup")) {
    MPI_Comm_free(&m.own);
    throw std::runtime_error(problem.empty() ? "dfbwall: rank " + std::to_string(*first) +
                                                   " could not set up the session (it says why)"
                                             : problem);
  }
  if (!options.connect.empty()) {
    m.directory = wall::service::shareDirectory(m.own, m.service.get(), m.timeout);
    m.credentials = wall::service::shareCredentials(m.own, m.service.get(), m.timeout);
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
  m.wallControl = std::make_unique<runtime::MpiWallControl>(*m.messenger, m.roles.renderRanks,
                                                            m.roles.worldSize());
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
    activeTiles = runtime::routeToDisplays(dfbOptions, *layout, options.tileSize);
  } else {
    dfbOptions.format = dfb::DisplayFormat::RGBA8;
  }
  // The driver's operation (composite, then accumulate): the same for every scene version.
  renderers::scivis::configureBrickDfb(dfbOptions, activeTiles);
  fb = std::make_unique<dfb::DistributedFrameBuffer>(*messenger, role, dfbOptions);
  arena = std::make_unique<base::TaskArena>(options.threads);
  if (route) {
    runtime::RenderWallSettings w;
    w.layout = &*layout;
    w.roles = roles;
    w.tileSize = options.tileSize;
    w.framesInFlight = options.framesInFlight;
    w.timeout = timeout;
    if (directory) w.directory = &*directory;
    w.credentials = credentials;
    w.service = std::move(service);
    w.codec = wall::service::parseCodec(options.codec);
    w.mpiControl = wallControl.get();
    // The wall ending the job, or going silent, is this rank's next call's error.
    wallSide = std::make_unique<runtime::RenderWall>(
        *messenger, rank, w,
        [error = error](const std::string& why) { error->record("dfbwall: " + why); });
    wallSide->attach(*fb);
  }
  // Pairs with runWall's: every object of every rank is registered before anyone sends.
  base::barrier(own, bound(timeout, "dfbwall session start-up"));
}

void Session::Impl::setUp() {
  if (options.connect.empty() && !options.window.empty())
    throw std::runtime_error(
        "dfbwall: SessionOptions window is for connect: a window of a wall that `dfbwall serve` "
        "runs");
  if (!options.connect.empty()) {
    if (!options.wall.empty())
      throw std::runtime_error(
          "dfbwall: SessionOptions wall and connect: a wall you connect to has its own layout");
    const wall::service::CodecSpec codec = wall::service::parseCodec(options.codec);
    roles = wall::RankRoles{size, 0};  // every rank renders; the wall is elsewhere
    wall::service::Hello hello =
        wall::service::jobHello(size, options.tileSize, codec, options.framesInFlight, options.wait,
                                options.captureDir, options.captureEvery);
    hello.window = wall::parseWindowRequest(options.window);
    if (rank == 0)
      service = std::make_shared<wall::service::ServiceClient>(
          options.connect,
          wall::service::loadCredentials(
              {options.token, options.tokenFile, {}, options.serverKeyFile}, false),
          hello, timeout);
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
    if (std::string problem =
            wall::checkCaptureFolders(options.captureDir, *layout, roles.processOfRank(rank));
        !problem.empty())
      throw std::runtime_error("dfbwall: capture folder " + problem);
}

Session::~Session() {
  if (!impl_ || impl_->closed || !impl_->messenger) return;
  // No collective here (another rank may never join one): the others learn that this rank left
  // and fail at once. What the session still holds is released without waiting for anyone.
  impl_->messenger->leave();
}

bool Session::isWallRank() const { return impl_->isWall(); }
MPI_Comm Session::renderComm() const { return impl_->isWall() ? MPI_COMM_NULL : impl_->role; }
int Session::canvasWidth() const { return impl_->width; }
int Session::canvasHeight() const { return impl_->height; }

void Session::runWall() try {
  Impl& m = *impl_;
  if (!m.isWall()) throw std::logic_error("dfbwall: runWall() on a render rank");
  base::FloatModeGuard callersMode;  // a GL implementation may change it (llvmpipe)
  runtime::WallProcessSettings settings;
  settings.tileSize = m.options.tileSize;
  settings.captureDir = m.options.captureDir;
  settings.captureEvery = m.options.captureEvery;
  settings.lastFrame = 0;  // unknown: the render ranks announce it when they close
  settings.timeout = m.timeout;
  settings.framesInFlight = m.options.framesInFlight;
  settings.offscreen = m.options.offscreen;
  {
    runtime::MpiWallProcess process(*m.layout, m.roles.processOfRank(m.rank), settings);
    runtime::WallProcessHooks hooks;
    hooks.after = [&m](const wall::PresentReport&) {
      if (m.error->failed()) m.error->raise();  // the render ranks fail at their deadline
    };
    process.run(*m.messenger, m.role, m.own, *m.wallControl, hooks);
  }
  m.wallControl.reset();
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
  if (impl_->isWall()) throw std::logic_error("dfbwall: setStyle() on a wall rank");
  impl_->style = style;
  impl_->hashOfStyle = styleHash(style);
  impl_->styleSet = true;
  impl_->dirty = true;
}

void Session::addBrick(const Brick& brick) {
  Impl& m = *impl_;
  if (!m.styleSet) throw std::logic_error("dfbwall: addBrick() before setStyle()");
  if (!m.replacing) {
    m.pending.clear();
    m.pendingOwned.clear();
    m.refused.clear();
  }
  m.replacing = true;
  m.dirty = true;
  // Refused here on this rank alone; thrown by the next frame on every rank, so they stay in step.
  try {
    m.pending.push_back({brick.id, brickContent(m.style, brick)});
    for (std::size_t v = 0; v < brick.volumes.size(); ++v) {
      const VolumePart& p = brick.volumes[v];
      if (p.ghosts == Ghosts::Exchange && p.lo != p.hi)
        m.pendingOwned.push_back(
            {brick.id, v, {{p.lo[0], p.lo[1], p.lo[2]}, {p.hi[0], p.hi[1], p.hi[2]}}});
    }
  } catch (const std::runtime_error& e) {
    if (m.refused.empty()) m.refused = e.what();
  }
}

void Session::dataChanged() {
  if (impl_->isWall()) throw std::logic_error("dfbwall: dataChanged() on a wall rank");
  impl_->dirty = true;
}

void Session::refuseInput(const std::string& why) {
  Impl& m = *impl_;
  if (!m.replacing) {
    m.pending.clear();
    m.pendingOwned.clear();
  }
  m.replacing = true;
  m.dirty = true;
  if (m.refused.empty()) m.refused = why;
}

void Session::clearBricks() {
  impl_->pending.clear();
  impl_->pendingOwned.clear();
  impl_->refused.clear();
  impl_->replacing = true;
  impl_->dirty = true;
}

void Session::setCamera(const Camera& camera) {
  impl_->camera = camera;
  impl_->haveCamera = true;
}

void Session::Impl::commit() {
  // This rank's bricks: the ones added since the last frame, or the ones it had.
  std::vector<renderers::scivis::HeldBrick> bricks =
      replacing ? std::move(pending)
                : (driver ? driver->releaseBricks() : std::vector<renderers::scivis::HeldBrick>{});
  std::vector<OwnedPart> parts = replacing ? std::move(pendingOwned)
                                 : driver  ? std::move(owned)
                                           : std::vector<OwnedPart>{};
  pending.clear();
  pendingOwned.clear();
  owned.clear();
  replacing = false;
  driver.reset();
  // Every rank, with or without exchanged parts; the held bricks grow to what their renderer reads
  // (from the owned voxels they keep, for a new style with the same bricks).
  ghostBytes = exchangeGhosts(style, bricks, parts, role, bound(timeout, "ghost exchange"));
  owned = std::move(parts);
  // Borrowed voxels may have changed since they were added or last rendered (dataChanged()):
  // their value ranges are taken now, before the ranges are shared and the scenes built.
  borrowedBytes = 0;
  for (renderers::scivis::HeldBrick& b : bricks)
    for (renderers::Volume& v : b.content.volumes)
      if (v.borrowed) {
        v.updateRange();
        borrowedBytes += v.dataBytes();
      }
  renderers::RenderSettings settings;
  settings.width = width;
  settings.height = height;
  settings.seed = style.seed;
  settings.room = layout ? runtime::roomView(*layout) : nullptr;  // screens placed in a room
  auto desc = std::make_shared<renderers::SceneDesc>(sceneDesc(style, bricks, role, timeout));
  renderers::scivis::BrickDriverOptions driving;
  driving.samplesPerPixel = static_cast<std::uint32_t>(std::max(1, style.samplesPerPixel));
  driving.threads = 0;  // no process-wide cap: the arena renderFrame runs in has the threads
  driving.activeTiles = activeTiles;
  driving.timeout = timeout;
  driver = std::make_unique<renderers::scivis::BrickFrameDriver>(std::move(desc), settings, driving,
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

void Session::Impl::throwRefusal(int refusing, std::uint32_t next) {
  // The refusing rank's message, for every rank to throw alike (only on this error path).
  std::string why = refused.starts_with("dfbwall: ") ? refused.substr(9) : refused;
  int length = rank == refusing ? static_cast<int>(why.size()) : 0;
  const base::Bound b = bound(timeout, "frame " + std::to_string(next) + ": refused input");
  base::bcast(&length, sizeof length, refusing, role, b);
  why.resize(static_cast<std::size_t>(length));
  base::bcast(why.data(), length, refusing, role, b);
  // The bricks given since the last frame are dropped on every rank: the program gives them again.
  pending.clear();
  pendingOwned.clear();
  refused.clear();
  replacing = true;
  throw InputError("dfbwall: render rank " + std::to_string(refusing) +
                   " refused its input: " + why);
}

void Session::Impl::renderFrame() {
  const std::uint32_t next = frameId + 1;
  // Frames in flight: rank 0 starts frame F once the wall presented F - K.
  if (wallSide) wallSide->waitForCredit(next);
  FrameOrder order{};
  const Camera& c = camera;
  const float floats[10] = {c.position[0], c.position[1], c.position[2], c.lookAt[0], c.lookAt[1],
                            c.lookAt[2],   c.up[0],       c.up[1],       c.up[2],     c.fovY};
  std::memcpy(order.camera, floats, sizeof floats);
  order.styleHash = hashOfStyle;
  if (wallSide) order.rosterVersion = wallSide->rosterVersion();
  // Rank 0 may first wait for the wall's credit: twice the timeout is the bound.
  base::bcast(&order, sizeof order, 0, role, bound(2 * timeout, "frame " + std::to_string(next)));
  // The wall lost a process or got one back: its pieces stop, or go to its new endpoint.
  if (wallSide) wallSide->followRoster(order.rosterVersion, role);
  // What the ranks must agree on, each the lowest rank it concerns as renderRanks - rank (MPI_MAX;
  // 0: none): whether any rank changed its bricks or style (a new scene version), a rank without
  // a style, a rank whose style is not render rank 0's, a rank that failed (its messenger
  // reported an error), a rank that refused a brick: then every rank throws here, together,
  // instead of the others waiting for it until their deadline.
  const int renderRanks = roles.renderRanks, mark = renderRanks - rank;
  const bool failed = error->failed();
  int mine[5] = {dirty || !driver ? 1 : 0, styleSet ? 0 : mark,
                 styleSet && hashOfStyle != order.styleHash ? mark : 0, failed ? mark : 0,
                 refused.empty() ? 0 : mark};
  int agreed[5] = {0, 0, 0, 0, 0};
  base::allreduce(mine, agreed, 5, MPI_INT, MPI_MAX, role,
                  bound(timeout, "frame " + std::to_string(next)));
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
      throw InputError(
          "dfbwall: the render ranks passed different styles to setStyle() (render rank " +
          std::to_string(renderRanks - agreed[2]) + " differs from render rank 0)");
    if (agreed[4]) throwRefusal(renderRanks - agreed[4], next);
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
  if (wallSide) wallSide->endFrame(next);
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
std::size_t Session::borrowedBytes() const { return impl_->driver ? impl_->borrowedBytes : 0; }

std::size_t Session::ghostBytesReceived() const { return impl_->ghostBytes; }

void Session::close() try {
  Impl& m = *impl_;
  if (m.closed) return;
  if (m.isWall()) throw std::logic_error("dfbwall: close() on a wall rank (runWall() returns)");
  // The wall's processes run until told: a program does not know its frame count in advance.
  if (m.wallSide) m.wallSide->finish(m.frameId, 0, false);
  m.driver.reset();
  m.wallSide.reset();  // after the goodbye and the last credit
  m.fb.reset();
  m.wallControl.reset();
  m.messenger->stop();
  MPI_Comm_free(&m.role);
  MPI_Comm_free(&m.own);
  m.closed = true;
  m.error->raiseUnlessThrown();  // one that came after the last frame
} catch (const std::exception& e) {
  impl_->error->raiseInstead(e);
  throw;
}

void TestedSession::send(int toRank, std::uint64_t object) {
  impl().messenger->send(toRank, object, messaging::Bytes{});
}

void TestedSession::quiesce() { impl().messenger->quiesce(); }

}  // namespace dfbwall
