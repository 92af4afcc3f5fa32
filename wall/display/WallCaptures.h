#pragma once
// What a service wall's displays show, written as it is presented (serve --capture DIR,
// docs/service.md): DIR/<display>/frame-<wall frame>.png for every display of this process,
// every K-th wall frame (WallNode's PresentReport::wallFrame, the same on every process). The
// composite is read back from the display's own presenter (the job's window over the background,
// or the whole frame); the PNGs are encoded and written on a thread of this object's, so presenting
// goes on while they are, and waits only when captures fall kMaxQueued frames behind.
//
// DIR is the operator's, yet written like a job's folder: reached without following a link
// (base/ConfinedFolder.h), each file atomic (base/AtomicFile.h), at most a quota of bytes over
// the process's run. A capture that cannot be written is logged and ends the wall's captures,
// never the wall or its job.
//
// Threading: presented() on the presenting thread (it reads back GL); writing on the writer's.
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "base/ConfinedFolder.h"
#include "wall/display/Capture.h"
#include "wall/display/Presenter.h"
#include "wall/image/Image.h"
#include "wall/layout/Layout.h"

namespace wall {

class WallCaptures {
 public:
  // Frames read back but not written yet, at most (then presented() waits for the writer).
  static constexpr std::size_t kMaxQueued = 4;

  // `presenters`: the displays of wall process `process`, in layout.displaysOfProcess order.
  WallCaptures(const Layout& layout, int process, std::vector<Presenter*> presenters,
               std::shared_ptr<const base::ConfinedFolder> dir, int every, std::uint64_t quota,
               std::function<void(const std::string&)> log);
  // Writes what is queued, then stops the writer.
  ~WallCaptures();
  WallCaptures(const WallCaptures&) = delete;
  WallCaptures& operator=(const WallCaptures&) = delete;

  // Wall frame `wallFrame` is on the displays: read back and queued when it is a K-th one.
  void presented(std::uint64_t wallFrame);
  // Waits until everything queued is written (tests, and a stopping wall).
  void flush();

 private:
  struct Frame {
    std::uint64_t wallFrame = 0;
    std::vector<Image> displays;  // by position in displaysOfProcess
  };
  void run();

  const Layout& layout_;
  std::vector<int> mine_;
  std::vector<Presenter*> presenters_;
  int every_;
  std::function<void(const std::string&)> log_;
  CaptureWriter writer_;  // the writer thread's only

  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<Frame> queue_;
  bool writing_ = false;  // the writer holds a frame taken from the queue
  bool stop_ = false;
  bool failed_ = false;  // a capture could not be written: no more are taken
  std::thread thread_;
};

}  // namespace wall
