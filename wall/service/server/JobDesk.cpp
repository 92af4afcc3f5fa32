#include "wall/service/server/JobDesk.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "base/Error.h"
#include "wall/display/WallNode.h"
#include "wall/service/protocol/PeerText.h"
#include "wall/service/server/WindowMoves.h"

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

// A job's page as the window manager links it: a plain http(s) address of printable ASCII, else
// nothing (a page that links a hostile job's `javascript:` would run it).
std::string pageAddress(const std::string& page) {
  const bool web = page.rfind("http://", 0) == 0 || page.rfind("https://", 0) == 0;
  const bool plain = page.size() <= 256 && std::all_of(page.begin(), page.end(), [](char c) {
                       return c > ' ' && c < 127 && c != '"' && c != '<' && c != '>' && c != '\\';
                     });
  return web && plain ? page : std::string();
}

ServiceCommand shutdownCommand() {
  ServiceCommand c;
  c.header.kind = Command::Shutdown;
  return c;
}

}  // namespace

JobDesk::JobDesk(Setup setup, const Membership& members)
    : s_(std::move(setup)),
      members_(members),
      ended_(std::make_unique<Slot>(members.processCount())) {}

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
  } else if (slots_.size() < std::max<std::size_t>(s_.maxJobs, 1)) {
    slots_.push_back(std::make_unique<Slot>(members_.processCount()));
    j_ = slots_.back().get();
    j_->job = {peer, hello, now, 0, {}};
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
  if (byPeer(peer)) return true;
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
  j_ = byPeer(m.peer);
  const bool ours = j_ && m.session == j_->job.session;
  if (!ours) {
    if (m.kind != Kind::Keepalive && m.kind != Kind::Bye)
      log("ignored a message on the directory port: message kind " +
              std::to_string(static_cast<int>(m.kind)) + " outside a job",
          m.peer);
    return take();
  }
  j_->job.lastHeard = now;
  if (!m.malformed.empty()) {
    endJob(m.malformed);
    return take();
  }
  // The job counts the wall silent after its --timeout without a message: a frame that takes
  // longer to render than that must not end it, so every keepalive is answered.
  if (m.kind == Kind::Keepalive)
    reply(m.peer, Kind::Keepalive, packControl(Kind::Keepalive, j_->job.session, 0));
  if (j_->state == State::Running) onControl(m);
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
      j_->namedLastFrame = static_cast<std::uint32_t>(m.control.value);
      toJob(command(Command::LastFrame, static_cast<std::int64_t>(m.control.value)));
      notRenderedFrom(*j_->namedLastFrame + 1);
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
      j_->lastCredited > kCaptureFramesBehind ? j_->lastCredited - kCaptureFramesBehind : 1;
  const std::uint64_t latest =
      std::uint64_t{j_->lastCredited} + framesAheadFor(static_cast<int>(j_->granted));
  std::string refused;
  if (frame < earliest || frame > latest)
    refused = "frame " + std::to_string(frame) + " is not near the frames in flight (" +
              std::to_string(earliest) + ".." + std::to_string(latest) + ")";
  else if (m.control.second < 1)
    refused = "sequence " + std::to_string(m.control.second) + " (expected 1 or more)";
  else if (j_->pendingCaptures.size() >= kMaxPendingCaptures)
    refused = std::to_string(kMaxPendingCaptures) + " captures wait for their frames already";
  if (!refused.empty()) {
    log("refused a capture request of the job from " + peerText(j_->job.hello.host) + ": " +
            (j_->pendingCaptures.size() >= kMaxPendingCaptures
                 ? "too many pending"
                 : "a frame or sequence out of range"),
        m.peer);
    reply(m.peer, Kind::Refused,
          packText(Kind::Refused, j_->job.session, "capture request refused: " + refused));
    return;
  }
  // Taken at that frame, or at the next presented one when it is presented already.
  j_->pendingCaptures.push_back(std::max(static_cast<std::uint32_t>(frame), j_->lastCredited + 1));
  toJob(command(Command::Capture, static_cast<std::int64_t>(frame), m.control.second));
}

JobDesk::Actions JobDesk::answer(int p, const ServiceCommand& c, Clock::time_point now) {
  now_ = now;
  const CommandHeader& e = c.header;
  if (e.kind == Command::Shutdown) {  // a member confirms the wall's shutdown
    if (closed_) ++shutdownAcks_;
    return take();
  }
  if (e.kind == Command::StopAsked) {
    stopAsked(p);
    return take();
  }
  j_ = bySession(e.session);
  if (!j_ || !j_->seats[static_cast<size_t>(p)].in) return take();
  switch (e.kind) {
    case Command::Ready:
      onReady(p, c);
      break;
    case Command::Failed:
      if (j_->state == State::Running) {
        endJob(c.text);
      } else if (j_->state == State::Ending && j_->failure.empty()) {
        // Past the job's last frame (a capture of it that could not be written, after another
        // process was done): the job waits for that frame's credit, so it hears why instead.
        j_->failure = c.text;
        reply(j_->job.peer, Kind::Ended, packText(Kind::Ended, j_->job.session, c.text));
        log("dropping the job from " + j_->job.hello.host + ": " + c.text);
      }
      break;
    case Command::Done:
      onDone(p, c);
      break;
    case Command::Reshaped:
      onReshaped(p, c);
      break;
    case Command::Input:
      onInput(p, c);
      break;
    default:
      break;
  }
  overIfAllDone();
  return take();
}

