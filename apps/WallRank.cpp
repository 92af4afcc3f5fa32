// A wall rank: its displays' presenters and the wall node's frame loop (runtime/MpiWallProcess.h),
// with what the executable adds: the wall's keyboard, signals, a closed window, statistics.
#include <algorithm>
#include <cstdio>
#include <optional>
#include <utility>

#include "apps/Job.h"
#include "apps/RunControl.h"
#include "apps/Steering.h"
#include "apps/ThreadCpu.h"
#include "apps/WallKeys.h"
#include "base/Timing.h"
#include "runtime/MpiWallProcess.h"

namespace app {
namespace {

// Mesa's software rasterizer threads (OSMesa and GLX on llvmpipe): GL's CPU, not the wall's.
constexpr const char* kGlThreadPrefix = "llvmpipe";

// Keys become steering requests for render rank 0, applied at its next frame boundary like the
// control API's; Esc asks for the graceful stop (once).
std::function<void(const std::vector<wall::WallKey>&)> keysToSteering(Steering& steering,
                                                                      int process) {
  return [&steering, process, escaped = false](const std::vector<wall::WallKey>& keys) mutable {
    for (wall::WallKey key : keys) {
      if (key == wall::WallKey::Escape) {
        if (std::exchange(escaped, true)) continue;
        std::fprintf(stderr, "dfbwall: Esc pressed on wall process %d: stopping\n", process);
        SteeringRequest stop;
        stop.kind = SteeringRequest::kStop;
        steering.submit(stop);
      } else if (const std::optional<SteeringRequest> r = requestForKey(key)) {
        steering.submit(*r);
      }
    }
  };
}

void addFrameTimes(const wall::PresentReport& r, RankTotals& totals) {
  StageTimes& t = totals.stages;
  t.pieceUnpack += r.unpackMs;
  t.assemble += r.assembleMs;
  t.wallWait += r.waitMs;
  t.upload += r.uploadMs;
  t.draw += r.drawMs;
  t.barrier += r.barrierMs;
  t.present += r.presentMs;
  if (r.previousSwapSpreadMs >= 0) {
    totals.swapSpreadMaxMs = std::max(totals.swapSpreadMaxMs, r.previousSwapSpreadMs);
    totals.swapSpreadSumMs += r.previousSwapSpreadMs;
    totals.swapSpreadFrames += 1;
  }
}

}  // namespace

int runWallRank(const Job& job, messaging::Messenger& messenger, MPI_Comm wallComm,
                RunControl& control, runtime::MpiWallControl& wallControl, Steering& steering,
                RankTotals& totals) {
  const Options& o = job.options;
  const int process = job.roles.processOfRank(job.worldRank);
  runtime::WallProcessSettings settings;
  settings.tileSize = o.tileSize;
  settings.gatherMode = job.gatherMode();
  settings.captureDir = o.captureDir;
  settings.captureEvery = o.captureEvery;
  settings.lastFrame = static_cast<std::uint32_t>(o.frames);
  settings.timeout = std::chrono::seconds(o.timeoutSeconds);
  settings.framesInFlight = o.framesInFlight;
  settings.offscreen = o.offscreen;
  // Only wall ranks ever start GL: OSMesa offscreen, or GLFW windows on this host's displays.
  runtime::MpiWallProcess wall(*job.layout, process, settings);
  if (!o.offscreen) wall.nodeOptions().onKeys = keysToSteering(steering, process);

  std::int64_t cpuAtStart = 0, mainAtStart = 0, glAtStart = 0;
  bool closed = false;
  runtime::WallProcessHooks hooks;
  hooks.started = [&] {
    cpuAtStart = base::processCpuNs();
    mainAtStart = base::threadCpuNs();
    glAtStart = cpuNsOfThreadsNamed(kGlThreadPrefix);
  };
  hooks.before = [&](std::uint32_t frameId) {
    control.pollSignals();
    job.failIfAsked(frameId);
  };
  hooks.after = [&](const wall::PresentReport& r) {
    if (!r.closedDisplay.empty() && !closed) {
      closed = true;
      std::fprintf(stderr, "dfbwall: the window of display '%s' was closed: stopping\n",
                   r.closedDisplay.c_str());
      control.askToStop(0);
    }
    addFrameTimes(r, totals);
  };
  hooks.failed = [&job](const std::exception& e) { job.failure->fail(e); };
  wall.run(messenger, wallComm, MPI_COMM_WORLD, wallControl, hooks);
  StageTimes& t = totals.stages;
  t.processCpu = static_cast<double>(base::processCpuNs() - cpuAtStart) * 1e-6;
  t.mainThreadCpu = static_cast<double>(base::threadCpuNs() - mainAtStart) * 1e-6;
  t.glThreadsCpu = static_cast<double>(cpuNsOfThreadsNamed(kGlThreadPrefix) - glAtStart) * 1e-6;
  totals.role = 1;
  return wallControl.exitCode();
}

}  // namespace app
