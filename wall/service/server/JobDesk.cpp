#include "wall/service/server/JobDesk.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "wall/display/WallNode.h"
#include "wall/service/protocol/PeerText.h"

namespace wall::service {
namespace {

using Json = nlohmann::ordered_json;  // keys in the order written: lines read like the docs
constexpr std::uint32_t kNotYet = 0xffffffffu;  // a seat's first frame before the process is Ready

// Host names and reasons come from the wire: bytes that are not UTF-8 are replaced, not thrown.
std::string jsonLine(const Json& j) {
  return j.dump(-1, ' ', false, Json::error_handler_t::replace);
}

// Reasons other processes send (a frame's missing pieces, a folder) are longer than names.
constexpr std::size_t kMaxReasonBytes = 400;

std::string reason(const std::string& text) { return peerText(text, kMaxReasonBytes); }

ServiceCommand shutdownCommand() {
  ServiceCommand c;
  c.header.kind = Command::Shutdown;
  return c;
}

}  // namespace

JobDesk::JobDesk(Setup setup, const Membership& members)
    : s_(std::move(setup)),
      members_(members),
      seats_(static_cast<size_t>(members.processCount())),
      agreements_(members.processCount()) {}

// ---- events ----

JobDesk::Actions JobDesk::hello(const std::string& peer, const Hello& hello,
                                Clock::time_point now) {
  now_ = now;
  const std::string from = hello.host.empty() ? "an unnamed host" : peerText(hello.host);
  if (hasJobFrom(peer)) {
    log("refused a second job from " + from + " on the same connection", peer);
    reply(peer, Kind::Refused,
          packText(Kind::Refused, 0, "this connection has a job at the wall already"));
  } else if (!s_.token.empty() && hello.token != s_.token) {
    log("refused a job from " + from + ": " + (hello.token.empty() ? "no token" : "wrong token"),
        peer);
    reply(peer, Kind::Refused,
          packText(Kind::Refused, 0,
                   hello.token.empty() ? "this wall needs a token (--token)" : "wrong token"));
  } else if (shuttingDown_) {
    reply(peer, Kind::Refused, packText(Kind::Refused, 0, "the wall is shutting down"));
  } else if (const std::string problem = reason(windowProblem(hello)); !problem.empty()) {
    // reason(): a display name from the wire is printable, bounded text in the wall's log.
    log("refused a job from " + from + ": " + problem, peer);
    reply(peer, Kind::Refused, packText(Kind::Refused, 0, problem));
  } else if (state_ == State::Idle) {
    job_ = {peer, hello, now, 0, {}};
    log("job from " + from + ": " + std::to_string(hello.renderRanks) + " render ranks, codec " +
        codecName(hello.codec) + ", window " + peerText(windowText(hello.window)));
    startJob();
  } else {
    queueOrRefuse(peer, hello, from);
  }
  return take();
}

std::string JobDesk::windowProblem(const Hello& hello) const {
  try {
    resolveWindow(*s_.layout, hello.window);
    return {};
  } catch (const std::exception& e) {
    return e.what();
  }
}

bool JobDesk::hasJobFrom(const std::string& peer) const {
  if (state_ != State::Idle && state_ != State::Closed && job_.peer == peer) return true;
  return std::any_of(queue_.begin(), queue_.end(),
                     [&](const Job& queued) { return queued.peer == peer; });
}

void JobDesk::queueOrRefuse(const std::string& peer, const Hello& hello, const std::string& from) {
  if (!hello.wait) {
    log("refused a job from " + from + ": " + busy(), peer);
    reply(peer, Kind::Refused, packText(Kind::Refused, 0, busy()));
    return;
  }
  if (queue_.size() >= kMaxQueued) {
    log("refused a job from " + from + ": the queue is full", peer);
    reply(peer, Kind::Refused,
          packText(Kind::Refused, 0,
                   busy() + ", and " + std::to_string(kMaxQueued) + " jobs wait already"));
    return;
  }
  queue_.push_back({peer, hello, now_, 0, {}});
  const std::string place = "place " + std::to_string(queue_.size());
  log("queued a job from " + from + " (" + place + ")");
  reply(peer, Kind::Queued, packText(Kind::Queued, 0, busy() + "; waiting (" + place + ")"));
}

JobDesk::Actions JobDesk::message(const JobMessage& m, Clock::time_point now) {
  now_ = now;
  if (queuedMessage(m)) return take();
  const bool ours = state_ != State::Idle && state_ != State::Closed && m.peer == job_.peer &&
                    m.session == job_.session;
  if (!ours) {
    if (m.kind != Kind::Keepalive && m.kind != Kind::Bye)
      log("ignored a message on the directory port: message kind " +
              std::to_string(static_cast<int>(m.kind)) + " outside a job",
          m.peer);
    return take();
  }
  job_.lastHeard = now;
  if (!m.malformed.empty()) {
    endJob(m.malformed);
    return take();
  }
  // The job counts the wall silent after its --timeout without a message: a frame that takes
  // longer to render than that must not end it, so every keepalive is answered.
  if (m.kind == Kind::Keepalive)
    reply(m.peer, Kind::Keepalive, packControl(Kind::Keepalive, job_.session, 0));
  if (state_ == State::Running) onControl(m);
  return take();
}

// A waiting job's message says it is still there; a keepalive is told where it stands.
bool JobDesk::queuedMessage(const JobMessage& m) {
  for (size_t place = 0; place < queue_.size(); ++place) {
    if (queue_[place].peer != m.peer) continue;
    queue_[place].lastHeard = now_;
    if (m.kind == Kind::Keepalive)
      reply(m.peer, Kind::Queued,
            packText(Kind::Queued, 0,
                     busy() + "; waiting (place " + std::to_string(place + 1) + ")"));
    return true;
  }
  return false;
}

void JobDesk::onControl(const JobMessage& m) {
  switch (m.kind) {
    case Kind::Keepalive:
      toJob(command(Command::KeepWaiting));
      break;
    case Kind::Capture:
      onCapture(m);
      break;
    case Kind::Bye:
      if (m.control.second < 0) return endJob("the job left without naming its last frame");
      namedLastFrame_ = static_cast<std::uint32_t>(m.control.value);
      toJob(command(Command::LastFrame, static_cast<std::int64_t>(m.control.value)));
      break;
    default:
      endJob("unexpected message kind " + std::to_string(static_cast<int>(m.kind)));
  }
}

// Every process keeps a capture request until its frame is presented: only requests near the
// frames in flight, and a few at a time, go out to them.
void JobDesk::onCapture(const JobMessage& m) {
  const std::uint64_t frame = m.control.value;
  const std::uint32_t earliest =
      lastCredited_ > kCaptureFramesBehind ? lastCredited_ - kCaptureFramesBehind : 1;
  const std::uint64_t latest =
      std::uint64_t{lastCredited_} + framesAheadFor(static_cast<int>(granted_));
  std::string refused;
  if (frame < earliest || frame > latest)
    refused = "frame " + std::to_string(frame) + " is not near the frames in flight (" +
              std::to_string(earliest) + ".." + std::to_string(latest) + ")";
  else if (m.control.second < 1)
    refused = "sequence " + std::to_string(m.control.second) + " (expected 1 or more)";
  else if (pendingCaptures_.size() >= kMaxPendingCaptures)
    refused = std::to_string(kMaxPendingCaptures) + " captures wait for their frames already";
  if (!refused.empty()) {
    log("refused a capture request of the job from " + peerText(job_.hello.host) + ": " +
            (pendingCaptures_.size() >= kMaxPendingCaptures ? "too many pending"
                                                            : "a frame or sequence out of range"),
        m.peer);
    reply(m.peer, Kind::Refused,
          packText(Kind::Refused, job_.session, "capture request refused: " + refused));
    return;
  }
  // Taken at that frame, or at the next presented one when it is presented already.
  pendingCaptures_.push_back(std::max(static_cast<std::uint32_t>(frame), lastCredited_ + 1));
  toJob(command(Command::Capture, static_cast<std::int64_t>(frame), m.control.second));
}

JobDesk::Actions JobDesk::answer(int p, const ServiceCommand& c, Clock::time_point now) {
  now_ = now;
  const CommandHeader& e = c.header;
  if (e.kind == Command::Shutdown) {  // a member confirms the wall's shutdown
    if (state_ == State::Closed) ++shutdownAcks_;
    return take();
  }
  if (e.kind == Command::StopAsked) {
    stopAsked(p);
    return take();
  }
  if (state_ == State::Idle || state_ == State::Closed || e.session != job_.session ||
      !seats_[static_cast<size_t>(p)].in)
    return take();
  switch (e.kind) {
    case Command::Ready:
      onReady(p, c);
      break;
    case Command::Failed:
      if (state_ == State::Running) {
        endJob(c.text);
      } else if (state_ == State::Ending && failure_.empty()) {
        // Past the job's last frame (a capture of it that could not be written, after another
        // process was done): the job waits for that frame's credit, so it hears why instead.
        failure_ = c.text;
        reply(job_.peer, Kind::Ended, packText(Kind::Ended, job_.session, c.text));
        log("dropping the job from " + job_.hello.host + ": " + c.text);
      }
      break;
    case Command::Done:
      onDone(p, c);
      break;
    default:
      break;
  }
  overIfAllDone();
  return take();
}

void JobDesk::stopAsked(int p) {
  if (!shuttingDown_) log("stopping the wall (asked by wall process " + std::to_string(p) + ")");
  shuttingDown_ = true;
  for (const Job& queued : queue_)
    reply(queued.peer, Kind::Refused, packText(Kind::Refused, 0, "the wall is shutting down"));
  queue_.clear();
  endJob("the wall is shutting down");
}

void JobDesk::onReady(int p, const ServiceCommand& c) {
  Seat& seat = seats_[static_cast<size_t>(p)];
  seat.ready = true;
  if (c.header.a != 0 && seat.fromFrame == kNotYet) {
    if (state_ == State::Running) joinedJob(p);
    return;
  }
  if (c.header.a == 0) {
    seat.done = true;
    if (state_ == State::Running) {  // a process that joined mid-job cannot take it
      log(members_.who(p) + " cannot take the running job: " + reason(c.text));
      sendRoster(0, members_.who(p) + " cannot take the job: " + reason(c.text));
    } else if (failure_.empty()) {
      failure_ = reason(c.text);
    }
  }
  if (state_ == State::Starting) maybeRun();
}

void JobDesk::onDone(int p, const ServiceCommand& c) {
  lastPresented_ = std::max(lastPresented_, c.header.a);
  bytes_ += c.header.b;
  seats_[static_cast<size_t>(p)].done = true;
  if (state_ == State::Running && !c.text.empty() && p != 0) {
    // This process could not go on (its node failed); the others can.
    log(members_.who(p) + " left the job: " + reason(c.text));
    sendRoster(0, members_.who(p) + " left the job: " + reason(c.text));
    releaseWhatCan();
  } else {
    if (!c.text.empty() && failure_.empty()) failure_ = reason(c.text);
    if (state_ == State::Running) state_ = State::Ending;  // it ended by itself
  }
}

JobDesk::Actions JobDesk::joined(int p, Clock::time_point now) {
  now_ = now;
  if (state_ == State::Closed) {  // the wall is stopping: so does this process
    emit(ToProcess{p, shutdownCommand()});
  } else if (state_ == State::Running) {
    admitToJob(p);
  } else {
    log(members_.who(p) + " joined the wall");
    if (state_ == State::Starting) waitingToJoinJob_.insert(p);
  }
  return take();
}

JobDesk::Actions JobDesk::lost(int p, const std::string& why, Clock::time_point now) {
  now_ = now;
  Seat& seat = seats_[static_cast<size_t>(p)];
  const bool inJob = state_ != State::Idle && state_ != State::Closed && seat.in && !seat.done;
  const std::string line = "lost " + members_.who(p) +
                           (inJob ? " after frame " + std::to_string(lastCredited_) : "") + ": " +
                           why;
  log(line);
  emit(Record{jsonLine(Json{{"event", "lost"},
                            {"process", p},
                            {"host", members_.member(p).host},
                            {"frame", lastCredited_},
                            {"why", why}})});
  waitingToJoinJob_.erase(p);
  if (!inJob) return take();
  ++processesLost_;
  seat.done = true;
  sendRoster(0, line);
  if (state_ == State::Starting) maybeRun();
  releaseWhatCan();
  overIfAllDone();
  return take();
}

JobDesk::Actions JobDesk::arrive(int p, std::uint64_t session, std::uint32_t frameId,
                                 const std::vector<std::int64_t>& values, Clock::time_point now) {
  now_ = now;
  if (session != job_.session || (state_ != State::Running && state_ != State::Ending) ||
      !participates(p, frameId))
    return take();
  // A process arrives at frame F once F - 1 was released; the head credits F - 1 right after
  // its own release. Anything else would open a barrier nobody else comes to.
  const std::uint64_t latest =
      std::uint64_t{lastCredited_} + framesAheadFor(static_cast<int>(granted_));
  if (p != 0 && (frameId <= lastCredited_ || frameId > latest)) {
    emit(Drop{p, "its swap barrier of frame " + std::to_string(frameId) +
                     " is outside the frames in flight (" + std::to_string(lastCredited_ + 1) +
                     ".." + std::to_string(latest) + ")"});
    return take();
  }
  if (!agreements_.arrive(p, frameId, values, now)) {
    emit(Drop{p, "its swap barrier of frame " + std::to_string(frameId) + " has " +
                     std::to_string(values.size()) + " values, not the others' count"});
    return take();
  }
  releaseWhatCan();
  return take();
}

JobDesk::Actions JobDesk::pixels(int p, std::uint64_t session, std::uint32_t frameId,
                                 std::vector<std::uint32_t> pixels, Clock::time_point now) {
  now_ = now;
  if (session != job_.session || !participates(p, frameId)) return take();
  agreements_.pixels(p, frameId, std::move(pixels));
  releaseWhatCan();
  return take();
}

JobDesk::Actions JobDesk::headPixels(std::uint64_t session, std::uint32_t frameId,
                                     std::vector<std::uint32_t> pixels, Clock::time_point deadline,
                                     Clock::time_point now) {
  now_ = now;
  if (session != job_.session) return take();
  agreements_.headPixels(frameId, std::move(pixels), deadline);
  releaseWhatCan();
  return take();
}

JobDesk::Actions JobDesk::presented(std::uint64_t session, std::uint32_t frameId,
                                    std::int64_t completeNs) {
  if (session != job_.session || (state_ != State::Running && state_ != State::Ending))
    return take();
  lastCredited_ = std::max(lastCredited_, frameId);
  std::erase_if(pendingCaptures_, [&](std::uint32_t f) { return f <= lastCredited_; });
  reply(job_.peer, Kind::Presented,
        packControl(Kind::Presented, job_.session, frameId, completeNs));
  return take();
}

JobDesk::Actions JobDesk::tick(Clock::time_point now) {
  now_ = now;
  if (state_ == State::Closed) {
    // Every process said it got the shutdown, or a second passed (a process that did not hear
    // it stops once it misses the head): only then the head's own process stops.
    if (shutdownAcks_ == members_.liveMembers() || now > closedAt_ + std::chrono::seconds(1)) {
      emit(ToProcess{0, shutdownCommand()});
      emit(Closed{});
    }
    return take();
  }
  releaseWhatCan();
  if (state_ == State::Running || state_ == State::Ending) dropOverdue();
  if (state_ == State::Running && now - job_.lastHeard > s_.timeout)
    endJob("no word from the job for " + durationText(s_.timeout));
  closeIfIdle();
  return take();
}

JobDesk::Actions JobDesk::failed(const std::string& peer, const std::string& why,
                                 Clock::time_point now) {
  now_ = now;
  if (peer == job_.peer) endJob(reason(why));
  std::erase_if(queue_, [&](const Job& queued) { return queued.peer == peer; });
  return take();
}

JobDesk::Actions JobDesk::disconnected(const std::string& peer, Clock::time_point now) {
  now_ = now;
  const auto queued =
      std::find_if(queue_.begin(), queue_.end(), [&](const Job& job) { return job.peer == peer; });
  if (queued != queue_.end()) {
    log("a queued job from " + peerText(queued->hello.host) +
        " left the queue: its connection closed");
    queue_.erase(queued);
  }
  const bool over = namedLastFrame_ && lastCredited_ >= *namedLastFrame_;
  if (peer == job_.peer && !over) endJob("its connection closed");
  return take();
}

// ---- what goes out ----

JobDesk::Actions JobDesk::take() {
  Actions out;
  out.swap(out_);
  return out;
}

void JobDesk::log(std::string line, std::string oncePer) {
  emit(Log{std::move(line), std::move(oncePer)});
}

void JobDesk::reply(const std::string& peer, Kind kind, messaging::Bytes message) {
  emit(Reply{peer, kind, std::move(message)});
}

ServiceCommand JobDesk::command(Command kind, std::int64_t a, std::int64_t b,
                                std::string text) const {
  ServiceCommand c;
  c.header.kind = kind;
  c.header.session = job_.session;
  c.header.a = a;
  c.header.b = b;
  c.text = std::move(text);
  return c;
}

ServiceCommand JobDesk::startCommand(std::uint32_t firstFrame) const {
  ServiceCommand c = command(Command::Start, firstFrame, 0, job_.hello.captureDir);
  c.header.tileSize = job_.hello.tileSize;
  c.header.renderRanks = job_.hello.renderRanks;
  c.header.framesInFlight = granted_;
  c.header.captureEvery = job_.hello.captureEvery;
  c.header.codec = static_cast<std::uint32_t>(job_.hello.codec.codec);
  const dfb::Region window = resolveWindow(*s_.layout, job_.hello.window);  // checked at hello
  c.header.windowX0 = window.x0;
  c.header.windowY0 = window.y0;
  c.header.windowX1 = window.x1;
  c.header.windowY1 = window.y1;
  return c;
}

// To every process in the job that is not done with it.
void JobDesk::toJob(const ServiceCommand& c) {
  for (int p = 0; p < members_.processCount(); ++p) {
    const Seat& seat = seats_[static_cast<size_t>(p)];
    if (seat.in && !seat.done) emit(ToProcess{p, c});
  }
}

std::vector<DirectoryProcess> JobDesk::roster() const {
  std::vector<DirectoryProcess> out;
  for (int p = 0; p < members_.processCount(); ++p) {
    const Seat& seat = seats_[static_cast<size_t>(p)];
    out.push_back({members_.member(p).endpoint,
                   members_.live(p) && seat.in && !seat.done && seat.fromFrame != kNotYet});
  }
  return out;
}

void JobDesk::sendRoster(std::uint32_t fromFrame, const std::string& why) {
  if (state_ != State::Running) return;  // a starting job gets the directory, which has it all
  Roster r;
  r.session = job_.session;
  r.version = ++rosterVersion_;
  r.fromFrame = fromFrame;
  r.processes = roster();
  r.why = why;
  reply(job_.peer, Kind::Roster, packRoster(r));
}

std::string JobDesk::busy() const {
  return "busy: a job from " + peerText(job_.hello.host) + " is connected";
}

// ---- the job's life ----

void JobDesk::startJob() {
  job_.session = s_.newSession();
  emit(Session{job_.session, false});
  job_.started = now_;
  failure_.clear();
  namedLastFrame_.reset();
  lastPresented_ = bytes_ = 0;
  lastCredited_ = 0;
  rosterVersion_ = 0;
  processesLost_ = processesRejoined_ = 0;
  agreements_.clear();
  waitingToJoinJob_.clear();
  pendingCaptures_.clear();
  granted_ = std::min<std::uint32_t>(job_.hello.framesInFlight,
                                     static_cast<std::uint32_t>(s_.framesInFlight));
  state_ = State::Starting;
  for (int p = 0; p < members_.processCount(); ++p)
    seats_[static_cast<size_t>(p)] = {members_.live(p), false, false, 1};
  toJob(startCommand(1));
}

bool JobDesk::allDone() const {
  return std::none_of(seats_.begin(), seats_.end(),
                      [](const Seat& seat) { return seat.in && !seat.done; });
}

void JobDesk::overIfAllDone() {
  if ((state_ == State::Ending || state_ == State::Running) && allDone()) jobOver();
}

// The job is gone or broken: drop it everywhere.
void JobDesk::endJob(const std::string& why) {
  if (state_ != State::Running && state_ != State::Starting) return;
  failure_ = why;
  toJob(command(state_ == State::Starting ? Command::Cancel : Command::Abort, 0, 0, why));
  reply(job_.peer, Kind::Ended, packText(Kind::Ended, job_.session, why));
  state_ = State::Ending;
  log("dropping the job from " + peerText(job_.hello.host) + ": " + why);
  if (allDone()) jobOver();
}

void JobDesk::nextJob() {
  state_ = State::Idle;
  while (!queue_.empty() && !shuttingDown_) {
    job_ = queue_.front();
    queue_.pop_front();
    if (now_ - job_.lastHeard > s_.timeout) continue;  // it left the queue
    log("taking the queued job from " + peerText(job_.hello.host));
    startJob();
    return;
  }
}

void JobDesk::jobOver() {
  const double seconds = std::chrono::duration<double>(now_ - job_.started).count();
  log("the job from " + peerText(job_.hello.host) + " ended after frame " +
      std::to_string(lastPresented_) + (failure_.empty() ? "" : " (" + failure_ + ")"));
  emit(Record{jsonLine(Json{{"job", job_.session % 1000000007},
                            {"host", job_.hello.host},
                            {"render_ranks", job_.hello.renderRanks},
                            {"codec", codecName(job_.hello.codec)},
                            {"frames_presented", lastPresented_},
                            {"wall_bytes_received", bytes_},
                            {"processes_lost", processesLost_},
                            {"processes_rejoined", processesRejoined_},
                            {"seconds", std::round(seconds * 1e6) / 1e6},
                            {"ended", failure_.empty() ? "last frame" : failure_}})});
  agreements_.clear();
  emit(Session{0, true});
  nextJob();
}

// Every process in the job answered Start: the job gets its directory (or the refusal).
void JobDesk::maybeRun() {
  for (const Seat& seat : seats_)
    if (seat.in && !seat.ready && !seat.done) return;
  if (!failure_.empty()) {
    toJob(command(Command::Cancel));
    reply(job_.peer, Kind::Refused, packText(Kind::Refused, 0, failure_));
    log("refused the job from " + peerText(job_.hello.host) + ": " + failure_);
    state_ = State::Ending;
    if (allDone()) jobOver();
    return;
  }
  Directory d;
  d.session = job_.session;
  d.window = resolveWindow(*s_.layout, job_.hello.window);
  d.layout = windowLayout(*s_.layout, d.window);
  d.processes = roster();
  d.framesInFlight = granted_;
  d.timeoutMs = static_cast<std::uint32_t>(s_.timeout.count());
  d.rosterVersion = 0;
  reply(job_.peer, Kind::Directory, packDirectory(d));
  state_ = State::Running;
  // A process none of whose displays the window touches waits for this before its first swap
  // barrier (it has no pieces to wait for): one it came to before the job ran would be lost.
  for (int p = 0; p < members_.processCount(); ++p) {
    const Seat& seat = seats_[static_cast<size_t>(p)];
    if (seat.in && !seat.done && d.layout.displaysOfProcess(p).empty())
      emit(ToProcess{p, command(Command::FirstFrame, 1)});
  }
  for (int p : waitingToJoinJob_) admitToJob(p);
  waitingToJoinJob_.clear();
}

void JobDesk::closeIfIdle() {
  if (!shuttingDown_ || state_ != State::Idle) return;
  for (int p = 1; p < members_.processCount(); ++p) emit(ToProcess{p, shutdownCommand()});
  state_ = State::Closed;
  closedAt_ = now_;
  emit(Closing{});
}

// ---- processes that come back ----

// It takes part from the frame named once it is Ready (taking pieces): see joinedJob.
void JobDesk::admitToJob(int p) {
  if (!members_.live(p)) return;
  seats_[static_cast<size_t>(p)] = {true, false, false, kNotYet};
  emit(ToProcess{p, startCommand(0)});
}

// A process admitted to the running job is ready for pieces. Frames up to lastCredited +
// granted may have started without it; the next credit (sent after the roster, on the same
// socket) is the first that lets the job start a later one.
void JobDesk::joinedJob(int p) {
  const std::uint32_t first = lastCredited_ + granted_ + 1;
  seats_[static_cast<size_t>(p)].fromFrame = first;
  emit(ToProcess{p, command(Command::FirstFrame, first)});
  ++processesRejoined_;
  const std::string line = members_.who(p) +
                           " is back in the wall; it shows the job's frames from " +
                           std::to_string(first);
  log(line);
  emit(Record{jsonLine(Json{{"event", "rejoined"},
                            {"process", p},
                            {"host", members_.member(p).host},
                            {"frame", first}})});
  sendRoster(first, line);
}

// ---- barriers and gathers ----

bool JobDesk::participates(int p, std::uint32_t frameId) const {
  const Seat& seat = seats_[static_cast<size_t>(p)];
  return seat.in && !seat.done && seat.fromFrame <= frameId && members_.live(p);
}

// A process alive (it beats) that has not come to a barrier the others came to the timeout ago,
// while the job is alive, is dropped as if silent; the head's own process is never dropped (its
// presenting thread holds the wall's display side: when it hangs, so does the wall, beats or not).
void JobDesk::dropOverdue() {
  // Only while the job is heard from: pieces that stopped coming because the job died leave a
  // barrier open too, and that is the job's timeout's to end (every process gives the frame up).
  if (now_ - job_.lastHeard > s_.timeout / 2) return;
  const auto takesPart = [this](int p, std::uint32_t frameId) { return participates(p, frameId); };
  for (const FrameAgreements::Overdue& o : agreements_.overdue(takesPart, now_ - s_.timeout))
    for (int p : o.missing)
      if (p != 0)
        emit(Drop{p, "it did not come to the swap barrier of frame " + std::to_string(o.frameId) +
                         " within " + durationText(s_.timeout) + " of the others"});
}

// Barriers and gathers that nobody holds up any more go back to their processes.
void JobDesk::releaseWhatCan() {
  const auto takesPart = [this](int p, std::uint32_t frameId) { return participates(p, frameId); };
  for (FrameAgreements::Release& r : agreements_.complete(takesPart))
    for (int p : r.processes) emit(Release{p, job_.session, r.frameId, r.values});
  for (FrameAgreements::Gathered& g : agreements_.gathered(takesPart, now_))
    emit(Gathered{job_.session, g.frameId, std::move(g.pixels)});
}

}  // namespace wall::service
