#pragma once
// A time series on a render rank: the data of the next step, read and built on a thread of its
// own while the current step renders, so a frame that shows it need not wait for I/O
// (docs/scivis.md, "Time series"). Which step a frame shows is rank 0's decision (FrameOrder);
// this only guesses the next one, and loads another when the guess was wrong (a seek).
#include <cstdint>
#include <functional>
#include <future>
#include <memory>
#include <optional>
#include <vector>

#include "renderers/RenderScene.h"
#include "renderers/SceneDesc.h"
#include "renderers/scivis/bricks/BrickFrameDriver.h"

namespace app {

// One time step's data on this rank, ready to render: its bricks built (--bricks) or its whole
// scene (image-parallel), with what making them took.
struct StepData {
  std::uint32_t step = 0;
  std::shared_ptr<const renderers::SceneDesc> desc;
  std::vector<renderers::scivis::BuiltBrick> bricks;  // --bricks
  std::optional<renderers::RenderScene> scene;        // image-parallel
  double readMs = 0;   // the voxels from the files (image-parallel: read and build together)
  double buildMs = 0;  // macrocells, value ranges, isosurfaces and their BVHs
};

class StepPrefetch {
 public:
  // `load` makes a step's data; it runs on the prefetch thread, in the floating-point mode of
  // the thread constructing this (the mode step 0 was built in), and may throw base::Error.
  explicit StepPrefetch(std::function<StepData(std::uint32_t step)> load);
  ~StepPrefetch();  // waits for a load in flight
  StepPrefetch(const StepPrefetch&) = delete;
  StepPrefetch& operator=(const StepPrefetch&) = delete;

  // Starts loading `step` on the prefetch thread (after any load in flight is taken or done).
  void start(std::uint32_t step);
  // The data of `step`: the prefetched one, waiting for it if it is still loading (`waitedMs`:
  // how long), or, when another step was prefetched, loaded now (a seek; waitedMs the whole
  // load). Rethrows a load's error.
  StepData take(std::uint32_t step, double& waitedMs);

 private:
  std::function<StepData(std::uint32_t)> load_;
  unsigned flushZero_, denormalsZero_;
  std::optional<std::uint32_t> pendingStep_;
  std::future<StepData> pending_;
};

}  // namespace app