// A key or the mouse over the job's window on process p's display: told to the job in its
// window's pixels, if it is a running job's, on a display of p's inside the window, well formed,
// and within the job's rate. Anything else is dropped (a window that went, a process that lies).
void JobDesk::onInput(int p, const ServiceCommand& c) {
  if (j_->state != State::Running) return;
  const std::string from = "wall process " + std::to_string(p);
  WindowInput in;
  try {
    const auto* data = reinterpret_cast<const std::byte*>(c.text.data());
    if (parseHeader(data, c.text.size()).session != j_->job.session)
      throw base::Error("an input event for another session");
    in = parseInput(data, c.text.size());
  } catch (const std::exception& e) {
    log(from + " sent a malformed input event: " + e.what(), "input " + from);
    return;
  }
  const dfb::Region& w = j_->window;
  bool onItsDisplay = false;
  for (const Display& d : s_.layout->displays)
    onItsDisplay = onItsDisplay || (d.process == p && in.x >= d.rect.x0 && in.x < d.rect.x1 &&
                                    in.y >= d.rect.y0 && in.y < d.rect.y1);
  if (!onItsDisplay || in.x < w.x0 || in.x >= w.x1 || in.y < w.y0 || in.y >= w.y1) {
    log(from + " sent an input event at " + std::to_string(in.x) + "," + std::to_string(in.y) +
            ", outside the job's window on its displays",
        "input " + from);
    return;
  }
  if (now_ - j_->inputSince >= std::chrono::seconds(1)) {
    j_->inputSince = now_;
    j_->inputs = 0;
  }
  if (++j_->inputs > kMaxInputsPerSecond) return;
  in.x -= w.x0;
  in.y -= w.y0;
  reply(j_->job.peer, Kind::Input, packInput(j_->job.session, in));
}

void JobDesk::stopAsked(int p) {
  if (!shuttingDown_) log("stopping the wall (asked by wall process " + std::to_string(p) + ")");
  shuttingDown_ = true;
  for (const Job& queued : queue_)
    reply(queued.peer, Kind::Refused, packText(Kind::Refused, 0, "the wall is shutting down"));
  queue_.clear();
  for (Slot* slot : inOrder()) {
    j_ = slot;
    endJob("the wall is shutting down");
  }
}

void JobDesk::onReady(int p, const ServiceCommand& c) {
  Seat& seat = j_->seats[static_cast<size_t>(p)];
  seat.ready = true;
  if (c.header.a != 0 && seat.fromFrame == kNotYet) {
    if (j_->state == State::Running) joinedJob(p);
    return;
  }
  if (c.header.a == 0) {
    seat.done = true;
    if (j_->state == State::Running) {  // a process that joined mid-job cannot take it
      log(members_.who(p) + " cannot take the running job: " + reason(c.text));
      sendRoster(0, members_.who(p) + " cannot take the job: " + reason(c.text));
    } else if (j_->failure.empty()) {
      j_->failure = reason(c.text);
    }
  }
  if (j_->state == State::Starting) maybeRun();
}

void JobDesk::onDone(int p, const ServiceCommand& c) {
  j_->lastPresented = std::max(j_->lastPresented, c.header.a);
  j_->bytes += c.header.b;
  j_->seats[static_cast<size_t>(p)].done = true;
  if (j_->state == State::Running && !c.text.empty() && p != 0) {
    // This process could not go on (its node failed); the others can.
    log(members_.who(p) + " left the job: " + reason(c.text));
    sendRoster(0, members_.who(p) + " left the job: " + reason(c.text));
  } else {
    if (!c.text.empty() && j_->failure.empty()) j_->failure = reason(c.text);
    if (j_->state == State::Running) j_->state = State::Ending;  // it ended by itself
  }
  releaseWhatCan();  // a barrier it held up (one past the job's last frame, out of the window)
}

JobDesk::Actions JobDesk::joined(int p, Clock::time_point now) {
  now_ = now;
  if (closed_) {  // the wall is stopping: so does this process
    emit(ToProcess{p, shutdownCommand()});
    return take();
  }
  bool running = false;  // a job running takes it in (admitToJob); said otherwise
  for (const auto& slot : slots_) running = running || slot->state == State::Running;
  if (!running) log(members_.who(p) + " joined the wall");
  for (Slot* slot : inOrder()) {
    j_ = slot;
    if (j_->state == State::Running)
      admitToJob(p);
    else if (j_->state == State::Starting)
      j_->waitingToJoinJob.insert(p);
  }
  return take();
}

JobDesk::Actions JobDesk::lost(int p, const std::string& why, Clock::time_point now) {
  now_ = now;
  const auto inJob = [p](const Slot& slot) {
    const Seat& seat = slot.seats[static_cast<size_t>(p)];
    return slot.state != State::Idle && seat.in && !seat.done;
  };
  // The frame said is that of the oldest job it was in (with one job: the job's).
  const Slot* in = nullptr;
  for (const Slot* slot : inOrder())
    if (!in && inJob(*slot)) in = slot;
  const std::uint32_t frame = in ? in->lastCredited : shown().lastCredited;
  const std::string line =
      "lost " + members_.who(p) + (in ? " after frame " + std::to_string(frame) : "") + ": " + why;
  log(line);
  emit(Record{jsonLine(Json{{"event", "lost"},
                            {"process", p},
                            {"host", members_.member(p).host},
                            {"frame", frame},
                            {"why", why}})});
  for (Slot* slot : inOrder()) {
    j_ = slot;
    j_->waitingToJoinJob.erase(p);
    if (!inJob(*j_)) continue;
    ++j_->processesLost;
    j_->seats[static_cast<size_t>(p)].done = true;
    sendRoster(0, line);
    commitMoveIfBuilt();
    if (j_->state == State::Starting) maybeRun();
    releaseWhatCan();
    overIfAllDone();
  }
  return take();
}

