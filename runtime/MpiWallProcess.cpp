#include "runtime/MpiWallProcess.h"

#include "base/Collectives.h"
#include "wall/display/WallPeers.h"
#include "wall/route/PieceMessage.h"

namespace runtime {

wall::WallNodeOptions wallNodeOptions(const WallProcessSettings& settings) {
  wall::WallNodeOptions options;
  options.tileSize = settings.tileSize;
  options.gatherMode = settings.gatherMode;
  options.captureDir = settings.captureDir;
  options.captureEvery = settings.captureEvery;
  options.lastFrame = settings.lastFrame;
  options.timeout = settings.timeout;
  options.framesAhead = wall::framesAheadFor(settings.framesInFlight);
  return options;
}

MpiWallProcess::MpiWallProcess(const wall::Layout& layout, int process,
                               const WallProcessSettings& settings)
    : layout_(layout),
      presenters_(wall::makeDisplayPresenters(layout, process, settings.offscreen)),
      options_(wallNodeOptions(settings)) {}

void MpiWallProcess::run(messaging::Messenger& messenger, MPI_Comm wallComm, MPI_Comm startComm,
                         MpiWallControl& control, const WallProcessHooks& hooks) {
  wall::MpiWallPeers peers(messenger, wallComm, options_.timeout);
  wall::WallNode node(layout_, peers, presenters_->list(), options_);
  const messaging::Registration pieces(messenger, wall::kWallNodeObject, &node);
  control.listen({[&node](std::uint32_t last) { node.stopAfter(last); },
                  [&node, &messenger] {
                    node.keepWaiting();
                    messenger.setResting(true);  // ends by itself with the next frame's piece
                  },
                  [&node](std::uint32_t frameId, std::uint64_t sequence) {
                    node.requestCapture(frameId, sequence);
                  }});
  // However this is left (a throw too), the control no longer reaches the node it leaves.
  struct Forget {
    MpiWallControl& control;
    ~Forget() { control.listen({}); }
  } forget{control};
  try {
    // Pairs with the render ranks' barrier: every object of every rank is registered.
    base::barrier(startComm, base::Bound::joinWithin(options_.timeout, "start-up"));
    if (hooks.started) hooks.started();
    for (std::uint32_t frameId = 1; options_.lastFrame == 0 || frameId <= options_.lastFrame;
         ++frameId) {
      if (hooks.before) hooks.before(frameId);
      const wall::PresentReport report = node.presentFrame(frameId);
      if (report.stopped) break;
      if (hooks.after) hooks.after(report);
    }
    node.finish();  // the last frame's captures, when the run stopped early
  } catch (const std::exception& e) {
    if (hooks.failed) hooks.failed(e);
    throw;
  }
}

}  // namespace runtime
