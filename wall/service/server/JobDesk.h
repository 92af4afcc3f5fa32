#pragma once
// The jobs of a service wall's desk (wall/service/server/Desk.h) as a state machine with no
// socket, thread or clock of its own: the desk decodes each message and hands it in with the
// time, and carries out the actions it gets back, in order. Testable in process.
//
// Up to Setup::maxJobs jobs at a time, each with its own seats, credits, agreements, captures and
// timeout (a job silent or slow holds up only itself): a hello with the wrong token is refused, a
// job beyond them is refused as busy or queued (`wait`, at most kMaxQueued), and queued jobs
// start in order as jobs leave. An event for a job finds it by its session or its connection. A job
// starts when every process in the wall answered Start (its node attached), gets its directory,
// sends keepalives, captures and goodbye (turned into commands to the processes), is credited each
// presented frame and ends with every process's Done, a failure, its connection closing (at once),
// or the timeout of its silence; then the next. Each process has a seat in the job (in it, ready,
// done, first frame): a process lost is done and the job gets a roster without it; one that joins
// during the job is admitted from the first frame the job cannot have started without it (the last
// credited frame + frames in flight + 1). The job's swap barriers and capture gathers wait for the
// processes taking part in each frame (FrameAgreements), for the timeout at most: a process that
// has not arrived at a barrier the timeout after the first did, while the job is heard from, is
// dropped like a silent one, so one that beats but never arrives cannot hold every frame. A barrier
// for a frame outside the frames in flight drops its process.
//
// What a job may ask for is bounded: one job per connection (a second hello from it is refused),
// capture requests for frames near the credited one only, at most kMaxPendingCaptures not yet
// taken; anything over is refused with a message (Refused with the job's session: the job goes on).
// Key and mouse events from a wall process over a running job's window are told to the job only
// when well formed, on a display of that process inside the window, and within
// kMaxInputsPerSecond; the rest are dropped.
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <variant>
#include <vector>

#include "wall/image/Thumbnail.h"
#include "wall/layout/Layout.h"
#include "wall/layout/Window.h"
#include "wall/service/protocol/LinkMessages.h"
#include "wall/service/protocol/Protocol.h"
#include "wall/service/protocol/ServiceCommands.h"
#include "wall/service/server/FrameAgreements.h"
#include "wall/service/server/Membership.h"

namespace wall::service {

class JobDesk {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr std::size_t kMaxQueued = 16;  // jobs waiting behind the connected one
  // Capture requests of the job for frames not presented yet.
  static constexpr std::size_t kMaxPendingCaptures = 8;
  // How far behind the last credited frame a capture request may name a frame (it is taken at
  // the next presented frame: the job's request crossed the credits on the way).
  static constexpr std::uint32_t kCaptureFramesBehind = 256;
  // Key and mouse events from the wall's windows told to a job per second (more are dropped).
  static constexpr int kMaxInputsPerSecond = 120;

  struct Setup {
    const Layout* layout = nullptr;  // what the directory tells a job
    std::string token;               // what a job must present (empty: none)
    std::chrono::milliseconds timeout{60000};
    int framesInFlight = 2;  // the most a job is granted
    // A fresh, non-zero session id for each job.
    std::function<std::uint64_t()> newSession;
    std::size_t maxJobs = 1;  // jobs on the wall at once (each in its window)
    // The windows' thumbnails (serve --control's page): their longest side (0: none are made)
    // and how often every process is asked for its cells.
    int thumbnailSide = 0;
    std::chrono::milliseconds thumbnailEvery{1000};
  };

  // A message to a connection on the directory socket (a job, or a refused stranger).
  struct Reply {
    std::string peer;
    Kind kind = Kind::Refused;
    messaging::Bytes message;  // the packed wire message
  };
  // A command to wall process `process` (0: the head's own, in process).
  struct ToProcess {
    int process = 0;
    ServiceCommand command;
  };
  // Frame `frameId`'s swap barrier is released for `process` with the agreed values.
  struct Release {
    int process = 0;
    std::uint64_t session = 0;
    std::uint32_t frameId = 0;
    std::vector<std::int64_t> values;
  };
  // The pixels of a captured frame, for the head's process (empty: a process that sent none).
  struct Gathered {
    std::uint64_t session = 0;
    std::uint32_t frameId = 0;
    std::vector<std::vector<std::uint32_t>> pixels;
  };
  // A process broke the job's rules (a barrier with a value count that differs): drop it.
  struct Drop {
    int process = 0;
    std::string why;
  };
  // A line for the wall's log; with `oncePer` (a connection), said once per connection and line
  // until the job ends, so a stranger's retries do not flood the log.
  struct Log {
    std::string line;
    std::string oncePer;
  };
  // A JSON line for `--stats`: a job that ended, a process lost or back.
  struct Record {
    std::string json;
  };
  // Job `session` is on the wall now (the head's process waits for its barriers), or it ended
  // (`ended`: it is not any more).
  struct Session {
    std::uint64_t session = 0;
    bool ended = false;
  };
  // The wall stops: the shutdown went out to every process (Closing), and every process
  // confirmed it or a second passed (Closed: the desk stops).
  struct Closing {};
  struct Closed {};
  using Action = std::variant<Reply, ToProcess, Release, Gathered, Drop, Log, Record, Session,
                              Closing, Closed>;
  using Actions = std::vector<Action>;

