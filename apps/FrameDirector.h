#pragma once
// Render rank 0's decision for each frame: which camera and settings it renders (the scene's
// camera, an --orbit, a --camera-path, steering requests on top), its accumulation epoch, and
// whether the wall has converged (--max-spp reached with a still camera) so the ranks can idle.
// Pure bookkeeping, no communication: RenderRank.cpp broadcasts what it decides.
#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "apps/FrameOrder.h"
#include "apps/Steering.h"

namespace app {

// `view` changed by camera or settings request `r`; a camera request starts from `shown`, the
// camera the wall shows now. False (and `view` untouched) when the camera
// would be unusable: look-at at the position, or along up.
bool steerView(FrameView& view, const renderers::CameraDesc& shown, const SteeringRequest& r);

struct DirectorOptions {
  FrameView initial;        // the scene's camera and the command line's settings
  float orbitDegrees = 0;   // per frame (--orbit)
  std::int64_t maxSpp = 0;  // per epoch; 0: never converges
  // The camera of frame F from a --camera-path (empty: none). A steering camera request ends
  // the path: the operator has the camera from then on.
  std::function<renderers::CameraDesc(std::uint32_t frameId)> path;
  // The time step frame F shows from the camera path's keyframes, when they name one; while it
  // gives one, the path holds the series' time (play, step and seek wait until it ends).
  std::function<std::optional<std::uint32_t>(std::uint32_t frameId)> pathStep;
  // What frame F draws besides the camera (`dfbwall show`: the index of its picture); not
  // converged while the next frame's differs. Empty: nothing else.
  std::function<std::uint64_t(std::uint32_t frameId)> content;
  // A time series (docs/scivis.md, "Time series"): its steps (1: none) and playback rate (steps
  // a second; 0: one a frame, the next frame always the next step). It plays from step 0,
  // looping, never skipping a step: when frames are slower than `fps`, one step a frame.
  std::uint32_t timeSteps = 1;
  float fps = 0;
  std::function<std::chrono::steady_clock::time_point()> now = std::chrono::steady_clock::now;
};

class FrameDirector {
 public:
  explicit FrameDirector(DirectorOptions options);

  // The order for frame `frameId` with `requests` applied (in order); stop and capture requests
  // only set the order's flags. Call once per frame that is begun.
  FrameOrder next(std::uint32_t frameId, const std::vector<SteeringRequest>& requests);
  // True when the current epoch has its sample budget and nothing moves by itself (no orbit,
  // no path): rendering more would not change the picture.
  bool converged() const;
  // Samples per pixel accumulated in the current epoch (after the last next()).
  std::int64_t epochSpp() const { return epochSpp_; }
  const FrameView& view() const { return view_; }
  std::uint32_t epoch() const { return epoch_; }
  // The last steering request applied and the frame that first showed it (0: none yet).
  std::uint64_t lastRequest() const { return lastRequest_; }
  std::uint32_t lastRequestFrame() const { return lastRequestFrame_; }
  // The frame buffer was made anew (a moved window): the next frame starts accumulating from
  // epoch 0, as the first frame of a run does.
  void restartAccumulation();
  // The time series: playing or paused (the status' "time").
  bool playing() const { return playing_; }
  // Requests that could not be applied since the last call (for the status' "errors").
  std::vector<std::string> takeErrors();

 private:
  void apply(const SteeringRequest& r);
  void applyTime(const SteeringRequest& r);
  // While playing: base_.timeStep moves on to the step the frame being ordered shows.
  void advanceTime();

  DirectorOptions options_;
  FrameView base_;  // before the orbit / path of the frame
  FrameView view_;  // of the last frame ordered
  bool haveView_ = false;
  bool pathActive_ = false;
  std::uint32_t epoch_ = 0;
  std::int64_t epochSpp_ = 0;
  std::uint64_t captures_ = 0;
  std::uint32_t orbitFrom_ = 0;  // the frame the orbit (re)started from; 0: the next one
  std::uint32_t lastFrame_ = 0;
  std::uint64_t lastRequest_ = 0;
  std::uint32_t lastRequestFrame_ = 0;
  std::vector<std::string> errors_;
  bool playing_ = false;
  bool timeMoved_ = false;  // a request moved the step of the frame being ordered
  std::chrono::steady_clock::time_point nextStepDue_{};
};

}  // namespace app