JobDesk::Actions JobDesk::arrive(int p, std::uint64_t session, std::uint32_t frameId,
                                 const std::vector<std::int64_t>& values, Clock::time_point now) {
  now_ = now;
  j_ = bySession(session);
  if (!j_ || (j_->state != State::Running && j_->state != State::Ending) ||
      !participates(p, frameId))
    return take();
  // A process arrives at frame F once F - 1 was released; the head credits F - 1 right after
  // its own release. Anything else would open a barrier nobody else comes to.
  const std::uint64_t latest =
      std::uint64_t{j_->lastCredited} + framesAheadFor(static_cast<int>(j_->granted));
  if (p != 0 && (frameId <= j_->lastCredited || frameId > latest)) {
    emit(Drop{p, "its swap barrier of frame " + std::to_string(frameId) +
                     " is outside the frames in flight (" + std::to_string(j_->lastCredited + 1) +
                     ".." + std::to_string(latest) + ")"});
    return take();
  }
  if (!j_->agreements.arrive(p, frameId, values, now, inWindowAt(p, frameId))) {
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
  j_ = bySession(session);
  if (!j_ || !participates(p, frameId)) return take();
  j_->agreements.pixels(p, frameId, std::move(pixels));
  releaseWhatCan();
  return take();
}

JobDesk::Actions JobDesk::headPixels(std::uint64_t session, std::uint32_t frameId,
                                     std::vector<std::uint32_t> pixels, Clock::time_point deadline,
                                     Clock::time_point now) {
  now_ = now;
  j_ = bySession(session);
  if (!j_) return take();
  j_->agreements.headPixels(frameId, std::move(pixels), deadline);
  releaseWhatCan();
  return take();
}

JobDesk::Actions JobDesk::presented(std::uint64_t session, std::uint32_t frameId,
                                    std::int64_t completeNs, Clock::time_point now) {
  j_ = bySession(session);
  if (!j_ || (j_->state != State::Running && j_->state != State::Ending)) return take();
  if (frameId > j_->lastCredited) {
    j_->credits.push_back(now);
    while (j_->credits.front() < now - kFpsWindow) j_->credits.pop_front();
  }
  j_->lastCredited = std::max(j_->lastCredited, frameId);
  if (j_->move && j_->move->fromFrame > 0 && j_->lastCredited >= j_->move->fromFrame) {
    j_->inWindow = j_->move->inWindow;
    j_->move.reset();  // the new window is on the wall: the next move may come
  }
  std::erase_if(j_->pendingCaptures, [&](std::uint32_t f) { return f <= j_->lastCredited; });
  reply(j_->job.peer, Kind::Presented,
        packControl(Kind::Presented, j_->job.session, frameId, completeNs));
  return take();
}

JobDesk::Actions JobDesk::tick(Clock::time_point now) {
  now_ = now;
  if (closed_) {
    // Every process said it got the shutdown, or a second passed (a process that did not hear
    // it stops once it misses the head): only then the head's own process stops.
    if (shutdownAcks_ == members_.liveMembers() || now > closedAt_ + std::chrono::seconds(1)) {
      emit(ToProcess{0, shutdownCommand()});
      emit(Closed{});
    }
    return take();
  }
  // Each job on its own: one silent or slow holds up its own frames only.
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    j_ = slots_[i].get();
    releaseWhatCan();
    if (j_->state == State::Running || j_->state == State::Ending) dropOverdue();
    if (j_->state == State::Running && now - j_->job.lastHeard > s_.timeout)
      endJob("no word from the job for " + durationText(s_.timeout));
  }
  closeIfIdle();
  if (s_.thumbnailSide > 0 && now >= nextThumbnails_) {
    nextThumbnails_ = now + s_.thumbnailEvery;
    askThumbnails();
  }
  return take();
}

// What the last request brought is published (a process that did not answer keeps its cells of
// the thumbnail before), and every live process is asked again while a job runs.
void JobDesk::askThumbnails() {
  for (const std::unique_ptr<Slot>& slot : slots_)
    if (slot->assembling) publishThumbnail(*slot);
  const bool running = std::any_of(slots_.begin(), slots_.end(),
                                   [](const auto& slot) { return slot->state == State::Running; });
  if (!running) return;
  ++thumbnailRequest_;
  thumbnailAsked_.assign(static_cast<std::size_t>(members_.processCount()), false);
  for (int p = 0; p < members_.processCount(); ++p) {
    if (p != 0 && !members_.live(p)) continue;
    thumbnailAsked_[static_cast<std::size_t>(p)] = true;
    ServiceCommand c;
    c.header.kind = Command::Thumbnails;
    c.header.a = thumbnailRequest_;
    c.header.b = s_.thumbnailSide;
    emit(ToProcess{p, c});
  }
}