  // A message from a job's connection other than a hello: Keepalive, Capture, Bye, or a kind a
  // job must not send. `malformed`: why its body did not decode as a Control.
  struct JobMessage {
    std::string peer;
    Kind kind = Kind::Keepalive;
    std::uint64_t session = 0;
    Control control;
    std::string malformed;
  };

  enum class State { Idle, Starting, Running, Ending, Closed };

  // `members` is read for who is live and where their pieces go; it outlives this.
  JobDesk(Setup setup, const Membership& members);

  Actions hello(const std::string& peer, const Hello& hello, Clock::time_point now);
  Actions message(const JobMessage& message, Clock::time_point now);
  // An answer of process `process` (Ready, Done, Failed, StopAsked, Shutdown's confirmation).
  Actions answer(int process, const ServiceCommand& command, Clock::time_point now);
  // After Membership admitted it / after Membership dropped it.
  Actions joined(int process, Clock::time_point now);
  Actions lost(int process, const std::string& why, Clock::time_point now);
  Actions arrive(int process, std::uint64_t session, std::uint32_t frameId,
                 const std::vector<std::int64_t>& values, Clock::time_point now);
  Actions pixels(int process, std::uint64_t session, std::uint32_t frameId,
                 std::vector<std::uint32_t> pixels, Clock::time_point now);
  // Process p's cells of job `session`'s window thumbnail (ProcessLink::thumbnail). Taken only
  // for the request under way, once per process and job, from a process asked, for the job's
  // window as it is now, inside its grid, never more pixels in a cell than it has; the rest is
  // dropped. A job's thumbnail is published once every process in its window answered, or when
  // the next request goes out.
  void thumbnail(int p, std::uint64_t session, const ThumbnailPart& part);
  Actions headPixels(std::uint64_t session, std::uint32_t frameId,
                     std::vector<std::uint32_t> pixels, Clock::time_point deadline,
                     Clock::time_point now);
  // The head's process presented `frameId` on every display in the job: the job's credit.
  Actions presented(std::uint64_t session, std::uint32_t frameId, std::int64_t completeNs,
                    Clock::time_point now = Clock::now());
  // Time passing: gathers past their deadline, barriers a process has not arrived at within the
  // timeout (it is dropped), a job silent for the timeout, the shutdown.
  Actions tick(Clock::time_point now);
  // Move and resize the window of job `session` to `window` on the canvas, while it runs
  // (docs/design.md, "Moving and resizing a window"). Every process builds the new window's node
  // beside the old one (Reshape, answered Reshaped); then the job is told its new directory and
  // switch frame (Kind::Reshape) and every process the frame its new node takes over
  // (ReshapeAt). `verdict` says whether it was taken and, if not, why.
  struct MoveVerdict {
    enum class Code { Moving, UnknownWindow, Conflict, BadWindow };
    Code code = Code::Moving;
    std::string why;
  };
  Actions reshape(std::uint64_t session, const dfb::Region& window, Clock::time_point now,
                  MoveVerdict& verdict);
  // Handling a message from `peer` failed, or the wall cannot send to it: if it is the job's
  // connection, the job ends; a queued job from it leaves the queue.
  Actions failed(const std::string& peer, const std::string& why, Clock::time_point now);
  // The connection `peer` closed (the desk's socket says so): its job is gone, ended at once as
  // if silent for the timeout, and a queued job from it leaves the queue. Not a job whose named
  // last frame was credited: its rank 0 leaves once it saw that credit, and the processes' Done
  // end it as usual.
  Actions disconnected(const std::string& peer, Clock::time_point now);

