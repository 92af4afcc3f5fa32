#pragma once
// The display-format gather of paper 3.2: at the end of a frame every other rank packs the final
// pixels of the tiles it owns into one buffer, compresses it, and rank 0 receives all of them
// with a single MPI_Gatherv and places them; rank 0 places its own tiles straight from their
// owners' buffers while the others' blocks are on the way. Internal to the DFB.
#include <mpi.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <vector>

#include "base/Collectives.h"
#include "dfb/Tile.h"
#include "messaging/Compression.h"

namespace dfb {

struct GatherCounts {
  std::uint64_t bytesSent = 0;           // compressed, this rank
  std::uint64_t bytesReceived = 0;       // compressed, root only
  std::uint64_t pixelBytesReceived = 0;  // uncompressed pixels placed in the root's image
};

// The gather's working memory, kept by the caller from one frame to the next: fresh buffers
// every frame touch every page anew, and first-touch page faults cost more than the gather.
struct GatherBuffers {
  messaging::Bytes raw, block, filtered, body, unpacked, unfiltered;
  base::Gathered<std::byte> gathered;
};

// `bytesPerPixel` 4 (RGBA8) or 16 (RGBAF32). `ownedTiles` in ascending order on each rank;
// `tilesOf(rank)` gives another rank's list on the root. `pixelsOf(tile)` points at the final
// pixels of an owned tile. The root's `image` is width*height*bytesPerPixel bytes. Sizes are
// 64-bit; MPI's int counts limit one rank's block, and the gathered total, to 2^31-1 bytes (a
// base::Error says so). Throws base::Error when another rank does not join by `deadline`.
GatherCounts gatherImage(MPI_Comm comm, const TileGrid& grid, int bytesPerPixel, bool compress,
                         const std::vector<int>& ownedTiles,
                         const std::function<std::vector<int>(int rank)>& tilesOf,
                         const std::function<const std::byte*(int tile)>& pixelsOf,
                         std::byte* image, std::chrono::steady_clock::time_point deadline,
                         GatherBuffers& buffers);

}  // namespace dfb