void JobDesk::thumbnail(int p, std::uint64_t session, const ThumbnailPart& part) {
  Slot* slot = bySession(session);
  if (!slot || slot->state != State::Running || part.request != thumbnailRequest_ ||
      part.request == 0 || part.request == slot->publishedRequest || p < 0 ||
      static_cast<std::size_t>(p) >= thumbnailAsked_.size() ||
      !thumbnailAsked_[static_cast<std::size_t>(p)] || part.window != slot->window)
    return;
  const int w = part.window.width(), h = part.window.height();
  const ThumbnailGrid grid = thumbnailGrid(w, h, s_.thumbnailSide);
  const dfb::Region& cells = part.cells.cells;
  if (cells.empty() || cells.x1 > grid.width || cells.y1 > grid.height) return;
  if (slot->assembling && slot->assembling->request != part.request) publishThumbnail(*slot);
  if (slot->assembling && slot->assembling->answered.count(p)) return;
  // No cell may hold more pixels than it covers, counting what other processes sent: so no sum
  // can wrap (wall/image/Thumbnail.h), and a process cannot fill another's cells.
  const CellSums* had = slot->assembling ? &slot->assembling->sums : nullptr;
  for (int cy = cells.y0; cy < cells.y1; ++cy)
    for (int cx = cells.x0; cx < cells.x1; ++cx) {
      const std::uint32_t* in =
          part.cells.sums.data() +
          static_cast<std::size_t>((cy - cells.y0) * cells.width() + (cx - cells.x0)) *
              CellSums::kChannels;
      const std::uint64_t before =
          had ? had->sums[(static_cast<std::size_t>(cy) * grid.width + cx) * CellSums::kChannels +
                          4]
              : 0;
      if (before + in[4] > cellArea(grid, w, h, cx, cy)) return;
      for (int ch = 0; ch < 4; ++ch)
        if (in[ch] > 255ull * in[4]) return;
    }
  if (!slot->assembling)
    slot->assembling = Slot::Assembly{
        part.request, part.window, grid, emptySums({0, 0, grid.width, grid.height}), {}};
  Slot::Assembly& a = *slot->assembling;
  for (int cy = cells.y0; cy < cells.y1; ++cy) {
    const std::uint32_t* in = part.cells.sums.data() + static_cast<std::size_t>(cy - cells.y0) *
                                                           cells.width() * CellSums::kChannels;
    std::uint32_t* out =
        a.sums.sums.data() +
        (static_cast<std::size_t>(cy) * grid.width + cells.x0) * CellSums::kChannels;
    for (int i = 0; i < cells.width() * CellSums::kChannels; ++i) out[i] += in[i];
  }
  a.answered.insert(p);
  // Every process asked that shows a part of the window answered: no need to wait.
  for (int q = 0; q < static_cast<int>(slot->inWindow.size()); ++q)
    if (slot->inWindow[static_cast<std::size_t>(q)] &&
        thumbnailAsked_[static_cast<std::size_t>(q)] && (q == 0 || members_.live(q)) &&
        !a.answered.count(q))
      return;
  publishThumbnail(*slot);
}

void JobDesk::publishThumbnail(Slot& slot) {
  Slot::Assembly& a = *slot.assembling;
  const Image* previous = slot.thumbnail.get();
  slot.thumbnail = std::make_shared<const Image>(averageCells(a.grid, a.sums, previous));
  slot.publishedRequest = a.request;
  slot.assembling.reset();
}

JobDesk::Actions JobDesk::failed(const std::string& peer, const std::string& why,
                                 Clock::time_point now) {
  now_ = now;
  j_ = byPeer(peer);
  if (j_) endJob(reason(why));
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
  j_ = byPeer(peer);
  if (j_ && !(j_->namedLastFrame && j_->lastCredited >= *j_->namedLastFrame))
    endJob("its connection closed");
  return take();
}

// ---- what goes out ----

JobDesk::Actions JobDesk::take() {
  removeEnded();
  j_ = nullptr;
  Actions out;
  out.swap(out_);
  return out;
}

JobDesk::Slot* JobDesk::bySession(std::uint64_t session) const {
  for (const auto& slot : slots_)
    if (slot->state != State::Idle && slot->job.session == session) return slot.get();
  return nullptr;
}

JobDesk::Slot* JobDesk::byPeer(const std::string& peer) const {
  for (const auto& slot : slots_)
    if (slot->state != State::Idle && slot->job.peer == peer) return slot.get();
  return nullptr;
}

const JobDesk::Slot& JobDesk::shown() const {
  const std::vector<Slot*> jobs = inOrder();
  return jobs.empty() ? *ended_ : *jobs.back();
}

std::vector<JobDesk::Slot*> JobDesk::inOrder() const {
  std::vector<Slot*> out;
  for (const auto& slot : slots_)
    if (slot->state != State::Idle) out.push_back(slot.get());
  std::sort(out.begin(), out.end(),
            [](const Slot* x, const Slot* y) { return x->number < y->number; });
  return out;
}

JobDesk::Slot* JobDesk::byNumber(std::uint64_t number) const {
  for (const auto& slot : slots_)
    if (slot->state != State::Idle && slot->number == number) return slot.get();
  return nullptr;
}

// ---- the window manager ----

