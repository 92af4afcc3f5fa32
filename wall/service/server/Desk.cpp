#include "wall/service/server/Desk.h"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <future>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <set>
#include <sstream>
#include <thread>
#include <unordered_map>
#include <unordered_set>

#include "base/Error.h"
#include "wall/service/protocol/ConnectionWatch.h"
#include "wall/service/protocol/LinkMessages.h"
#include "wall/service/protocol/PeerText.h"
#include "wall/service/protocol/Protocol.h"
#include "wall/service/protocol/Zmq.h"
#include "wall/service/security/Gatekeeper.h"
#include "wall/service/server/JobDesk.h"
#include "wall/service/server/Membership.h"

namespace wall::service {
namespace {

using Clock = std::chrono::steady_clock;
constexpr std::size_t kMaxLogged = 1024;  // lines about strangers between two jobs
constexpr auto kTick = std::chrono::milliseconds(100);
// Messages taken off the directory socket in one turn of the loop: then the desk's own work
// (commands of the head's process, beats, silences, deadlines) runs, however many wait.
constexpr int kMaxBurst = 256;
// Connections whose messages are ignored (one sent something malformed), and connections whose
// hellos are counted: the oldest forgotten past these.
constexpr std::size_t kMaxBannedPeers = 4096;
constexpr std::size_t kMaxCountedPeers = 4096;
// A job says hello once per connection; past this a connection's messages are ignored.
constexpr int kMaxHellosPerPeer = 3;
// Parse errors quote what the peer sent.
constexpr std::size_t kMaxLoggedError = 200;

std::uint64_t randomId() {
  std::random_device device;
  std::uint64_t id = 0;
  while (id == 0) id = (static_cast<std::uint64_t>(device()) << 32) ^ device();
  return id;
}

Membership::Setup membershipSetup(const Desk::Setup& s) {
  // Tokens are checked at the handshake (the desk's gatekeeper), before any message arrives.
  return {s.layout->processCount, {}, layoutHash(*s.layout), s.layout->file, s.ownEndpoint,
          s.options.timeout};
}

JobDesk::Setup jobSetup(const Desk::Setup& s) {
  return {s.layout,
          {},
          s.options.timeout,
          s.options.framesInFlight,
          randomId,
          s.options.maxJobs,
          s.options.maxJobs > 1 ? s.options.thumbnailSide : 0};
}

template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};
template <class... F>
Overloaded(F...) -> Overloaded<F...>;

}  // namespace

// The desk thread owns the socket, the membership and the job machine; other threads (the head's
// own process) post tasks to it and wait for what it hands back.
struct Desk::Impl {
  Setup s;
  const int processCount;
  zmq::context_t context{1};
  Gatekeeper gatekeeper;
  zmq::socket_t socket;
  ConnectionWatch connections;  // of `socket`: a job whose connection closed is gone at once
  Waker waker;
  std::thread thread;
  std::atomic<bool> stop{false}, isClosed{false};

  // Shared with the head's process: its work for the desk thread, and its barrier releases and
  // gathers.
  mutable std::mutex mutex;
  std::deque<std::function<void()>> tasks;
  std::condition_variable handedBack;
  std::map<std::pair<std::uint64_t, std::uint32_t>, std::vector<std::int64_t>> releases;
  std::map<std::pair<std::uint64_t, std::uint32_t>, std::vector<std::vector<std::uint32_t>>>
      gathered;
  std::vector<int> absent;               // copy of members.absent(), for absentProcesses()
  std::vector<JobDesk::Window> windows;  // copy of jobs.windows(), for the window manager
  std::set<std::uint64_t> jobSessions;   // the jobs on the wall, for the head's barrier waits

  // The desk thread's own.
  Membership members;
  JobDesk jobs;
  std::set<std::string> logged;
  bool finished = false;
  // Connections the desk no longer listens to (FIFO, bounded), hellos per connection, and
  // connections a message could not be sent to this turn (why).
  std::unordered_set<std::string> banned;
  std::deque<std::string> bannedOrder;
  std::unordered_map<std::string, int> hellos;
  std::vector<std::pair<std::string, std::string>> unreachable;

