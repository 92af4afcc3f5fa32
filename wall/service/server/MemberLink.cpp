#include "wall/service/server/MemberLink.h"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <map>
#include <mutex>
#include <random>
#include <thread>
#include <vector>

#include "base/Error.h"
#include "wall/service/protocol/Protocol.h"
#include "wall/service/protocol/Zmq.h"
#include "wall/service/security/HandshakeWatch.h"

namespace wall::service {
namespace {
constexpr auto kJoinEvery = std::chrono::milliseconds(500);
constexpr auto kTick = std::chrono::milliseconds(50);

std::uint64_t newIncarnation() {
  std::random_device device;
  std::uint64_t id = 0;
  while (id == 0) id = (static_cast<std::uint64_t>(device()) << 32) ^ device();
  return id;
}
}  // namespace

struct MemberLink::Impl {
  Setup s;
  const std::chrono::milliseconds beat;
  zmq::context_t context{1};
  std::unique_ptr<zmq::socket_t> socket;
  std::unique_ptr<HandshakeWatch> watch;  // of `socket`
  bool handshakeLogged = false;
  Waker waker;
  std::thread thread;
  std::atomic<bool> stop{false};
  std::atomic<std::int64_t> mainAliveNs{Clock::now().time_since_epoch().count()};

  mutable std::mutex mutex;
  std::condition_variable changed;
  std::vector<messaging::Bytes> outbox;
  bool isJoined = false;
  std::uint64_t generation = 0;  // counts losses: a wait that began before one ends with it
  std::string refusedWhy;
  std::map<std::pair<std::uint64_t, std::uint32_t>, std::vector<std::int64_t>> releases;

  // The link thread's own.
  std::uint64_t incarnation = newIncarnation();
  Clock::time_point lastJoinSent, lastHeard, lastBeat;
  bool everJoined = false;

  explicit Impl(Setup setup)
      : s(std::move(setup)),
        beat(std::clamp<std::chrono::milliseconds>(s.timeout / 4, std::chrono::milliseconds(50),
                                                   std::chrono::milliseconds(1000))) {}

