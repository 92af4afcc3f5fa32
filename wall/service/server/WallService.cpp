#include "wall/service/server/WallService.h"

#include <unistd.h>
#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <list>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

#include "base/Error.h"
#include "wall/display/Capture.h"
#include "wall/display/IdleScreen.h"
#include "wall/display/WallCaptures.h"
#include "wall/display/WallNode.h"
#include "wall/display/WindowPresenter.h"
#include "wall/display/WindowStack.h"
#include "wall/layout/Window.h"
#include "wall/service/protocol/LinkMessages.h"
#include "wall/service/protocol/Zmq.h"
#include "wall/service/server/Desk.h"
#include "wall/service/server/MemberLink.h"
#include "wall/service/server/PieceReceiver.h"

namespace wall::service {
namespace {

using Clock = std::chrono::steady_clock;

std::string hostName() {
  char name[256] = {};
  if (gethostname(name, sizeof name - 1) != 0) return "an unnamed host";
  return name;
}

// A window's part of display `d`, in the display's own coordinates (empty: it misses `d`).
dfb::Region partOnDisplay(const Display& d, const dfb::Region& window) {
  const dfb::Region part = dfb::intersect(d.rect, window);
  if (part.empty()) return {};
  return {part.x0 - d.rect.x0, part.y0 - d.rect.y0, part.x1 - d.rect.x0, part.y1 - d.rect.y0};
}

}  // namespace

struct WallService::Impl {
  const Layout& layout;
  std::vector<Presenter*> presenters;
  ServiceOptions options;
  int process = 0, processCount = 1;
  std::string address;
  std::unique_ptr<PieceReceiver> receiver;
  std::unique_ptr<Desk> desk;                  // the head
  std::unique_ptr<MemberLink> link;            // every other process
  ProcessLink* head = nullptr;                 // one of the two
  std::unique_ptr<WallCaptures> wallCaptures;  // serve --capture
  std::uint64_t wallFrames = 0;                // presented, over every job (PresentReport)

  // One shape of a job's window on this process: the layout its node sees, what it presents
  // through, and the node. A move builds the next shape beside the running one (docs/design.md,
  // "Moving and resizing a window"), its pieces under a piece session of their own.
  struct Shape {
    std::uint64_t pieceSession = 0;
    Layout seen;
    std::vector<std::unique_ptr<WindowPresenter>> parts;
    std::unique_ptr<WindowStack::Window> onStack;  // several jobs: the job's window
    // While it exists, a Raise reaches onStack (it leaves windowOf before onStack goes).
    struct Raisable {
      Impl* impl = nullptr;
      std::uint64_t session = 0;
      WindowStack::Window* window = nullptr;
      dfb::Region rect;  // the window on the canvas
      Raisable() = default;
      Raisable(const Raisable&) = delete;
      Raisable& operator=(const Raisable&) = delete;
      ~Raisable();
    } raisable;
    std::unique_ptr<LinkPeers> peers;
    std::unique_ptr<WallNode> node;
    bool waitsForFirstFrame = false;  // no display in the window: FirstFrame names it
    std::uint32_t fromFrame = 0;      // the next shape's: the frame it takes over (0: not told yet)
  };
  // A job in progress on this process, for the link's thread: its shape now (the job's thread
  // swaps it) and the next one a move built; what the next is built from.
  struct RunningJob {
    Shape* current = nullptr;
    std::unique_ptr<Shape> next;
    WallNodeOptions options;
    std::uint64_t epoch = 0;
    Codec codec = Codec::Raw;
    int renderRanks = 1;
  };

  // Commands for the main thread; the jobs in progress, by session, for the link's thread.
  std::mutex mutex;
  std::condition_variable commanded;
  std::deque<ServiceCommand> commands;
  std::map<std::uint64_t, RunningJob*> jobs;
  bool linkLost = false;
  // Several jobs at once (maxJobs > 1): the windows on this process's displays, composed and
  // presented by the main thread (composeWanted: a window changed since), and each job's thread
  // (done: it returned, to be joined).
  std::unique_ptr<WindowStack> stack;
  bool composeWanted = false;
  // Several jobs: each job's stacking order (Start, then Raise) and its window on this process's
  // displays, by session. A lock of their own: the stack's calls wake the main thread under
  // `mutex`, so they must not run under it.
  std::mutex windowsMutex;
  std::map<std::uint64_t, std::uint64_t> orders;
  struct OnStack {
    WindowStack::Window* window = nullptr;
    dfb::Region rect;  // on the canvas
  };
  std::map<std::uint64_t, std::vector<OnStack>> windowOf;  // a move: two at once
  struct JobThread {
    std::thread thread;
    std::shared_ptr<std::atomic<bool>> done;
  };
  std::list<JobThread> jobThreads;

  Impl(const Layout& l, std::vector<Presenter*> p, ServiceOptions o)
      : layout(l), presenters(std::move(p)), options(std::move(o)) {}

