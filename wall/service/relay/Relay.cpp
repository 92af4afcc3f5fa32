#include "wall/service/relay/Relay.h"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <vector>

#include "base/Error.h"
#include "wall/service/protocol/ConnectionWatch.h"
#include "wall/service/protocol/PeerText.h"
#include "wall/service/protocol/Protocol.h"
#include "wall/service/protocol/Zmq.h"
#include "wall/service/relay/RelayRoutes.h"
#include "wall/service/security/Gatekeeper.h"
#include "wall/service/security/HandshakeWatch.h"

namespace wall::service {
namespace {

using Clock = std::chrono::steady_clock;
// Job connections at once (a queue of waiting jobs included): a flood of connections gets
// refusals, not a socket each.
constexpr std::size_t kMaxJobs = 256;
// Job connections at once from one peer address: enough for a host's jobs queued behind each
// other, too few for one host to hold every slot.
constexpr std::size_t kMaxJobsPerPeer = 8;
// Batches queued per wall process towards the wall, and per job connection towards the relay:
// a batch holds up to a few MiB, so this bounds the relay's memory (about 16 x 4 MiB per wall
// process and connection), and a full queue stops the relay reading that process's socket.
constexpr int kPieceHwm = 16;
// Batches forwarded per wall process before the other sockets get their turn.
constexpr int kBurst = 64;
// A job that said goodbye (or was ended or refused) is forgotten this much later: its last
// batches, which travel beside the goodbye, still pass.
constexpr auto kGrace = std::chrono::seconds(5);
constexpr std::size_t kMaxLogged = 1024;
// The wall answers a hello at once (a directory, a refusal or the job's place in its queue); a
// job whose hello it has not answered this long (or within the relay's timeout) learns so from
// the relay instead of waiting for its own timeout.
constexpr auto kHelloAnswer = std::chrono::seconds(10);

const std::byte* bytesOf(const zmq::message_t& m) {
  return static_cast<const std::byte*>(m.data());
}

std::string hex(const void* data, std::size_t size) {
  static const char* digits = "0123456789abcdef";
  std::string s;
  const auto* b = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i) {
    s += digits[b[i] >> 4];
    s += digits[b[i] & 15];
  }
  return s;
}

}  // namespace

struct Relay::Impl {
  RelayOptions options;
  zmq::context_t context{1};
  std::unique_ptr<Gatekeeper> gatekeeper;                  // before any socket binds
  zmq::socket_t front{context, zmq::socket_type::router};  // the jobs' directory links
  // Of `front`: a job connection that closes closes the job's own link to the wall at once, so
  // the wall drops it at once too (and a relay that dies closes every job's link).
  ConnectionWatch frontConnections{context, front};
  std::string wallEndpoint;  // the wall's directory
  std::string bindHost, advertised, address;
  int deadPeerMs = 60000;

  // One job connection (a render job's rank 0), by its routing id on `front`.
  struct Job {
    zmq::socket_t wall;                         // its own connection to the wall's directory
    std::unique_ptr<HandshakeWatch> handshake;  // of `wall`
    std::string id, host = "an unnamed host", peerAddress;
    std::uint64_t session = 0;                 // from the wall's Directory
    std::vector<std::uint64_t> pieceSessions;  // of its moved windows (Reshape)
    Clock::time_point lastHeard, started;
    bool wallAnswered = false;
    std::optional<Clock::time_point> over;  // goodbye, Ended or Refused: forgotten kGrace later
    std::string end;                        // why it is over
    std::uint64_t batches = 0, bytes = 0, dropped = 0;
  };
  std::map<std::string, std::unique_ptr<Job>> jobs;
  std::map<std::uint64_t, Job*> bySession;
  RelaySessions sessions;

  // One wall process: the relay's piece socket for it and the connection to the real one.
  struct Process {
    zmq::socket_t down, up;
    std::string relayEndpoint, wallEndpoint;
    std::optional<zmq::message_t> pending;  // a batch `up` could not take yet
    Job* pendingJob = nullptr;
  };
  std::vector<std::unique_ptr<Process>> processes;
  std::uint64_t strangers = 0;  // piece messages dropped since the last job record
  std::set<std::string> logged;

