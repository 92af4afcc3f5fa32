#pragma once
// `dfbwall serve`: the wall processes of a layout as a persistent service that render jobs
// connect to (README, "A wall that stays up"). Every process keeps its displays (idle screens
// before the first job, the last complete frame after each), receives the pieces of the
// connected job on its own piece socket (wall/service/PieceReceiver.h) and presents them with
// the same wall node as a single-job wall. Process 0 also runs the desk: the directory socket a
// job says hello to, one job at a time (a second is refused as busy, or queued with `wait`),
// the job's keepalives, captures and goodbye, its credits, and the end of a job that goes
// silent. Nothing a job does ends the wall: a job that dies or sends garbage is dropped within
// the timeout, its partial frame given up on every display, and the next job taken at once.
//
// The wall processes coordinate through the wall job's messenger (commands from the desk) and
// WallPeers (the swap barrier), both MPI here.
#include <mpi.h>

#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "messaging/Messenger.h"
#include "wall/Layout.h"
#include "wall/Presenter.h"

namespace wall::service {

struct ServiceOptions {
  std::string listen;                        // [ADDR:]PORT of process 0's directory socket
  std::string token;                         // required from jobs when not empty
  std::chrono::milliseconds timeout{60000};  // a silent job is dropped after this long
  int handlerThreads = 0;                    // piece decoding threads per process (0: cores)
  int framesInFlight = 2;                    // the most a job is granted
  // Polled on every process between frames and while idle (stop signals, closed windows); true
  // asks the wall to shut down after the job in progress is dropped.
  std::function<bool()> stopRequested;
  // One line to the wall's log (stderr), prefixed by the caller.
  std::function<void(const std::string&)> log;
  // Process 0, one JSON line per job that ended (--stats).
  std::function<void(const std::string&)> jobRecord;
};

class WallService {
 public:
  // Collective over the messenger's ranks, which are the wall processes (rank p = process p),
  // and `wallComm` (the same ranks). Binds the sockets; throws wall::Error on a bad --listen or
  // a port in use.
  WallService(messaging::Messenger& messenger, MPI_Comm wallComm, const Layout& layout,
              std::vector<Presenter*> presenters, ServiceOptions options);
  ~WallService();
  WallService(const WallService&) = delete;
  WallService& operator=(const WallService&) = delete;

  // Process 0: "HOST:PORT" that jobs pass to --connect, and the token they need (generated when
  // the listen address is not loopback and none was given; empty: none).
  std::string address() const;
  std::string token() const;
  // Presents jobs until the wall is asked to stop; returns on every process then.
  void run();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace wall::service
