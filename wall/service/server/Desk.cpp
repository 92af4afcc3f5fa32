#include "wall/service/server/Desk.h"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <map>
#include <mutex>
#include <random>
#include <set>
#include <thread>

#include "base/Error.h"
#include "wall/service/protocol/JsonText.h"
#include "wall/service/protocol/LinkMessages.h"
#include "wall/service/protocol/Protocol.h"
#include "wall/service/protocol/Zmq.h"
#include "wall/service/server/FrameAgreements.h"

namespace wall::service {
namespace {

using Clock = std::chrono::steady_clock;
constexpr std::size_t kMaxQueued = 16;    // jobs waiting behind the connected one (--wait)
constexpr std::size_t kMaxLogged = 1024;  // lines about strangers between two jobs
constexpr auto kTick = std::chrono::milliseconds(100);
constexpr std::uint32_t kNotYet = 0xffffffffu;  // a seat's first frame before the process is Ready

std::uint64_t randomId() {
  std::random_device device;
  std::uint64_t id = 0;
  while (id == 0) id = (static_cast<std::uint64_t>(device()) << 32) ^ device();
  return id;
}

std::string seconds(std::chrono::milliseconds t) {
  const long long ms = t.count();
  return ms % 1000 == 0 ? std::to_string(ms / 1000) + " s" : std::to_string(ms) + " ms";
}

}  // namespace

struct Desk::Impl {
  Setup s;
  const Layout& layout;
  const int processCount;
  const std::chrono::milliseconds timeout;
  const std::chrono::milliseconds beat;
  zmq::context_t context{1};
  zmq::socket_t socket;
  Waker waker;
  std::thread thread;
  std::atomic<bool> stop{false}, isClosed{false};

  // From other threads (the head's own process): work for the desk thread, and what the desk
  // hands back to the process's barrier and gather waits.
  mutable std::mutex mutex;
  std::deque<std::function<void()>> tasks;
  std::condition_variable handedBack;
  std::map<std::pair<std::uint64_t, std::uint32_t>, std::vector<std::int64_t>> releases;
  std::map<std::pair<std::uint64_t, std::uint32_t>, std::vector<std::vector<std::uint32_t>>>
      gathered;
  std::vector<int> absent;       // copy of who is not joined, for absentProcesses()
  std::uint64_t jobSession = 0;  // copy of job.session, for the head's barrier waits

  // The desk thread's own.
  struct Member {
    bool live = false;
    std::string peer;  // ZeroMQ routing id of its link
    std::uint64_t incarnation = 0;
    std::string host, endpoint;
    Clock::time_point lastHeard;
  };
  std::vector<Member> members;  // [0]: the head's own process, always live
  struct Job {
    std::string peer;
    Hello hello;
    Clock::time_point lastHeard;
    std::uint64_t session = 0;
    Clock::time_point started;
  };
  enum class State { Idle, Starting, Running, Ending, Closed } state = State::Idle;
  Job job;
  std::deque<Job> queue;
  // Each process's part in the job: in it (given Start), answered Start, done with it (Done, a
  // refusal, or lost), and the first frame it shows (later than 1 when it joined mid-job).
  struct Seat {
    bool in = false, ready = false, done = false;
    std::uint32_t fromFrame = 1;
  };
  std::vector<Seat> seats;
  std::set<int> waitingToJoinJob;  // joined while the job was starting
  std::string failure;
  std::int64_t lastPresented = 0, bytes = 0;
  std::uint32_t lastCredited = 0, granted = 2, rosterVersion = 0;
  int processesLost = 0, processesRejoined = 0;
  bool shuttingDown = false;
  int shutdownAcks = 0;  // members that confirmed the shutdown (State::Closed)
  Clock::time_point closedAt;
  int liveMembers() const {
    int n = 0;
    for (int p = 1; p < processCount; ++p) n += members[static_cast<size_t>(p)].live ? 1 : 0;
    return n;
  }
  std::set<std::string> logged;
  Clock::time_point lastBeat;
  FrameAgreements agreements;

