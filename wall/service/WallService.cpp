#include "wall/service/WallService.h"

#include <algorithm>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <filesystem>
#include <mutex>
#include <optional>
#include <random>
#include <set>
#include <thread>

#include "dfb/AtomicFile.h"
#include "dfb/Error.h"
#include "messaging/BoundedWait.h"
#include "wall/Error.h"
#include "wall/IdleScreen.h"
#include "wall/WallNode.h"
#include "wall/WallPeers.h"
#include "wall/service/PieceReceiver.h"
#include "wall/service/Protocol.h"
#include "wall/service/Zmq.h"

namespace wall::service {
namespace {

using Clock = std::chrono::steady_clock;
constexpr messaging::ObjectId kServiceObject = 0x3A11'0010;
constexpr std::size_t kMaxQueued = 16;    // jobs waiting behind the connected one (--wait)
constexpr std::size_t kMaxLogged = 1024;  // lines about strangers between two jobs

// Between the wall processes (the wall job's messenger): the desk's commands to every process,
// and the processes' answers to the desk.
enum class Command : std::uint32_t {
  Start = 1,        // a job: run a wall node for it (text: its capture folder)
  Cancel = 2,       // the job never started (a process could not): stop before frame 1
  LastFrame = 3,    // a: the job's last frame
  Abort = 4,        // the job is gone (text: why): give the frame in progress up
  KeepWaiting = 5,  // the job is alive but idle
  Capture = 6,      // a: frame, b: sequence
  Shutdown = 7,     // the wall stops
  Ready = 8,        // a: 1 ready, 0 not (text: why)
  Done = 9,         // a: last presented frame, b: bytes received (text: failure, if any)
  Failed = 10,      // this process gave a frame up (text: why)
  StopAsked = 11,   // this process was asked to stop the wall
};

struct CommandHeader {
  Command kind;
  std::int32_t process;
  std::uint64_t session;
  std::int64_t a, b;
  std::uint32_t tileSize, renderRanks, framesInFlight, captureEvery;
  std::uint32_t codec;
  std::uint32_t textBytes;
};

messaging::Bytes packCommand(CommandHeader h, const std::string& text = {}) {
  h.textBytes = static_cast<std::uint32_t>(std::min<size_t>(text.size(), kMaxStringBytes));
  messaging::Bytes out(sizeof h + h.textBytes);
  std::memcpy(out.data(), &h, sizeof h);
  std::memcpy(out.data() + sizeof h, text.data(), h.textBytes);
  return out;
}

std::uint64_t randomId() {
  std::random_device device;
  std::uint64_t id = 0;
  while (id == 0) id = (static_cast<std::uint64_t>(device()) << 32) ^ device();
  return id;
}

std::string randomToken() {
  static const char* digits = "0123456789abcdef";
  std::random_device device;
  std::string token;
  for (int i = 0; i < 24; ++i) token += digits[device() % 16];
  return token;
}

std::string jsonText(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) continue;
    out += c;
  }
  return out + "\"";
}

}  // namespace

struct WallService::Impl : messaging::MessageHandler {
  messaging::Messenger& messenger;
  const Layout& layout;
  std::vector<Presenter*> presenters;
  ServiceOptions options;
  int process = 0, processCount = 1;
  std::string address, token;
  std::vector<std::string> endpoints;  // process 0: every process's piece endpoint
  std::unique_ptr<MpiWallPeers> peers;
  std::unique_ptr<PieceReceiver> receiver;
  std::optional<messaging::Registration> registration;

  // Commands for the main thread; the node of the job in progress for the inbox thread.
  std::mutex mutex;
  std::condition_variable commanded;
  std::deque<std::pair<CommandHeader, std::string>> commands;
  WallNode* node = nullptr;
  std::uint64_t nodeSession = 0;
  bool stopAsked = false;

  // The desk (process 0): its thread owns the directory socket; events from the other threads
  // come through `events` and the waker.
  struct Desk;
  std::unique_ptr<Desk> desk;

  Impl(messaging::Messenger& m, const Layout& l, std::vector<Presenter*> p, ServiceOptions o)
      : messenger(m), layout(l), presenters(std::move(p)), options(std::move(o)) {}

