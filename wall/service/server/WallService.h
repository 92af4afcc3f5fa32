#pragma once
// `dfbwall serve`: the wall processes of a layout as a persistent service that render jobs
// connect to (docs/service.md, "A wall that stays up"). Every process keeps its displays (idle
// screens before the first job, the last complete frame after each), receives the pieces of the
// connected job on its own piece socket (wall/service/server/PieceReceiver.h) and presents them
// with the same wall node as a single-job wall.
//
// Process 0 is the head: its desk (wall/service/server/Desk.h) takes the jobs and coordinates the
// processes. Every other process joins the head over its own link
// (wall/service/server/MemberLink.h): the processes share no MPI job, so one that dies, hangs or
// loses its network is dropped after the timeout and the others go on; started again (or back on
// the network) it joins again and shows the running job's frames. Nothing a job does ends the wall:
// a job that dies or sends garbage is dropped within the timeout, its partial frame given up on
// every display, and the next job taken at once.
#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "base/ConfinedFolder.h"
#include "wall/display/Presenter.h"
#include "wall/layout/Layout.h"
#include "wall/service/security/Credentials.h"
#include "wall/service/server/JobDesk.h"

namespace wall::service {

struct ServiceOptions {
  int process = 0;     // which of the layout's processes this is (0: the head)
  std::string listen;  // the head: [ADDR:]PORT of the directory socket
  std::string join;    // the others: the head's HOST:PORT
  // What every peer must hold at the handshake (the token; with CURVE this process's key pair
  // and, for a joining process, the head's public key): wall/service/security/Credentials.h.
  Credentials credentials;
  // The address jobs and the head are told to dial for this process (--advertise); empty: the
  // listen address, or this host's first when listening on every interface.
  std::string advertise;
  std::chrono::milliseconds timeout{60000};  // a silent job or process is dropped after this long
  int handlerThreads = 0;                    // piece decoding threads per process (0: cores)
  int framesInFlight = 2;                    // the most a job is granted
  // Where this process writes a job's captures (a folder the job names beneath it), and at most
  // how many bytes per job; none: a job that asks for captures is refused.
  std::shared_ptr<const base::ConfinedFolder> captureRoot;
  std::uint64_t captureQuota = 0;
  // serve --capture: what this process's displays show, written beneath this folder every
  // `wallCaptureEvery`-th wall frame (wall/display/WallCaptures.h), within captureQuota bytes
  // over the process's run; none: not captured.
  std::shared_ptr<const base::ConfinedFolder> wallCapture;
  int wallCaptureEvery = 1;
  // What a display shows where no job's window covers it (RGBA8 as in Image; --background,
  // default black): see docs/service.md, "A job in a window".
  std::uint32_t background = 0xff000000u;
  // Jobs on the wall at once, each in its window (--max-jobs): above 1, each job runs on its own
  // thread of every process, and the process's main thread composes their windows
  // (wall/display/WindowStack.h) and presents them.
  std::size_t maxJobs = 1;
  // The windows' thumbnails for serve --control's page (docs/service.md, "The wall's control
  // page"): their longest side, 16..kMaxThumbnailSide (0: none). Made with several jobs only:
  // each process shrinks its windows' parts, and the head asks for them about once a second.
  int thumbnailSide = 0;
  // A stop asked of a process other than the head (a signal, a closed window) makes it leave
  // the wall alone (true: a process started on its own) or stop the whole wall (false).
  bool leaveAlone = false;
  // Polled between frames and while idle (stop signals); true asks for a stop.
  std::function<bool()> stopRequested;
  // One line to the process's log (stderr), prefixed by the caller.
  std::function<void(const std::string&)> log;
  // The head: one JSON line per job that ended and per process lost or back (--stats).
  std::function<void(const std::string&)> jobRecord;
};

class WallService {
 public:
  // Binds this process's sockets (the head: its directory socket too) and starts its link; a
  // member joins in the background. Throws base::Error on a bad --listen / --join or a port in
  // use.
  WallService(const Layout& layout, std::vector<Presenter*> presenters, ServiceOptions options);
  ~WallService();
  WallService(const WallService&) = delete;
  WallService& operator=(const WallService&) = delete;

  // The head: "HOST:PORT" that jobs pass to --connect and processes to --join. The others: the
  // head's address they joined.
  std::string address() const;
  // The head: waits until every process joined, or `until`; returns those that did not.
  // Another process: waits until it joined (returns nothing) or `until` (returns itself); throws
  // base::Error when the head refused it (wrong token, another layout).
  std::vector<int> waitForProcesses(std::chrono::steady_clock::time_point until);
  // The head: moves and resizes job `session`'s window to `window` on the canvas while it runs
  // (docs/design.md, "Moving and resizing a window"). Returns empty when the move is under way,
  // else why not, with `code` 404 (no such job), 409 (starting, ending, moving already, or a job
  // that cannot re-plan) or 400 (a window outside the canvas, too small, on the bezels only).
  std::string reshape(std::uint64_t session, const dfb::Region& window, int* code = nullptr);
  // Presents jobs until the wall is asked to stop (or this process leaves it); returns then.
  // Throws base::Error when the head refuses this process.
  void run();

  // The head only (process 0; others throw base::Error), thread-safe: the window manager of
  // serve --control (apps/WallControl.h). The jobs' windows; a job's window raised on every
  // display of every process, or the job ended, told `why` (false: no job of that number).
  std::vector<JobDesk::Window> windows() const;
  bool raise(std::uint64_t number);
  bool close(std::uint64_t number, const std::string& why);
  // Job `number`'s window moved and resized to `window`, as reshape() does with its session.
  std::string moveWindow(std::uint64_t number, const dfb::Region& window, int* code = nullptr);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace wall::service
