#include "wall/service/client/ServiceClient.h"

#include <algorithm>
#include <cstdio>
#include <cstring>

#include "base/Collectives.h"
#include "base/Error.h"
#include "base/Timing.h"
#include "wall/service/security/HandshakeWatch.h"

namespace wall::service {
namespace {

using Clock = std::chrono::steady_clock;
constexpr auto kKeepalive = std::chrono::seconds(1);
// A batch is sent before the frame ends once it holds this much: the link stays busy while the
// rank still renders, and a wall process never needs a whole display's frame in one message.
constexpr std::size_t kFlushBytes = std::size_t{4} << 20;

const std::byte* bytesOf(const zmq::message_t& m) {
  return static_cast<const std::byte*>(m.data());
}

}  // namespace

ServiceClient::ServiceClient(const std::string& address, const Credentials& credentials,
                             const Hello& hello, std::chrono::milliseconds timeout,
                             const std::function<void(const std::string&)>& onQueued)
    : address_(address), credentials_(credentials), socket_(context_, zmq::socket_type::dealer) {
  const std::string endpoint = tcpEndpoint(address, "--connect");
  // The goodbye of a job that fails gets a second to leave.
  configureSocket(socket_, Side::dials, static_cast<int>(timeout.count()), kMaxMessageBytes, 1000);
  makeClient(socket_, credentials);
  HandshakeWatch watch(context_, socket_);
  socket_.connect(endpoint);
  socket_.send(toMessage(packHello(hello)), zmq::send_flags::none);
  auto deadline = Clock::now() + timeout;
  bool queued = false;
  while (true) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (left.count() <= 0)
      throw base::Error("no dfbwall wall answered at " + address + " within " +
                        std::to_string(timeout.count() / 1000) +
                        " s (is `dfbwall serve` running there?)");
    const HandshakeWatch::State handshake = watch.poll();
    if (handshake == HandshakeWatch::State::Refused)
      throw base::Error("the wall at " + address + " refused the job at the handshake: " +
                        watch.problem() + "; give the wall's token (--token-file FILE or " +
                        "DFBWALL_TOKEN; this job's came from " + credentials.tokenSource + ")");
    if (handshake == HandshakeWatch::State::Failed)
      throw base::Error("no handshake with the wall at " + address + ": " + watch.problem());
    zmq::pollitem_t items[2] = {{socket_.handle(), 0, ZMQ_POLLIN, 0}, watch.pollItem()};
    zmq::poll(items, 2, std::min<std::chrono::milliseconds>(left, kKeepalive));
    if (items[1].revents) continue;  // the handshake's news first
    if (items[0].revents == 0) {
      // Waiting in the wall's queue: say so every second, or the wall forgets the job.
      if (queued)
        socket_.send(toMessage(packControl(Kind::Keepalive, 0, 0)), zmq::send_flags::none);
      continue;
    }
    zmq::message_t reply;
    if (!socket_.recv(reply, zmq::recv_flags::none)) continue;
    const MessageHeader h = parseHeader(bytesOf(reply), reply.size());
    switch (static_cast<Kind>(h.kind)) {
      case Kind::Directory:
        directory_ = parseDirectory(bytesOf(reply), reply.size());
        setWindowSize(directory_.layout);
        directoryBytes_.assign(bytesOf(reply), bytesOf(reply) + reply.size());
        // The wall counts the job from now on: keepalives go while the job still sets up (a
        // scene or bricks that take longer than the wall's timeout to load under load).
        thread_ = std::thread([this] { run(); });
        return;
      case Kind::Refused:
        throw base::Error("the wall at " + address +
                          " refused the job: " + parseText(bytesOf(reply), reply.size()));
      case Kind::Queued:
        if (onQueued && !queued) onQueued(parseText(bytesOf(reply), reply.size()));
        queued = true;
        deadline = Clock::now() + timeout;  // the wall answers; it is not dead
        break;
      default:
        throw base::Error("the wall at " + address + " answered the hello with message kind " +
                          std::to_string(h.kind));
    }
  }
}

ServiceClient::~ServiceClient() {
  stop_ = true;
  waker_.notify();
  if (thread_.joinable()) thread_.join();
  if (!byeSent_ && directory_.session != 0) {
    // A job that fails says so, so the wall takes the next one at once instead of at its timeout.
    try {
      socket_.send(toMessage(packControl(Kind::Bye, directory_.session, 0, -1)),
                   zmq::send_flags::dontwait);
    } catch (const std::exception&) {
    }
  }
}

