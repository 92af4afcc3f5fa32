// A wall rank: its displays' presenters and the wall node's frame loop.
#include <optional>

#include "apps/Job.h"
#include "wall/GlfwPresenter.h"
#include "wall/OsmesaPresenter.h"
#include "wall/WallNode.h"

namespace app {

std::vector<std::int64_t> runWallRank(const Job& job, dfb::Messenger& messenger, MPI_Comm wallComm,
                                      RankTotals& totals) {
  const Options& o = job.options;
  const wall::Layout& layout = *job.layout;
  const int process = job.roles.processOfRank(job.worldRank);

  // Only wall ranks ever start GL: OSMesa offscreen, or GLFW windows on this host's displays.
  std::optional<wall::GlfwSession> glfw;
  if (!o.offscreen) glfw.emplace();
  std::vector<std::unique_ptr<wall::Presenter>> presenters;
  for (int d : layout.displaysOfProcess(process)) {
    const wall::Display& display = layout.displays[static_cast<size_t>(d)];
    presenters.push_back(
        o.offscreen ? wall::makeOsmesaPresenter(display.rect.width(), display.rect.height())
                    : wall::makeGlfwPresenter(*glfw, wall::windowOptionsFor(display)));
  }

  wall::WallNodeOptions options;
  options.tileSize = o.tileSize;
  options.gatherMode = job.gatherMode();
  options.captureDir = o.captureDir;
  options.captureEvery = o.captureEvery;
  options.lastFrame = static_cast<std::uint32_t>(o.frames);
  options.timeout = std::chrono::seconds(o.timeoutSeconds);
  std::vector<std::int64_t> completeNs;
  {
    wall::WallNode node(messenger, layout, process, wallComm, std::move(presenters), options);
    MPI_Barrier(MPI_COMM_WORLD);  // pairs with the render ranks' barrier: everyone registered
    for (std::uint32_t frameId = 1; frameId <= static_cast<std::uint32_t>(o.frames); ++frameId) {
      const wall::PresentReport r = node.presentFrame(frameId);
      completeNs.push_back(r.completeNs);
      totals.stageMs[7] += r.unpackMs;
      totals.stageMs[8] += r.assembleMs;
      totals.stageMs[9] += r.waitMs;
      totals.stageMs[10] += r.barrierMs;
      totals.stageMs[11] += r.presentMs;
    }
  }
  totals.role = 1;
  return completeNs;
}

}  // namespace app
