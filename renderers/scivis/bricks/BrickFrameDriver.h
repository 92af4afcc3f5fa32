#pragma once
// Data- and mixed-parallel rendering through the DFB (paper 4.2-4.3, listings 3-4): the scene is
// cut into bricks (BrickPlan.h), each rank loads only the bricks it holds, and per frame every tile
// becomes a dependency tree: its owner sends the generation-0 background tile announcing one
// child per brick the tile needs, and for each of those bricks one of its holders (the
// tile-brick owner) renders the brick clipped to its bounds as a generation-1 tile. The DFB's
// composite-then-accumulate operation sorts each pixel's fragments by depth (ties by brick id,
// so the result never depends on who rendered what) and averages the composited frames.
// One brick per rank is data-parallel, every brick everywhere image-parallel, between mixed.
//
// A brick's rank does not trace a ray where a nearer brick certainly composites an opaque
// isosurface in front of it (BrickOcclusion.h: a summary of every brick's faces, exchanged with
// the bounds), so sort-last costs less than every brick's whole screen footprint.
//
// Contracts: construction takes this rank's bricks and is collective over `comm` (the render
// ranks, the DFB's communicator): the ranks exchange their bricks' ids and bounds once
// (exchangeBricks), and their occlusion summaries, so a new scene (new data) is a new driver.
// renderFrame() is collective over the DFB's communicator like begin()/end(); the DFB must be built
// with options from configure().
#include <mpi.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <vector>

#include "dfb/DistributedFrameBuffer.h"
#include "renderers/FrameDriver.h"
#include "renderers/Renderer.h"
#include "renderers/scivis/bricks/BrickLoad.h"
#include "renderers/scivis/bricks/Bricks.h"
#include "renderers/scivis/render/SciVisRenderer.h"

namespace renderers::scivis {

struct BrickDriverOptions {
  std::uint32_t samplesPerPixel = 1;
  int threads = 0;
  std::vector<bool> activeTiles;             // as FrameDriverOptions::activeTiles; empty: all
  std::chrono::milliseconds timeout{60000};  // for the bounds exchange
  // Skip the rays of a brick that a nearer brick certainly hides behind an opaque isosurface
  // (BrickOcclusion.h; only where that is exact: one sample per pixel a frame, no visible
  // volume, every material opaque). The same image either way; false: trace them all.
  bool occlusionCut = true;
  // How the bricks' camera rays find their first hits (SciVisOptions::firstHits).
  FirstHits firstHits = FirstHits::Auto;
};

// The DFB options every brick driver needs (the composite-then-accumulate operation, one root
// input per active tile): a DFB set up once serves every scene version's driver.
void configureBrickDfb(dfb::DfbOptions& options, std::vector<bool> activeTiles);

// A held brick with its scene built (macrocells, value ranges, isosurfaces and their BVHs):
// the part of a driver's construction that needs no other rank, so a next time step's bricks can
// be built on a thread of their own while the current ones render (apps/StepPrefetch.h).
struct BuiltBrick {
  int id = 0;
  std::unique_ptr<SciVisScene> scene;
};
// Builds each brick's scene for `desc` (as the driver's constructor does). Pure.
std::vector<BuiltBrick> buildBricks(std::shared_ptr<const SceneDesc> desc,
                                    std::vector<HeldBrick> mine);

class BrickFrameDriver {
 public:
  // `desc` gives everything but the bricks' data: materials, transfer functions, isosurfaces,
  // lights, background, the camera and the renderer's settings; its volumes' grids place the
  // bricks' voxels (BrickContent::volumes has one entry per SciVisDesc::volumes).
  BrickFrameDriver(std::shared_ptr<const SceneDesc> desc, const RenderSettings& settings,
                   BrickDriverOptions options, std::vector<HeldBrick> mine, MPI_Comm comm);
  // The same with the bricks built already (buildBricks with the same `desc`).
  BrickFrameDriver(std::shared_ptr<const SceneDesc> desc, const RenderSettings& settings,
                   BrickDriverOptions options, std::vector<BuiltBrick> mine, MPI_Comm comm);
  ~BrickFrameDriver();

  // configureBrickDfb with this driver's active tiles.
  void configure(dfb::DfbOptions& options) const;
  // `camera`: the frame's camera, the same on every rank (it comes with the frame order).
  FrameReport renderFrame(dfb::DistributedFrameBuffer& dfb, const dfb::FrameInfo& frame,
                          const CameraDesc& camera);
  void setSamplesPerPixel(std::uint32_t samples);  // from the next frame on, on every rank
  void setLiveSettings(const LiveSettings& live);  // the same

  // Every brick of the job by ascending id (from the exchange); "brick" below is an index here.
  const std::vector<BrickPlan>& bricks() const;
  const std::vector<int>& holders(int brick) const;  // render ranks, ascending
  std::vector<int> heldBricks() const;               // ids, on this rank
  std::size_t sceneBytes() const;                    // the brick data this rank holds
  // Over this rank's bricks: isosurface triangles and the seconds making them (at load).
  SciVisScene::IsosurfaceStats isosurfaceStats() const;
  // This rank's bricks, moved out for the next scene version; the driver is spent afterwards.
  std::vector<HeldBrick> releaseBricks();
  std::uint64_t brickTilesRendered() const;
  // Camera rays of this rank's bricks not traced since construction: a nearer brick certainly
  // composites an opaque surface in front of them (BrickDriverOptions::occlusionCut).
  std::uint64_t raysSkipped() const;
  // The holder of brick `brick` that renders it for tile `tile` (round robin over its holders,
  // offset by the tile, so neighbouring tiles of one brick go to different ranks).
  int tileBrickOwner(int tile, int brick) const;
  // The bricks (indices) that may reach tile `region` under `camera`: the screen projection of
  // their bounds, widened by a pixel (every brick when the camera is inside or beside one).
  std::vector<int> candidateBricks(const CameraDesc& camera, const dfb::Region& region) const;
  // The bricks (indices) tile `region` needs in the frame of `accumulationId`: the candidates
  // that some sample ray of the tile enters or leaves (the rays every rank traces identically,
  // so every rank agrees; a camera inside a brick counts it).
  std::vector<int> bricksOfTile(const CameraDesc& camera, const dfb::Region& region,
                                std::uint32_t accumulationId) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace renderers::scivis