void ServiceClient::start(FrameCredits& credits, std::function<void(const std::string&)> onError) {
  {
    std::lock_guard lock(mutex_);
    credits_ = &credits;
    onError_ = std::move(onError);
  }
  waker_.notify();  // a failure the link saw before now is reported at once
}

void ServiceClient::post(messaging::Bytes message) {
  {
    std::lock_guard lock(mutex_);
    outbox_.push_back(std::move(message));
  }
  waker_.notify();
}

void ServiceClient::capture(std::uint32_t frameId, std::uint64_t sequence) {
  post(
      packControl(Kind::Capture, directory_.session, frameId, static_cast<std::int64_t>(sequence)));
}

void ServiceClient::bye(std::uint32_t lastFrame) {
  {
    std::lock_guard lock(mutex_);
    byeSent_ = true;
    lastFrame_ = lastFrame;
  }
  post(packControl(Kind::Bye, directory_.session, lastFrame));
}

std::uint32_t ServiceClient::rosterVersion() const {
  std::lock_guard lock(mutex_);
  return rosterVersion_;
}

messaging::Bytes ServiceClient::rosterBytes() const {
  std::lock_guard lock(mutex_);
  return rosterBytes_;
}

ServiceClient::Size ServiceClient::windowSize() const {
  const std::uint64_t packed = windowSize_;
  return {static_cast<int>(packed >> 32), static_cast<int>(packed & 0xffffffffu)};
}

void ServiceClient::setWindowSize(const Layout& window) {
  windowSize_ = static_cast<std::uint64_t>(static_cast<std::uint32_t>(window.canvasWidth)) << 32 |
                static_cast<std::uint32_t>(window.canvasHeight);
}

ServiceClient::ReshapeNews ServiceClient::reshapeNews() const {
  std::lock_guard lock(mutex_);
  return reshape_;
}

messaging::Bytes ServiceClient::reshapeBytes() const {
  std::lock_guard lock(mutex_);
  return reshapeBytes_;
}

void ServiceClient::onInput(std::function<void(const WindowInput&)> handler) {
  std::lock_guard lock(mutex_);
  onInput_ = std::move(handler);
}

