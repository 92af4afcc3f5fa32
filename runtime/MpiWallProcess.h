#pragma once
// One wall process that is a rank of the job's MPI communicator (dfbwall --wall, or a session of
// the data-distributed API with a layout): its displays' presenters, its wall node, the render
// side's wall control, and the frames from the start-up barrier to the last one.
#include <mpi.h>

#include <chrono>
#include <exception>
#include <functional>
#include <memory>

#include "messaging/Messenger.h"
#include "runtime/WallControl.h"
#include "wall/display/DisplayPresenters.h"
#include "wall/display/WallNode.h"
#include "wall/layout/Layout.h"

namespace runtime {

// What a wall process takes from the job's own settings: the node's options follow from them by
// one rule (wall::framesAheadFor).
struct WallProcessSettings {
  int tileSize = 64;
  bool gatherMode = false;
  std::string captureDir;
  int captureEvery = 0;
  std::uint32_t lastFrame = 0;  // 0: the render side announces it
  std::chrono::milliseconds timeout{60000};
  int framesInFlight = 2;
  bool offscreen = true;
};

wall::WallNodeOptions wallNodeOptions(const WallProcessSettings& settings);

// What the caller adds to each step of the run, on the calling thread. Each may be empty.
struct WallProcessHooks {
  std::function<void()> started;                          // after the start-up barrier
  std::function<void(std::uint32_t frameId)> before;      // before each frame
  std::function<void(const wall::PresentReport&)> after;  // after each presented frame
  // A failure, while the node and its registration still exist: unwinding them first would
  // turn a message arriving for them into the reported cause. The exception goes on after.
  std::function<void(const std::exception&)> failed;
};

class MpiWallProcess {
 public:
  // Makes the presenters (windows or offscreen contexts) of wall process `process`.
  MpiWallProcess(const wall::Layout& layout, int process, const WallProcessSettings& settings);

  // Node options the caller sets beyond the settings (keys, event polls) before run().
  wall::WallNodeOptions& nodeOptions() { return options_; }

  // Presents frames 1, 2, ... until the last (known from the settings or from `control`), then
  // captures what is due. The start-up barrier on `startComm` pairs with the render ranks'.
  // While the node exists, `control` stops it after the last frame, keeps it waiting and asks
  // for captures; a keep-waiting also lets the messenger rest until the next piece.
  void run(messaging::Messenger& messenger, MPI_Comm wallComm, MPI_Comm startComm,
           MpiWallControl& control, const WallProcessHooks& hooks);

 private:
  const wall::Layout& layout_;
  std::unique_ptr<wall::DisplayPresenters> presenters_;
  wall::WallNodeOptions options_;
};

}  // namespace runtime