  explicit Impl(Setup setup)
      : s(std::move(setup)),
        layout(*s.layout),
        processCount(s.layout->processCount),
        timeout(s.options.timeout),
        beat(std::clamp<std::chrono::milliseconds>(
            s.options.timeout / 4, std::chrono::milliseconds(50), std::chrono::milliseconds(1000))),
        socket(context, zmq::socket_type::router),
        members(static_cast<size_t>(s.layout->processCount)),
        seats(static_cast<size_t>(s.layout->processCount)),
        agreements(s.layout->processCount) {
    configureSocket(socket, static_cast<int>(timeout.count()));
    socket.set(zmq::sockopt::router_mandatory, 0);
    members[0].live = true;
    members[0].endpoint = s.ownEndpoint;
    members[0].host = "the head";
    for (int p = 1; p < processCount; ++p) absent.push_back(p);
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
  void record(const std::string& json) {
    if (s.options.jobRecord) s.options.jobRecord(json);
  }
  void reply(const std::string& peer, messaging::Bytes message) {
    zmq::message_t id(peer.data(), peer.size());
    socket.send(id, zmq::send_flags::sndmore | zmq::send_flags::dontwait);
    socket.send(toMessage(std::move(message)), zmq::send_flags::dontwait);
  }
  std::string who(int p) const {
    return "wall process " + std::to_string(p) + " on " + members[static_cast<size_t>(p)].host;
  }
  void publishAbsent() {
    std::vector<int> now;
    for (int p = 1; p < processCount; ++p)
      if (!members[static_cast<size_t>(p)].live) now.push_back(p);
    std::lock_guard lock(mutex);
    absent = std::move(now);
  }

  // ---- commands to the processes ----
  void sendTo(int p, const ServiceCommand& command) {
    if (p == 0) return s.deliver(command);
    const Member& m = members[static_cast<size_t>(p)];
    if (m.live) reply(m.peer, packCommandMessage(command.header.session, packCommand(command)));
  }
  ServiceCommand command(Command kind, std::int64_t a = 0, std::int64_t b = 0,
                         std::string text = {}) const {
    ServiceCommand c;
    c.header.kind = kind;
    c.header.session = job.session;
    c.header.a = a;
    c.header.b = b;
    c.text = std::move(text);
    return c;
  }
  // To every process in the job that is not done with it.
  void toJob(const ServiceCommand& c) {
    for (int p = 0; p < processCount; ++p) {
      const Seat& seat = seats[static_cast<size_t>(p)];
      if (seat.in && !seat.done) sendTo(p, c);
    }
  }
  ServiceCommand startCommand(std::uint32_t firstFrame) const {
    ServiceCommand c = command(Command::Start, firstFrame, 0, job.hello.captureDir);
    c.header.tileSize = job.hello.tileSize;
    c.header.renderRanks = job.hello.renderRanks;
    c.header.framesInFlight = granted;
    c.header.captureEvery = job.hello.captureEvery;
    c.header.codec = static_cast<std::uint32_t>(job.hello.codec.codec);
    return c;
  }

  // ---- the roster a job routes with ----
  std::vector<DirectoryProcess> roster() const {
    std::vector<DirectoryProcess> out;
    for (int p = 0; p < processCount; ++p) {
      const Seat& seat = seats[static_cast<size_t>(p)];
      const Member& m = members[static_cast<size_t>(p)];
      out.push_back({m.endpoint, m.live && seat.in && !seat.done && seat.fromFrame != kNotYet});
    }
    return out;
  }
  void sendRoster(std::uint32_t fromFrame, const std::string& why) {
    if (state != State::Running) return;  // a starting job gets the directory, which has it all
    Roster r;
    r.session = job.session;
    r.version = ++rosterVersion;
    r.fromFrame = fromFrame;
    r.processes = roster();
    r.why = why;
    reply(job.peer, packRoster(r));
  }

  // ---- jobs ----
  void startJob() {
    job.session = randomId();
    {
      std::lock_guard lock(mutex);
      jobSession = job.session;
    }
    job.started = Clock::now();
    failure.clear();
    lastPresented = bytes = 0;
    lastCredited = 0;
    rosterVersion = 0;
    processesLost = processesRejoined = 0;
    agreements.clear();
    waitingToJoinJob.clear();
    granted = std::min<std::uint32_t>(job.hello.framesInFlight,
                                      static_cast<std::uint32_t>(s.options.framesInFlight));
    state = State::Starting;
    for (int p = 0; p < processCount; ++p)
      seats[static_cast<size_t>(p)] = {members[static_cast<size_t>(p)].live, false, false, 1};
    toJob(startCommand(1));
  }
  bool allDone() const {
    for (const Seat& seat : seats)
      if (seat.in && !seat.done) return false;
    return true;
  }
  void endJob(const std::string& why) {  // the job is gone or broken: drop it everywhere
    if (state != State::Running && state != State::Starting) return;
    failure = why;
    toJob(command(state == State::Starting ? Command::Cancel : Command::Abort, 0, 0, why));
    reply(job.peer, packText(Kind::Ended, job.session, why));
    state = State::Ending;
    log("dropping the job from " + job.hello.host + ": " + why);
    if (allDone()) jobOver();
  }
  void nextJob() {
    state = State::Idle;
    logged.clear();
    while (!queue.empty() && !shuttingDown) {
      job = queue.front();
      queue.pop_front();
      if (Clock::now() - job.lastHeard > timeout) continue;  // it left the queue
      log("taking the queued job from " + job.hello.host);
      startJob();
      return;
    }
  }
  void jobOver() {
    const double secs = std::chrono::duration<double>(Clock::now() - job.started).count();
    log("the job from " + job.hello.host + " ended after frame " + std::to_string(lastPresented) +
        (failure.empty() ? "" : " (" + failure + ")"));
    record("{\"job\":" + std::to_string(job.session % 1000000007) + ",\"host\":" +
           jsonText(job.hello.host) + ",\"render_ranks\":" + std::to_string(job.hello.renderRanks) +
           ",\"codec\":" + jsonText(codecName(job.hello.codec)) + ",\"frames_presented\":" +
           std::to_string(lastPresented) + ",\"wall_bytes_received\":" + std::to_string(bytes) +
           ",\"processes_lost\":" + std::to_string(processesLost) + ",\"processes_rejoined\":" +
           std::to_string(processesRejoined) + ",\"seconds\":" + std::to_string(secs) +
           ",\"ended\":" + jsonText(failure.empty() ? "last frame" : failure) + "}");
    agreements.clear();
    {
      std::lock_guard lock(mutex);
      jobSession = 0;
      handedBack.notify_all();
    }
    nextJob();
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
    const std::string from = hello.host.empty() ? "an unnamed host" : hello.host;
    if (!s.token.empty() && hello.token != s.token) {
      logOnce(peer, "refused a job from " + from + ": " +
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
      log("job from " + from + ": " + std::to_string(hello.renderRanks) + " render ranks, codec " +
          codecName(hello.codec));
      startJob();
      return;
    }
    const std::string busy = "busy: a job from " + job.hello.host + " is connected";
    if (!hello.wait) {
      logOnce(peer, "refused a job from " + from + ": " + busy);
      reply(peer, packText(Kind::Refused, 0, busy));
      return;
    }
    if (queue.size() >= kMaxQueued) {
      logOnce(peer, "refused a job from " + from + ": the queue is full");
      reply(peer, packText(Kind::Refused, 0,
                           busy + ", and " + std::to_string(kMaxQueued) + " jobs wait already"));
      return;
    }
    queue.push_back({peer, hello, Clock::now(), 0, {}});
    log("queued a job from " + from + " (place " + std::to_string(queue.size()) + ")");
    reply(peer, packText(Kind::Queued, 0,
                         busy + "; waiting (place " + std::to_string(queue.size()) + ")"));
  }

  void onJobMessage(const std::string& peer, const MessageHeader& h, const std::byte* data,
                    size_t size) {
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
    switch (kind) {
      case Kind::Keepalive:
        toJob(command(Command::KeepWaiting));
        break;
      case Kind::Capture:
        toJob(command(Command::Capture, static_cast<std::int64_t>(c.value), c.second));
        break;
      case Kind::Bye:
        if (c.second < 0) return endJob("the job left without naming its last frame");
        toJob(command(Command::LastFrame, static_cast<std::int64_t>(c.value)));
        break;
      default:
        endJob("unexpected message kind " + std::to_string(h.kind));
    }
  }

  // An answer of process `p` (its own or over its link).
  void onAnswer(int p, const ServiceCommand& c) {
    const CommandHeader& e = c.header;
    if (e.kind == Command::Shutdown) {  // a member confirms the wall's shutdown
      if (state == State::Closed) ++shutdownAcks;
      return;
    }
    if (e.kind == Command::StopAsked) {
      if (!shuttingDown) log("stopping the wall (asked by wall process " + std::to_string(p) + ")");
      shuttingDown = true;
      for (Job& queued : queue)
        reply(queued.peer, packText(Kind::Refused, 0, "the wall is shutting down"));
      queue.clear();
      endJob("the wall is shutting down");
      return;
    }
    if (state == State::Idle || state == State::Closed || e.session != job.session) return;
    Seat& seat = seats[static_cast<size_t>(p)];
    if (!seat.in) return;
    switch (e.kind) {
      case Command::Ready:
        seat.ready = true;
        if (e.a != 0 && seat.fromFrame == kNotYet) {
          if (state == State::Running) joinedJob(p);
          break;
        }
        if (e.a == 0) {
          seat.done = true;
          if (state == State::Running) {  // a process that joined mid-job cannot take it
            log(who(p) + " cannot take the running job: " + c.text);
            sendRoster(0, who(p) + " cannot take the job: " + c.text);
          } else if (failure.empty()) {
            failure = c.text;
          }
        }
        if (state == State::Starting) maybeRun();
        break;
      case Command::Failed:
        if (state == State::Running) endJob(c.text);
        break;
      case Command::Done:
        lastPresented = std::max(lastPresented, e.a);
        bytes += e.b;
        seat.done = true;
        if (state == State::Running && !c.text.empty() && p != 0) {
          // This process could not go on (its node failed); the others can.
          log(who(p) + " left the job: " + c.text);
          sendRoster(0, who(p) + " left the job: " + c.text);
          releaseWhatCan();
        } else {
          if (!c.text.empty() && failure.empty()) failure = c.text;
          if (state == State::Running) state = State::Ending;  // it ended by itself
        }
        break;
      default:
        break;
    }
    if ((state == State::Ending || state == State::Running) && allDone()) jobOver();
  }
  // Every process in the job answered Start: the job gets its directory (or the refusal).
  void maybeRun() {
    for (const Seat& seat : seats)
      if (seat.in && !seat.ready && !seat.done) return;
    if (!failure.empty()) {
      toJob(command(Command::Cancel));
      reply(job.peer, packText(Kind::Refused, 0, failure));
      log("refused the job from " + job.hello.host + ": " + failure);
      state = State::Ending;
      if (allDone()) jobOver();
      return;
    }
    Directory d;
    d.session = job.session;
    d.layout = layout;
    d.processes = roster();
    d.framesInFlight = granted;
    d.timeoutMs = static_cast<std::uint32_t>(timeout.count());
    d.rosterVersion = 0;
    reply(job.peer, packDirectory(d));
    state = State::Running;
    for (int p : waitingToJoinJob) admitToJob(p);
    waitingToJoinJob.clear();
  }

  // ---- the wall's processes ----
  void admitToJob(int p) {
    if (!members[static_cast<size_t>(p)].live) return;
    // Frames up to lastCredited + granted may have started without this process; the next
    // credit (sent after the roster) is the first that lets the job start a later one.
    // It takes part from the frame named once it is Ready (taking pieces): see joinedJob.
    seats[static_cast<size_t>(p)] = {true, false, false, kNotYet};
    sendTo(p, startCommand(0));
  }
  // A process admitted to the running job is ready for pieces. Frames up to lastCredited +
  // granted may have started without it; the next credit (sent after the roster, on the same
  // socket) is the first that lets the job start a later one.
  void joinedJob(int p) {
    const std::uint32_t first = lastCredited + granted + 1;
    seats[static_cast<size_t>(p)].fromFrame = first;
    sendTo(p, command(Command::FirstFrame, first));
    ++processesRejoined;
    const std::string line =
        who(p) + " is back in the wall; it shows the job's frames from " + std::to_string(first);
    log(line);
    record("{\"event\":\"rejoined\",\"process\":" + std::to_string(p) +
           ",\"host\":" + jsonText(members[static_cast<size_t>(p)].host) +
           ",\"frame\":" + std::to_string(first) + "}");
    sendRoster(first, line);
  }
  void drop(int p, const std::string& why) {
    Member& m = members[static_cast<size_t>(p)];
    if (!m.live) return;
    m.live = false;
    publishAbsent();
    reply(m.peer, packText(Kind::Dropped, 0, why));  // heard if it only hung (SIGSTOP)
    const bool inJob = state != State::Idle && state != State::Closed &&
                       seats[static_cast<size_t>(p)].in && !seats[static_cast<size_t>(p)].done;
    const std::string line = "lost " + who(p) +
                             (inJob ? " after frame " + std::to_string(lastCredited) : "") + ": " +
                             why;
    log(line);
    record("{\"event\":\"lost\",\"process\":" + std::to_string(p) +
           ",\"host\":" + jsonText(m.host) + ",\"frame\":" + std::to_string(lastCredited) +
           ",\"why\":" + jsonText(why) + "}");
    waitingToJoinJob.erase(p);
    if (!inJob) return;
    ++processesLost;
    seats[static_cast<size_t>(p)].done = true;
    sendRoster(0, line);
    if (state == State::Starting) maybeRun();
    releaseWhatCan();
    if ((state == State::Ending || state == State::Running) && allDone()) jobOver();
  }
  void onJoin(const std::string& peer, const std::byte* data, size_t size) {
    Join j;
    try {
      j = parseJoin(data, size);
    } catch (const std::exception& e) {
      logOnce(peer, std::string("refused a wall process: ") + e.what());
      reply(peer, packText(Kind::Refused, 0, e.what()));
      return;
    }
    std::string problem;
    if (!s.token.empty() && j.token != s.token)
      problem = j.token.empty() ? "this wall needs a token (--token)" : "wrong token";
    else if (j.process < 1 || j.process >= static_cast<std::uint32_t>(processCount))
      problem = "the layout has wall processes 0.." + std::to_string(processCount - 1) +
                "; process " + std::to_string(j.process) +
                (j.process == 0 ? " is the head, which does not join" : " is not one of them");
    else if (j.layoutHash != layoutHash(layout))
      problem = "its layout is not the wall's (" + layout.file +
                "): every process must run "
                "the same displays";
    if (!problem.empty()) {
      logOnce(peer, "refused wall process " + std::to_string(j.process) + " from " + j.host + ": " +
                        problem);
      reply(peer, packText(Kind::Refused, 0, problem));
      return;
    }
    const int p = static_cast<int>(j.process);
    Member& m = members[static_cast<size_t>(p)];
    if (m.live && m.incarnation == j.incarnation) {  // a repeated join: it missed the welcome
      m.lastHeard = Clock::now();
      reply(peer, packControl(Kind::Welcome, 0, j.incarnation));
      return;
    }
    if (m.live) drop(p, "it started again (on " + j.host + ")");
    m.live = true;
    m.peer = peer;
    m.incarnation = j.incarnation;
    m.host = j.host;
    m.endpoint = j.pieceEndpoint;
    m.lastHeard = Clock::now();
    publishAbsent();
    reply(peer, packControl(Kind::Welcome, 0, j.incarnation));
    if (state == State::Closed) {  // the wall is stopping: so does this process
      ServiceCommand c;
      c.header.kind = Command::Shutdown;
      sendTo(p, c);
      return;
    }
    if (state == State::Running) {
      admitToJob(p);
    } else {
      log(who(p) + " joined the wall");
      if (state == State::Starting) waitingToJoinJob.insert(p);
    }
  }
  int processOfPeer(const std::string& peer) const {
    for (int p = 1; p < processCount; ++p)
      if (members[static_cast<size_t>(p)].live && members[static_cast<size_t>(p)].peer == peer)
        return p;
    return -1;
  }
  void onMemberMessage(const std::string& peer, const MessageHeader& h, const std::byte* data,
                       size_t size) {
    const Kind kind = static_cast<Kind>(h.kind);
    if (kind == Kind::Join) return onJoin(peer, data, size);
    const int p = processOfPeer(peer);
    if (p < 0) {
      // A process the wall dropped, or that joined a head before this one: it must join again.
      reply(peer, packText(Kind::Dropped, 0, "this wall process is not in the wall (now)"));
      return;
    }
    members[static_cast<size_t>(p)].lastHeard = Clock::now();
    switch (kind) {
      case Kind::Beat:
        return;
      case Kind::Command: {
        ServiceCommand c = parseCommand(commandBody(data, size));
        c.header.process = p;
        return onAnswer(p, c);
      }
      case Kind::Barrier: {
        BarrierValues b = parseBarrier(data, size);
        return arrive(p, h.session, b.frameId, std::move(b.values));
      }
      case Kind::Pixels: {
        CapturePixels c = parsePixels(data, size);
        return gatherPixels(p, h.session, c.frameId, std::move(c.pixels));
      }
      default:
        logOnce(peer, "message kind " + std::to_string(h.kind) + " from " + who(p));
    }
  }

  // ---- barriers and gathers ----
  bool participates(int p, std::uint32_t frameId) const {
    const Seat& seat = seats[static_cast<size_t>(p)];
    return seat.in && !seat.done && seat.fromFrame <= frameId &&
           members[static_cast<size_t>(p)].live;
  }
  void arrive(int p, std::uint64_t session, std::uint32_t frameId,
              const std::vector<std::int64_t>& values) {
    if (session != job.session || (state != State::Running && state != State::Ending)) return;
    if (!participates(p, frameId)) return;
    if (!agreements.arrive(p, frameId, values))
      return drop(p, "its swap barrier of frame " + std::to_string(frameId) + " has " +
                         std::to_string(values.size()) + " values, not the others' count");
    releaseWhatCan();
  }
  void gatherPixels(int p, std::uint64_t session, std::uint32_t frameId,
                    std::vector<std::uint32_t> pixels) {
    if (session != job.session || !participates(p, frameId)) return;
    agreements.pixels(p, frameId, std::move(pixels));
    releaseWhatCan();
  }
  // Barriers and gathers that nobody holds up any more go back to their processes.
  void releaseWhatCan() {
    const auto takesPart = [this](int p, std::uint32_t frameId) {
      return participates(p, frameId);
    };
    for (FrameAgreements::Release& r : agreements.complete(takesPart)) {
      for (int p : r.processes) {
        if (p == 0) {
          std::lock_guard lock(mutex);
          releases[{job.session, r.frameId}] = r.values;
          handedBack.notify_all();
        } else if (members[static_cast<size_t>(p)].live) {
          reply(members[static_cast<size_t>(p)].peer,
                packBarrier(job.session, {r.frameId, r.values}));
        }
      }
    }
    for (FrameAgreements::Gathered& g : agreements.gathered(takesPart, Clock::now())) {
      std::lock_guard lock(mutex);
      gathered[{job.session, g.frameId}] = std::move(g.pixels);
      handedBack.notify_all();
    }
  }

  // ---- the thread ----
  void logOnce(const std::string& peer, const std::string& what) {
    if (logged.size() >= kMaxLogged || !logged.insert(peer + what.substr(0, 48)).second) return;
    log(what.rfind("refused", 0) == 0 ? what : "ignored a message on the directory port: " + what);
  }
  void watch() {
    const auto now = Clock::now();
    if (now - lastBeat >= beat) {
      lastBeat = now;
      for (int p = 1; p < processCount; ++p) {
        const Member& m = members[static_cast<size_t>(p)];
        if (m.live) reply(m.peer, packControl(Kind::Beat, 0, m.incarnation));
      }
    }
    for (int p = 1; p < processCount; ++p) {
      const Member& m = members[static_cast<size_t>(p)];
      if (m.live && now - m.lastHeard > timeout) drop(p, "no word from it for " + seconds(timeout));
    }
    releaseWhatCan();
    if (state == State::Running && now - job.lastHeard > timeout)
      endJob("no word from the job for " + seconds(timeout));
  }
  void run() {
    lastBeat = Clock::now();
    while (!stop) {
      zmq::pollitem_t items[2] = {{socket.handle(), 0, ZMQ_POLLIN, 0}, waker.pollItem()};
      zmq::poll(items, 2, kTick);
      if (items[1].revents) waker.drain();
      std::deque<std::function<void()>> now;
      {
        std::lock_guard lock(mutex);
        now.swap(tasks);
      }
      for (auto& task : now) task();
      zmq::message_t id, body;
      while (socket.recv(id, zmq::recv_flags::dontwait)) {
        if (!id.more() || !socket.recv(body, zmq::recv_flags::dontwait)) continue;
        while (body.more()) {
          zmq::message_t extra;
          if (!socket.recv(extra, zmq::recv_flags::dontwait)) break;
        }
        const std::string peer(static_cast<const char*>(id.data()), id.size());
        onMessage(peer, static_cast<const std::byte*>(body.data()), body.size());
      }
      if (state == State::Closed) {
        // Every process said it got the shutdown, or a second passed (a process that did not
        // hear it stops once it misses the head): only then the head's own process stops, and
        // with it this socket.
        if (shutdownAcks == liveMembers() || Clock::now() > closedAt + std::chrono::seconds(1)) {
          ServiceCommand c;
          c.header.kind = Command::Shutdown;
          sendTo(0, c);
          break;
        }
        continue;
      }
      watch();
      if (shuttingDown && state == State::Idle) {
        ServiceCommand c;
        c.header.kind = Command::Shutdown;
        for (int p = 1; p < processCount; ++p) sendTo(p, c);
        state = State::Closed;
        closedAt = Clock::now();
        socket.set(zmq::sockopt::linger, 1000);
      }
    }
    isClosed = true;
    std::lock_guard lock(mutex);
    handedBack.notify_all();
  }
  void onMessage(const std::string& peer, const std::byte* data, size_t size) {
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
    const bool fromMember = kind == Kind::Join || kind == Kind::Beat || kind == Kind::Command ||
                            kind == Kind::Barrier || kind == Kind::Pixels;
    try {
      if (fromMember)
        onMemberMessage(peer, h, data, size);
      else
        onJobMessage(peer, h, data, size);
    } catch (const std::exception& e) {
      // Nothing a client sends ends the wall; a failure handling it drops its job (or its
      // process) at most.
      log(std::string("handling a message on the directory port: ") + e.what());
      if (peer == job.peer) endJob(e.what());
      if (const int p = processOfPeer(peer); p > 0) drop(p, e.what());
    }
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

void Desk::toHead(const ServiceCommand& command, std::uint64_t) {
  impl_->post([this, command] { impl_->onAnswer(0, command); });
}

void Desk::agreeMax(std::uint64_t, std::uint64_t session, std::uint32_t frameId,
                    std::int64_t* values, int count, Clock::time_point) {
  std::vector<std::int64_t> mine(values, values + count);
  impl_->post([this, session, frameId, mine] { impl_->arrive(0, session, frameId, mine); });
  // The desk releases the barrier once every process in it arrived or was dropped (a process
  // whose frame is slow is alive and waited for; a silent one is dropped at the timeout; a job
  // that goes silent is aborted, and every node then arrives giving the frame up): no deadline
  // of the node's applies here.
  std::unique_lock lock(impl_->mutex);
  const auto key = std::make_pair(session, frameId);
  impl_->handedBack.wait(lock, [&] {
    return impl_->releases.count(key) > 0 || impl_->isClosed || impl_->jobSession != session;
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
    if (session != impl_->job.session) return;
    impl_->agreements.headPixels(frameId, std::move(*pixels), deadline);
    impl_->releaseWhatCan();
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

void Desk::presented(std::uint64_t session, std::uint32_t frameId, std::int64_t completeNs) {
  impl_->post([this, session, frameId, completeNs] {
    Impl& m = *impl_;
    if (session != m.job.session ||
        (m.state != Impl::State::Running && m.state != Impl::State::Ending))
      return;
    m.lastCredited = std::max(m.lastCredited, frameId);
    m.reply(m.job.peer, packControl(Kind::Presented, m.job.session, frameId, completeNs));
  });
}

}  // namespace wall::service
