// A wall rank: its displays' presenters and the wall node's frame loop.
#include <optional>

#include "apps/Job.h"
#include "wall/GlfwPresenter.h"
#include "wall/OsmesaPresenter.h"
#include "wall/WallNode.h"

namespace app {

void runWallRank(const Job& job, dfb::Messenger& messenger, MPI_Comm wallComm) {
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
  {
    wall::WallNode node(messenger, layout, process, wallComm, std::move(presenters), options);
    MPI_Barrier(MPI_COMM_WORLD);  // pairs with the render ranks' barrier: everyone registered
    for (std::uint32_t frameId = 1; frameId <= static_cast<std::uint32_t>(o.frames); ++frameId)
      node.presentFrame(frameId);
  }
}

}  // namespace app