std::vector<JobDesk::Window> JobDesk::windows(Clock::time_point now) const {
  std::vector<Slot*> jobs = inOrder();
  std::vector<Slot*> stacked = jobs;
  std::sort(stacked.begin(), stacked.end(),
            [](const Slot* x, const Slot* y) { return x->order < y->order; });
  std::vector<Window> out;
  for (const Slot* slot : jobs) {
    Window w;
    w.number = slot->number;
    w.host = peerText(slot->job.hello.host);
    w.job = peerText(slot->job.hello.job);
    w.page = pageAddress(slot->job.hello.page);
    w.rect = slot->window;
    w.z = static_cast<int>(std::find(stacked.begin(), stacked.end(), slot) - stacked.begin());
    w.state = slot->state;
    w.frames = slot->lastCredited;
    const auto recent = std::count_if(slot->credits.begin(), slot->credits.end(),
                                      [&](Clock::time_point t) { return t >= now - kFpsWindow; });
    // Frames over the window, or since the job started when that is shorter.
    const double span = std::chrono::duration<double>(
                            std::min<Clock::duration>(kFpsWindow, now - slot->job.started))
                            .count();
    w.fps = span > 0 ? static_cast<double>(recent) / span : 0;
    const Clock::time_point last = slot->credits.empty() ? slot->job.started : slot->credits.back();
    w.idle = slot->state == State::Running && now - last > kIdleAfter;
    w.thumbnail = slot->thumbnail;
    out.push_back(std::move(w));
  }
  return out;
}

std::optional<JobDesk::Actions> JobDesk::raise(std::uint64_t number) {
  j_ = byNumber(number);
  if (!j_) return std::nullopt;
  // Already on top: nothing to tell the processes.
  if (j_->order != stackTop_) {
    j_->order = ++stackTop_;
    toJob(command(Command::Raise, static_cast<std::int64_t>(j_->order)));
  }
  return take();
}

std::optional<std::uint64_t> JobDesk::sessionOf(std::uint64_t number) const {
  const Slot* slot = byNumber(number);
  if (!slot) return std::nullopt;
  return slot->job.session;
}

std::optional<JobDesk::Actions> JobDesk::close(std::uint64_t number, const std::string& why,
                                               Clock::time_point now) {
  now_ = now;
  j_ = byNumber(number);
  if (!j_) return std::nullopt;
  endJob(why);
  return take();
}

void JobDesk::removeEnded() {
  for (auto it = slots_.begin(); it != slots_.end();) {
    if ((*it)->state != State::Idle) {
      ++it;
      continue;
    }
    ended_ = std::move(*it);
    it = slots_.erase(it);
  }
}

JobDesk::State JobDesk::state() const {
  if (closed_) return State::Closed;
  const std::vector<Slot*> jobs = inOrder();
  return jobs.empty() ? State::Idle : jobs.back()->state;
}

std::vector<std::uint64_t> JobDesk::sessions() const {
  std::vector<std::uint64_t> out;
  for (const Slot* slot : inOrder()) out.push_back(slot->job.session);
  return out;
}

JobDesk::State JobDesk::state(std::uint64_t session) const {
  const Slot* slot = bySession(session);
  return slot ? slot->state : State::Idle;
}

std::uint32_t JobDesk::lastCredited(std::uint64_t session) const {
  const Slot* slot = bySession(session);
  return slot ? slot->lastCredited : 0;
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
  c.header.session = j_->job.session;
  c.header.a = a;
  c.header.b = b;
  c.text = std::move(text);
  return c;
}

ServiceCommand JobDesk::startCommand(std::uint32_t firstFrame) const {
  ServiceCommand c = command(Command::Start, firstFrame, static_cast<std::int64_t>(j_->order),
                             j_->job.hello.captureDir);
  // A process that joins after a move takes the moved window's pieces.
  c.header.pieceSession = j_->pieceSession;
  c.header.tileSize = j_->job.hello.tileSize;
  c.header.renderRanks = j_->job.hello.renderRanks;
  c.header.framesInFlight = j_->granted;
  c.header.captureEvery = j_->job.hello.captureEvery;
  c.header.codec = static_cast<std::uint32_t>(j_->job.hello.codec.codec);
  const dfb::Region window = j_->window;
  c.header.windowX0 = window.x0;
  c.header.windowY0 = window.y0;
  c.header.windowX1 = window.x1;
  c.header.windowY1 = window.y1;
  return c;
}

// To every process in the job that is not done with it.
void JobDesk::toJob(const ServiceCommand& c) {
  for (int p = 0; p < members_.processCount(); ++p) {
    const Seat& seat = j_->seats[static_cast<size_t>(p)];
    if (seat.in && !seat.done) emit(ToProcess{p, c});
  }
}

std::vector<DirectoryProcess> JobDesk::roster() const {
  std::vector<DirectoryProcess> out;
  for (int p = 0; p < members_.processCount(); ++p) {
    const Seat& seat = j_->seats[static_cast<size_t>(p)];
    out.push_back({members_.member(p).endpoint,
                   members_.live(p) && seat.in && !seat.done && seat.fromFrame != kNotYet});
  }
  return out;
}

void JobDesk::sendRoster(std::uint32_t fromFrame, const std::string& why) {
  if (j_->state != State::Running) return;  // a starting job gets the directory, which has it all
  Roster r;
  r.session = j_->job.session;
  r.version = ++j_->rosterVersion;
  r.fromFrame = fromFrame;
  r.processes = roster();
  r.why = why;
  reply(j_->job.peer, Kind::Roster, packRoster(r));
}

std::string JobDesk::busy() const {
  if (s_.maxJobs <= 1)
    return "busy: a job from " + peerText(shown().job.hello.host) + " is connected";
  std::string hosts;
  const std::vector<Slot*> jobs = inOrder();
  for (const Slot* slot : jobs)
    hosts += (hosts.empty() ? "" : ", ") + peerText(slot->job.hello.host);
  return "busy: " + std::to_string(jobs.size()) + " jobs are on the wall (from " + hosts + ")";
}