  void toDesk(CommandHeader h, const std::string& text = {}) {
    h.process = process;
    messenger.send(0, kServiceObject, packCommand(h, text));
  }
  void toAll(CommandHeader h, const std::string& text = {}) {
    for (int p = 0; p < processCount; ++p) messenger.send(p, kServiceObject, packCommand(h, text));
  }
  void incoming(int fromRank, messaging::Bytes&& payload) override;
  void showIdle(const std::string& status);
  void runJob(const CommandHeader& start, const std::string& captureDir);
};

struct WallService::Impl::Desk {
  Impl& service;
  zmq::context_t context{1};
  zmq::socket_t socket;
  Waker waker;
  std::mutex mutex;
  std::deque<std::pair<CommandHeader, std::string>> events;
  std::thread thread;

  struct Job {
    std::string peer;  // routing id
    Hello hello;
    Clock::time_point lastHeard;
    std::uint64_t session = 0;
    Clock::time_point started;
  };
  enum class State { Idle, Starting, Running, Ending, Closed } state = State::Idle;
  Job job;
  std::deque<Job> queue;
  // Of this job: processes that answered Start (Ready), and processes done with it (Done, or a
  // Ready that refused it: such a process never ran a node). The job is over when all are done.
  int readies = 0, dones = 0;
  std::string failure;             // why the job failed or was dropped
  std::int64_t lastPresented = 0;  // from the Done answers
  std::int64_t bytes = 0;
  bool shuttingDown = false;
  std::set<std::string> logged;

