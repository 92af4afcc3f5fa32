// `dfbwall relay`: forwards render jobs to a serving wall for hosts that cannot reach it (README,
// "A wall that stays up"; wall/service/relay/Relay.h). One process, no MPI: it runs on a gateway.
#include <cstdio>
#include <string>

#include "apps/Options.h"
#include "apps/Run.h"
#include "apps/StopSignals.h"
#include "base/OutputFile.h"
#include "wall/service/relay/Relay.h"

namespace app {

int runRelay(int argc, char** argv, StopSignals& signals) {
  RelayCommand command;
  if (const int code = parseRelayOptions(argc, argv, command); code >= 0) return code;
  const std::string &wall = command.wall, &statsFile = command.statsFile;
  FILE* stats = nullptr;
  try {
    if (!statsFile.empty()) stats = base::openOutputStream(statsFile, true);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dfbwall relay: error: --stats %s\n", e.what());
    return 1;
  }
  int stopSignal = 0;
  wall::service::RelayOptions options;
  options.listen = command.listen;
  options.wall = wall;
  options.timeout = std::chrono::seconds(command.timeoutSeconds);
  try {
    options.credentials = wall::service::loadCredentials(
        {command.token, command.tokenFile, command.curveDir, command.serverKey}, false);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dfbwall relay: error: %s\n", e.what());
    if (stats) std::fclose(stats);
    return 1;
  }
  options.stopRequested = [&] {
    if (const int s = signals.poll()) stopSignal = s;
    return stopSignal != 0;
  };
  options.log = [](const std::string& line) {
    std::fprintf(stderr, "dfbwall relay: %s\n", line.c_str());
  };
  options.jobRecord = [stats](const std::string& line) {
    if (!stats) return;
    std::fprintf(stats, "%s\n", line.c_str());
    std::fflush(stats);
  };
  int code = 0;
  try {
    wall::service::Relay relay(options);
    // One line a script can read: where jobs connect.
    std::printf("dfbwall: relay on %s for the wall at %s\n", relay.address().c_str(), wall.c_str());
    std::fflush(stdout);
    relay.run();
    code = stopSignal ? exitCodeForStop(stopSignal) : 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dfbwall relay: error: %s\n", e.what());
    code = 1;
  }
  if (stats) std::fclose(stats);
  return code;
}

}  // namespace app