void ServiceClient::run() {
  const std::uint64_t session = directory_.session;
  const auto wallTimeout = std::chrono::milliseconds(directory_.timeoutMs);
  // Often enough for the wall's timeout however short it is.
  const auto keepalive = std::clamp<std::chrono::milliseconds>(
      wallTimeout / 4, std::chrono::milliseconds(50), kKeepalive);
  auto lastKeepalive = Clock::time_point{};
  auto lastHeard = Clock::now();
  bool failed = false;
  std::string failure;         // what failed before start() gave somewhere to report it
  std::uint64_t credited = 0;  // the latest frame the wall presented
  // Reports through onError_ once start() set it, else keeps the reason until then.
  const auto report = [&] {
    std::function<void(const std::string&)> onError;
    {
      std::lock_guard lock(mutex_);
      onError = onError_;
    }
    if (failure.empty() || !onError) return;
    onError(failure);
    failure.clear();
  };
  const auto fail = [&](const std::string& why) {
    if (!failed) failure = why;
    failed = true;
    report();
  };
  try {
    while (!stop_) {
      report();
      zmq::pollitem_t items[2] = {{socket_.handle(), 0, ZMQ_POLLIN, 0}, waker_.pollItem()};
      zmq::poll(items, 2,
                std::min<std::chrono::milliseconds>(keepalive, std::chrono::milliseconds(200)));
      if (items[1].revents) waker_.drain();
      std::vector<messaging::Bytes> out;
      {
        std::lock_guard lock(mutex_);
        out.swap(outbox_);
      }
      for (messaging::Bytes& m : out) socket_.send(toMessage(std::move(m)), zmq::send_flags::none);
      if (Clock::now() - lastKeepalive >= keepalive) {
        socket_.send(toMessage(packControl(Kind::Keepalive, session, 0)), zmq::send_flags::none);
        lastKeepalive = Clock::now();
      }
      zmq::message_t m;
      while (socket_.recv(m, zmq::recv_flags::dontwait)) {
        lastHeard = Clock::now();
        const MessageHeader h = parseHeader(bytesOf(m), m.size());
        if (h.session != session) continue;  // a late answer to nothing of ours
        if (h.kind == static_cast<std::uint16_t>(Kind::Presented)) {
          const Control c = parseControl(bytesOf(m), m.size());
          FrameCredits* credits = nullptr;
          {
            std::lock_guard lock(mutex_);
            credits = credits_;
          }
          // No frame goes to the wall before start(): a credit without credits is the wall's
          // mistake.
          if (!credits)
            throw base::Error("the wall at " + address_ + " presented frame " +
                              std::to_string(c.value) + " before the job sent any");
          credits->acknowledged(static_cast<std::uint32_t>(c.value), c.second,
                                "the wall at " + address_);
          credited = std::max(credited, c.value);
        } else if (h.kind == static_cast<std::uint16_t>(Kind::Roster)) {
          const Roster roster = parseRoster(bytesOf(m), m.size());
          if (roster.processes.size() != directory_.processes.size())
            throw base::Error("the wall at " + address_ + " sent a roster of " +
                              std::to_string(roster.processes.size()) + " processes for " +
                              std::to_string(directory_.processes.size()));
          if (!roster.why.empty()) {
            std::fprintf(stderr, "dfbwall: the wall at %s: %s\n", address_.c_str(),
                         roster.why.c_str());
            std::fflush(stderr);
          }
          std::lock_guard lock(mutex_);
          if (roster.version > rosterVersion_) {
            rosterVersion_ = roster.version;
            rosterBytes_.assign(bytesOf(m), bytesOf(m) + m.size());
          }
        } else if (h.kind == static_cast<std::uint16_t>(Kind::Reshape)) {
          const Reshape reshape = parseReshape(bytesOf(m), m.size());
          if (reshape.directory.processes.size() != directory_.processes.size() ||
              reshape.session != session)
            throw base::Error("the wall at " + address_ + " sent a move of another window");
          std::lock_guard lock(mutex_);
          if (reshape.version > reshape_.version) {
            setWindowSize(reshape.directory.layout);
            reshape_ = {reshape.version, reshape.fromFrame};
            reshapeBytes_.assign(bytesOf(m), bytesOf(m) + m.size());
          }
        } else if (h.kind == static_cast<std::uint16_t>(Kind::Refused)) {
          // A request of the job (a capture) the wall would not take: the job goes on.
          std::fprintf(stderr, "dfbwall: the wall at %s: %s\n", address_.c_str(),
                       parseText(bytesOf(m), m.size()).c_str());
          std::fflush(stderr);
        } else if (h.kind == static_cast<std::uint16_t>(Kind::Input)) {
          const WindowInput in = parseInput(bytesOf(m), m.size());
          std::lock_guard lock(mutex_);
          if (onInput_) onInput_(in);
        } else if (h.kind == static_cast<std::uint16_t>(Kind::Ended)) {
          fail("the wall at " + address_ + " ended the job: " + parseText(bytesOf(m), m.size()));
        } else if (h.kind != static_cast<std::uint16_t>(Kind::Keepalive)) {
          fail("the wall at " + address_ + " sent message kind " + std::to_string(h.kind));
        }
      }
      // Once the last frame is credited the wall's job is over and it answers no keepalive: its
      // silence while this rank winds down is no failure.
      bool over = false;
      {
        std::lock_guard lock(mutex_);
        over = byeSent_ && credited >= lastFrame_ && credited > 0;
      }
      if (!failed && !over && Clock::now() - lastHeard > wallTimeout + kKeepalive * 2)
        fail("the wall at " + address_ + " has not answered for " +
             std::to_string(wallTimeout.count() / 1000) + " s");
    }
  } catch (const std::exception& e) {
    fail(e.what());
  }
}

Directory shareDirectory(MPI_Comm comm, const ServiceClient* client,
                         std::chrono::milliseconds timeout) {
  messaging::Bytes bytes = client ? client->directoryBytes() : messaging::Bytes{};
  std::uint64_t size = bytes.size();
  const base::Bound bound{.until = timeout,
                          .late = "sharing the wall's directory: a rank did not join in time"};
  base::bcast(&size, sizeof size, 0, comm, bound);
  if (size > kMaxMessageBytes)
    throw base::Error("a directory of " + std::to_string(size) + " bytes");
  bytes.resize(size);
  base::bcast(bytes.data(), static_cast<int>(size), 0, comm, bound);
  return parseDirectory(bytes.data(), bytes.size());
}