// ---- the job's life ----

void JobDesk::startJob() {
  j_->job.session = s_.newSession();
  j_->number = ++jobsStarted_;
  j_->order = ++stackTop_;  // a new window opens on top
  j_->credits.clear();
  j_->window = placeWindow(j_->job.hello);
  emit(Session{j_->job.session, false});
  j_->job.started = now_;
  j_->failure.clear();
  j_->namedLastFrame.reset();
  j_->unrenderedFrom.reset();
  const Layout seen = windowLayout(*s_.layout, j_->window);
  j_->inWindow.assign(static_cast<size_t>(members_.processCount()), false);
  for (int p = 0; p < members_.processCount(); ++p)
    j_->inWindow[static_cast<size_t>(p)] = !seen.displaysOfProcess(p).empty();
  j_->lastPresented = j_->bytes = 0;
  j_->lastCredited = 0;
  j_->rosterVersion = 0;
  j_->processesLost = j_->processesRejoined = 0;
  j_->agreements.clear();
  j_->waitingToJoinJob.clear();
  j_->pendingCaptures.clear();
  j_->move.reset();
  j_->reshapeVersion = 0;
  j_->pieceSession = 0;
  j_->granted = std::min<std::uint32_t>(j_->job.hello.framesInFlight,
                                        static_cast<std::uint32_t>(s_.framesInFlight));
  j_->state = State::Starting;
  for (int p = 0; p < members_.processCount(); ++p)
    j_->seats[static_cast<size_t>(p)] = {members_.live(p), false, false, 1};
  toJob(startCommand(1));
}

// A job that asks for the whole wall while others are on it gets the first display no other
// job's window touches, if there is one, else the whole wall (on top). Any other window is the
// one asked for (checked at hello), wherever the others are.
dfb::Region JobDesk::placeWindow(const Hello& hello) const {
  const dfb::Region asked = resolveWindow(*s_.layout, hello.window);
  if (hello.window.kind != WindowRequest::Kind::Full) return asked;
  std::vector<dfb::Region> taken;
  for (const Slot* slot : inOrder())
    if (slot != j_) taken.push_back(slot->window);
  if (taken.empty()) return asked;
  for (const Display& d : s_.layout->displays)
    if (std::none_of(taken.begin(), taken.end(),
                     [&](const dfb::Region& w) { return !dfb::intersect(w, d.rect).empty(); }))
      return d.rect;
  return asked;
}

bool JobDesk::allDone() const {
  return std::none_of(j_->seats.begin(), j_->seats.end(),
                      [](const Seat& seat) { return seat.in && !seat.done; });
}

void JobDesk::overIfAllDone() {
  if ((j_->state == State::Ending || j_->state == State::Running) && allDone()) jobOver();
}

// The job is gone or broken: drop it everywhere.
void JobDesk::endJob(const std::string& why) {
  if (j_->state != State::Running && j_->state != State::Starting) return;
  j_->failure = why;
  toJob(command(j_->state == State::Starting ? Command::Cancel : Command::Abort, 0, 0, why));
  notRenderedFrom(0);
  reply(j_->job.peer, Kind::Ended, packText(Kind::Ended, j_->job.session, why));
  j_->state = State::Ending;
  log("dropping the job from " + peerText(j_->job.hello.host) + ": " + why);
  if (allDone()) jobOver();
}

// The seat of the job that ended goes to the first job still waiting.
void JobDesk::nextJob() {
  j_->state = State::Idle;
  while (!queue_.empty() && !shuttingDown_) {
    j_->job = queue_.front();
    queue_.pop_front();
    if (now_ - j_->job.lastHeard > s_.timeout) continue;  // it left the queue
    log("taking the queued job from " + peerText(j_->job.hello.host));
    startJob();
    return;
  }
}

void JobDesk::jobOver() {
  const double seconds = std::chrono::duration<double>(now_ - j_->job.started).count();
  log("the job from " + peerText(j_->job.hello.host) + " ended after frame " +
      std::to_string(j_->lastPresented) + (j_->failure.empty() ? "" : " (" + j_->failure + ")"));
  emit(Record{jsonLine(Json{{"job", j_->job.session % 1000000007},
                            {"host", j_->job.hello.host},
                            {"render_ranks", j_->job.hello.renderRanks},
                            {"codec", codecName(j_->job.hello.codec)},
                            {"frames_presented", j_->lastPresented},
                            {"wall_bytes_received", j_->bytes},
                            {"processes_lost", j_->processesLost},
                            {"processes_rejoined", j_->processesRejoined},
                            {"seconds", std::round(seconds * 1e6) / 1e6},
                            {"ended", j_->failure.empty() ? "last frame" : j_->failure}})});
  j_->agreements.clear();
  emit(Session{j_->job.session, true});
  nextJob();
}