  // Test-only (the service tests, until the wall's control port moves windows):
  // DFBWALL_TEST_MOVES="JOB:FRAME:X,Y,W,H;..." moves the window of the JOB-th job the wall took
  // (from 1) to each rectangle once that job's credited frame reaches FRAME, in order
  // (tests/apps/window_move_test.sh).
  struct TestMove {
    std::size_t job = 0;
    std::uint32_t frame = 0;
    dfb::Region window;
  };
  std::deque<TestMove> testMoves;
  std::vector<std::uint64_t> jobsSeen;  // sessions, in the order they came
  void readTestMoves() {
    const char* text = std::getenv("DFBWALL_TEST_MOVES");
    if (!text) return;
    std::stringstream all(text);
    std::string one;
    while (std::getline(all, one, ';')) {
      unsigned job = 0, frame = 0;
      int x = 0, y = 0, w = 0, h = 0;
      if (std::sscanf(one.c_str(), "%u:%u:%d,%d,%d,%d", &job, &frame, &x, &y, &w, &h) != 6 ||
          job == 0)
        throw base::Error("DFBWALL_TEST_MOVES: '" + one + "' is not JOB:FRAME:X,Y,W,H");
      testMoves.push_back({job, frame, {x, y, x + w, y + h}});
    }
  }
  void moveForTest() {
    if (testMoves.empty()) return;
    for (const std::uint64_t session : jobs.sessions())
      if (std::find(jobsSeen.begin(), jobsSeen.end(), session) == jobsSeen.end())
        jobsSeen.push_back(session);
    const TestMove& move = testMoves.front();
    if (jobsSeen.size() < move.job) return;
    const std::uint64_t session = jobsSeen[move.job - 1];
    if (jobs.state(session) != JobDesk::State::Running || jobs.moving(session) ||
        jobs.lastCredited(session) < move.frame)
      return;
    JobDesk::MoveVerdict v;
    carry(jobs.reshape(session, move.window, Clock::now(), v));
    if (v.code != JobDesk::MoveVerdict::Code::Moving) log("DFBWALL_TEST_MOVES: " + v.why);
    testMoves.pop_front();
  }

  explicit Impl(Setup setup)
      : s(std::move(setup)),
        processCount(s.layout->processCount),
        gatekeeper(context, s.options.credentials, s.options.log),
        socket(context, zmq::socket_type::router),
        connections(context, socket),
        members(membershipSetup(s), Clock::now()),
        jobs(jobSetup(s), members) {
    configureSocket(socket, Side::accepts, static_cast<int>(s.options.timeout.count()),
                    kMaxLinkMessageBytes);
    makeServer(socket, s.options.credentials);
    // A message the desk cannot hand to a connection (gone, or its queue full) is an error it
    // sees, never a silent drop: a barrier release that does not go out loses that process.
    socket.set(zmq::sockopt::router_mandatory, 1);
    absent = members.absent();
    readTestMoves();
  }

