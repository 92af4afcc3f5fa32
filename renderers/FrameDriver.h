#pragma once
// Renders frames through the Distributed FrameBuffer: plans this frame's work from the previous
// frame's tile errors, begins the frame, renders this rank's assignments on the TBB workers
// (each finished tile straight into setTile), ends the frame.
//
// Contracts: renderFrame() is collective over the DFB's communicator, like begin()/end(); every
// rank must use the same distribution and samples per pixel. The DFB must have been built with
// options from configure(), which tells it how many inputs each tile gets.
#include <cstdint>
#include <memory>

#include "dfb/DistributedFrameBuffer.h"
#include "renderers/Renderer.h"
#include "renderers/WorkDistribution.h"

namespace renderers {

struct FrameDriverOptions {
  Distribution distribution = Distribution::RoundRobin;
  std::uint32_t samplesPerPixel = 1;  // per frame and input
  int threads = 0;                    // 0: all cores
  DynamicOptions dynamic;
  // Tiles to render (e.g. those some display shows); empty: all. The work is planned over the
  // active tiles only, numbered in tile order, so round robin stays balanced; tiles left out
  // expect no inputs. Pair it with activeTileOwnership() so tiles are owned where rendered.
  std::vector<bool> activeTiles;
};

// Round-robin ownership over the active tiles (inactive ones go to rank 0, which has nothing to
// do for them): with the round-robin distribution each active tile is owned where it is rendered.
dfb::OwnershipFunction activeTileOwnership(std::vector<bool> activeTiles);

struct FrameReport {
  int tilesRendered = 0;      // on this rank (inputs, counting redundant ones)
  std::uint64_t samples = 0;  // pixel samples rendered on this rank
  double renderMs = 0;        // begin() returned .. last setTile() returned
  double renderCpuMs = 0;     // CPU of the renderer's render() calls, summed over threads
  double frameMs = 0;         // plan .. end() returned
};

class FrameDriver {
 public:
  FrameDriver(Renderer& renderer, FrameDriverOptions options);
  ~FrameDriver();

  // Sets options.expectedInputs; call before constructing the DFB with `options`. The driver
  // must outlive that DFB.
  void configure(dfb::DfbOptions& options) const;

  // `camera`: the frame's camera, the same on every rank (it comes with the frame order).
  FrameReport renderFrame(dfb::DistributedFrameBuffer& dfb, const dfb::FrameInfo& frame,
                          const CameraDesc& camera);
  // Samples per pixel per frame from the next frame on (the same on every rank; a steering
  // change, applied at a frame boundary with a new epoch).
  void setSamplesPerPixel(std::uint32_t samples);

  const WorkPlan& lastPlan() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace renderers