  void log(const std::string& line) {
    if (options.log) options.log(line);
  }
  // One line per connection and kind of problem (`problem` names it), bounded.
  void logOnce(const std::string& peer, const std::string& problem, const std::string& line) {
    if (logged.size() >= kMaxLogged || !logged.insert(peer + "/" + problem.substr(0, 40)).second)
      return;
    log(line);
  }
  void toJob(const std::string& id, zmq::message_t&& body) {
    zmq::message_t routing(id.data(), id.size());
    if (front.send(routing, zmq::send_flags::sndmore | zmq::send_flags::dontwait))
      front.send(body, zmq::send_flags::dontwait);
  }
  void refuse(const std::string& id, const std::string& why) {
    toJob(id, toMessage(packText(Kind::Refused, 0, "relay: " + why)));
  }

  // Sockets for wall processes 0..count-1 (bound once; their ports stay the relay's).
  void ensureProcesses(std::size_t count) {
    while (processes.size() < count) {
      auto p = std::make_unique<Process>();
      p->down = zmq::socket_t(context, zmq::socket_type::router);
      configureSocket(p->down, Side::accepts, deadPeerMs, kMaxBatchBytes);
      makeServer(p->down, options.credentials);
      p->down.set(zmq::sockopt::rcvhwm, kPieceHwm);
      p->down.bind("tcp://" + bindHost + ":*");
      p->relayEndpoint =
          "tcp://" + advertised + ":" + std::to_string(portOf(lastEndpoint(p->down)));
      p->up = zmq::socket_t(context, zmq::socket_type::dealer);
      configureSocket(p->up, Side::dials, deadPeerMs, kMaxLinkMessageBytes);
      makeClient(p->up, options.credentials);
      p->up.set(zmq::sockopt::sndhwm, kPieceHwm);
      log("wall process " + std::to_string(processes.size()) + ": pieces on " + p->relayEndpoint);
      processes.push_back(std::move(p));
    }
  }
  // Where wall process `p` takes pieces now (a process that restarted binds a new port).
  void wallProcessAt(std::size_t p, const std::string& endpoint) {
    Process& process = *processes[p];
    if (endpoint.empty() || endpoint == process.wallEndpoint) return;
    if (!process.wallEndpoint.empty()) {
      try {
        process.up.disconnect(process.wallEndpoint);
      } catch (const zmq::error_t&) {
      }
      log("wall process " + std::to_string(p) + " moved from " + process.wallEndpoint + " to " +
          endpoint);
    }
    process.up.connect(endpoint);
    process.wallEndpoint = endpoint;
  }
  RelayEndpointOf relayEndpoint() {
    return [this](int p) { return processes.at(static_cast<std::size_t>(p))->relayEndpoint; };
  }