  void log(const std::string& line) {
    if (s.log) s.log(line);
  }
  void newSocket() {
    watch.reset();
    socket = std::make_unique<zmq::socket_t>(context, zmq::socket_type::dealer);
    configureSocket(*socket, Side::dials, static_cast<int>(s.timeout.count()), kMaxBatchBytes);
    makeClient(*socket, s.credentials);
    watch = std::make_unique<HandshakeWatch>(context, *socket);
    // Nothing queues for a head that is not connected: joins are repeated, and anything else
    // sent while the link is down belongs to a job the head will have forgotten.
    socket->set(zmq::sockopt::immediate, 1);
    socket->connect(tcpEndpoint(s.head, "--join"));
  }
  void send(messaging::Bytes bytes) {
    // The head takes parts of at most kMaxLinkMessageBytes (captured pixels are larger).
    if (bytes.size() > kMaxLinkMessageBytes)
      sendInParts(*socket, bytes, kMaxLinkMessageBytes);
    else
      socket->send(toMessage(std::move(bytes)), zmq::send_flags::dontwait);
  }
  // A head that refuses the token will not change its mind: fatal. So is a handshake that breaks
  // off before this process ever joined (another key: a start with the wrong files). One that
  // breaks off later may be a head that is stopped or restarting: said once, and the link keeps
  // trying.
  void checkHandshake() {
    const HandshakeWatch::State state = watch->poll();
    if (state == HandshakeWatch::State::Refused ||
        (state == HandshakeWatch::State::Failed && !everJoined)) {
      std::lock_guard lock(mutex);
      refusedWhy = "at the handshake: " + watch->problem() +
                   (state == HandshakeWatch::State::Refused
                        ? " (this process needs the wall's token: --token-file FILE or "
                          "DFBWALL_TOKEN)"
                        : "");
      changed.notify_all();
    } else if (state == HandshakeWatch::State::Failed && !handshakeLogged) {
      log("no handshake with the head at " + s.head + " yet: " + watch->problem());
      handshakeLogged = true;
    } else if (state == HandshakeWatch::State::Succeeded) {
      handshakeLogged = false;
    }
  }
  void post(messaging::Bytes bytes, std::uint64_t epoch) {
    {
      std::lock_guard lock(mutex);
      if (!isJoined || epoch != generation) return;
      outbox.push_back(std::move(bytes));
    }
    waker.notify();
  }
  void lose(const std::string& why) {
    {
      std::lock_guard lock(mutex);
      isJoined = false;
      ++generation;
      outbox.clear();
      releases.clear();
      changed.notify_all();
    }
    log("lost the wall's head at " + s.head + " (" + why + "); joining again");
    if (s.onLost) s.onLost(why);
    newSocket();
    incarnation = newIncarnation();
    lastJoinSent = {};
  }
  void onMessage(const zmq::message_t& m) {
    const auto* data = static_cast<const std::byte*>(m.data());
    const MessageHeader h = parseHeader(data, m.size());
    bool joinedNow = false;
    {
      std::lock_guard lock(mutex);
      joinedNow = isJoined;
    }
    switch (static_cast<Kind>(h.kind)) {
      case Kind::Welcome: {
        if (joinedNow || parseControl(data, m.size()).value != incarnation) return;
        lastHeard = lastBeat = Clock::now();
        {
          std::lock_guard lock(mutex);
          isJoined = true;
          changed.notify_all();
        }
        log(std::string(everJoined ? "joined the wall again" : "joined the wall") + " at " +
            s.head);
        everJoined = true;
        return;
      }
      case Kind::Refused: {
        if (joinedNow) return;
        std::lock_guard lock(mutex);
        refusedWhy = parseText(data, m.size());
        changed.notify_all();
        return;
      }
      case Kind::Beat:
        lastHeard = Clock::now();
        return;
      case Kind::Dropped:
        if (joinedNow) lose("the head dropped this process: " + parseText(data, m.size()));
        return;
      case Kind::Command: {
        if (!joinedNow) return;
        lastHeard = Clock::now();
        const ServiceCommand c = parseCommand(commandBody(data, m.size()));
        // The head waits for this before it closes its socket: its shutdown reached us.
        if (c.header.kind == Command::Shutdown) send(packCommandMessage(0, packCommand(c)));
        if (s.deliver) s.deliver(c);
        return;
      }
      case Kind::Barrier: {
        if (!joinedNow) return;
        lastHeard = Clock::now();
        BarrierValues b = parseBarrier(data, m.size());
        std::lock_guard lock(mutex);
        releases[{h.session, b.frameId}] = std::move(b.values);
        changed.notify_all();
        return;
      }
      default:
        return;
    }
  }
  void run() {
    newSocket();
    while (!stop) {
      zmq::pollitem_t items[2] = {{socket->handle(), 0, ZMQ_POLLIN, 0}, waker.pollItem()};
      zmq::poll(items, 2, kTick);
      if (items[1].revents) waker.drain();
      std::vector<messaging::Bytes> out;
      bool joinedNow = false;
      {
        std::lock_guard lock(mutex);
        out.swap(outbox);
        joinedNow = isJoined;
      }
      checkHandshake();
      const auto now = Clock::now();
      for (messaging::Bytes& m : out) send(std::move(m));
      const bool mainIsAlive = now.time_since_epoch().count() - mainAliveNs <
                               std::chrono::duration_cast<Clock::duration>(s.timeout).count();
      // A process whose presenting thread hangs stays out of the wall until it runs again.
      if (!joinedNow && mainIsAlive && now - lastJoinSent >= kJoinEvery) {
        Join j = s.join;
        j.incarnation = incarnation;
        send(packJoin(j));
        lastJoinSent = now;
      }
      if (joinedNow && mainIsAlive && now - lastBeat >= beat) {
        send(packControl(Kind::Beat, 0, incarnation));
        lastBeat = now;
      }
      if (joinedNow && now - lastHeard > s.timeout)
        lose("no word from it for " + std::to_string(s.timeout.count()) + " ms");
      zmq::message_t m;
      while (socket->recv(m, zmq::recv_flags::dontwait)) {
        try {
          onMessage(m);
        } catch (const std::exception& e) {
          log(std::string("ignored a message from the head: ") + e.what());
        }
      }
    }
  }
};

MemberLink::MemberLink(Setup setup) : impl_(std::make_unique<Impl>(std::move(setup))) {
  tcpEndpoint(impl_->s.head, "--join");  // a bad address is an error now, not in the thread
}

MemberLink::~MemberLink() {
  impl_->stop = true;
  impl_->waker.notify();
  if (impl_->thread.joinable()) impl_->thread.join();
}

void MemberLink::start() {
  impl_->thread = std::thread([this] {
    try {
      impl_->run();
    } catch (const std::exception& e) {
      impl_->log(std::string("the link to the head failed: ") + e.what());
      std::abort();
    }
  });
}

bool MemberLink::waitUntilJoined(Clock::time_point until) {
  std::unique_lock lock(impl_->mutex);
  // The process waits here on its presenting thread, alive.
  while (Clock::now() < until && !impl_->isJoined && impl_->refusedWhy.empty()) {
    impl_->mainAliveNs = Clock::now().time_since_epoch().count();
    impl_->changed.wait_until(lock, std::min(until, Clock::now() + std::chrono::milliseconds(250)));
  }
  if (!impl_->refusedWhy.empty())
    throw base::Error("the wall's head at " + impl_->s.head +
                      " refused this process: " + impl_->refusedWhy);
  return impl_->isJoined;
}

void MemberLink::mainAlive() { impl_->mainAliveNs = Clock::now().time_since_epoch().count(); }

bool MemberLink::joined() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->isJoined;
}