Credentials shareCredentials(MPI_Comm comm, const ServiceClient* client,
                             std::chrono::milliseconds timeout) {
  const Credentials* mine = client ? &client->credentials() : nullptr;
  // What a client needs: the token and the pinned key, each at most 1024 bytes.
  char buffer[2 * 1024 + 8] = {};
  std::uint32_t sizes[2] = {0, 0};
  if (mine) {
    sizes[0] = static_cast<std::uint32_t>(std::min<std::size_t>(mine->token.size(), 1024));
    sizes[1] = static_cast<std::uint32_t>(std::min<std::size_t>(mine->serverKey.size(), 1024));
    std::memcpy(buffer, mine->token.data(), sizes[0]);
    std::memcpy(buffer + 1024, mine->serverKey.data(), sizes[1]);
  }
  const base::Bound bound{.until = timeout,
                          .late = "sharing the wall's credentials: a rank did not join in time"};
  base::bcast(sizes, sizeof sizes, 0, comm, bound);
  base::bcast(buffer, sizeof buffer, 0, comm, bound);
  Credentials shared;
  shared.token.assign(buffer, std::min<std::uint32_t>(sizes[0], 1024));
  shared.serverKey.assign(buffer + 1024, std::min<std::uint32_t>(sizes[1], 1024));
  shared.tokenSource = "render rank 0";
  return shared;
}

Roster shareRoster(MPI_Comm comm, const ServiceClient* client, std::chrono::milliseconds timeout) {
  messaging::Bytes bytes = client ? client->rosterBytes() : messaging::Bytes{};
  std::uint64_t size = bytes.size();
  const base::Bound bound{.until = timeout,
                          .late = "sharing the wall's roster: a rank did not join in time"};
  base::bcast(&size, sizeof size, 0, comm, bound);
  if (size > kMaxMessageBytes) throw base::Error("a roster of " + std::to_string(size) + " bytes");
  bytes.resize(size);
  base::bcast(bytes.data(), static_cast<int>(size), 0, comm, bound);
  return parseRoster(bytes.data(), bytes.size());
}

Reshape shareReshape(MPI_Comm comm, const ServiceClient* client,
                     std::chrono::milliseconds timeout) {
  messaging::Bytes bytes = client ? client->reshapeBytes() : messaging::Bytes{};
  std::uint64_t size = bytes.size();
  const base::Bound bound{.until = timeout,
                          .late = "sharing the wall's move of the window: a rank did not join"};
  base::bcast(&size, sizeof size, 0, comm, bound);
  if (size > kMaxMessageBytes)
    throw base::Error("a move of the window of " + std::to_string(size) + " bytes");
  bytes.resize(size);
  base::bcast(bytes.data(), static_cast<int>(size), 0, comm, bound);
  return parseReshape(bytes.data(), bytes.size());
}

Hello jobHello(int renderRanks, int tileSize, const CodecSpec& codec, int framesInFlight, bool wait,
               const std::string& captureDir, int captureEvery) {
  Hello hello;
  char name[MPI_MAX_PROCESSOR_NAME];
  int length = 0;
  MPI_Get_processor_name(name, &length);
  hello.host = std::string(name, static_cast<size_t>(length));
  hello.renderRanks = static_cast<std::uint32_t>(renderRanks);
  hello.tileSize = static_cast<std::uint32_t>(tileSize);
  hello.codec = codec;
  hello.framesInFlight = static_cast<std::uint32_t>(framesInFlight);
  hello.wait = wait;
  hello.captureDir = captureDir;
  hello.captureEvery = static_cast<std::uint32_t>(captureEvery);
  return hello;
}

ServicePieceSink::ServicePieceSink(const Directory& directory, const Credentials& credentials,
                                   int renderRank, const CodecSpec& codec, int deadPeerMs)
    : session_(directory.session),
      credentials_(credentials),
      renderRank_(renderRank),
      codec_(codec),
      deadPeerMs_(deadPeerMs),
      sendWaitMs_(std::min<int>(deadPeerMs, static_cast<int>(directory.timeoutMs))),
      live_(new std::atomic<bool>[directory.processes.size()]) {
  for (const Display& d : directory.layout.displays) {
    processOfDisplay_.push_back(d.process);
    batches_.push_back(std::make_unique<Batch>());
  }
  sockets_.resize(directory.processes.size());
  endpoints_.resize(directory.processes.size());
  for (size_t p = 0; p < directory.processes.size(); ++p) {
    socketMutex_.push_back(std::make_unique<std::mutex>());
    live_[p] = directory.processes[p].live;
    if (!directory.processes[p].endpoint.empty()) connect(p, directory.processes[p].endpoint);
  }
}