  // The wall's state: Closed, Idle without a job, else the state of the newest job.
  State state() const;
  // The newest job (or the last that ended): its session, connection, credits, captures.
  std::uint64_t session() const { return shown().job.session; }
  const std::string& peer() const { return shown().job.peer; }
  std::size_t queued() const { return queue_.size(); }
  // A job on the wall (starting, running or ending) has this connection.
  bool connected(const std::string& peer) const { return byPeer(peer) != nullptr; }
  std::uint32_t lastCredited() const { return shown().lastCredited; }
  std::size_t pendingCaptures() const { return shown().pendingCaptures.size(); }
  // The jobs on the wall now (Starting, Running or Ending), oldest first; one of them by session
  // (Idle: none such on the wall).
  std::vector<std::uint64_t> sessions() const;
  State state(std::uint64_t session) const;
  std::uint32_t lastCredited(std::uint64_t session) const;
  // The job's window on the canvas (the new one from the moment a move was committed to the job).
  dfb::Region window(std::uint64_t session) const;
  // A move of the job's window is under way (from reshape() until its switch frame is credited).
  bool moving(std::uint64_t session) const;

  // ---- the window manager (serve --control: apps/WallControl.h) ----
  // A job's window on the wall. `number` names it (1 for the wall's first job, never reused):
  // the session id stays between the wall and the job, since pieces are checked against it.
  struct Window {
    std::uint64_t number = 0;
    std::string host;  // the job's rank-0 host, as its hello said (printable)
    std::string job;   // what it renders, as its hello said (printable; may be empty)
    std::string page;  // its own control page: an http(s) address, or empty
    dfb::Region rect;  // on the wall's canvas
    int z = 0;         // 0 at the bottom
    State state = State::Starting;
    bool idle = false;         // running, no frame presented for kIdleAfter (converged, or stalled)
    std::uint32_t frames = 0;  // presented on every display (credited)
    double fps = 0;            // presented frames per second over the last kFpsWindow
    // What the window shows, shrunk (wall/image/Thumbnail.h); null until the first is made.
    std::shared_ptr<const Image> thumbnail;
  };
  static constexpr auto kFpsWindow = std::chrono::seconds(2);
  static constexpr auto kIdleAfter = std::chrono::seconds(2);
  std::vector<Window> windows(Clock::time_point now) const;
  // Job `number`'s window goes on top of the others on every display; `nullopt` when no job of
  // that number is on the wall.
  std::optional<Actions> raise(std::uint64_t number);
  // Job `number` ends as a dropped job does: told `why` (Ended), its window closed at once.
  std::optional<Actions> close(std::uint64_t number, const std::string& why, Clock::time_point now);
  // The session of job `number` (its window's move goes through reshape()); nullopt when no job
  // of that number is on the wall.
  std::optional<std::uint64_t> sessionOf(std::uint64_t number) const;

 private:
  struct Job {
    std::string peer;
    Hello hello;
    Clock::time_point lastHeard;
    std::uint64_t session = 0;
    Clock::time_point started;
  };
  // Each process's part in the job: in it (given Start), answered Start, done with it (Done, a
  // refusal, or lost), and the first frame it shows (later than 1 when it joined mid-job).
  struct Seat {
    bool in = false, ready = false, done = false;
    std::uint32_t fromFrame = 1;
  };

  void queueOrRefuse(const std::string& peer, const Hello& hello, const std::string& from);
  bool queuedMessage(const JobMessage& m);
  void onControl(const JobMessage& m);
  void onCapture(const JobMessage& m);
  bool hasJobFrom(const std::string& peer) const;
  // Why the window the hello asks for does not fit the wall (empty: it does).
  std::string windowProblem(const Hello& hello) const;
  void dropOverdue();
  void onReady(int p, const ServiceCommand& c);
  void onDone(int p, const ServiceCommand& c);
  void stopAsked(int p);
  void onInput(int p, const ServiceCommand& c);

  void emit(Action action) { out_.push_back(std::move(action)); }
  Actions take();
  void log(std::string line, std::string oncePer = {});
  void reply(const std::string& peer, Kind kind, messaging::Bytes message);
  ServiceCommand command(Command kind, std::int64_t a = 0, std::int64_t b = 0,
                         std::string text = {}) const;
  ServiceCommand startCommand(std::uint32_t firstFrame) const;
  void toJob(const ServiceCommand& c);
  std::vector<DirectoryProcess> roster() const;
  void sendRoster(std::uint32_t fromFrame, const std::string& why);
  std::string busy() const;

