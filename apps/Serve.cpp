// `dfbwall serve`: the wall processes of a layout as a persistent service (docs/service.md, "A wall
// that stays up"; wall/service/server/WallService.h). Either every process at once under one mpirun
// (rank p is process p; MPI only tells the others where the head listens), or one process on its
// own, started or restarted by hand or by a service manager (`--process N`, `--join HOST:PORT`).
// The processes share no MPI communication after start-up, so under
// `mpirun --enable-recovery` one that dies leaves the others running.
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <thread>

#include "apps/ControlServer.h"
#include "apps/Failure.h"
#include "apps/Options.h"
#include "apps/PageRoutes.h"
#include "apps/Run.h"
#include "apps/StopSignals.h"
#include "apps/WallControl.h"
#include "base/Collectives.h"
#include "base/ConfinedFolder.h"
#include "base/OutputFile.h"
#include "runtime/SetupAgreement.h"
#include "wall/display/Capture.h"
#include "wall/display/DisplayPresenters.h"
#include "wall/layout/Ranks.h"
#include "wall/service/server/WallService.h"

namespace app {
namespace {

// A wall process that fails ends alone (the others drop it), never through MPI_Abort, which
// would end every process mpirun started.
[[noreturn]] void failAlone(int process, const std::string& what) {
  char host[256] = {};
  gethostname(host, sizeof host - 1);
  std::fprintf(stderr, "dfbwall serve: wall process %d on %s: error: %s\n", process, host,
               what.c_str());
  std::fflush(stderr);
  std::fflush(stdout);
  std::_Exit(1);
}

// Under mpirun: the head's address and token to every process (empty: the head failed to start
// and said why). MPI carries it between the wall's own hosts only; it is never printed.
std::pair<std::string, std::string> shareHead(const std::string& address, const std::string& token,
                                              std::chrono::milliseconds timeout) {
  char buffer[2304] = {};  // an address and a token of up to 1024 characters
  if (!address.empty())
    std::snprintf(buffer, sizeof buffer, "%s\n%s", address.c_str(), token.c_str());
  base::bcast(buffer, sizeof buffer, 0, MPI_COMM_WORLD,
              {.until = timeout, .late = "starting the wall service: the head did not answer"});
  buffer[sizeof buffer - 1] = 0;
  const char* newline = std::strchr(buffer, '\n');
  if (!newline) return {};
  return {std::string(buffer, static_cast<size_t>(newline - buffer)), std::string(newline + 1)};
}

// The layout and whether this start fits it; the problem, or an empty string.
std::string checkStart(const Options& o, int worldSize, int process, bool alone,
                       std::optional<wall::Layout>& layout) {
  try {
    layout = wall::loadLayout(o.wall);
    if (layout->inRoom())
      return o.wall +
             ": its displays are placed in a room (docs/rooms.md); a serving wall does not hand "
             "that to its jobs yet: run the job with --wall";
    if (alone && worldSize != 1)
      return "serve --process starts one wall process on its own; under mpirun -np " +
             std::to_string(worldSize) + " every rank is a process already (leave it out)";
    if (alone && process >= layout->processCount)
      return o.wall + ": the layout has wall processes 0.." +
             std::to_string(layout->processCount - 1) + "; there is no process " +
             std::to_string(process);
    if (!alone && worldSize != layout->processCount)
      return o.wall + ": the layout has " + std::to_string(layout->processCount) +
             " wall processes; start serve with mpirun -np " +
             std::to_string(layout->processCount) + " (got " + std::to_string(worldSize) +
             "), or each process on its own with --process N";
    return {};
  } catch (const std::exception& e) {
    return e.what();
  }
}

// serve --capture DIR: the operator's folder, made with its parents, each display folder of this
// process made in it and written to once, never a folder where jobs name theirs (a job's
// --capture could then land on the wall's files). The problem, or an empty string.
std::string openWallCapture(const Options& o, const wall::Layout& layout, int process,
                            std::shared_ptr<const base::ConfinedFolder>& folder) {
  namespace fs = std::filesystem;
  const std::string prefix = "--capture " + o.captureDir + ": ";
  try {
    std::error_code ec;
    fs::create_directories(o.captureDir, ec);
    if (ec) return prefix + "cannot create the folder: " + ec.message();
    if (!o.captureRoot.empty()) {
      const fs::path inRoot = fs::weakly_canonical(o.captureDir)
                                  .lexically_relative(fs::weakly_canonical(o.captureRoot));
      if (!inRoot.empty() && *inRoot.begin() != "..")
        return prefix + "lies inside --capture-root " + o.captureRoot +
               ", where jobs name their capture folders; give the wall's captures a folder of "
               "their own";
    }
    folder =
        std::make_shared<const base::ConfinedFolder>(o.captureDir, "the wall's capture folder");
    const std::string problem = wall::checkWallCaptureFolders(*folder, layout, process);
    return problem.empty() ? problem : prefix + problem;
  } catch (const std::exception& e) {
    return prefix + e.what();
  }
}

wall::service::ServiceOptions serviceOptions(const Options& o, int process, bool alone,
                                             StopSignals& signals, int& stopSignal, FILE* stats) {
  wall::service::ServiceOptions service;
  service.process = process;
  service.listen = o.listen;
  service.join = o.join;
  service.advertise = o.advertise;
  service.timeout = std::chrono::seconds(o.timeoutSeconds);
  service.handlerThreads = o.handlerThreads;
  service.framesInFlight = o.framesInFlight;
  service.maxJobs = static_cast<std::size_t>(o.maxJobs);
  service.thumbnailSide = o.control.empty() ? 0 : o.thumbnailSize;
  service.leaveAlone = alone;
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
  return service;
}

// Says which processes have not joined yet (the head), and where jobs connect.
void reportStart(const wall::service::WallService& wall, const wall::service::ServiceOptions& s,
                 const std::vector<int>& absent, int timeoutSeconds) {
  if (s.process != 0) {
    if (!absent.empty())
      s.log("no answer from the head at " + wall.address() + " yet; still trying");
    return;
  }
  if (!absent.empty()) {
    std::string list;
    for (int p : absent) list += (list.empty() ? "" : ", ") + std::to_string(p);
    s.log("wall process" + std::string(absent.size() > 1 ? "es " : " ") + list +
          " did not join within " + std::to_string(timeoutSeconds) +
          " s; the wall starts without them (they join when they come)");
  }
  // One line a script can read: where jobs connect, and where the token is (never the token).
  std::printf("dfbwall: wall service on %s  token: %s%s\n", wall.address().c_str(),
              s.credentials.tokenSource.c_str(), s.credentials.secretKey.empty() ? "" : "  CURVE");
  std::fflush(stdout);
}

// serve --control on the head: the window manager's routes on a control server, serving.
std::unique_ptr<ControlServer> startWallControl(const Options& o, const wall::Layout& layout,
                                                wall::service::WallService& wall) {
  auto server =
      std::make_unique<ControlServer>(o.control, controlSecret(o.controlTokenFile), o.controlHosts);
  WallWindows windows;
  windows.list = [&wall] { return wall.windows(); };
  windows.raise = [&wall](std::uint64_t number) { return wall.raise(number); };
  windows.close = [&wall](std::uint64_t number, const std::string& why) {
    return wall.close(number, why);
  };
  windows.move = [&wall](std::uint64_t number, const dfb::Region& rect, int& code) {
    return wall.moveWindow(number, rect, &code);
  };
  addWallRoutes(server->requests(), WallFacts{&layout, o.background, o.maxJobs},
                std::move(windows));
  addWallPageRoutes(server->requests());
  server->start();
  return server;
}

}  // namespace

int runServe(const Options& o, int worldRank, StopSignals& signals, FailurePath& /*failure*/) {
  const auto timeout = std::chrono::milliseconds(std::chrono::seconds(o.timeoutSeconds));
  int worldSize = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &worldSize);
  const bool alone = o.process >= 0;
  const int process = alone ? o.process : worldRank;
  // Setup problems (a bad layout, a rank count that does not fit, a port in use) are bad input:
  // one message, every process exits 1.
  std::optional<wall::Layout> layout;
  std::string problem = checkStart(o, worldSize, process, alone, layout);
  FILE* stats = nullptr;
  if (problem.empty() && process == 0 && !o.statsFile.empty()) {
    try {
      stats = base::openOutputStream(o.statsFile, true);
    } catch (const std::exception& e) {
      problem = std::string("--stats ") + e.what();
    }
  }
  std::shared_ptr<const base::ConfinedFolder> captureRoot;
  if (problem.empty() && !o.captureRoot.empty()) {
    try {
      captureRoot = std::make_shared<const base::ConfinedFolder>(o.captureRoot, "the capture root");
    } catch (const std::exception& e) {
      problem = std::string("--capture-root ") + e.what();
    }
  }
  std::shared_ptr<const base::ConfinedFolder> wallCapture;
  if (problem.empty() && !o.captureDir.empty())
    problem = openWallCapture(o, *layout, process, wallCapture);
  if (alone && !problem.empty()) {
    std::fprintf(stderr, "dfbwall: error: %s\n", problem.c_str());
    return 1;
  }
  if (!alone) {
    const std::optional<int> first =
        runtime::firstRankWithProblem(problem, MPI_COMM_WORLD, timeout, "setup");
    if (first == worldRank) std::fprintf(stderr, "dfbwall: error: %s\n", problem.c_str());
    if (first) return 1;
  }
  int stopSignal = 0;
  try {
    const auto presenters = wall::makeDisplayPresenters(*layout, process, o.offscreen);
    wall::service::ServiceOptions service =
        serviceOptions(o, process, alone, signals, stopSignal, stats);
    service.captureRoot = captureRoot;
    service.captureQuota = o.captureQuota;
    service.background = o.background;
    service.wallCapture = wallCapture;
    service.wallCaptureEvery = o.captureEvery;
    // The token: the head's own (its file created when absent), or a process's on its own; under
    // mpirun the others get the head's. Key files: every process reads its own.
    wall::service::CredentialOptions credentials{o.token, o.tokenFile, o.curveDir, o.serverKey};
    std::optional<wall::service::WallService> wallService;
    std::unique_ptr<ControlServer> control;  // serve --control: the head's window manager
    if (process == 0) {
      try {
        service.credentials = wall::service::loadCredentials(credentials, true);
        wallService.emplace(*layout, presenters->list(), service);
        if (!o.control.empty()) control = startWallControl(o, *layout, *wallService);
      } catch (const std::exception& e) {
        if (!alone) shareHead({}, {}, timeout);  // the others learn there is no head, and stop
        std::fprintf(stderr, "dfbwall: error: %s\n", e.what());
        return 1;
      }
      if (!alone) shareHead(wallService->address(), service.credentials.token, timeout);
    } else {
      if (!alone) {
        const auto [address, token] = shareHead({}, {}, timeout);
        if (address.empty()) return 1;  // the head said why
        service.join = address;
        credentials.token = token;
        credentials.tokenFile.clear();
      }
      service.credentials = wall::service::loadCredentials(credentials, false);
      wallService.emplace(*layout, presenters->list(), service);
    }
    reportStart(*wallService, service,
                wallService->waitForProcesses(std::chrono::steady_clock::now() + timeout),
                o.timeoutSeconds);
    if (control) {
      std::printf("dfbwall: window manager: %s\n", control->startLine().c_str());
      std::fflush(stdout);
    }
    wallService->run();
    control.reset();  // its routes use the wall
    wallService.reset();
    if (stats) std::fclose(stats);
    const int code = stopSignal ? exitCodeForStop(stopSignal) : 0;
    if (!alone) {
      // MPI_Finalize (when this returns) is a fence among every process mpirun started; with one
      // of them killed (mpirun --enable-recovery) it was seen to hang now and then under load.
      // The wall has stopped and nothing is left to say over MPI: the process ends at the latest
      // a timeout from now.
      std::thread([code, timeout] {
        std::this_thread::sleep_for(timeout);
        std::_Exit(code);
      }).detach();
    }
    return code;
  } catch (const std::exception& e) {
    failAlone(process, e.what());
  }
}

}  // namespace app