  explicit Desk(Impl& s) : service(s), socket(context, zmq::socket_type::router) {
    configureSocket(socket, static_cast<int>(s.options.timeout.count()));
    socket.set(zmq::sockopt::router_mandatory, 0);
  }
  void post(CommandHeader h, std::string text) {
    {
      std::lock_guard lock(mutex);
      events.emplace_back(h, std::move(text));
    }
    waker.notify();
  }
  void reply(const std::string& peer, messaging::Bytes message) {
    zmq::message_t id(peer.data(), peer.size());
    socket.send(id, zmq::send_flags::sndmore | zmq::send_flags::dontwait);
    socket.send(toMessage(std::move(message)), zmq::send_flags::dontwait);
  }
  void log(const std::string& line) { service.options.log(line); }
  void startJob() {
    job.session = randomId();
    job.started = Clock::now();
    readies = dones = 0;
    failure.clear();
    lastPresented = bytes = 0;
    state = State::Starting;
    CommandHeader h{};
    h.kind = Command::Start;
    h.session = job.session;
    h.tileSize = job.hello.tileSize;
    h.renderRanks = job.hello.renderRanks;
    h.framesInFlight = std::min<std::uint32_t>(
        job.hello.framesInFlight, static_cast<std::uint32_t>(service.options.framesInFlight));
    h.captureEvery = job.hello.captureEvery;
    h.codec = static_cast<std::uint32_t>(job.hello.codec.codec);
    service.toAll(h, job.hello.captureDir);
  }
  void endJob(const std::string& why) {  // the job is gone or broken: drop it everywhere
    if (state != State::Running && state != State::Starting) return;
    failure = why;
    CommandHeader h{};
    h.kind = state == State::Starting ? Command::Cancel : Command::Abort;
    h.session = job.session;
    service.toAll(h, why);
    reply(job.peer, packText(Kind::Ended, job.session, why));
    state = State::Ending;
    log("dropping the job from " + job.hello.host + ": " + why);
  }
  void nextJob() {
    state = State::Idle;
    logged.clear();
    while (!queue.empty() && !shuttingDown) {
      job = queue.front();
      queue.pop_front();
      if (Clock::now() - job.lastHeard > service.options.timeout) continue;  // it left the queue
      log("taking the queued job from " + job.hello.host);
      startJob();
      return;
    }
  }
  void onHello(const std::string& peer, const std::byte* data, size_t size) {
    Hello hello;
    try {
      hello = parseHello(data, size);
    } catch (const std::exception& e) {
      log("refused a job: " + std::string(e.what()));
      reply(peer, packText(Kind::Refused, 0, e.what()));
      return;
    }
    const std::string who = hello.host.empty() ? "an unnamed host" : hello.host;
    if (!service.token.empty() && hello.token != service.token) {
      logOnce(peer, "refused a job from " + who + ": " +
                        (hello.token.empty() ? "no token" : "wrong token"));
      reply(peer,
            packText(Kind::Refused, 0,
                     hello.token.empty() ? "this wall needs a token (--token)" : "wrong token"));
      return;
    }
    if (shuttingDown) {
      reply(peer, packText(Kind::Refused, 0, "the wall is shutting down"));
      return;
    }
    if (state == State::Idle) {
      job = {peer, hello, Clock::now(), 0, {}};
      log("job from " + who + ": " + std::to_string(hello.renderRanks) + " render ranks, codec " +
          codecName(hello.codec));
      startJob();
      return;
    }
    const std::string busy = "busy: a job from " + job.hello.host + " is connected";
    if (!hello.wait) {
      logOnce(peer, "refused a job from " + who + ": " + busy);
      reply(peer, packText(Kind::Refused, 0, busy));
      return;
    }
    if (queue.size() >= kMaxQueued) {
      logOnce(peer, "refused a job from " + who + ": the queue is full");
      reply(peer, packText(Kind::Refused, 0,
                           busy + ", and " + std::to_string(kMaxQueued) + " jobs wait already"));
      return;
    }
    queue.push_back({peer, hello, Clock::now(), 0, {}});
    log("queued a job from " + who + " (place " + std::to_string(queue.size()) + ")");
    reply(peer, packText(Kind::Queued, 0,
                         busy + "; waiting (place " + std::to_string(queue.size()) + ")"));
  }
  void onClient(const std::string& peer, const std::byte* data, size_t size) {
    MessageHeader h;
    try {
      h = parseHeader(data, size);
    } catch (const std::exception& e) {
      logOnce(peer, e.what());
      // A dfbwall of another version learns why at once instead of at its timeout.
      MessageHeader mine;
      std::memcpy(&mine, data, std::min(size, sizeof mine));
      if (size >= sizeof mine && mine.magic == kMagic)
        reply(peer, packText(Kind::Refused, 0, e.what()));
      return;
    }
    const Kind kind = static_cast<Kind>(h.kind);
    if (kind == Kind::Hello) return onHello(peer, data, size);
    for (size_t place = 0; place < queue.size(); ++place) {
      if (queue[place].peer != peer) continue;
      // A waiting job's keepalive: it is still there; tell it where it stands.
      queue[place].lastHeard = Clock::now();
      if (kind == Kind::Keepalive)
        reply(peer,
              packText(Kind::Queued, 0,
                       "busy: a job from " + job.hello.host + " is connected; waiting (place " +
                           std::to_string(place + 1) + ")"));
      return;
    }
    const bool ours = state != State::Idle && state != State::Closed && peer == job.peer &&
                      h.session == job.session;
    if (!ours) {
      if (kind != Kind::Keepalive && kind != Kind::Bye)
        logOnce(peer, "message kind " + std::to_string(h.kind) + " outside a job");
      return;
    }
    job.lastHeard = Clock::now();
    Control c;
    try {
      c = parseControl(data, size);
    } catch (const std::exception& e) {
      return endJob(e.what());
    }
    // The job counts the wall silent after its --timeout without a message: a frame that takes
    // longer to render than that must not end it, so every keepalive is answered.
    if (kind == Kind::Keepalive) reply(peer, packControl(Kind::Keepalive, job.session, 0));
    if (state != State::Running) return;
    CommandHeader command{};
    command.session = job.session;
    switch (kind) {
      case Kind::Keepalive:
        command.kind = Command::KeepWaiting;
        service.toAll(command);
        break;
      case Kind::Capture:
        command.kind = Command::Capture;
        command.a = static_cast<std::int64_t>(c.value);
        command.b = c.second;
        service.toAll(command);
        break;
      case Kind::Bye:
        if (c.second < 0) return endJob("the job left without naming its last frame");
        command.kind = Command::LastFrame;
        command.a = static_cast<std::int64_t>(c.value);
        service.toAll(command);
        break;
      default:
        endJob("unexpected message kind " + std::to_string(h.kind));
    }
  }
  // One line per connection and kind of problem (a client that repeats itself, or a flood of
  // them, cannot fill the log), at most kMaxLogged lines between two jobs.
  static std::string peerOf(const zmq::message_t& id) {
    return std::string(static_cast<const char*>(id.data()), id.size());
  }
  void logOnce(const std::string& peer, const std::string& what) {
    if (logged.size() >= kMaxLogged || !logged.insert(peer + what.substr(0, 48)).second) return;
    log(what.rfind("refused", 0) == 0 ? what : "ignored a message on the directory port: " + what);
  }
  void onEvent(const CommandHeader& e, const std::string& text) {
    if (e.kind == Command::StopAsked) {
      if (!shuttingDown) log("stopping the wall");
      shuttingDown = true;
      for (Job& queued : queue)
        reply(queued.peer, packText(Kind::Refused, 0, "the wall is shutting down"));
      queue.clear();
      endJob("the wall is shutting down");
      return;
    }
    if (e.session != job.session) return;
    switch (e.kind) {
      case Command::Ready:
        if (e.a == 0) {
          if (failure.empty()) failure = text;
          ++dones;
        }
        if (state == State::Starting && ++readies == service.processCount) {
          if (!failure.empty()) {
            CommandHeader cancel{};
            cancel.kind = Command::Cancel;
            cancel.session = job.session;
            service.toAll(cancel);
            reply(job.peer, packText(Kind::Refused, 0, failure));
            log("refused the job from " + job.hello.host + ": " + failure);
            state = State::Ending;
          } else {
            Directory d;
            d.session = job.session;
            d.layout = service.layout;
            for (const std::string& endpoint : service.endpoints) d.processes.push_back({endpoint});
            d.framesInFlight =
                std::min<std::uint32_t>(job.hello.framesInFlight,
                                        static_cast<std::uint32_t>(service.options.framesInFlight));
            d.timeoutMs = static_cast<std::uint32_t>(service.options.timeout.count());
            reply(job.peer, packDirectory(d));
            state = State::Running;
          }
        }
        if (dones == service.processCount) jobOver();
        return;
      case Command::Failed:
        if (state == State::Running) endJob(text);
        return;
      case Command::Done:
        lastPresented = std::max(lastPresented, e.a);
        bytes += e.b;
        if (!text.empty() && failure.empty()) failure = text;
        if (state == State::Running) state = State::Ending;  // it ended by itself (last frame)
        if (++dones == service.processCount) jobOver();
        return;
      default:
        return;
    }
  }
  void jobOver() {
    {
      const double seconds = std::chrono::duration<double>(Clock::now() - job.started).count();
      log("the job from " + job.hello.host + " ended after frame " + std::to_string(lastPresented) +
          (failure.empty() ? "" : " (" + failure + ")"));
      if (service.options.jobRecord)
        service.options.jobRecord("{\"job\":" + std::to_string(job.session % 1000000007) +
                                  ",\"host\":" + jsonText(job.hello.host) +
                                  ",\"render_ranks\":" + std::to_string(job.hello.renderRanks) +
                                  ",\"codec\":" + jsonText(codecName(job.hello.codec)) +
                                  ",\"frames_presented\":" + std::to_string(lastPresented) +
                                  ",\"wall_bytes_received\":" + std::to_string(bytes) +
                                  ",\"seconds\":" + std::to_string(seconds) + ",\"ended\":" +
                                  jsonText(failure.empty() ? "last frame" : failure) + "}");
    }
    nextJob();
  }
  // Process 0's node presented a frame on every display: the job's credit, from the desk's
  // thread (the only one that touches the socket).
  void presented(std::uint32_t frameId, std::int64_t completeNs) {
    std::lock_guard lock(mutex);
    presentedFrames.emplace_back(frameId, completeNs);
    waker.notify();
  }
  std::deque<std::pair<std::uint32_t, std::int64_t>> presentedFrames;
  void run() {
    const auto tick = std::chrono::milliseconds(100);
    while (true) {
      zmq::pollitem_t items[2] = {{socket.handle(), 0, ZMQ_POLLIN, 0}, waker.pollItem()};
      zmq::poll(items, 2, tick);
      if (items[1].revents) waker.drain();
      std::deque<std::pair<CommandHeader, std::string>> now;
      std::deque<std::pair<std::uint32_t, std::int64_t>> frames;
      {
        std::lock_guard lock(mutex);
        now.swap(events);
        frames.swap(presentedFrames);
      }
      for (const auto& [frameId, ns] : frames)
        if (state == State::Running || state == State::Ending)
          reply(job.peer, packControl(Kind::Presented, job.session, frameId, ns));
      for (const auto& [h, text] : now) onEvent(h, text);
      zmq::message_t id, body;
      while (socket.recv(id, zmq::recv_flags::dontwait)) {
        if (!id.more() || !socket.recv(body, zmq::recv_flags::dontwait)) continue;
        while (body.more()) {
          zmq::message_t extra;
          if (!socket.recv(extra, zmq::recv_flags::dontwait)) break;
        }
        try {
          onClient(std::string(static_cast<const char*>(id.data()), id.size()),
                   static_cast<const std::byte*>(body.data()), body.size());
        } catch (const std::exception& e) {
          // Nothing a client sends ends the wall; a failure handling it drops its job at most.
          log(std::string("handling a message on the directory port: ") + e.what());
          if (peerOf(id) == job.peer) endJob(e.what());
        }
      }
      if (state == State::Running && Clock::now() - job.lastHeard > service.options.timeout)
        endJob("no word from the job for " +
               std::to_string(service.options.timeout.count() / 1000) + " s");
      if (shuttingDown && state == State::Idle) {
        CommandHeader h{};
        h.kind = Command::Shutdown;
        service.toAll(h);
        state = State::Closed;
        return;
      }
    }
  }
};

