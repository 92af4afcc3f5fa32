#pragma once
// The signals that ask for a graceful stop (docs/design.md, "Stopping"): SIGINT and SIGTERM
// (mpirun turns Ctrl-C into SIGTERM on every rank, followed by SIGKILL about a second later) and
// SIGUSR1 (mpirun forwards it to every rank unchanged and then waits for them).
//
// They are blocked in every thread and taken by polling between frames, so there is no
// handler and no global flag: the kernel keeps a blocked signal pending until poll() takes it.
// The mask is inherited by threads created later, so construct this before MPI or any library
// starts a thread (first thing in main).
namespace app {

class StopSignals {
 public:
  StopSignals();
  // The stop signal pending for this process, taken (so the next call says 0), or 0.
  int poll();
};

// What the process exits with after a graceful stop on `signal`: 0 for SIGUSR1 (the stop
// dfbwall offers for scripts), 128 + signal for SIGINT and SIGTERM (interrupted, as shells say).
int exitCodeForStop(int signal);

}  // namespace app