  std::size_t jobsFrom(const std::string& peerAddress) const {
    std::size_t n = 0;
    for (const auto& [id, job] : jobs) n += job->peerAddress == peerAddress;
    return n;
  }
  void fromJob(const std::string& id, zmq::message_t&& body) {
    const std::string peer = hex(id.data(), id.size());
    MessageHeader h;
    try {
      h = parseHeader(bytesOf(body), body.size());
    } catch (const std::exception& e) {
      logOnce(peer, e.what(), "dropped a message from connection " + peer + ": " + e.what());
      // A dfbwall of another version learns why at once, as from the wall.
      MessageHeader mine;
      if (body.size() >= sizeof mine) {
        std::memcpy(&mine, body.data(), sizeof mine);
        if (mine.magic == kMagic) refuse(id, e.what());
      }
      return;
    }
    if (!jobKind(static_cast<Kind>(h.kind))) {
      logOnce(peer, "kind " + std::to_string(h.kind),
              "dropped message kind " + std::to_string(h.kind) + " from connection " + peer +
                  ": not one a job sends");
      return;
    }
    auto found = jobs.find(id);
    if (found == jobs.end()) {
      if (h.kind != static_cast<std::uint16_t>(Kind::Hello)) {
        logOnce(peer, "no hello",
                "dropped message kind " + std::to_string(h.kind) + " from connection " + peer +
                    ": it said no hello");
        return;
      }
      if (jobs.size() >= kMaxJobs) {
        logOnce("", "full", "refused a job: " + std::to_string(kMaxJobs) + " connections already");
        return refuse(id, "it has " + std::to_string(kMaxJobs) + " job connections already");
      }
      const char* peerAddress = body.gets("Peer-Address");
      const std::string from = peerAddress ? peerAddress : "";
      if (jobsFrom(from) >= kMaxJobsPerPeer) {
        logOnce(from, "peer full",
                "refused a job from " + from + ": " + std::to_string(kMaxJobsPerPeer) +
                    " job connections from there already");
        return refuse(id, "it has " + std::to_string(kMaxJobsPerPeer) +
                              " job connections from this address already");
      }
      auto job = std::make_unique<Job>();
      job->id = id;
      job->peerAddress = from;
      job->started = Clock::now();
      job->wall = zmq::socket_t(context, zmq::socket_type::dealer);
      // A job's goodbye gets a second to reach the wall after the relay forgets the job.
      configureSocket(job->wall, Side::dials, deadPeerMs, kMaxMessageBytes, 1000);
      job->wall.set(zmq::sockopt::sndhwm, kPieceHwm * 4);
      makeClient(job->wall, options.credentials);
      job->handshake = std::make_unique<HandshakeWatch>(context, job->wall);
      job->wall.connect(wallEndpoint);
      try {
        const std::string host = parseHello(bytesOf(body), body.size()).host;
        if (!host.empty()) job->host = peerText(host);  // for the relay's log
      } catch (const std::exception&) {
        // The wall refuses it, saying why; the refusal comes back through.
      }
      found = jobs.emplace(id, std::move(job)).first;
    }
    Job& job = *found->second;
    job.lastHeard = Clock::now();
    if (h.kind == static_cast<std::uint16_t>(Kind::Bye) && job.session != 0 &&
        h.session == job.session && !job.over) {
      job.over = Clock::now();
      job.end = "goodbye";
    }
    if (!job.wall.send(body, zmq::send_flags::dontwait)) ++job.dropped;
  }

  void fromWall(Job& job, zmq::message_t&& body) {
    job.wallAnswered = true;
    MessageHeader h;
    try {
      h = parseHeader(bytesOf(body), body.size());
    } catch (const std::exception& e) {
      logOnce("wall", e.what(), std::string("dropped a message from the wall: ") + e.what());
      return;
    }
    const Kind kind = static_cast<Kind>(h.kind);
    if (!wallToJobKind(kind)) {
      logOnce("wall", "kind " + std::to_string(h.kind),
              "dropped message kind " + std::to_string(h.kind) + " from the wall to a job");
      return;
    }
    try {
      if (kind == Kind::Directory) {
        const Directory d = parseDirectory(bytesOf(body), body.size());
        ensureProcesses(d.processes.size());
        for (std::size_t p = 0; p < d.processes.size(); ++p)
          wallProcessAt(p, d.processes[p].endpoint);
        if (job.session != 0) {
          sessions.remove(job.session);
          bySession.erase(job.session);
        }
        job.session = d.session;
        sessions.add(d.session);
        bySession[d.session] = &job;
        log("job from " + job.host + ": the wall accepted it (session " +
            hex(&d.session, sizeof d.session) + ", " + std::to_string(d.processes.size()) +
            " wall processes through the relay)");
        body = toMessage(relayDirectory(d, relayEndpoint()));
      } else if (kind == Kind::Roster) {
        const Roster r = parseRoster(bytesOf(body), body.size());
        ensureProcesses(r.processes.size());
        for (std::size_t p = 0; p < r.processes.size(); ++p)
          if (r.processes[p].live) wallProcessAt(p, r.processes[p].endpoint);
        log("job from " + job.host + ": roster " + std::to_string(r.version) + ": " + r.why);
        body = toMessage(relayRoster(r, relayEndpoint()));
      } else if (kind == Kind::Reshape) {
        const Reshape r = parseReshape(bytesOf(body), body.size());
        if (r.session != job.session) throw base::Error("a reshape of another job");
        ensureProcesses(r.directory.processes.size());
        for (std::size_t p = 0; p < r.directory.processes.size(); ++p)
          if (r.directory.processes[p].live) wallProcessAt(p, r.directory.processes[p].endpoint);
        sessions.add(r.directory.session);
        bySession[r.directory.session] = &job;
        job.pieceSessions.push_back(r.directory.session);
        log("job from " + job.host + ": its window moves from frame " +
            std::to_string(r.fromFrame));
        body = toMessage(relayReshape(r, relayEndpoint()));
      } else if ((kind == Kind::Refused && h.session == 0) || kind == Kind::Ended) {
        // (A Refused with the job's session refuses one request of the job, which goes on.)
        const std::string text = parseText(bytesOf(body), body.size());
        log(std::string(kind == Kind::Refused ? "the wall refused the job from "
                                              : "the wall ended the job from ") +
            job.host + ": " + text);
        if (!job.over) {
          job.over = Clock::now();
          job.end = text;
        }
      }
    } catch (const std::exception& e) {
      // The job could not use it either: it learns why, from the relay.
      log("the wall sent the job from " + job.host +
          " a message the relay cannot use: " + e.what());
      return refuse(job.id, std::string("the wall's message: ") + e.what());
    }
    toJob(job.id, std::move(body));
  }