void WallService::Impl::incoming(int /*fromRank*/, messaging::Bytes&& payload) {
  CommandHeader h;
  if (payload.size() < sizeof h) throw Error("malformed service command");
  std::memcpy(&h, payload.data(), sizeof h);
  if (payload.size() != sizeof h + h.textBytes) throw Error("malformed service command");
  std::string text(reinterpret_cast<const char*>(payload.data() + sizeof h), h.textBytes);
  switch (h.kind) {
    case Command::Ready:
    case Command::Done:
    case Command::Failed:
    case Command::StopAsked:
      if (desk) desk->post(h, std::move(text));
      return;
    default:
      break;
  }
  std::lock_guard lock(mutex);
  if (node && h.session == nodeSession) {
    switch (h.kind) {
      case Command::Cancel:
        node->stopAfter(0);
        return;
      case Command::LastFrame:
        node->stopAfter(static_cast<std::uint32_t>(h.a));
        return;
      case Command::Abort:
        node->abort(text);
        return;
      case Command::KeepWaiting:
        node->keepWaiting();
        return;
      case Command::Capture:
        node->requestCapture(static_cast<std::uint32_t>(h.a), static_cast<std::uint64_t>(h.b));
        return;
      default:
        break;
    }
  }
  if (h.kind == Command::Start || h.kind == Command::Shutdown) {
    commands.emplace_back(h, std::move(text));
    commanded.notify_all();
  }
}