// Every process in the job answered Start: the job gets its directory (or the refusal).
void JobDesk::maybeRun() {
  for (const Seat& seat : j_->seats)
    if (seat.in && !seat.ready && !seat.done) return;
  if (!j_->failure.empty()) {
    toJob(command(Command::Cancel));
    reply(j_->job.peer, Kind::Refused, packText(Kind::Refused, 0, j_->failure));
    log("refused the job from " + peerText(j_->job.hello.host) + ": " + j_->failure);
    j_->state = State::Ending;
    if (allDone()) jobOver();
    return;
  }
  Directory d;
  d.session = j_->job.session;
  d.window = j_->window;
  d.layout = windowLayout(*s_.layout, d.window);
  d.processes = roster();
  d.framesInFlight = j_->granted;
  d.timeoutMs = static_cast<std::uint32_t>(s_.timeout.count());
  d.rosterVersion = 0;
  reply(j_->job.peer, Kind::Directory, packDirectory(d));
  j_->state = State::Running;
  // A process none of whose displays the window touches waits for this before its first swap
  // barrier (it has no pieces to wait for): one it came to before the job ran would be lost.
  for (int p = 0; p < members_.processCount(); ++p) {
    const Seat& seat = j_->seats[static_cast<size_t>(p)];
    if (seat.in && !seat.done && !j_->inWindow[static_cast<size_t>(p)])
      emit(ToProcess{p, command(Command::FirstFrame, 1)});
  }
  for (int p : j_->waitingToJoinJob) admitToJob(p);
  j_->waitingToJoinJob.clear();
}

void JobDesk::closeIfIdle() {
  if (!shuttingDown_ || closed_ || state() != State::Idle) return;
  for (int p = 1; p < members_.processCount(); ++p) emit(ToProcess{p, shutdownCommand()});
  closed_ = true;
  closedAt_ = now_;
  emit(Closing{});
}

// ---- processes that come back ----

// It takes part from the frame named once it is Ready (taking pieces): see joinedJob.
void JobDesk::admitToJob(int p) {
  if (!members_.live(p)) return;
  j_->seats[static_cast<size_t>(p)] = {true, false, false, kNotYet};
  emit(ToProcess{p, startCommand(0)});
}

// A process admitted to the running job is ready for pieces. Frames up to lastCredited +
// granted may have started without it; the next credit (sent after the roster, on the same
// socket) is the first that lets the job start a later one.
void JobDesk::joinedJob(int p) {
  const std::uint32_t first = j_->lastCredited + j_->granted + 1;
  j_->seats[static_cast<size_t>(p)].fromFrame = first;
  emit(ToProcess{p, command(Command::FirstFrame, first)});
  ++j_->processesRejoined;
  const std::string line = members_.who(p) +
                           " is back in the wall; it shows the job's frames from " +
                           std::to_string(first);
  log(line);
  emit(Record{jsonLine(Json{{"event", "rejoined"},
                            {"process", p},
                            {"host", members_.member(p).host},
                            {"frame", first}})});
  sendRoster(first, line);
  releaseWhatCan();  // frames before its first that no other process of the window shows
}

// ---- barriers and gathers ----

// The processes were told the job renders no frame from `frameId` on: a process out of the
// window waiting at such a frame's barrier is let go (it does not present it: WallNode).
void JobDesk::notRenderedFrom(std::uint32_t frameId) {
  j_->unrenderedFrom = std::min(j_->unrenderedFrom.value_or(frameId), frameId);
  releaseWhatCan();
}

bool JobDesk::participates(int p, std::uint32_t frameId) const {
  const Seat& seat = j_->seats[static_cast<size_t>(p)];
  return seat.in && !seat.done && seat.fromFrame <= frameId && members_.live(p);
}

// A process alive (it beats) that has not come to a barrier the others came to the timeout ago,
// while the job is alive, is dropped as if silent; the head's own process is never dropped (its
// presenting thread holds the wall's display side: when it hangs, so does the wall, beats or not).
void JobDesk::dropOverdue() {
  // Only while the job is heard from: pieces that stopped coming because the job died leave a
  // barrier open too, and that is the job's timeout's to end (every process gives the frame up).
  if (now_ - j_->job.lastHeard > s_.timeout / 2) return;
  const auto takesPart = [this](int p, std::uint32_t frameId) { return participates(p, frameId); };
  for (const FrameAgreements::Overdue& o : j_->agreements.overdue(takesPart, now_ - s_.timeout))
    for (int p : o.missing)
      if (p != 0)
        emit(Drop{p, "it did not come to the swap barrier of frame " + std::to_string(o.frameId) +
                         " within " + durationText(s_.timeout) + " of the others"});
}

// Barriers and gathers that nobody holds up any more go back to their processes.
void JobDesk::releaseWhatCan() {
  const auto takesPart = [this](int p, std::uint32_t frameId) { return participates(p, frameId); };
  // A frame no process of the window came to goes when the job will not render it, or when no
  // process of the window can show it: one back in the job shows frames from a later one only,
  // and the job may have rendered those before it (it gets their credits to go on).
  const auto goesUnpaced = [this](std::uint32_t frameId) {
    if (j_->unrenderedFrom && frameId >= *j_->unrenderedFrom) return true;
    bool later = false;
    for (int p = 0; p < members_.processCount(); ++p) {
      if (!inWindowAt(p, frameId)) continue;
      if (participates(p, frameId)) return false;
      const Seat& seat = j_->seats[static_cast<size_t>(p)];
      later = later || (seat.in && !seat.done && members_.live(p) && seat.fromFrame != kNotYet);
    }
    return later;
  };
  for (FrameAgreements::Release& r : j_->agreements.complete(takesPart, goesUnpaced))
    for (int p : r.processes) emit(Release{p, j_->job.session, r.frameId, r.values});
  for (FrameAgreements::Gathered& g : j_->agreements.gathered(takesPart, now_))
    emit(Gathered{j_->job.session, g.frameId, std::move(g.pixels)});
}

}  // namespace wall::service

