#pragma once
// What the control server reports (GET /api/status): render rank 0's frame loop publishes it
// after every frame and while it idles, the server's threads read a copy.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <vector>

#include "apps/FrameOrder.h"

namespace app {

struct RunStatus {
  std::uint32_t frame = 0;     // the last frame rendered
  std::int64_t presented = 0;  // the last frame every display presented (0: no wall)
  double fps = 0;              // frames per second over the last few frames; 0 while idle
  std::int64_t spp = 0;        // samples per pixel accumulated in the current epoch
  std::uint32_t epoch = 0;
  bool idle = false;  // converged: nothing is rendered until something changes
  FrameView view;
  std::uint32_t timeSteps = 1;         // a time series' steps (view.timeStep is the one shown)
  bool playing = false;                // the series plays (else paused)
  std::uint64_t lastRequest = 0;       // the last steering request applied ...
  std::uint32_t lastRequestFrame = 0;  // ... first shown by this frame
  std::vector<std::string> errors;     // the latest last
  // --connect: displays of wall processes the wall lost (dark until they rejoin).
  std::vector<std::string> lostDisplays;
  // --connect: the displays the job's window touches after the wall moved it (empty: those at
  // its start, ControlFacts::displays).
  std::vector<std::string> displays;
};

class StatusBoard {
 public:
  // After frame `status.frame` (or an idle heartbeat): keeps the errors, computes fps.
  void publish(RunStatus status);
  // Something an operator should read (a request that could not be applied); the last 20 kept.
  void addError(std::string message);
  // The wall lost (or got back) processes: the displays that show nothing of this job now.
  void setLostDisplays(std::vector<std::string> names);
  // The wall moved the job's window: the displays it touches now.
  void setDisplays(std::vector<std::string> names);
  RunStatus snapshot() const;
  // The server starts before the scene is loaded; a request checked against the view must wait
  // for the first publish, or it is checked against a default camera. False after `wait`.
  bool waitForFirstPublish(std::chrono::milliseconds wait) const;

 private:
  mutable std::mutex mutex_;
  mutable std::condition_variable published_;
  bool everPublished_ = false;
  RunStatus status_;
  std::deque<std::string> errors_;
  std::vector<std::string> lostDisplays_;
  std::vector<std::string> displays_;
  std::deque<std::chrono::steady_clock::time_point> frameTimes_;  // of the last frames
};

}  // namespace app
