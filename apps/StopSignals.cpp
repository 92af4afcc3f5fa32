#include "apps/StopSignals.h"

#include <pthread.h>
#include <signal.h>

#include <ctime>

namespace app {
namespace {

sigset_t stopSet() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGUSR1);
  return set;
}

}  // namespace

StopSignals::StopSignals() {
  const sigset_t set = stopSet();
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

int StopSignals::poll() {
  const sigset_t set = stopSet();
  const timespec now{0, 0};
  const int taken = sigtimedwait(&set, nullptr, &now);
  return taken > 0 ? taken : 0;
}

int exitCodeForStop(int signal) { return signal == SIGUSR1 ? 0 : 128 + signal; }

}  // namespace app
