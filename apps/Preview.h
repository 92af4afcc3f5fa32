#pragma once
// The whole-wall preview in the app: every render rank runs the preview's pixel op,
// render rank 0 assembles the shrunk tiles (wall/route/PreviewAssembler.h). Wanted when the control
// server runs (it serves /api/preview.png) or with --preview FILE.png (written at the end).
#include <chrono>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "apps/Job.h"
#include "messaging/Messenger.h"
#include "wall/route/PreviewAssembler.h"
#include "wall/route/PreviewOp.h"

namespace app {

class Preview {
 public:
  // Every render rank, before the start-up barrier (and before the control server starts, which
  // serves it). Lives until the messenger has stopped.
  Preview(const Job& job, messaging::Messenger& messenger);
  // The render thread only: the pixel op of the frame buffer now (a new one after replan()).
  std::shared_ptr<wall::PreviewOp> op() const { return op_; }
  // Render rank 0 only (nullptr elsewhere).
  wall::PreviewAssembler* assembler() const { return assembler_.get(); }

  // Every render rank, on its render thread, before the new frame buffer is made: a service wall
  // moved or resized the job's window, whose layout `layout` is, from frame `fromFrame` on. The
  // preview is of the new canvas from then on; op() is a new op for the new frame buffer.
  void replan(const wall::Layout& layout, std::uint32_t fromFrame);

  // Rank 0: the latest preview as PNG bytes, decorated (bezels dark, display outlines), and its
  // frame. Encoded once per frame, whatever the number of readers. Thread-safe.
  struct Png {
    std::uint32_t frame = 0;
    std::shared_ptr<const std::string> bytes;
  };
  Png png() const;
  // Rank 0, thread-safe: the canvas the preview shows now (its layout: nullptr without a wall)
  // and its grid, for /api/layout.
  struct Canvas {
    std::shared_ptr<const wall::Layout> layout;
    wall::PreviewGrid grid;
  };
  Canvas canvas() const;
  // Rank 0 at the end of the run: waits (up to `timeout`) until the last frame's preview is in,
  // so no preview message is still travelling when the assembler goes, then writes --preview.
  void finish(std::uint32_t lastFrame, std::chrono::milliseconds timeout) const;
  // Thread-safe: the displays (by layout index) a service wall lost; the preview crosses them out.
  void setLostDisplays(std::vector<bool> lost);

 private:
  const Job& job_;
  messaging::Messenger& messenger_;
  std::shared_ptr<wall::PreviewOp> op_;
  std::unique_ptr<wall::PreviewAssembler> assembler_;
  mutable std::mutex pngMutex_;  // taken before the assembler's own
  mutable Png png_;
  std::shared_ptr<const wall::Layout> layout_;  // under pngMutex_
  std::vector<bool> lost_;                      // under pngMutex_
  mutable bool lostChanged_ = false;
};

}  // namespace app