WallService::WallService(messaging::Messenger& messenger, MPI_Comm wallComm, const Layout& layout,
                         std::vector<Presenter*> presenters, ServiceOptions options)
    : impl_(std::make_unique<Impl>(messenger, layout, std::move(presenters), std::move(options))) {
  Impl& m = *impl_;
  m.process = messenger.rank();
  m.processCount = messenger.size();
  const std::string endpoint = tcpEndpoint(m.options.listen, "--listen");
  const std::string listenHost = hostOf(m.options.listen);
  const bool loopback = isLoopback(listenHost);
  m.token = m.options.token;
  if (!loopback && m.token.empty()) m.token = randomToken();
  // Pieces: any port, on the listen address where it is this host's (loopback, or process 0's
  // own), else on every interface.
  const std::string pieceHost =
      loopback ? listenHost : (m.process == 0 && listenHost != "0.0.0.0" ? listenHost : "0.0.0.0");
  const int deadPeerMs = static_cast<int>(m.options.timeout.count());
  m.receiver = std::make_unique<PieceReceiver>("tcp://" + pieceHost + ":*",
                                               m.options.handlerThreads, deadPeerMs, m.options.log);
  const std::string mine = "tcp://" + (loopback ? listenHost : advertisedHost(pieceHost)) + ":" +
                           std::to_string(m.receiver->port());
  // Every process's endpoint to process 0, for the directory (bounded, as every wait).
  char buffer[256] = {};
  std::strncpy(buffer, mine.c_str(), sizeof buffer - 1);
  std::vector<char> all(m.process == 0 ? sizeof buffer * static_cast<size_t>(m.processCount) : 0);
  MPI_Request request;
  dfb::checkMpi(MPI_Igather(buffer, sizeof buffer, MPI_CHAR, all.data(), sizeof buffer, MPI_CHAR, 0,
                            wallComm, &request),
                "MPI_Igather");
  messaging::waitWithDeadline(request, Clock::now() + m.options.timeout,
                              "starting the wall service: a wall process did not answer");
  for (int p = 0; m.process == 0 && p < m.processCount; ++p)
    m.endpoints.emplace_back(all.data() + static_cast<size_t>(p) * sizeof buffer);
  if (m.process == 0) {
    m.desk = std::make_unique<Impl::Desk>(m);
    try {
      m.desk->socket.bind(endpoint);
    } catch (const zmq::error_t& e) {
      throw Error("--listen " + m.options.listen + ": cannot listen there (" + e.what() + ")");
    }
    m.address = (loopback || listenHost != "0.0.0.0" ? listenHost : advertisedHost(listenHost)) +
                ":" + std::to_string(portOf(lastEndpoint(m.desk->socket)));
  }
  m.peers = std::make_unique<MpiWallPeers>(wallComm, m.options.timeout,
                                           [this](std::uint32_t frameId, std::int64_t completeNs) {
                                             if (impl_->desk)
                                               impl_->desk->presented(frameId, completeNs);
                                           });
  m.registration.emplace(messenger, kServiceObject, &m);
  // Every process's handler is registered before the desk may send.
  MPI_Request barrier;
  dfb::checkMpi(MPI_Ibarrier(wallComm, &barrier), "MPI_Ibarrier");
  messaging::waitWithDeadline(barrier, Clock::now() + m.options.timeout,
                              "starting the wall service: a wall process did not answer");
  // The address is known on process 0 only: the idle screens show it everywhere.
  char shown[256] = {};
  std::strncpy(shown, m.address.c_str(), sizeof shown - 1);
  dfb::checkMpi(MPI_Ibcast(shown, sizeof shown, MPI_CHAR, 0, wallComm, &request), "MPI_Ibcast");
  messaging::waitWithDeadline(request, Clock::now() + m.options.timeout,
                              "starting the wall service: a wall process did not answer");
  m.address = shown;
}