void ServicePieceSink::connect(size_t process, const std::string& endpoint) {
  zmq::socket_t socket(context_, zmq::socket_type::dealer);
  // A rank that is done still delivers its last batches (up to the timeout) as it exits.
  configureSocket(socket, Side::dials, deadPeerMs_, kMaxLinkMessageBytes, deadPeerMs_);
  makeClient(socket, credentials_);
  // A few frames of a whole display in flight at most; then send() waits (back-pressure).
  socket.set(zmq::sockopt::sndhwm, 64);
  socket.connect(endpoint);
  // What the old socket still held was for a process that is gone: it goes with it.
  if (sockets_[process]) sockets_[process].set(zmq::sockopt::linger, 0);
  sockets_[process] = std::move(socket);
  endpoints_[process] = endpoint;
}

void ServicePieceSink::setRoster(const Roster& roster) {
  if (roster.processes.size() != sockets_.size())
    throw base::Error("a roster of " + std::to_string(roster.processes.size()) +
                      " wall processes for " + std::to_string(sockets_.size()));
  for (size_t p = 0; p < sockets_.size(); ++p) {
    const DirectoryProcess& next = roster.processes[p];
    std::lock_guard lock(*socketMutex_[p]);
    if (!next.live && sockets_[p]) {
      // Batches still queued for a lost process would hold the rank's exit for its linger; the
      // process gets a fresh socket if it comes back.
      sockets_[p].set(zmq::sockopt::linger, 0);
      sockets_[p].close();
      endpoints_[p].clear();
    }
    if (next.live && next.endpoint != endpoints_[p]) connect(p, next.endpoint);
    live_[p] = next.live;
  }
}

// Waits while the process's queue is full (back-pressure from a slow wall), but not forever: a
// process that takes nothing for the wall's timeout is stuck or gone (the wall drops it within
// that time too, and the roster that says so is applied only between frames); its batch is
// dropped here rather than stalling the whole job.
void ServicePieceSink::sendBounded(size_t process, messaging::Bytes bytes, std::uint32_t pieces) {
  std::lock_guard lock(*socketMutex_[process]);
  zmq::socket_t& socket = sockets_[process];
  zmq::message_t message = toMessage(std::move(bytes));
  const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(sendWaitMs_);
  while (true) {
    if (!live_[process]) break;
    if (socket.send(message, zmq::send_flags::dontwait)) return;
    if (std::chrono::steady_clock::now() >= until) break;
    zmq::pollitem_t item{socket.handle(), 0, ZMQ_POLLOUT, 0};
    zmq::poll(&item, 1, std::chrono::milliseconds(100));
  }
  dropped_ += pieces;
}

ServicePieceSink::~ServicePieceSink() = default;

void ServicePieceSink::flush(int display, Batch& batch) {
  if (!batch.open) return;
  batch.open = false;
  const std::uint32_t pieces = batch.writer.pieces();
  messaging::Bytes bytes = batch.writer.take();
  const std::int64_t t0 = base::threadCpuNs();
  wireBytes_ += bytes.size();
  messages_++;
  sendBounded(static_cast<size_t>(processOfDisplay_[static_cast<size_t>(display)]),
              std::move(bytes), pieces);
  sendNs_ += base::threadCpuNs() - t0;
}

std::size_t ServicePieceSink::send(std::uint32_t frameId, int display, const dfb::Region& local,
                                   const std::uint32_t* pixels, int stride) {
  // A lost wall process's pieces are not even encoded.
  if (!live_[static_cast<size_t>(processOfDisplay_.at(static_cast<size_t>(display)))]) {
    ++dropped_;
    return 0;
  }
  const std::int64_t t0 = base::threadCpuNs();
  thread_local messaging::Bytes piece;
  encodePiece(codec_, local, pixels, stride, piece);
  cutNs_ += base::threadCpuNs() - t0;
  Batch& batch = *batches_.at(static_cast<size_t>(display));
  std::lock_guard lock(batch.mutex);
  if (batch.open && batch.frameId != frameId) flush(display, batch);
  if (!batch.open) {
    BatchHeader h;
    h.frameId = frameId;
    h.display = display;
    h.renderRank = static_cast<std::uint32_t>(renderRank_);
    h.codec = codec_.codec;
    batch.writer.start(session_, h);
    batch.frameId = frameId;
    batch.open = true;
  }
  batch.writer.append(piece);
  if (batch.writer.bytes() >= kFlushBytes) flush(display, batch);
  return static_cast<std::size_t>(local.pixelCount()) * 4 + kPieceRecordBytes;
}

void ServicePieceSink::endFrame(std::uint32_t frameId) {
  for (size_t d = 0; d < batches_.size(); ++d) {
    Batch& batch = *batches_[d];
    std::lock_guard lock(batch.mutex);
    if (batch.open && batch.frameId == frameId) flush(static_cast<int>(d), batch);
  }
}

}  // namespace wall::service