  // Forwards what process `p`'s socket holds while the wall process takes it.
  void pump(Process& process) {
    const auto send = [&](zmq::message_t& m, Job* job) {
      const std::size_t size = m.size();
      if (!process.up.send(m, zmq::send_flags::dontwait)) return false;
      if (job) {
        ++job->batches;
        job->bytes += size;
      }
      return true;
    };
    if (process.pending) {
      if (!send(*process.pending, process.pendingJob)) return;
      process.pending.reset();
    }
    for (int n = 0; n < kBurst; ++n) {
      zmq::message_t id, body;
      if (!process.down.recv(id, zmq::recv_flags::dontwait)) return;
      if (!id.more() || !process.down.recv(body, zmq::recv_flags::dontwait)) continue;
      const std::string peer = hex(id.data(), id.size());
      bool parts = false;
      while (body.more()) {
        zmq::message_t extra;
        if (!process.down.recv(extra, zmq::recv_flags::dontwait)) break;
        body.swap(extra);
        parts = true;
      }
      RelaySessions::Verdict v = sessions.admit(bytesOf(body), body.size());
      if (parts && v.forward) v = {false, v.session, "a message of several parts"};
      const auto owner = bySession.find(v.session);
      Job* job = owner == bySession.end() ? nullptr : owner->second;
      if (!v.forward) {
        if (job)
          ++job->dropped;
        else
          ++strangers;
        logOnce(peer, v.why,
                "dropped a message on the piece port from connection " + peer + ": " + v.why);
        continue;
      }
      if (!send(body, job)) {
        process.pending.emplace(std::move(body));
        process.pendingJob = job;
        return;
      }
    }
  }