  void post(std::function<void()> task) {
    {
      std::lock_guard lock(mutex);
      tasks.push_back(std::move(task));
    }
    waker.notify();
  }
  void log(const std::string& line) {
    if (s.options.log) s.options.log(line);
  }
  // Lines about a connection's messages, once each until the job ends.
  void logOnce(const std::string& peer, const std::string& line) {
    if (logged.size() >= kMaxLogged || !logged.insert(peer + line).second) return;
    log(line);
  }
  // False when the message could not go out: the connection is gone or its queue is full.
  // `mustArrive`: the desk then deals with that connection this turn (settleUnreachable).
  bool reply(const std::string& peer, messaging::Bytes message, bool mustArrive = true) {
    std::string why;
    try {
      zmq::message_t id(peer.data(), peer.size());
      if (socket.send(id, zmq::send_flags::sndmore | zmq::send_flags::dontwait)) {
        // Past the first part the router takes the rest of the message.
        socket.send(toMessage(std::move(message)), zmq::send_flags::dontwait);
        return true;
      }
      why = "its send queue is full";
    } catch (const zmq::error_t& e) {
      why = e.num() == EHOSTUNREACH ? std::string("it is no longer connected") : e.what();
    }
    if (mustArrive) unreachable.emplace_back(peer, why);
    return false;
  }
  // A process the head cannot send to is lost; a job it cannot send to (its credits) ends.
  void settleUnreachable() {
    std::vector<std::pair<std::string, std::string>> now;
    now.swap(unreachable);
    for (const auto& [peer, why] : now) {
      if (const int p = members.processOf(peer); p > 0)
        drop(p, "the head could not send to it: " + why);
      else
        carry(jobs.failed(peer, "the wall could not send to the job: " + why, Clock::now()));
    }
  }
  // A connection that sent something malformed: out of the desk's tables, and what it sends
  // from now on is dropped unread (a ROUTER socket cannot close one connection; it closes once
  // the peer's heartbeats stop or its host stops answering TCP keepalives).
  void banish(const std::string& peer, const std::string& why) {
    hellos.erase(peer);
    carry(jobs.failed(peer, why, Clock::now()));
    if (const int p = members.processOf(peer); p > 0) drop(p, why);
    if (!banned.insert(peer).second) return;
    bannedOrder.push_back(peer);
    if (bannedOrder.size() > kMaxBannedPeers) {
      banned.erase(bannedOrder.front());
      bannedOrder.pop_front();
    }
  }
  void publishAbsent() {
    std::vector<int> now = members.absent();
    std::lock_guard lock(mutex);
    absent = std::move(now);
  }
  void publishWindows() {
    std::vector<JobDesk::Window> now = jobs.windows(Clock::now());
    std::lock_guard lock(mutex);
    windows = std::move(now);
  }
  // `work` on the desk thread; its answer, once it ran.
  bool onDeskThread(std::function<bool()> work) {
    auto answer = std::make_shared<std::optional<bool>>();
    post([this, work, answer] {
      const bool result = work();
      publishWindows();
      handBack([&] { *answer = result; });
    });
    std::unique_lock lock(mutex);
    handedBack.wait_for(lock, std::chrono::seconds(5),
                        [&] { return answer->has_value() || isClosed; });
    if (!answer->has_value()) throw base::Error("the wall's desk did not answer (it stopped)");
    return **answer;
  }
  // A move of the window of the job `session()` names (on the desk thread), and its verdict.
  JobDesk::MoveVerdict moveOnDeskThread(std::function<std::optional<std::uint64_t>()> session,
                                        const dfb::Region& window) {
    auto verdict = std::make_shared<std::promise<JobDesk::MoveVerdict>>();
    std::future<JobDesk::MoveVerdict> answered = verdict->get_future();
    post([this, session, window, verdict] {
      JobDesk::MoveVerdict v{JobDesk::MoveVerdict::Code::UnknownWindow, "no such window"};
      if (const std::optional<std::uint64_t> id = session())
        carry(jobs.reshape(*id, window, Clock::now(), v));
      publishWindows();
      verdict->set_value(v);
    });
    if (answered.wait_for(std::chrono::seconds(5)) != std::future_status::ready || isClosed)
      return {JobDesk::MoveVerdict::Code::Conflict, "the wall is stopping"};
    return answered.get();
  }
  void handBack(const std::function<void()>& change) {
    std::lock_guard lock(mutex);
    change();
    handedBack.notify_all();
  }

  // ---- carrying out the job machine's actions, in order ----
  void sendTo(int p, const ServiceCommand& command) {
    if (p == 0) return s.deliver(command);
    if (members.live(p))
      reply(members.member(p).peer,
            packCommandMessage(command.header.session, packCommand(command)));
  }
  void carry(JobDesk::Actions actions) {
    const Overloaded carryOut{
        [&](JobDesk::Reply& r) { reply(r.peer, std::move(r.message), jobs.connected(r.peer)); },
        [&](JobDesk::ToProcess& c) { sendTo(c.process, c.command); },
        [&](JobDesk::Release& r) { release(r); },
        [&](JobDesk::Gathered& g) {
          handBack([&] { gathered[{g.session, g.frameId}] = std::move(g.pixels); });
        },
        [&](JobDesk::Drop& d) { drop(d.process, d.why); },
        [&](JobDesk::Log& l) { l.oncePer.empty() ? log(l.line) : logOnce(l.oncePer, l.line); },
        [&](JobDesk::Record& r) {
          if (s.options.jobRecord) s.options.jobRecord(r.json);
        },
        [&](JobDesk::Session& j) {
          handBack([&] {
            if (j.ended)
              jobSessions.erase(j.session);
            else
              jobSessions.insert(j.session);
          });
          if (j.ended) logged.clear();
        },
        [&](JobDesk::Closing&) { socket.set(zmq::sockopt::linger, 1000); },
        [&](JobDesk::Closed&) { finished = true; },
    };
    for (JobDesk::Action& action : actions) std::visit(carryOut, action);
  }
  void release(JobDesk::Release& r) {
    if (r.process == 0)
      handBack([&] { releases[{r.session, r.frameId}] = std::move(r.values); });
    else if (members.live(r.process))
      reply(members.member(r.process).peer,
            packBarrier(r.session, {r.frameId, std::move(r.values)}));
  }