namespace wall::service {

JobDesk::Actions JobDesk::reshape(std::uint64_t session, const dfb::Region& window,
                                  Clock::time_point now, MoveVerdict& verdict) {
  now_ = now;
  using Code = MoveVerdict::Code;
  j_ = bySession(session);
  verdict = {};
  if (!j_ || j_->state == State::Idle) {
    verdict = {Code::UnknownWindow, "no window of a job " + std::to_string(session)};
  } else if (j_->state != State::Running) {
    verdict = {Code::Conflict,
               j_->state == State::Starting ? "the job is starting" : "the job is ending"};
  } else if (!j_->job.hello.canReshape) {
    verdict = {
        Code::Conflict,
        "the job cannot re-plan its frame buffer while it runs (a program on the "
        "data-distributed API, or a job of an earlier dfbwall with its own page or preview): "
        "its window stays"};
  } else if (s_.maxJobs <= 1) {
    verdict = {Code::Conflict,
               "this wall runs one job at a time (serve --max-jobs 1): its window does not move"};
  } else if (j_->move) {
    verdict = {Code::Conflict, "the window is moving already"};
  } else if (const std::string problem = windowMoveProblem(*s_.layout, window); !problem.empty()) {
    verdict = {Code::BadWindow, problem};
  }
  if (verdict.code != Code::Moving || window == j_->window) return take();
  Slot::Move move;
  move.window = window;
  move.pieceSession = s_.newSession();
  ServiceCommand build = startCommand(0);
  build.header.kind = Command::Reshape;
  build.header.pieceSession = move.pieceSession;
  build.header.windowX0 = window.x0;
  build.header.windowY0 = window.y0;
  build.header.windowX1 = window.x1;
  build.header.windowY1 = window.y1;
  build.text.clear();
  for (int p = 0; p < members_.processCount(); ++p) {
    const Seat& seat = j_->seats[static_cast<size_t>(p)];
    if (seat.in && !seat.done) move.building.insert(p);
  }
  log("moving the window of the job from " + peerText(j_->job.hello.host) + " to " +
      std::to_string(window.x0) + "," + std::to_string(window.y0) + "," +
      std::to_string(window.width()) + "," + std::to_string(window.height()));
  j_->move = std::move(move);
  toJob(build);
  commitMoveIfBuilt();
  return take();
}

void JobDesk::onReshaped(int p, const ServiceCommand& c) {
  if (!j_->move || j_->move->fromFrame > 0 || c.header.pieceSession != j_->move->pieceSession)
    return;
  if (c.header.a == 0) {
    // A process that cannot show the new window cannot show the job: it ends, told why.
    ServiceCommand drop = command(Command::ReshapeAt, 0);
    drop.header.pieceSession = j_->move->pieceSession;
    toJob(drop);
    j_->move.reset();
    endJob(members_.who(p) + " could not move the window: " + reason(c.text));
    return;
  }
  j_->move->building.erase(p);
  commitMoveIfBuilt();
}

// Every process in the job has the new window's node (or left the job): the job hears its new
// directory and switch frame before any later credit, the processes the frame their new nodes
// take over at.
void JobDesk::commitMoveIfBuilt() {
  if (!j_->move || j_->move->fromFrame > 0 || j_->state != State::Running) return;
  std::erase_if(j_->move->building, [&](int p) { return j_->seats[static_cast<size_t>(p)].done; });
  if (!j_->move->building.empty()) return;
  Slot::Move& move = *j_->move;
  move.fromFrame = switchFrame(j_->lastCredited, j_->granted);
  j_->window = move.window;
  j_->pieceSession = move.pieceSession;
  const Layout seen = windowLayout(*s_.layout, move.window);
  move.inWindow.assign(static_cast<size_t>(members_.processCount()), false);
  for (int p = 0; p < members_.processCount(); ++p)
    move.inWindow[static_cast<size_t>(p)] = !seen.displaysOfProcess(p).empty();
  Reshape r;
  r.session = j_->job.session;
  r.version = ++j_->reshapeVersion;
  r.fromFrame = move.fromFrame;
  r.directory.session = move.pieceSession;
  r.directory.window = move.window;
  r.directory.layout = windowLayout(*s_.layout, move.window);
  r.directory.processes = roster();
  r.directory.framesInFlight = j_->granted;
  r.directory.timeoutMs = static_cast<std::uint32_t>(s_.timeout.count());
  r.directory.rosterVersion = j_->rosterVersion;
  reply(j_->job.peer, Kind::Reshape, packReshape(r));
  ServiceCommand at = command(Command::ReshapeAt, move.fromFrame);
  at.header.pieceSession = move.pieceSession;
  toJob(at);
}

bool JobDesk::inWindowAt(int p, std::uint32_t frameId) const {
  const bool moved = j_->move && j_->move->fromFrame > 0 && frameId >= j_->move->fromFrame;
  return (moved ? j_->move->inWindow : j_->inWindow)[static_cast<size_t>(p)];
}

dfb::Region JobDesk::window(std::uint64_t session) const {
  const Slot* slot = bySession(session);
  return slot ? slot->window : dfb::Region{};
}

bool JobDesk::moving(std::uint64_t session) const {
  const Slot* slot = bySession(session);
  return slot && slot->move.has_value();
}

}  // namespace wall::service