  // The job's --stats line; `job` is the number serve's --stats gives the same job.
  std::string record(const Job& job, double seconds, const std::string& why) const {
    const nlohmann::ordered_json line{{"job", job.session % 1000000007},
                                      {"host", job.host},
                                      {"session", hex(&job.session, sizeof job.session)},
                                      {"batches_forwarded", job.batches},
                                      {"bytes_forwarded", job.bytes},
                                      {"dropped", job.dropped},
                                      {"strangers_dropped", strangers},
                                      {"seconds", std::round(seconds * 1e6) / 1e6},
                                      {"ended", why}};
    // The host comes from the wire: bytes that are not UTF-8 are replaced, not thrown.
    return line.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
  }
  void forget(Job& job, const std::string& why) {
    const double seconds =
        std::chrono::duration<double>(job.over.value_or(Clock::now()) - job.started).count();
    if (job.session != 0) {
      log("job from " + job.host + " (session " + hex(&job.session, sizeof job.session) +
          ") through the relay: " + std::to_string(job.batches) + " batches, " +
          std::to_string(job.bytes) + " bytes forwarded, " + std::to_string(job.dropped) +
          " dropped, " + std::to_string(strangers) + " strangers' messages dropped, " +
          std::to_string(static_cast<long long>(seconds)) + " s (" + why + ")");
      if (options.jobRecord) options.jobRecord(record(job, seconds, why));
      strangers = 0;
      sessions.remove(job.session);
      bySession.erase(job.session);
    }
    for (const std::uint64_t pieces : job.pieceSessions) {
      sessions.remove(pieces);
      bySession.erase(pieces);
    }
    for (auto& p : processes)
      if (p->pendingJob == &job) p->pendingJob = nullptr;
    jobs.erase(job.id);
  }
  // Job connections that closed: the job is forgotten and its link to the wall closes.
  void forgetClosed() {
    for (const std::string& id : frontConnections.closed()) {
      const auto found = jobs.find(id);
      if (found == jobs.end()) continue;
      Job& job = *found->second;
      if (!job.over) log("job from " + job.host + ": its connection to the relay closed");
      forget(job, job.over ? job.end : "its connection closed");
    }
  }
  void reap() {
    const auto now = Clock::now();
    std::vector<std::pair<Job*, std::string>> done;
    const auto helloAnswer = std::min<std::chrono::milliseconds>(kHelloAnswer, options.timeout);
    for (auto& [id, job] : jobs) {
      const HandshakeWatch::State handshake = job->handshake->poll();
      if (!job->wallAnswered && !job->over &&
          (handshake == HandshakeWatch::State::Refused ||
           handshake == HandshakeWatch::State::Failed)) {
        const std::string why = "no link to the wall at " + options.wall + ": " +
                                job->handshake->problem() +
                                " (the relay's --token-file or "
                                "--server-key is not the wall's)";
        log("job from " + job->host + ": " + why);
        refuse(job->id, why);
        job->over = now;
        job->end = why;
      }
      if (!job->wallAnswered && !job->over && now - job->started > helloAnswer) {
        const std::string why = "the wall at " + options.wall + " did not answer within " +
                                std::to_string(helloAnswer.count() / 1000) + " s";
        log("job from " + job->host + ": " + why);
        refuse(job->id, why);
        job->over = now;
        job->end = why;
      }
      if (job->over && now - *job->over > kGrace)
        done.emplace_back(job.get(), job->end);
      else if (now - job->lastHeard > options.timeout + std::chrono::seconds(2))
        done.emplace_back(job.get(),
                          "silent for " + std::to_string(options.timeout.count() / 1000) + " s");
    }
    for (auto& [job, why] : done) forget(*job, why);
  }
};

Relay::Relay(RelayOptions options) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.options = std::move(options);
  m.deadPeerMs = static_cast<int>(m.options.timeout.count());
  const std::string endpoint = tcpEndpoint(m.options.listen, "--listen");
  m.wallEndpoint = tcpEndpoint(m.options.wall, "--wall");
  if (m.options.wall.find(':') == std::string::npos)
    throw base::Error("--wall '" + m.options.wall +
                      "': expected HOST:PORT of the wall (serve --listen)");
  const std::string listenHost = hostOf(m.options.listen);
  // The piece sockets listen where the directory socket does; jobs are told the address they
  // can reach: the listen address, or this host's first when listening on every interface.
  m.bindHost = listenHost == "*" ? "0.0.0.0" : listenHost;
  m.advertised = advertisedHost(listenHost);
  m.gatekeeper = std::make_unique<Gatekeeper>(m.context, m.options.credentials, m.options.log);
  configureSocket(m.front, Side::accepts, m.deadPeerMs, kMaxLinkMessageBytes);
  makeServer(m.front, m.options.credentials);
  m.front.set(zmq::sockopt::router_mandatory, 0);
  try {
    m.front.bind(endpoint);
  } catch (const zmq::error_t& e) {
    throw base::Error("--listen " + m.options.listen + ": cannot listen there (" + e.what() + ")");
  }
  m.address = m.advertised + ":" + std::to_string(portOf(lastEndpoint(m.front)));
}