  // ---- the wall's processes ----
  void drop(int p, const std::string& why) {
    if (!members.drop(p)) return;
    publishAbsent();
    // Heard if it only hung; a link that cannot take it is gone already.
    reply(members.member(p).peer, packText(Kind::Dropped, 0, why), false);
    carry(jobs.lost(p, why, Clock::now()));
  }
  void onJoin(const std::string& peer, const std::byte* data, size_t size) {
    Join j;
    try {
      j = parseJoin(data, size);
    } catch (const std::exception& e) {
      logOnce(peer, "refused a wall process: " + peerText(e.what(), kMaxLoggedError));
      reply(peer, packText(Kind::Refused, 0, e.what()), false);
      banish(peer, e.what());
      return;
    }
    const Membership::Verdict verdict = members.check(j);
    const int p = static_cast<int>(j.process);
    const auto now = Clock::now();
    if (verdict.outcome == Membership::Verdict::Outcome::Refused) {
      logOnce(peer, "refused wall process " + std::to_string(j.process) + " from " +
                        peerText(j.host) + ": " + verdict.problem);
      reply(peer, packText(Kind::Refused, 0, verdict.problem), false);
      return;
    }
    if (verdict.outcome == Membership::Verdict::Outcome::Again) {  // it missed the welcome
      members.heard(p, now);
      reply(peer, packControl(Kind::Welcome, 0, j.incarnation));
      return;
    }
    if (verdict.replaces) drop(p, "it started again (on " + j.host + ")");
    members.admit(peer, j, now);
    publishAbsent();
    reply(peer, packControl(Kind::Welcome, 0, j.incarnation));
    carry(jobs.joined(p, now));
  }
  void onMemberMessage(const std::string& peer, const MessageHeader& h, const std::byte* data,
                       size_t size) {
    const Kind kind = static_cast<Kind>(h.kind);
    if (kind == Kind::Join) return onJoin(peer, data, size);
    const int p = members.processOf(peer);
    if (p < 0) {
      // A process the wall dropped, or that joined a head before this one: it must join again.
      reply(peer, packText(Kind::Dropped, 0, "this wall process is not in the wall (now)"), false);
      return;
    }
    const auto now = Clock::now();
    members.heard(p, now);
    switch (kind) {
      case Kind::Beat:
        return;
      case Kind::Command: {
        ServiceCommand c = parseCommand(commandBody(data, size));
        c.header.process = p;
        return carry(jobs.answer(p, c, now));
      }
      case Kind::Barrier: {
        BarrierValues b = parseBarrier(data, size);
        return carry(jobs.arrive(p, h.session, b.frameId, b.values, now));
      }
      case Kind::Pixels: {
        CapturePixels c = parsePixels(data, size);
        return carry(jobs.pixels(p, h.session, c.frameId, std::move(c.pixels), now));
      }
      case Kind::Thumbnail:
        return jobs.thumbnail(p, h.session, parseThumbnail(data, size));
      default:
        logOnce(peer, "ignored a message on the directory port: message kind " +
                          std::to_string(h.kind) + " from " + members.who(p));
    }
  }
  // Beats to every live member; the silent ones dropped.
  void watch(Clock::time_point now) {
    if (members.beatDue(now))
      for (int p = 1; p < members.processCount(); ++p)
        if (members.live(p))
          reply(members.member(p).peer, packControl(Kind::Beat, 0, members.member(p).incarnation));
    for (const Membership::Silent& silent : members.silent(now)) drop(silent.process, silent.why);
  }

  // ---- jobs ----
  void onJobMessage(const std::string& peer, const MessageHeader& h, const std::byte* data,
                    size_t size) {
    const Kind kind = static_cast<Kind>(h.kind);
    if (kind == Kind::Hello) {
      if (hellos.size() >= kMaxCountedPeers) hellos.clear();
      if (++hellos[peer] > kMaxHellosPerPeer)
        return banish(peer, "more than " + std::to_string(kMaxHellosPerPeer) + " hellos");
      Hello hello;
      try {
        hello = parseHello(data, size);
      } catch (const std::exception& e) {
        logOnce(peer, "refused a job: " + peerText(e.what(), kMaxLoggedError));
        reply(peer, packText(Kind::Refused, 0, e.what()), false);
        banish(peer, e.what());
        return;
      }
      return carry(jobs.hello(peer, hello, Clock::now()));
    }
    JobDesk::JobMessage m{peer, kind, h.session, {}, {}};
    try {
      m.control = parseControl(data, size);
    } catch (const std::exception& e) {
      m.malformed = e.what();
    }
    carry(jobs.message(m, Clock::now()));
    if (!m.malformed.empty()) banish(peer, m.malformed);
  }

