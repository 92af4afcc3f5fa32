// `dfbwall serve`: the wall processes of a layout as a persistent service (README, "A wall that
// stays up"; wall/service/WallService.h). One process per layout process, placed on the hosts
// the layout names, as wall ranks of a single job are.
#include <csignal>
#include <cstdio>
#include <optional>

#include "apps/Collectives.h"
#include "apps/Failure.h"
#include "apps/Options.h"
#include "apps/Run.h"
#include "apps/StopSignals.h"
#include "dfb/AtomicFile.h"
#include "messaging/Messenger.h"
#include "wall/DisplayPresenters.h"
#include "wall/Ranks.h"
#include "wall/service/WallService.h"

namespace app {

int runServe(const Options& o, int worldRank, StopSignals& signals, FailurePath& failure) {
  const auto timeout = std::chrono::milliseconds(std::chrono::seconds(o.timeoutSeconds));
  int worldSize = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &worldSize);
  // Setup problems (a bad layout, a rank count that does not fit, a port in use) are bad input:
  // one message, every process exits 1.
  std::optional<wall::Layout> layout;
  std::string problem;
  try {
    layout = wall::loadLayout(o.wall);
    if (worldSize != layout->processCount)
      problem = o.wall + ": the layout has " + std::to_string(layout->processCount) +
                " wall processes; start serve with mpirun -np " +
                std::to_string(layout->processCount) + " (got " + std::to_string(worldSize) + ")";
  } catch (const std::exception& e) {
    problem = e.what();
  }
  FILE* stats = nullptr;
  if (problem.empty() && worldRank == 0 && !o.statsFile.empty()) {
    stats = std::fopen(o.statsFile.c_str(), "a");
    if (!stats) problem = "--stats " + o.statsFile + ": cannot open it for writing";
  }
  {
    int failing = problem.empty() ? 1 << 30 : worldRank, first = 0;
    boundedAllreduce(&failing, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD, timeout, "setup");
    if (first == worldRank) std::fprintf(stderr, "dfbwall: error: %s\n", problem.c_str());
    if (first != 1 << 30) return 1;
  }
  try {
    const int process = worldRank;
    const auto presenters = wall::makeDisplayPresenters(*layout, process, o.offscreen);
    messaging::MessengerOptions messaging;
    messaging.quiesceTimeout = timeout;
    messaging.handlerThreads = 1;  // commands only: the pieces come through the service's sockets
    messaging::Messenger messenger(MPI_COMM_WORLD, messaging);
    messenger.setErrorCallback([&failure](const std::string& m) { failure.fail(m); });
    wall::service::ServiceOptions service;
    service.listen = o.listen;
    service.token = o.token;
    service.timeout = timeout;
    service.handlerThreads = o.handlerThreads;
    service.framesInFlight = o.framesInFlight;
    int stopSignal = 0;
    service.stopRequested = [&signals, &stopSignal] {
      if (const int s = signals.poll()) stopSignal = s;
      return stopSignal != 0;
    };
    service.log = [process](const std::string& line) {
      std::fprintf(stderr, "dfbwall serve: wall process %d: %s\n", process, line.c_str());
    };
    service.jobRecord = [stats](const std::string& line) {
      if (!stats) return;
      std::fprintf(stats, "%s\n", line.c_str());
      std::fflush(stats);
    };
    wall::service::WallService wallService(messenger, MPI_COMM_WORLD, *layout, presenters->list(),
                                           service);
    if (worldRank == 0) {
      // One line a script can read: where jobs connect, and the token when one is needed.
      std::printf("dfbwall: wall service on %s%s%s\n", wallService.address().c_str(),
                  wallService.token().empty() ? "" : "  token: ", wallService.token().c_str());
      std::fflush(stdout);
    }
    wallService.run();
    messenger.stop();
    if (stats) std::fclose(stats);
    return stopSignal ? exitCodeForStop(stopSignal) : 0;
  } catch (const std::exception& e) {
    failure.fail(e);
  }
}

}  // namespace app