std::string MemberLink::refusal() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->refusedWhy;
}

std::uint64_t MemberLink::epoch() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->generation;
}

void MemberLink::toHead(const ServiceCommand& command, std::uint64_t epoch) {
  impl_->post(packCommandMessage(command.header.session, packCommand(command)), epoch);
}

void MemberLink::thumbnail(std::uint64_t session, const ThumbnailPart& part) {
  impl_->post(packThumbnail(session, part), epoch());
}

void MemberLink::agreeMax(std::uint64_t epoch, std::uint64_t session, std::uint32_t frameId,
                          std::int64_t* values, int count, Clock::time_point) {
  std::unique_lock lock(impl_->mutex);
  if (!impl_->isJoined || epoch != impl_->generation)
    throw base::Error("swap barrier of frame " + std::to_string(frameId) +
                      ": this process is not in the wall (it lost the head)");
  const std::uint64_t generation = impl_->generation;
  impl_->outbox.push_back(
      packBarrier(session, {frameId, std::vector<std::int64_t>(values, values + count)}));
  impl_->waker.notify();
  // The head releases the barrier once every process in it arrived or was dropped (one that
  // has not come the timeout after the first is dropped), and a silent head is lost after the
  // timeout (a new generation): no deadline of the node's applies here.
  const auto key = std::make_pair(session, frameId);
  while (impl_->releases.count(key) == 0 && impl_->generation == generation) {
    // Waiting here is not hanging: the presenting thread stays alive for the head.
    impl_->mainAliveNs = Clock::now().time_since_epoch().count();
    impl_->changed.wait_for(lock, std::chrono::milliseconds(250));
  }
  auto found = impl_->releases.find(key);
  if (found == impl_->releases.end())
    throw base::Error("swap barrier of frame " + std::to_string(frameId) +
                      ": this process lost the wall's head");
  if (static_cast<int>(found->second.size()) != count)
    throw base::Error("swap barrier of frame " + std::to_string(frameId) + ": the head released " +
                      std::to_string(found->second.size()) + " values, not " +
                      std::to_string(count));
  std::copy(found->second.begin(), found->second.end(), values);
  impl_->releases.erase(found);
}

std::vector<std::vector<std::uint32_t>> MemberLink::gatherToFirst(std::uint64_t epoch,
                                                                  std::uint64_t session,
                                                                  std::uint32_t frameId,
                                                                  std::vector<std::uint32_t> mine,
                                                                  Clock::time_point) {
  impl_->post(packPixels(session, frameId, mine), epoch);
  return {};
}

}  // namespace wall::service
