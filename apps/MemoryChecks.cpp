#include "apps/MemoryChecks.h"

#include <cstdint>
#include <cstdlib>

#include "base/MemoryBudget.h"

namespace app {
namespace {

// A pixel of a tile a render rank owns: the accumulation (4 colour and 2 luminance doubles,
// 48 bytes), the accumulated tile (RGBA float, 16), the tile being rendered or received (16)
// and the display format (RGBA8, 4), rounded up for bookkeeping.
constexpr std::uint64_t kOwnedPixelBytes = 96;
// A pixel of a display a wall process shows: the frame being assembled, the one presented and
// the presenter's copy (RGBA8 each).
constexpr std::uint64_t kDisplayPixelBytes = 12;

std::string sizeText(const Job& job) {
  const std::string size = std::to_string(job.canvasWidth) + "x" + std::to_string(job.canvasHeight);
  if (!job.options.wall.empty()) return job.options.wall + ": the canvas, " + size + ",";
  if (!job.options.connect.empty()) return "the serving wall's canvas, " + size + ",";
  return "--size " + size;
}

}  // namespace

std::string canvasMemoryProblem(const Job& job) {
  const Options& o = job.options;
  const std::uint64_t pixels = std::uint64_t(job.canvasWidth > 0 ? job.canvasWidth : 0) *
                               std::uint64_t(job.canvasHeight > 0 ? job.canvasHeight : 0);
  if (!job.isWallRank()) {
    const std::uint64_t ranks =
        std::uint64_t(job.roles.renderRanks > 0 ? job.roles.renderRanks : 1);
    std::uint64_t bytes = base::bytesTimes((pixels + ranks - 1) / ranks, kOwnedPixelBytes);
    std::string what = sizeText(job) + ": the frame buffer tiles a render rank owns (1/" +
                       std::to_string(ranks) + " of " + std::to_string(pixels) + " pixels, " +
                       std::to_string(kOwnedPixelBytes) + " bytes each)";
    if (job.worldRank == 0 && !o.image.empty()) {
      // The gathered image and the file's copy of it.
      const bool pfm = o.image.size() >= 4 && o.image.compare(o.image.size() - 4, 4, ".pfm") == 0;
      bytes = base::bytesPlus(bytes, base::bytesTimes(pixels, pfm ? 32 : 8));
      what += " and the image --image " + o.image + " gathers on rank 0";
    }
    const std::string problem = base::memoryProblem(bytes);
    return problem.empty() ? problem : what + " " + problem;
  }
  if (!job.layout) return {};
  const int process = job.roles.processOfRank(job.worldRank);
  std::uint64_t mine = 0;
  for (int d : job.layout->displaysOfProcess(process))
    mine += std::uint64_t(job.layout->displays[static_cast<std::size_t>(d)].rect.pixelCount());
  std::uint64_t bytes = base::bytesTimes(mine, kDisplayPixelBytes);
  std::string what = o.wall + ": the displays of wall process " + std::to_string(process) + " (" +
                     std::to_string(mine) + " pixels, " + std::to_string(kDisplayPixelBytes) +
                     " bytes each)";
  if (!o.captureDir.empty()) {
    // Captures read each display back (4 bytes a pixel) and wall process 0 gathers every
    // display's pixels and composes the canvas (4 + 4 bytes a canvas pixel).
    bytes = base::bytesPlus(bytes, base::bytesTimes(mine, 4));
    if (process == 0) bytes = base::bytesPlus(bytes, base::bytesTimes(pixels, 8));
    what += " with --capture" + std::string(process == 0
                                                ? " (the whole-wall preview of " +
                                                      std::to_string(pixels) + " pixels included)"
                                                : "");
  }
  const std::string problem = base::memoryProblem(bytes);
  return problem.empty() ? problem : what + " " + problem;
}

int ranksOnThisHost() {
  for (const char* name : {"OMPI_COMM_WORLD_LOCAL_SIZE", "MPI_LOCALNRANKS"})
    if (const char* value = std::getenv(name)) {
      const int n = std::atoi(value);
      if (n > 0) return n;
    }
  return 1;
}

}  // namespace app