WallService::~WallService() {
  Impl& m = *impl_;
  if (m.desk && m.desk->thread.joinable()) m.desk->thread.join();
  m.registration.reset();
}

std::string WallService::address() const { return impl_->address; }
std::string WallService::token() const { return impl_->token; }

void WallService::Impl::showIdle(const std::string& status) {
  const std::vector<int> mine = layout.displaysOfProcess(process);
  for (size_t i = 0; i < mine.size(); ++i) {
    const Display& d = layout.displays[static_cast<size_t>(mine[i])];
    IdleText text;
    text.title = d.name;
    text.lines = {"dfbwall serve \u2014 connect with: dfbwall --connect " + address, status};
    const Image image = renderIdleScreen(d.rect.width(), d.rect.height(), text);
    presenters[i]->present(image.pixels.data(), image.width, image.height);
  }
}

void WallService::Impl::runJob(const CommandHeader& start, const std::string& captureDir) {
  CommandHeader answer{};
  answer.session = start.session;
  // Anything a job asks for that this process cannot do refuses the job, never ends the wall.
  std::string problem;
  if (!captureDir.empty()) {
    for (int d : layout.displaysOfProcess(process)) {
      problem = dfb::checkWritableFolder(
          (std::filesystem::path(captureDir) / layout.displays[static_cast<size_t>(d)].name)
              .string());
      if (!problem.empty()) {
        problem = "capture folder on wall process " + std::to_string(process) + ": " + problem;
        break;
      }
    }
  }
  if (!problem.empty()) {
    answer.kind = Command::Ready;
    answer.a = 0;  // counts as this process's Done too: it runs no node for the job
    toDesk(answer, problem);
    return;
  }
  WallNodeOptions o;
  o.tileSize = static_cast<int>(start.tileSize);
  o.captureDir = captureDir;
  o.captureEvery = static_cast<int>(start.captureEvery);
  o.lastFrame = 0;  // the job says when it ends
  o.timeout = options.timeout;
  o.framesAhead = start.framesInFlight + 2;
  o.abandonOnFailure = true;
  const std::uint64_t session = start.session;
  o.onAbandon = [this, session](const std::string& why) {
    CommandHeader failed{};
    failed.kind = Command::Failed;
    failed.session = session;
    toDesk(failed, why);
  };
  std::string failure;
  std::int64_t lastPresented = 0, bytes = 0;
  {
    WallNode job(layout, *peers, presenters, o);
    {
      std::lock_guard lock(mutex);
      node = &job;
      nodeSession = session;
    }
    receiver->attach(session, static_cast<Codec>(start.codec), static_cast<int>(start.renderRanks),
                     &job);
    answer.kind = Command::Ready;
    answer.a = 1;
    toDesk(answer);
    bool asked = false;
    for (std::uint32_t frameId = 1;; ++frameId) {
      const PresentReport r = job.presentFrame(frameId);
      if (r.stopped) {
        if (!r.failure.empty()) failure = r.failure;
        break;
      }
      lastPresented = frameId;
      bytes += static_cast<std::int64_t>(r.bytesReceived);
      if (!asked && options.stopRequested && options.stopRequested()) {
        asked = true;
        CommandHeader stop{};
        stop.kind = Command::StopAsked;
        toDesk(stop);
      }
    }
    try {
      job.finish();
    } catch (const std::exception& e) {
      if (failure.empty()) failure = e.what();
    }
    receiver->detach();
    std::lock_guard lock(mutex);
    node = nullptr;
    nodeSession = 0;
  }
  answer.kind = Command::Done;
  answer.a = lastPresented;
  answer.b = bytes;
  toDesk(answer, failure);
}

