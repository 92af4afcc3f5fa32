// A wall rank: its displays' presenters and the wall node's frame loop.
#include <algorithm>
#include <cstdio>
#include <optional>
#include <utility>

#include "apps/Job.h"
#include "apps/RunControl.h"
#include "apps/Steering.h"
#include "apps/ThreadCpu.h"
#include "apps/WallKeys.h"
#include "base/Collectives.h"
#include "base/Timing.h"
#include "wall/display/DisplayPresenters.h"
#include "wall/display/WallNode.h"
#include "wall/route/PieceMessage.h"

namespace app {
namespace {

// Mesa's software rasterizer threads (OSMesa and GLX on llvmpipe): GL's CPU, not the wall's.
constexpr const char* kGlThreadPrefix = "llvmpipe";

}  // namespace

int runWallRank(const Job& job, messaging::Messenger& messenger, MPI_Comm wallComm,
                RunControl& control, Steering& steering, RankTotals& totals) {
  const Options& o = job.options;
  const wall::Layout& layout = *job.layout;
  const int process = job.roles.processOfRank(job.worldRank);

  // Only wall ranks ever start GL: OSMesa offscreen, or GLFW windows on this host's displays.
  const auto presenters = wall::makeDisplayPresenters(layout, process, o.offscreen);

  wall::WallNodeOptions options;
  options.tileSize = o.tileSize;
  options.gatherMode = job.gatherMode();
  options.captureDir = o.captureDir;
  options.captureEvery = o.captureEvery;
  options.lastFrame = static_cast<std::uint32_t>(o.frames);
  options.timeout = std::chrono::seconds(o.timeoutSeconds);
  // Render rank 0 starts frame F once frame F - K is presented: pieces can be K + 1 frames
  // ahead of this process's last presented frame, one more while it is between the swap
  // barrier and noting the frame presented.
  options.framesAhead = static_cast<std::uint32_t>(o.framesInFlight) + 2;
  // A keyboard on the wall: keys become steering requests for render rank 0, applied at its next
  // frame boundary like the control API's; Esc asks for the graceful stop (once).
  bool escaped = false;
  if (!o.offscreen)
    options.onKeys = [&steering, &escaped, process](const std::vector<wall::WallKey>& keys) {
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
  {
    wall::MpiWallPeers peers(messenger, wallComm, options.timeout);
    wall::WallNode node(layout, peers, presenters->list(), options);
    const messaging::Registration pieces(messenger, wall::kWallNodeObject, &node);
    control.onLastFrame([&node](std::uint32_t last) { node.stopAfter(last); });
    // While the renderers idle (a converged wall), rank 0 tells the walls to keep waiting; a
    // capture asked for through the control API names its frame.
    steering.onKeepWaiting([&node, &messenger] {
      node.keepWaiting();
      messenger.setResting(true);  // ends by itself with the next frame's first piece
    });
    steering.onCapture([&node](std::uint32_t frameId, std::uint64_t sequence) {
      node.requestCapture(frameId, sequence);
    });
    try {
      // Pairs with the render ranks' barrier: every object of every rank is registered.
      base::boundedBarrier(MPI_COMM_WORLD, options.timeout, "start-up");
      const std::int64_t cpuAtStart = base::processCpuNs(), mainAtStart = base::threadCpuNs(),
                         glAtStart = cpuNsOfThreadsNamed(kGlThreadPrefix);
      bool closed = false;
      const std::uint32_t frames = static_cast<std::uint32_t>(o.frames);  // 0: until stopped
      for (std::uint32_t frameId = 1; frames == 0 || frameId <= frames; ++frameId) {
        control.pollSignals();
        job.failIfAsked(frameId);
        const wall::PresentReport r = node.presentFrame(frameId);
        if (r.stopped) break;
        if (!r.closedDisplay.empty() && !closed) {
          closed = true;
          std::fprintf(stderr, "dfbwall: the window of display '%s' was closed: stopping\n",
                       r.closedDisplay.c_str());
          control.askToStop(0);
        }
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
      StageTimes& t = totals.stages;
      t.processCpu = static_cast<double>(base::processCpuNs() - cpuAtStart) * 1e-6;
      t.mainThreadCpu = static_cast<double>(base::threadCpuNs() - mainAtStart) * 1e-6;
      t.glThreadsCpu = static_cast<double>(cpuNsOfThreadsNamed(kGlThreadPrefix) - glAtStart) * 1e-6;
      node.finish();  // the last frame's captures, when the run stopped early
    } catch (const std::exception& e) {
      job.failure->fail(e);
    }
    control.onLastFrame({});
    steering.onKeepWaiting({});
    steering.onCapture({});
  }
  totals.role = 1;
  return control.exitCode();
}

}  // namespace app