  void log(const std::string& line) {
    if (options.log) options.log(line);
  }
  void incoming(const ServiceCommand& c);
  void lost(const std::string& why);
  void showIdle(const std::string& status);
  // Several jobs: composes the displays whose windows changed and presents them (main thread).
  void presentWindows();
  // Keys and the mouse in this process's windows go to the job whose window is under the cursor,
  // through the head (main thread): `jobAt(display, x, y)` names it (0: the background) for a
  // point of this process's display (index among its displays, the display's pixels). Several
  // jobs: the stack's top window there; one job at a time: the job, inside its window.
  void forwardInput(const std::function<std::uint64_t(int, int, int)>& jobAt);
  void runJob(const ServiceCommand& start);
  // The job's window is no more to be raised (it is about to go).
  void forgetWindow(std::uint64_t session);
  // The job's node for `window` (its part of this process's displays, over the background or in
  // the displays' stacks), taking the pieces stamped `pieceSession`.
  std::unique_ptr<Shape> makeShape(const dfb::Region& window, std::uint64_t pieceSession,
                                   std::uint64_t session, std::uint64_t epoch,
                                   const WallNodeOptions& o);
  // Command::Reshape: builds the job's next shape (without the lock: a window added to the stack
  // asks the main thread to compose under it); the answer to send and its epoch, none when the
  // job is not on this process.
  std::optional<std::pair<ServiceCommand, std::uint64_t>> buildNext(const ServiceCommand& c);
  void startJobThread(const ServiceCommand& start);
  // Joins the job threads that returned (all: waits for every one).
  void reapJobs(bool all);
  // Command::Thumbnails (several jobs, main thread): this process's cells of every window it
  // shows, to the head.
  void sendThumbnails(const ServiceCommand& c);
};

void WallService::Impl::incoming(const ServiceCommand& c) {
  const CommandHeader& h = c.header;
  if (h.kind == Command::Raise) {
    // The job's window raised; none here yet: kept for its start (a Raise can overtake it).
    std::lock_guard windowsLock(windowsMutex);
    const auto order = static_cast<std::uint64_t>(std::max<std::int64_t>(0, h.a));
    orders[h.session] = order;
    if (const auto found = windowOf.find(h.session); found != windowOf.end()) {
      for (const OnStack& shown : found->second) shown.window->setOrder(order);
      return;
    }
    // Or the job ended here already: such orders are bounded, the oldest going first (at most
    // maxJobs jobs wait for their start on this process).
    std::size_t waiting = orders.size() - windowOf.size();
    for (auto it = orders.begin(); waiting > options.maxJobs && it != orders.end();)
      if (windowOf.count(it->first) == 0 && it->first != h.session) {
        it = orders.erase(it);
        --waiting;
      } else {
        ++it;
      }
    return;
  }
  if (h.kind == Command::Reshape) {
    if (const auto answer = buildNext(c)) head->toHead(answer->first, answer->second);
    return;
  }
  std::unique_ptr<Shape> dropped;  // a move given up: its node goes outside the lock
  {
    std::lock_guard lock(mutex);
    if (const auto found = jobs.find(h.session); found != jobs.end()) {
      RunningJob& job = *found->second;
      // Until the switch, what the job says holds for the next shape too.
      std::vector<WallNode*> nodes{job.current->node.get()};
      if (job.next) nodes.push_back(job.next->node.get());
      switch (h.kind) {
        case Command::Cancel:
          for (WallNode* node : nodes) node->stopAfter(0);
          return;
        case Command::LastFrame:
          for (WallNode* node : nodes) node->stopAfter(static_cast<std::uint32_t>(h.a));
          return;
        case Command::Abort:
          for (WallNode* node : nodes) node->abort(c.text);
          return;
        case Command::KeepWaiting:
          for (WallNode* node : nodes) node->keepWaiting();
          return;
        case Command::Capture:
          for (WallNode* node : nodes)
            node->requestCapture(static_cast<std::uint32_t>(h.a), static_cast<std::uint64_t>(h.b));
          return;
        case Command::FirstFrame:
          job.current->node->startAt(static_cast<std::uint32_t>(h.a));
          return;
        case Command::ReshapeAt:
          if (!job.next || job.next->pieceSession != h.pieceSession) return;
          if (h.a <= 0 || h.a > std::int64_t{0xffffffff}) {  // the move is given up
            receiver->detach(job.next->pieceSession);
            dropped = std::move(job.next);
            break;
          }
          job.next->fromFrame = static_cast<std::uint32_t>(h.a);
          job.next->node->startAt(job.next->fromFrame);
          return;
        default:
          break;
      }
    }
    if (!dropped && (h.kind == Command::Start || h.kind == Command::Shutdown ||
                     (h.kind == Command::Thumbnails && stack))) {
      commands.push_back(c);
      commanded.notify_all();
    }
  }
}

std::unique_ptr<WallService::Impl::Shape> WallService::Impl::makeShape(const dfb::Region& window,
                                                                       std::uint64_t pieceSession,
                                                                       std::uint64_t session,
                                                                       std::uint64_t epoch,
                                                                       const WallNodeOptions& o) {
  auto shape = std::make_unique<Shape>();
  shape->pieceSession = pieceSession;
  // A job in a window: its node sees the window's layout (what the job's directory said) and
  // presents through WindowPresenters, which put its part of each display at its offset over
  // the background. Every process takes part in the job's frames; a display the window does not
  // touch shows the background from the start of the job on. The whole canvas: as ever.
  const bool whole = window == dfb::Region{0, 0, layout.canvasWidth, layout.canvasHeight};
  shape->seen = whole ? layout : windowLayout(layout, window);
  std::vector<Presenter*> jobPresenters = presenters;
  if (stack) {
    // On top of the windows there (newest on top); it leaves the displays when the shape goes.
    // The node only trades its frames into the window's layers; the main thread presents.
    std::vector<dfb::Region> partsOf;
    for (int d : layout.displaysOfProcess(process))
      partsOf.push_back(partOnDisplay(layout.displays[static_cast<size_t>(d)], window));
    std::lock_guard windowsLock(windowsMutex);
    const auto known = orders.find(session);
    const std::uint64_t order = known != orders.end() ? known->second : WindowStack::kOnTop;
    shape->onStack = stack->add(partsOf, session, order);
    windowOf[session].push_back({shape->onStack.get(), window});
    shape->raisable.impl = this;
    shape->raisable.session = session;
    shape->raisable.window = shape->onStack.get();
    shape->raisable.rect = window;
    jobPresenters = shape->onStack->presenters();
  } else if (!whole) {
    jobPresenters.clear();
    const std::vector<int> ours = layout.displaysOfProcess(process);
    for (size_t i = 0; i < ours.size(); ++i) {
      const Display& d = layout.displays[static_cast<size_t>(ours[i])];
      const dfb::Region part = partOnDisplay(d, window);
      if (part.empty()) {
        WindowPresenter::presentBackground(*presenters[i], d.rect.width(), d.rect.height(),
                                           options.background);
        continue;
      }
      shape->parts.push_back(std::make_unique<WindowPresenter>(
          *presenters[i], d.rect.width(), d.rect.height(), part, options.background));
      jobPresenters.push_back(shape->parts.back().get());
    }
  }
  WallNodeOptions mine = o;
  // With no display in the window this process has no pieces to wait for: it waits for the
  // head's FirstFrame (or ReshapeAt), sent once the job runs, before it comes to a swap barrier.
  shape->waitsForFirstFrame = !whole && jobPresenters.empty();
  if (shape->waitsForFirstFrame) mine.firstFrame = 0;
  shape->peers = std::make_unique<LinkPeers>(*head, epoch, session, process, processCount);
  shape->node = std::make_unique<WallNode>(shape->seen, *shape->peers, jobPresenters, mine);
  return shape;
}

// Checked as a Start is (a process never trusts the head did): the window, the piece session.
std::optional<std::pair<ServiceCommand, std::uint64_t>> WallService::Impl::buildNext(
    const ServiceCommand& c) {
  const CommandHeader& h = c.header;
  WallNodeOptions o;
  std::uint64_t epoch = 0, currentPieces = 0;
  Codec codec = Codec::Raw;
  int renderRanks = 1;
  bool moving = false;
  {
    std::lock_guard lock(mutex);
    const auto found = jobs.find(h.session);
    if (found == jobs.end()) return std::nullopt;
    const RunningJob& job = *found->second;
    o = job.options;
    epoch = job.epoch;
    codec = job.codec;
    renderRanks = job.renderRanks;
    currentPieces = job.current->pieceSession;
    moving = job.next != nullptr;
  }
  ServiceCommand answer;
  answer.header.kind = Command::Reshaped;
  answer.header.session = h.session;
  answer.header.process = process;
  answer.header.pieceSession = h.pieceSession;
  const dfb::Region window{h.windowX0, h.windowY0, h.windowX1, h.windowY1};
  const std::uint64_t pieceSession = h.pieceSession;
  std::string problem;
  if (!stack)
    problem = "this wall process composes no windows (serve --max-jobs 1)";
  else if (moving)
    problem = "a move of the window is under way already";
  else if (pieceSession == 0 || pieceSession == h.session || pieceSession == currentPieces)
    problem = "the piece session " + std::to_string(pieceSession) + " is not a new one";
  else if (window.empty() || window.x0 < 0 || window.y0 < 0 || window.x1 > layout.canvasWidth ||
           window.y1 > layout.canvasHeight)
    problem = "the window " + std::to_string(window.x0) + "," + std::to_string(window.y0) + " to " +
              std::to_string(window.x1) + "," + std::to_string(window.y1) +
              " is not inside the canvas";
  std::unique_ptr<Shape> next;
  if (problem.empty()) {
    try {
      o.firstFrame = 0;  // ReshapeAt names it; until then every piece is dropped
      next = makeShape(window, pieceSession, h.session, epoch, o);
      receiver->attach(pieceSession, codec, renderRanks, next->node.get());
      std::lock_guard lock(mutex);
      const auto found = jobs.find(h.session);
      if (found == jobs.end() || found->second->next)
        problem = "the job ended or moved meanwhile";
      else
        found->second->next = std::move(next);
    } catch (const std::exception& e) {
      problem = e.what();
    }
  }
  if (next) receiver->detach(pieceSession);  // not installed: it goes (outside the lock)
  next.reset();
  answer.header.a = problem.empty() ? 1 : 0;
  if (!problem.empty()) {
    answer.text = "wall process " + std::to_string(process) + ": " + problem;
    log("could not move a job's window: " + answer.text);
  }
  return std::make_pair(answer, epoch);
}

// The head is gone for this process: the job's frame in progress is given up here (the node's
// barrier throws), and the process shows that it is out of the wall until it joined again.
void WallService::Impl::lost(const std::string& why) {
  std::lock_guard lock(mutex);
  for (const auto& [session, job] : jobs) {
    job->current->node->abort("lost the wall's head: " + why);
    if (job->next) job->next->node->abort("lost the wall's head: " + why);
  }
  commands.clear();
  linkLost = true;
  commanded.notify_all();
}

WallService::WallService(const Layout& layout, std::vector<Presenter*> presenters,
                         ServiceOptions options)
    : impl_(std::make_unique<Impl>(layout, std::move(presenters), std::move(options))) {
  Impl& m = *impl_;
  m.process = m.options.process;
  m.processCount = layout.processCount;
  const bool isHead = m.process == 0;
  const std::string headAddress = isHead ? m.options.listen : m.options.join;
  const std::string endpoint = tcpEndpoint(headAddress, isHead ? "--listen" : "--join");
  const std::string headHost = hostOf(headAddress);
  const bool loopback = isLoopback(headHost);
  // Pieces: any port, on the listen address where it is this host's (loopback, or the head's
  // own), else on every interface.
  const std::string pieceHost =
      loopback ? headHost : (isHead && headHost != "0.0.0.0" ? headHost : "0.0.0.0");
  // What others dial: --advertise (an address this process listens on), else as bound.
  std::string advertised = loopback ? headHost : advertisedHost(pieceHost);
  if (!m.options.advertise.empty()) {
    advertised = checkAdvertised(m.options.advertise, pieceHost, "--advertise");
    if (isHead) checkAdvertised(m.options.advertise, headHost, "--advertise");
  }
  if (m.options.wallCapture)
    m.wallCaptures = std::make_unique<WallCaptures>(
        layout, m.process, m.presenters, m.options.wallCapture, m.options.wallCaptureEvery,
        m.options.captureQuota, m.options.log);
  const int deadPeerMs = static_cast<int>(m.options.timeout.count());
  m.receiver = std::make_unique<PieceReceiver>("tcp://" + pieceHost + ":*", m.options.credentials,
                                               m.options.handlerThreads, deadPeerMs, m.options.log);
  const std::string mine = "tcp://" + advertised + ":" + std::to_string(m.receiver->port());
  if (isHead) {
    Desk::Setup setup;
    setup.layout = &layout;
    setup.options = m.options;
    setup.ownEndpoint = mine;
    setup.deliver = [this](const ServiceCommand& c) { impl_->incoming(c); };
    m.desk = std::make_unique<Desk>(std::move(setup));
    const std::string bound = m.desk->bind(endpoint);
    m.address = (m.options.advertise.empty() && headHost != "0.0.0.0" ? headHost : advertised) +
                ":" + std::to_string(portOf(bound));
    m.head = m.desk.get();
    m.desk->start();
  } else {
    MemberLink::Setup setup;
    setup.head = m.options.join;
    setup.credentials = m.options.credentials;
    setup.join.process = static_cast<std::uint32_t>(m.process);
    setup.join.host = hostName();
    setup.join.pieceEndpoint = mine;
    setup.join.layoutHash = layoutHash(layout);
    setup.timeout = m.options.timeout;
    setup.deliver = [this](const ServiceCommand& c) { impl_->incoming(c); };
    setup.onLost = [this](const std::string& why) { impl_->lost(why); };
    setup.log = m.options.log;
    m.link = std::make_unique<MemberLink>(std::move(setup));
    m.address = m.options.join;
    m.head = m.link.get();
    m.link->start();
  }
}

WallService::~WallService() {
  // The links stop before what they deliver to goes.
  impl_->desk.reset();
  impl_->link.reset();
}

std::string WallService::address() const { return impl_->address; }

namespace {
// A move's verdict as the window manager answers it: empty and 200 when under way.
std::string moveAnswer(const JobDesk::MoveVerdict& v, int* code) {
  using Code = JobDesk::MoveVerdict::Code;
  if (code)
    *code = v.code == Code::Moving          ? 200
            : v.code == Code::UnknownWindow ? 404
            : v.code == Code::BadWindow     ? 400
                                            : 409;
  return v.code == Code::Moving ? std::string() : v.why;
}
}  // namespace

std::string WallService::reshape(std::uint64_t session, const dfb::Region& window, int* code) {
  JobDesk::MoveVerdict v{JobDesk::MoveVerdict::Code::Conflict,
                         "only the wall's head moves windows"};
  if (impl_->desk) v = impl_->desk->reshape(session, window);
  return moveAnswer(v, code);
}

std::string WallService::moveWindow(std::uint64_t number, const dfb::Region& window, int* code) {
  JobDesk::MoveVerdict v{JobDesk::MoveVerdict::Code::Conflict,
                         "only the wall's head moves windows"};
  if (impl_->desk) v = impl_->desk->moveWindow(number, window);
  return moveAnswer(v, code);
}

std::vector<int> WallService::waitForProcesses(Clock::time_point until) {
  Impl& m = *impl_;
  if (m.link)
    return m.link->waitUntilJoined(until) ? std::vector<int>{} : std::vector<int>{m.process};
  while (true) {
    std::vector<int> absent = m.desk->absentProcesses();
    if (absent.empty() || Clock::now() >= until) return absent;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

void WallService::Impl::showIdle(const std::string& status) {
  const std::vector<int> ours = layout.displaysOfProcess(process);
  for (size_t i = 0; i < ours.size(); ++i) {
    const Display& d = layout.displays[static_cast<size_t>(ours[i])];
    IdleText text;
    text.title = d.name;
    text.lines = {"dfbwall serve \u2014 connect with: dfbwall --connect " + address, status};
    const Image image = renderIdleScreen(d.rect.width(), d.rect.height(), text);
    presenters[i]->present(image.pixels.data(), image.width, image.height);
  }
}

void WallService::Impl::runJob(const ServiceCommand& start) {
  // Everything this job's node says to the head is of the epoch the job started in.
  const std::uint64_t epoch = head->epoch();
  ServiceCommand answer;
  answer.header.session = start.header.session;
  answer.header.process = process;
  // Anything a job asks for that this process cannot do refuses the job, never ends the wall.
  // Nothing is made for it before every process said Ready: its capture folder is only checked.
  std::string problem = startProblem(start), captureDir;
  if (!problem.empty()) {
    problem = "wall process " + std::to_string(process) + " refused the job's Start: " + problem;
    log(problem);
  } else if (!start.text.empty()) {
    try {
      captureDir = resolveCaptureRequest(options.captureRoot.get(), start.text, layout, process);
    } catch (const std::exception& e) {
      problem = "capture folder on wall process " + std::to_string(process) + ": " + e.what();
    }
  }
  // The job's window, resolved by the head: checked here too (a process never trusts it did).
  const dfb::Region window{start.header.windowX0, start.header.windowY0, start.header.windowX1,
                           start.header.windowY1};
  if (problem.empty() && (window.empty() || window.x0 < 0 || window.y0 < 0 ||
                          window.x1 > layout.canvasWidth || window.y1 > layout.canvasHeight))
    problem = "wall process " + std::to_string(process) + " refused the job's window " +
              std::to_string(window.x0) + "," + std::to_string(window.y0) + " to " +
              std::to_string(window.x1) + "," + std::to_string(window.y1) + " (the canvas is " +
              std::to_string(layout.canvasWidth) + "x" + std::to_string(layout.canvasHeight) + ")";
  if (!problem.empty()) {
    answer.header.kind = Command::Ready;
    answer.header.a = 0;  // counts as this process's Done too: it runs no node for the job
    answer.text = problem;
    head->toHead(answer, epoch);
    return;
  }
  // 0: this process joins a running job; the head names its first frame once it is Ready.
  std::uint32_t firstFrame = static_cast<std::uint32_t>(std::max<std::int64_t>(0, start.header.a));
  WallNodeOptions o;
  o.tileSize = static_cast<int>(start.header.tileSize);
  o.captureDir = captureDir;
  o.captureRoot = options.captureRoot;
  o.captureQuota = options.captureQuota;
  o.captureEvery = static_cast<int>(start.header.captureEvery);
  o.lastFrame = 0;  // the job says when it ends
  o.firstFrame = firstFrame;
  o.timeout = options.timeout;
  o.framesAhead = framesAheadFor(static_cast<int>(start.header.framesInFlight));
  o.abandonOnFailure = true;
  o.wallFramesBefore = stack ? 0 : wallFrames;
  if (link) o.alive = [this] { link->mainAlive(); };
  const std::uint64_t session = start.header.session;
  if (!stack) {
    // One job at a time, on this (the main) thread: its node polls the windows while it
    // presents, and what falls inside the job's window (the one it has now: a wall of one job
    // moves none) steers it.
    const std::vector<int> ours = layout.displaysOfProcess(process);
    o.pollInput = [this, ours, window, session] {
      for (Presenter* p : presenters) p->pollEvents();
      forwardInput([&](int display, int x, int y) -> std::uint64_t {
        const dfb::Region& d =
            layout.displays[static_cast<size_t>(ours[static_cast<size_t>(display)])].rect;
        const int wx = d.x0 + x, wy = d.y0 + y;
        return wx >= window.x0 && wx < window.x1 && wy >= window.y0 && wy < window.y1 ? session : 0;
      });
    };
  }
  o.onAbandon = [this, session, epoch](const std::string& why) {
    ServiceCommand failed;
    failed.header.kind = Command::Failed;
    failed.header.session = session;
    failed.header.process = process;
    failed.text = why;
    head->toHead(failed, epoch);
  };
  std::string failure;
  std::int64_t lastPresented = 0, bytes = 0;
  RunningJob running;
  running.options = o;
  running.epoch = epoch;
  running.codec = static_cast<Codec>(start.header.codec);
  running.renderRanks = static_cast<int>(start.header.renderRanks);
  // A process that joins after a move takes the moved window's pieces.
  const std::uint64_t pieceSession =
      start.header.pieceSession != 0 ? start.header.pieceSession : session;
  struct Forget {  // however runJob leaves, no Raise is kept for the job once it went
    Impl& m;
    std::uint64_t session;
    ~Forget() { m.forgetWindow(session); }
  } forget{*this, session};
  if (stack) {
    // At the job's stacking order (a new window on top; a Raise may have come already).
    std::lock_guard windowsLock(windowsMutex);
    orders.emplace(session, static_cast<std::uint64_t>(std::max<std::int64_t>(0, start.header.b)));
  }
  std::unique_ptr<Shape> current = makeShape(window, pieceSession, session, epoch, o);
  if (current->waitsForFirstFrame) firstFrame = 0;
  running.current = current.get();
  // The shape a move replaced: its windows stay until the new shape presented a frame.
  std::unique_ptr<Shape> retired;
  {
    {
      std::lock_guard lock(mutex);
      jobs[session] = &running;
    }
    receiver->attach(pieceSession, running.codec, running.renderRanks, current->node.get());
    answer.header.kind = Command::Ready;
    answer.header.a = 1;
    head->toHead(answer, epoch);
    bool asked = false;
    try {
      if (firstFrame == 0) firstFrame = current->node->waitForStart(Clock::now() + options.timeout);
      for (std::uint32_t frameId = firstFrame; frameId > 0; ++frameId) {
        {
          // A move takes over at its frame; the old shape's pieces are no longer taken.
          std::lock_guard lock(mutex);
          if (running.next && running.next->fromFrame == frameId) {
            retired = std::move(current);
            current = std::move(running.next);
            running.current = current.get();
            receiver->detach(retired->pieceSession);
          }
        }
        const PresentReport r = current->node->presentFrame(frameId);
        if (r.stopped) {
          if (!r.failure.empty()) failure = r.failure;
          break;
        }
        if (retired && !r.abandoned) retired.reset();  // the new window shows: the old goes
        lastPresented = frameId;
        bytes += static_cast<std::int64_t>(r.bytesReceived);
        if (!stack) {  // several jobs: the main thread counts and captures what it presents
          wallFrames = r.wallFrame;
          if (wallCaptures) wallCaptures->presented(r.wallFrame);
        }
        // A closed display window stops the wall: one job at a time, its node polls the windows
        // while it presents (several: the main thread does).
        const bool closed = !stack && !r.closedDisplay.empty();
        if (!asked && (closed || (options.stopRequested && options.stopRequested()))) {
          asked = true;
          if (process != 0 && options.leaveAlone) {
            failure = "wall process " + std::to_string(process) + " was asked to stop";
            break;
          }
          ServiceCommand stop;
          stop.header.kind = Command::StopAsked;
          stop.header.process = process;
          head->toHead(stop, epoch);
        }
      }
      current->node->finish();
    } catch (const CaptureError& e) {
      // The job asked for captures it cannot have (its quota spent, a link planted, a full
      // disk): it ends, told why, rather than going on without them.
      failure = std::string("wall process ") + std::to_string(process) + ": " + e.what();
      log("ending the job: " + failure);
      o.onAbandon(failure);
    } catch (const std::exception& e) {
      // A lost head (the barrier throws) or a broken display ends this process's part in the
      // job; the head drops it, the others go on.
      if (failure.empty()) failure = e.what();
      log("gave the job up: " + failure);
    }
    std::unique_ptr<Shape> next;
    {
      std::lock_guard lock(mutex);
      jobs.erase(session);
      next = std::move(running.next);
    }
    receiver->detach(current->pieceSession);
    if (next) receiver->detach(next->pieceSession);
  }
  // The job's windows leave the displays at once.
  retired.reset();
  current.reset();
  answer.header.kind = Command::Done;
  answer.header.a = lastPresented;
  answer.header.b = bytes;
  answer.text = failure;
  head->toHead(answer, epoch);
}

WallService::Impl::Shape::Raisable::~Raisable() {
  if (!impl) return;
  std::lock_guard windowsLock(impl->windowsMutex);
  const auto found = impl->windowOf.find(session);
  if (found == impl->windowOf.end()) return;
  std::erase_if(found->second, [&](const OnStack& shown) { return shown.window == window; });
  if (found->second.empty()) impl->windowOf.erase(found);
}

void WallService::Impl::forgetWindow(std::uint64_t session) {
  std::lock_guard windowsLock(windowsMutex);
  windowOf.erase(session);
  orders.erase(session);
}

// Several jobs at once: each job's loop on its own thread, so a Start of the next comes through
// while others run.
void WallService::Impl::startJobThread(const ServiceCommand& start) {
  auto done = std::make_shared<std::atomic<bool>>(false);
  std::thread thread([this, start, done] {
    try {
      runJob(start);
    } catch (const std::exception& e) {
      log(std::string("a job's loop failed: ") + e.what());
    }
    *done = true;
    commanded.notify_all();
  });
  jobThreads.push_back({std::move(thread), std::move(done)});
}

void WallService::Impl::reapJobs(bool all) {
  for (auto it = jobThreads.begin(); it != jobThreads.end();) {
    if (!all && !*it->done) {
      ++it;
      continue;
    }
    it->thread.join();
    it = jobThreads.erase(it);
  }
}

// What the displays show while jobs run: one frame per display that changed, drawn on every
// display before any swaps (a window across two displays changes on both at once). Each such
// presentation is one of this process's wall frames (serve --capture's numbering).
void WallService::Impl::presentWindows() {
  const std::vector<int> changed = stack->compose();
  if (changed.empty()) return;
  for (int d : changed) {
    const Image& frame = stack->frame(d);
    Presenter& p = *presenters[static_cast<size_t>(d)];
    p.beginFrame(frame.width, frame.height);
    p.upload(frame.pixels.data(), frame.width, {0, 0, frame.width, frame.height});
    p.draw();
  }
  for (int d : changed) presenters[static_cast<size_t>(d)]->swap();
  ++wallFrames;
  if (wallCaptures) wallCaptures->presented(wallFrames);
}

// Only the sums of each cell travel: the pixels stay on the process that shows them.
void WallService::Impl::sendThumbnails(const ServiceCommand& c) {
  const int side = static_cast<int>(std::clamp<std::int64_t>(c.header.b, 1, kMaxThumbnailSide));
  struct Taken {
    std::uint64_t session = 0;
    dfb::Region window;
    std::vector<WindowStack::Window::Shown> parts;
  };
  std::vector<Taken> taken;
  {
    std::lock_guard windowsLock(windowsMutex);  // no window goes while it is read
    for (const auto& [session, shown] : windowOf)
      for (const OnStack& each : shown) taken.push_back({session, each.rect, each.window->shown()});
  }
  const std::vector<int> ours = layout.displaysOfProcess(process);
  for (const Taken& t : taken) {
    const ThumbnailGrid grid = thumbnailGrid(t.window.width(), t.window.height(), side);
    // Where each part's first pixel is in the window, and every cell they touch.
    std::vector<std::pair<int, int>> at;
    dfb::Region cells;
    for (const WindowStack::Window::Shown& p : t.parts) {
      const dfb::Region& d =
          layout.displays[static_cast<size_t>(ours[static_cast<size_t>(p.display)])].rect;
      at.emplace_back(d.x0 + p.part.x0 - t.window.x0, d.y0 + p.part.y0 - t.window.y0);
      if (!p.pixels) continue;
      const dfb::Region touched =
          cellsOf(grid, {at.back().first, at.back().second, at.back().first + p.part.width(),
                         at.back().second + p.part.height()});
      cells = cells.empty()
                  ? touched
                  : dfb::Region{std::min(cells.x0, touched.x0), std::min(cells.y0, touched.y0),
                                std::max(cells.x1, touched.x1), std::max(cells.y1, touched.y1)};
    }
    if (cells.empty()) continue;  // no frame of the window shown here yet
    ThumbnailPart part;
    part.request = static_cast<std::uint32_t>(c.header.a);
    part.window = t.window;
    part.cells = emptySums(cells);
    for (size_t i = 0; i < t.parts.size(); ++i)
      if (t.parts[i].pixels)
        addPixels(part.cells, grid, *t.parts[i].pixels, at[i].first, at[i].second);
    head->thumbnail(t.session, part);
  }
}

static_assert(static_cast<std::uint32_t>(WallKey::Left) == WindowInput::kLeft &&
                  static_cast<std::uint32_t>(WallKey::Minus) == WindowInput::kMinus,
              "the wire's keys are WallKey's");

void WallService::Impl::forwardInput(const std::function<std::uint64_t(int, int, int)>& jobAt) {
  const std::vector<int> ours = layout.displaysOfProcess(process);
  for (size_t i = 0; i < presenters.size(); ++i) {
    for (const WallInput& in : presenters[i]->takeInput()) {
      // Esc stops a single job's wall; on a service wall, which outlives its jobs and may be
      // shared, a stray press would end someone's work.
      if (in.kind == WallInput::Kind::Key && in.key == WallKey::Escape) continue;
      const std::uint64_t session = jobAt(static_cast<int>(i), in.x, in.y);
      if (session == 0) continue;  // over the background
      const Display& d = layout.displays[static_cast<size_t>(ours[i])];
      WindowInput w;
      w.kind = in.kind == WallInput::Kind::Key    ? WindowInput::kKey
               : in.kind == WallInput::Kind::Drag ? WindowInput::kDrag
                                                  : WindowInput::kScroll;
      w.key = static_cast<std::uint32_t>(in.key);
      w.x = d.rect.x0 + in.x;
      w.y = d.rect.y0 + in.y;
      w.dx = std::clamp(in.dx, -kMaxInputMove, kMaxInputMove);
      w.dy = std::clamp(in.dy, -kMaxInputMove, kMaxInputMove);
      w.pan = in.pan;
      const messaging::Bytes packed = packInput(session, w);
      ServiceCommand c;
      c.header.kind = Command::Input;
      c.header.session = session;
      c.header.process = process;
      c.text.assign(reinterpret_cast<const char*>(packed.data()), packed.size());
      head->toHead(c, head->epoch());
    }
  }
}

void WallService::run() {
  Impl& m = *impl_;
  if (m.options.maxJobs > 1 && !m.stack) {
    std::vector<WindowStack::Size> sizes;
    for (int d : m.layout.displaysOfProcess(m.process))
      sizes.push_back({m.layout.displays[static_cast<size_t>(d)].rect.width(),
                       m.layout.displays[static_cast<size_t>(d)].rect.height()});
    m.stack = std::make_unique<WindowStack>(std::move(sizes), m.options.background, [&m] {
      std::lock_guard lock(m.mutex);
      m.composeWanted = true;
      m.commanded.notify_all();
    });
  }
  // Every job's thread ends before this returns (the desk ends the jobs before its shutdown; a
  // lost head aborts them).
  struct Joiner {
    Impl& m;
    ~Joiner() { m.reapJobs(true); }
  } joiner{m};
  bool idleShown = false, wasJoined = true, asked = false;
  while (true) {
    std::optional<ServiceCommand> command;
    bool lostNow = false;
    {
      std::unique_lock lock(m.mutex);
      m.commanded.wait_for(lock, std::chrono::milliseconds(50),
                           [&] { return !m.commands.empty() || m.linkLost || m.composeWanted; });
      m.composeWanted = false;
      if (!m.commands.empty()) {
        command = std::move(m.commands.front());
        m.commands.pop_front();
      }
      lostNow = m.linkLost;
      m.linkLost = false;
    }
    if (m.link && !m.link->refusal().empty())
      throw base::Error("the wall's head at " + m.address +
                        " refused this process: " + m.link->refusal());
    const bool joined = !m.link || m.link->joined();
    // Asked to stop, this process waits for the head's shutdown; without a head there is none.
    if (asked && !joined) return;
    if (!m.jobThreads.empty()) {
      const std::size_t before = m.jobThreads.size();
      m.reapJobs(false);
      if (m.jobThreads.empty() && before > 0) idleShown = false;  // the wall's last job ended
    }
    if (m.jobThreads.empty() && (!idleShown || lostNow || joined != wasJoined)) {
      m.showIdle(joined ? "waiting for a render job"
                        : "not in the wall: joining the head at " + m.address + " again");
      idleShown = true;
      wasJoined = joined;
    }
    if (m.stack && m.jobThreads.empty()) m.stack->dropChanges();  // the idle screen shows
    if (m.stack && !m.jobThreads.empty()) {
      try {
        m.presentWindows();
      } catch (const std::exception& e) {
        // A display that fails ends this process's part in every job (their threads then
        // return, so the Joiner does not wait for their timeouts), then the process.
        std::lock_guard lock(m.mutex);
        const std::string why = std::string("a display of wall process ") +
                                std::to_string(m.process) + " failed: " + e.what();
        for (const auto& [session, job] : m.jobs) {
          job->current->node->abort(why);
          if (job->next) job->next->node->abort(why);
        }
        throw;
      }
    }
    if (m.link) m.link->mainAlive();
    for (Presenter* p : m.presenters) p->pollEvents();
    // Between jobs of a one-job wall nobody is steered: the events are dropped.
    m.forwardInput([&m](int display, int x, int y) -> std::uint64_t {
      return m.stack ? m.stack->topAt(display, x, y) : 0;
    });
    bool closed = false;
    for (Presenter* p : m.presenters) closed = closed || p->closeRequested();
    if (!asked && (closed || (m.options.stopRequested && m.options.stopRequested()))) {
      asked = true;
      // Out of the wall (or told to leave it alone), a process simply stops; otherwise the
      // head stops the wall.
      if (m.link && (m.options.leaveAlone || !joined)) return;
      ServiceCommand stop;
      stop.header.kind = Command::StopAsked;
      stop.header.process = m.process;
      m.head->toHead(stop, m.head->epoch());
    }
    if (!command) continue;
    if (command->header.kind == Command::Shutdown) break;
    if (command->header.kind == Command::Thumbnails) {
      m.sendThumbnails(*command);
      continue;
    }
    if (command->header.kind == Command::Start && m.options.maxJobs > 1) {
      m.startJobThread(*command);
    } else if (command->header.kind == Command::Start) {
      m.runJob(*command);
      if (m.link && !m.link->joined()) idleShown = false;  // it left the job by losing the head
    }
  }
}

std::vector<JobDesk::Window> WallService::windows() const {
  if (!impl_->desk) throw base::Error("only the wall's head (process 0) manages its windows");
  return impl_->desk->windows();
}

bool WallService::raise(std::uint64_t number) {
  if (!impl_->desk) throw base::Error("only the wall's head (process 0) manages its windows");
  return impl_->desk->raise(number);
}

bool WallService::close(std::uint64_t number, const std::string& why) {
  if (!impl_->desk) throw base::Error("only the wall's head (process 0) manages its windows");
  return impl_->desk->close(number, why);
}

}  // namespace wall::service