Relay::~Relay() = default;

std::string Relay::address() const { return impl_->address; }

void Relay::run() {
  Impl& m = *impl_;
  auto lastTick = Clock::now();
  std::vector<zmq::pollitem_t> items;
  std::vector<Impl::Job*> itemJob;
  while (!(m.options.stopRequested && m.options.stopRequested())) {
    // The directory links, then per wall process: its piece socket while the wall process takes
    // more, else the connection to it, to learn when it does.
    items.assign(1, {m.front.handle(), 0, ZMQ_POLLIN, 0});
    itemJob.assign(1, nullptr);
    for (auto& [id, job] : m.jobs) {
      items.push_back({job->wall.handle(), 0, ZMQ_POLLIN, 0});
      itemJob.push_back(job.get());
    }
    const std::size_t firstProcess = items.size();
    for (auto& p : m.processes) {
      const bool writable = !p->pending && (p->up.get(zmq::sockopt::events) & ZMQ_POLLOUT);
      items.push_back(writable ? zmq::pollitem_t{p->down.handle(), 0, ZMQ_POLLIN, 0}
                               : zmq::pollitem_t{p->up.handle(), 0, ZMQ_POLLOUT, 0});
    }
    const std::size_t afterProcesses = items.size();
    items.push_back(m.frontConnections.pollItem());
    try {
      zmq::poll(items.data(), items.size(), std::chrono::milliseconds(200));
    } catch (const zmq::error_t& e) {
      if (e.num() == EINTR) continue;  // a signal the caller did not block: poll again
      throw;
    }
    for (std::size_t i = firstProcess; i < afterProcesses; ++i)
      if (items[i].revents) m.pump(*m.processes[i - firstProcess]);
    // Read even when the poll saw nothing: a connection's close is acted on only once what it
    // sent before is taken.
    bool frontRead = true;  // every message of the jobs taken
    {
      zmq::message_t id, body;
      int n = 0;
      for (; n < kBurst && m.front.recv(id, zmq::recv_flags::dontwait); ++n) {
        if (!id.more() || !m.front.recv(body, zmq::recv_flags::dontwait)) continue;
        m.frontConnections.heard(std::string(static_cast<const char*>(id.data()), id.size()), body);
        while (body.more()) {  // several parts: only the last goes on, as at the wall
          zmq::message_t extra;
          if (!m.front.recv(extra, zmq::recv_flags::dontwait)) break;
          body.swap(extra);
        }
        m.fromJob(std::string(static_cast<const char*>(id.data()), id.size()), std::move(body));
      }
      frontRead = n < kBurst;
    }
    for (std::size_t i = 1; i < firstProcess; ++i) {
      if (!items[i].revents) continue;
      Impl::Job* job = itemJob[i];
      if (m.jobs.count(job->id) == 0) continue;
      zmq::message_t body;
      for (int n = 0; n < kBurst && job->wall.recv(body, zmq::recv_flags::dontwait); ++n) {
        while (body.more()) {
          zmq::message_t extra;
          if (!job->wall.recv(extra, zmq::recv_flags::dontwait)) break;
          body.swap(extra);
        }
        m.fromWall(*job, std::move(body));
      }
    }
    // Once what a job sent before its connection closed went on (its goodbye first).
    if (frontRead) m.forgetClosed();
    if (Clock::now() - lastTick > std::chrono::milliseconds(250)) {
      m.reap();
      lastTick = Clock::now();
    }
  }
  while (!m.jobs.empty()) {
    Impl::Job& job = *m.jobs.begin()->second;
    m.forget(job, job.over ? job.end : "the relay stopped");
  }
}

}  // namespace wall::service