  // ---- the thread ----
  void onMessage(const std::string& peer, const std::byte* data, size_t size) {
    MessageHeader h;
    try {
      h = parseHeader(data, size);
    } catch (const std::exception& e) {
      logOnce(peer,
              "ignored a message on the directory port: " + peerText(e.what(), kMaxLoggedError));
      // A dfbwall of another version learns why at once instead of at its timeout.
      MessageHeader mine;
      std::memcpy(&mine, data, std::min(size, sizeof mine));
      if (size >= sizeof mine && mine.magic == kMagic)
        reply(peer, packText(Kind::Refused, 0, e.what()), false);
      banish(peer, e.what());
      return;
    }
    const Kind kind = static_cast<Kind>(h.kind);
    const bool fromMember = kind == Kind::Join || kind == Kind::Beat || kind == Kind::Command ||
                            kind == Kind::Barrier || kind == Kind::Pixels ||
                            kind == Kind::Thumbnail;
    try {
      if (fromMember)
        onMemberMessage(peer, h, data, size);
      else
        onJobMessage(peer, h, data, size);
    } catch (const std::exception& e) {
      // Nothing a client sends ends the wall; a failure handling it drops its job (or its
      // process) at most.
      logOnce(peer,
              "handling a message on the directory port: " + peerText(e.what(), kMaxLoggedError));
      banish(peer, e.what());
    }
  }
  // True when every message waiting was taken.
  bool receive() {
    zmq::message_t id, body;
    int n = 0;
    for (; n < kMaxBurst && socket.recv(id, zmq::recv_flags::dontwait); ++n) {
      if (!id.more() || !socket.recv(body, zmq::recv_flags::dontwait)) continue;
      const std::string peer(static_cast<const char*>(id.data()), id.size());
      connections.heard(peer, body);
      const bool banishedPeer = banned.count(peer) != 0;
      // Parts (a process's captured pixels) join into one message; only a member sends them.
      // Every part is read even from a banished peer, so the next message starts where it should.
      const std::size_t joinable =
          !banishedPeer && members.processOf(peer) > 0 ? kMaxMessageBytes : 0;
      const bool whole = !body.more() || receiveJoined(socket, body, joinable);
      if (banishedPeer) continue;
      if (!whole) {
        banish(peer, "a message of several parts or too large");
        continue;
      }
      onMessage(peer, static_cast<const std::byte*>(body.data()), body.size());
    }
    return n < kMaxBurst;
  }
  // Connections that closed: a job's ends at once (a job that dies closes its socket; mpirun
  // ends its other ranks), a queued one leaves the queue. A wall process's link is left to its
  // beats: it rejoins over a new connection, and its silence or its Join decides.
  void settleClosed() {
    for (const std::string& peer : connections.closed()) {
      hellos.erase(peer);
      if (members.processOf(peer) < 0) carry(jobs.disconnected(peer, Clock::now()));
    }
  }
  void run() {
    while (!stop && !finished) {
      zmq::pollitem_t items[3] = {
          {socket.handle(), 0, ZMQ_POLLIN, 0}, waker.pollItem(), connections.pollItem()};
      zmq::poll(items, 3, kTick);
      if (items[1].revents) waker.drain();
      std::deque<std::function<void()>> now;
      {
        std::lock_guard lock(mutex);
        now.swap(tasks);
      }
      for (auto& task : now) task();
      // A closed connection once all it sent before is read: its goodbye decides first.
      if (receive()) settleClosed();
      settleUnreachable();
      // A closing wall waits for the processes' confirmations only: no beats, no drops.
      if (jobs.state() != JobDesk::State::Closed) watch(Clock::now());
      carry(jobs.tick(Clock::now()));
      moveForTest();
      settleUnreachable();
      publishWindows();
    }
    isClosed = true;
    std::lock_guard lock(mutex);
    handedBack.notify_all();
  }
};

Desk::Desk(Setup setup) : impl_(std::make_unique<Impl>(std::move(setup))) {}

Desk::~Desk() {
  impl_->stop = true;
  impl_->waker.notify();
  if (impl_->thread.joinable()) impl_->thread.join();
}

std::string Desk::bind(const std::string& endpoint) {
  try {
    impl_->socket.bind(endpoint);
  } catch (const zmq::error_t& e) {
    throw base::Error("--listen " + impl_->s.options.listen + ": cannot listen there (" + e.what() +
                      ")");
  }
  return lastEndpoint(impl_->socket);
}

