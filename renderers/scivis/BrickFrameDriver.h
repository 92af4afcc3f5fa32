#pragma once
// Data- and mixed-parallel rendering through the DFB (paper 4.2-4.3, listings 3-4): the scene is
// cut into bricks (Bricks.h), each rank loads only the bricks it holds, and per frame every tile
// becomes a dependency tree: its owner sends the generation-0 background tile announcing one
// child per brick the tile needs, and for each of those bricks one of its holders (the
// tile-brick owner) renders the brick clipped to its bounds as a generation-1 tile. The DFB's
// composite-then-accumulate operation sorts each pixel's fragments by depth (ties by brick id,
// so the result never depends on who rendered what) and averages the composited frames.
// One brick per rank is data-parallel, every brick everywhere image-parallel, between mixed.
//
// Contracts: construction loads this rank's bricks (no communication: every rank plans the
// same); renderFrame() is collective over the DFB's communicator like begin()/end(); the DFB
// must be built with options from configure().
#include <cstdint>
#include <memory>
#include <vector>

#include "dfb/DistributedFrameBuffer.h"
#include "renderers/FrameDriver.h"
#include "renderers/Renderer.h"
#include "renderers/scivis/Bricks.h"
#include "renderers/scivis/SciVisRenderer.h"

namespace renderers {

struct BrickDriverOptions {
  int bricks = 1;
  int replication = 1;  // ranks holding each brick (clamped to the rank count)
  std::uint32_t samplesPerPixel = 1;
  int threads = 0;
  std::vector<bool> activeTiles;  // as FrameDriverOptions::activeTiles; empty: all
};

class BrickFrameDriver {
 public:
  BrickFrameDriver(std::shared_ptr<const SceneDesc> desc, const RenderSettings& settings,
                   BrickDriverOptions options, int rank, int ranks);
  ~BrickFrameDriver();

  // The composite-then-accumulate operation; one root input per active tile.
  void configure(dfb::DfbOptions& options) const;
  // `camera`: the frame's camera, the same on every rank (it comes with the frame order).
  FrameReport renderFrame(dfb::DistributedFrameBuffer& dfb, const dfb::FrameInfo& frame,
                          const CameraDesc& camera);
  void setSamplesPerPixel(std::uint32_t samples);  // from the next frame on, on every rank
  void setLiveSettings(const LiveSettings& live);  // the same

  const std::vector<BrickPlan>& bricks() const;
  std::vector<int> heldBricks() const;  // ids, on this rank
  std::size_t sceneBytes() const;       // the brick data this rank holds
  std::uint64_t brickTilesRendered() const;
  // The holder of brick `brick` that renders it for tile `tile` (round robin over its holders,
  // offset by the tile, so neighbouring tiles of one brick go to different ranks).
  int tileBrickOwner(int tile, int brick) const;
  // The bricks tile `region` needs under `camera` (screen projection of their bounds; every
  // brick when the camera is inside or beside one).
  std::vector<int> bricksOfTile(const CameraDesc& camera, const dfb::Region& region) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace renderers