void WallService::run() {
  Impl& m = *impl_;
  if (m.desk)
    m.desk->thread = std::thread([&m] {
      try {
        m.desk->run();
      } catch (const std::exception& e) {
        m.options.log(std::string("the desk failed: ") + e.what());
        std::abort();
      }
    });
  m.showIdle("waiting for a render job");
  bool asked = false;
  while (true) {
    std::optional<std::pair<CommandHeader, std::string>> command;
    {
      std::unique_lock lock(m.mutex);
      m.commanded.wait_for(lock, std::chrono::milliseconds(50),
                           [&] { return !m.commands.empty(); });
      if (!m.commands.empty()) {
        command = std::move(m.commands.front());
        m.commands.pop_front();
      }
    }
    for (Presenter* p : m.presenters) p->pollEvents();
    bool closed = false;
    for (Presenter* p : m.presenters) closed = closed || p->closeRequested();
    if (!asked && (closed || (m.options.stopRequested && m.options.stopRequested()))) {
      asked = true;
      CommandHeader stop{};
      stop.kind = Command::StopAsked;
      m.toDesk(stop);
    }
    if (!command) continue;
    if (command->first.kind == Command::Shutdown) break;
    if (command->first.kind == Command::Start) m.runJob(command->first, command->second);
  }
}

}  // namespace wall::service