  void startJob();
  dfb::Region placeWindow(const Hello& hello) const;
  bool allDone() const;
  void endJob(const std::string& why);
  void nextJob();
  void jobOver();
  void overIfAllDone();
  void maybeRun();
  void admitToJob(int p);
  void joinedJob(int p);
  bool participates(int p, std::uint32_t frameId) const;
  void releaseWhatCan();
  void notRenderedFrom(std::uint32_t frameId);
  void closeIfIdle();
  void onReshaped(int p, const ServiceCommand& c);
  // Whether process `p` has a display in the window the job renders frame `frameId` in.
  bool inWindowAt(int p, std::uint32_t frameId) const;
  void commitMoveIfBuilt();
  // Thumbnails: every process asked for its cells (tick), and a job's assembled one published.
  void askThumbnails();

  // One job on the wall and all that is its own (up to Setup::maxJobs side by side).
  struct Slot {
    explicit Slot(int processes) : seats(static_cast<size_t>(processes)), agreements(processes) {}
    State state = State::Idle;
    std::uint64_t number = 0;  // when it started among the wall's jobs (1: the first)
    std::uint64_t order = 0;   // its window's stacking order (higher on top): started or raised
    std::deque<Clock::time_point> credits;  // when frames were credited, over kFpsWindow
    dfb::Region window;  // on the wall's canvas: asked for, or placed (placeWindow)
    Job job;
    std::vector<Seat> seats;
    std::set<int> waitingToJoinJob;  // joined while the job was starting
    // The frames the job's capture requests are taken at, until they are presented.
    std::deque<std::uint32_t> pendingCaptures;
    std::string failure;
    std::optional<std::uint32_t> namedLastFrame;  // from the job's goodbye
    // Whether each process has a display in the window (paces the job's frames: FrameAgreements)
    // and the first frame the job will not render, once its processes were told (LastFrame, or
    // Abort: every frame).
    std::vector<bool> inWindow;
    std::optional<std::uint32_t> unrenderedFrom;
    std::int64_t lastPresented = 0, bytes = 0;
    std::uint32_t lastCredited = 0, granted = 2, rosterVersion = 0;
    int processesLost = 0, processesRejoined = 0;
    FrameAgreements agreements;
    // A move of the window under way: the processes still building its node, then (fromFrame
    // above 0) the frame it switches at, until that frame is credited.
    struct Move {
      dfb::Region window;
      std::uint64_t pieceSession = 0;
      std::set<int> building;
      std::uint32_t fromFrame = 0;
      std::vector<bool> inWindow;  // of the new window (inWindow's), from fromFrame on
    };
    std::optional<Move> move;
    std::uint32_t reshapeVersion = 0;
    std::uint64_t pieceSession = 0;  // what the job's pieces are stamped with (0: its session)
    Clock::time_point inputSince{};  // the second kMaxInputsPerSecond counts in
    int inputs = 0;
    // The window's last thumbnail, and the one being assembled from the processes' cells (of
    // request `request`, for `window`; `answered`: the processes whose cells are in).
    std::shared_ptr<const Image> thumbnail;
    struct Assembly {
      std::uint32_t request = 0;
      dfb::Region window;
      ThumbnailGrid grid;
      CellSums sums;
      std::set<int> answered;
    };
    std::optional<Assembly> assembling;
    std::uint32_t publishedRequest = 0;  // what came after its publication is dropped
  };
  void publishThumbnail(Slot& slot);
  // The job on the wall with this session / connection (none: nullptr).
  Slot* bySession(std::uint64_t session) const;
  Slot* byPeer(const std::string& peer) const;
  const Slot& shown() const;
  // The jobs on the wall (not Idle), oldest first.
  std::vector<Slot*> inOrder() const;
  Slot* byNumber(std::uint64_t number) const;
  // Jobs that ended leave the wall (the last one is kept for the accessors).
  void removeEnded();

  Setup s_;
  const Membership& members_;
  Clock::time_point now_;
  Actions out_;
  std::vector<std::unique_ptr<Slot>> slots_;  // a queued job takes the seat of the one that left
  std::unique_ptr<Slot> ended_;               // the last job that left the wall
  Slot* j_ = nullptr;                         // the job the event at hand is for
  std::deque<Job> queue_;
  std::uint64_t jobsStarted_ = 0, stackTop_ = 0;
  bool shuttingDown_ = false, closed_ = false;
  int shutdownAcks_ = 0;  // members that confirmed the shutdown (State::Closed)
  // Thumbnails: the request under way (0: none yet), the processes asked for it, the next one.
  std::uint32_t thumbnailRequest_ = 0;
  std::vector<bool> thumbnailAsked_;
  Clock::time_point nextThumbnails_{};
  Clock::time_point closedAt_;
};

}  // namespace wall::service