void Desk::start() {
  impl_->thread = std::thread([this] {
    try {
      impl_->run();
    } catch (const std::exception& e) {
      impl_->log(std::string("the desk failed: ") + e.what());
      std::abort();
    }
  });
}

std::vector<int> Desk::absentProcesses() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->absent;
}

bool Desk::closed() const { return impl_->isClosed; }

std::vector<JobDesk::Window> Desk::windows() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->windows;
}

bool Desk::raise(std::uint64_t number) {
  return impl_->onDeskThread([this, number] {
    std::optional<JobDesk::Actions> actions = impl_->jobs.raise(number);
    if (actions) impl_->carry(std::move(*actions));
    return actions.has_value();
  });
}

bool Desk::close(std::uint64_t number, const std::string& why) {
  return impl_->onDeskThread([this, number, why] {
    std::optional<JobDesk::Actions> actions = impl_->jobs.close(number, why, Clock::now());
    if (actions) impl_->carry(std::move(*actions));
    return actions.has_value();
  });
}

void Desk::toHead(const ServiceCommand& command, std::uint64_t) {
  impl_->post([this, command] { impl_->carry(impl_->jobs.answer(0, command, Clock::now())); });
}

void Desk::agreeMax(std::uint64_t, std::uint64_t session, std::uint32_t frameId,
                    std::int64_t* values, int count, Clock::time_point) {
  std::vector<std::int64_t> mine(values, values + count);
  impl_->post([this, session, frameId, mine] {
    impl_->carry(impl_->jobs.arrive(0, session, frameId, mine, Clock::now()));
  });
  // The desk releases the barrier once every process in it arrived or was dropped (one silent,
  // or that has not come the timeout after the first while the job is alive, is dropped; a job
  // that goes silent is aborted, and every node then arrives giving the frame up): no deadline
  // of the node's applies here.
  std::unique_lock lock(impl_->mutex);
  const auto key = std::make_pair(session, frameId);
  impl_->handedBack.wait(lock, [&] {
    return impl_->releases.count(key) > 0 || impl_->isClosed ||
           impl_->jobSessions.count(session) == 0;
  });
  if (impl_->releases.count(key) == 0)
    throw base::Error("swap barrier of frame " + std::to_string(frameId) +
                      ": the job is no longer the wall's");
  const std::vector<std::int64_t> agreed = std::move(impl_->releases[key]);
  impl_->releases.erase(key);
  std::copy(agreed.begin(), agreed.end(), values);
}

std::vector<std::vector<std::uint32_t>> Desk::gatherToFirst(std::uint64_t, std::uint64_t session,
                                                            std::uint32_t frameId,
                                                            std::vector<std::uint32_t> mine,
                                                            Clock::time_point deadline) {
  auto pixels = std::make_shared<std::vector<std::uint32_t>>(std::move(mine));
  impl_->post([this, session, frameId, pixels, deadline] {
    impl_->carry(
        impl_->jobs.headPixels(session, frameId, std::move(*pixels), deadline, Clock::now()));
  });
  std::unique_lock lock(impl_->mutex);
  const auto key = std::make_pair(session, frameId);
  impl_->handedBack.wait_until(lock, deadline + std::chrono::seconds(1),
                               [&] { return impl_->gathered.count(key) > 0 || impl_->isClosed; });
  auto found = impl_->gathered.find(key);
  if (found == impl_->gathered.end())
    return std::vector<std::vector<std::uint32_t>>(static_cast<size_t>(impl_->processCount));
  auto out = std::move(found->second);
  impl_->gathered.erase(found);
  return out;
}

JobDesk::MoveVerdict Desk::reshape(std::uint64_t session, const dfb::Region& window) {
  return impl_->moveOnDeskThread([session] { return std::optional<std::uint64_t>(session); },
                                 window);
}

JobDesk::MoveVerdict Desk::moveWindow(std::uint64_t number, const dfb::Region& window) {
  return impl_->moveOnDeskThread([this, number] { return impl_->jobs.sessionOf(number); }, window);
}

void Desk::thumbnail(std::uint64_t session, const ThumbnailPart& part) {
  impl_->post([this, session, part] { impl_->jobs.thumbnail(0, session, part); });
}

void Desk::presented(std::uint64_t session, std::uint32_t frameId, std::int64_t completeNs) {
  impl_->post([this, session, frameId, completeNs] {
    impl_->carry(impl_->jobs.presented(session, frameId, completeNs, Clock::now()));
  });
}

}  // namespace wall::service
