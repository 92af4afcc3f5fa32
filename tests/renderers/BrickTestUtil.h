#pragma once
// Rendering held bricks through the real DFB, as the data-parallel MPI tests compare them.
#include <mpi.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "dfb/DistributedFrameBuffer.h"
#include "renderers/scivis/bricks/BrickFrameDriver.h"

namespace renderers::test {

// The RGBAF32 image of `frames` accumulated frames of the bricks `held` on the ranks of `comm`
// (rank 0's copy; empty elsewhere), rendered with 2 threads a rank in tiles of `tileSize`.
// `occlusionCut`: BrickDriverOptions::occlusionCut; `raysSkipped` (if given): this rank's
// BrickFrameDriver::raysSkipped() at the end; `samplesPerPixel`: per frame.
inline std::vector<float> renderHeldBricks(
    const std::shared_ptr<SceneDesc>& desc, const RenderSettings& settings,
    std::vector<scivis::HeldBrick> held, MPI_Comm comm, int tileSize, int frames,
    std::chrono::milliseconds frameTimeout, bool occlusionCut = true,
    std::uint64_t* raysSkipped = nullptr, scivis::FirstHits firstHits = scivis::FirstHits::Auto,
    std::uint32_t samplesPerPixel = 1) {
  scivis::BrickDriverOptions bo;
  bo.threads = 2;
  bo.samplesPerPixel = samplesPerPixel;
  bo.occlusionCut = occlusionCut;
  bo.firstHits = firstHits;
  scivis::BrickFrameDriver driver(desc, settings, bo, std::move(held), comm);
  messaging::Messenger messenger(comm);
  dfb::DfbOptions options;
  options.width = settings.width, options.height = settings.height, options.tileSize = tileSize;
  options.format = dfb::DisplayFormat::RGBAF32;
  options.frameTimeout = frameTimeout;
  driver.configure(options);
  std::vector<float> image;
  {
    dfb::DistributedFrameBuffer fb(messenger, comm, options);
    for (int f = 0; f < frames; ++f)
      driver.renderFrame(fb, {static_cast<std::uint32_t>(f), 0}, desc->camera);
    image = fb.imageRgbaF32();
  }
  messenger.stop();
  if (raysSkipped) *raysSkipped = driver.raysSkipped();
  return image;
}

// `render(comm, rank)` on the first `ranks` ranks of the world, on a communicator of their own
// (its image on rank 0; empty elsewhere); every rank of the world returns together.
template <class Render>
std::vector<float> onFirstRanks(int ranks, Render render) {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm comm;
  MPI_Comm_split(MPI_COMM_WORLD, rank < ranks ? 0 : 1, rank, &comm);
  std::vector<float> image;
  if (rank < ranks) image = render(comm, rank);
  MPI_Comm_free(&comm);
  MPI_Barrier(MPI_COMM_WORLD);
  return image;
}

}  // namespace renderers::test
