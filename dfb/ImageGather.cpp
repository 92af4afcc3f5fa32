#include "dfb/ImageGather.h"

#include <cstring>
#include <limits>
#include <string>

#include "base/Collectives.h"
#include "base/Error.h"

namespace dfb {
namespace {

struct BlockHeader {
  std::uint64_t rawBytes;
  std::uint32_t compressed;  // 0 raw, 1 Snappy, 2 plane-delta + Snappy
  std::uint32_t reserved;
};

std::size_t tileBytes(const TileGrid& grid, int tile, int bytesPerPixel) {
  return static_cast<std::size_t>(grid.region(tile).pixelCount()) *
         static_cast<std::size_t>(bytesPerPixel);
}

// Copies one tile's packed rows into the image.
void placeTile(const TileGrid& grid, int tile, int bytesPerPixel, const std::byte* pixels,
               std::byte* image) {
  const Region region = grid.region(tile);
  const std::size_t rowBytes =
      static_cast<std::size_t>(region.width()) * static_cast<std::size_t>(bytesPerPixel);
  for (int y = region.y0; y < region.y1; ++y) {
    std::memcpy(image + (static_cast<std::size_t>(y) * static_cast<std::size_t>(grid.width()) +
                         static_cast<std::size_t>(region.x0)) *
                            static_cast<std::size_t>(bytesPerPixel),
                pixels, rowBytes);
    pixels += rowBytes;
  }
}

// This rank's block: header + its tiles' pixels, packed in tile order, maybe compressed.
void packBlock(const TileGrid& grid, int bytesPerPixel, bool compress,
               const std::vector<int>& ownedTiles,
               const std::function<const std::byte*(int tile)>& pixelsOf, GatherBuffers& b) {
  std::uint64_t rawBytes = 0;
  for (int tile : ownedTiles) rawBytes += tileBytes(grid, tile, bytesPerPixel);
  BlockHeader header{rawBytes, 0, 0};
  // Appended rather than memcpy'd into a sized vector: GCC 12 at -O3 (Release) takes the
  // latter for a possible null dereference (-Wnull-dereference), which -Werror fails on.
  const auto* headerBytes = reinterpret_cast<const std::byte*>(&header);
  messaging::Bytes& out = compress ? b.raw : b.block;
  out.clear();
  // Reserved up front: GCC 12 at -O3 otherwise sees the inserts below write past a 16-byte
  // buffer (-Wstringop-overflow, -Warray-bounds false positives), and it saves regrowing.
  out.reserve(sizeof header + rawBytes);
  if (!compress) out.insert(out.end(), headerBytes, headerBytes + sizeof header);
  for (int tile : ownedTiles) {
    const std::byte* pixels = pixelsOf(tile);
    out.insert(out.end(), pixels, pixels + tileBytes(grid, tile, bytesPerPixel));
  }
  if (!compress) return;
  if (!b.raw.empty()) {
    if (bytesPerPixel == 4) {
      messaging::planeDeltaEncode(b.raw, 4, b.filtered);
      if (messaging::compressIfSmaller(b.filtered, b.body)) header.compressed = 2;
    } else if (messaging::compressIfSmaller(b.raw, b.body)) {
      header.compressed = 1;
    }
  }
  const messaging::Bytes& payload = header.compressed ? b.body : b.raw;
  b.block.assign(headerBytes, headerBytes + sizeof header);
  b.block.insert(b.block.end(), payload.begin(), payload.end());
}

}  // namespace

GatherCounts gatherImage(MPI_Comm comm, const TileGrid& grid, int bytesPerPixel, bool compress,
                         const std::vector<int>& ownedTiles,
                         const std::function<std::vector<int>(int rank)>& tilesOf,
                         const std::function<const std::byte*(int tile)>& pixelsOf,
                         std::byte* image, std::chrono::steady_clock::time_point deadline,
                         GatherBuffers& b) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  GatherCounts counts;

  // The root sends nothing to itself: it places its own tiles below, while the others' blocks
  // travel.
  b.block.clear();
  if (rank != 0) packBlock(grid, bytesPerPixel, compress, ownedTiles, pixelsOf, b);
  counts.bytesSent = b.block.size();

  constexpr std::uint64_t kMaxCount = std::numeric_limits<int>::max();
  if (b.block.size() > kMaxCount)
    throw base::Error("gather: rank " + std::to_string(rank) + " holds " +
                      std::to_string(b.block.size()) +
                      " bytes of the image, more than one MPI message carries (2^31-1)");
  const base::Bound bound{
      .until = deadline,
      .late = "gather of the image: another rank did not join in time",
      .tooLarge =
          "gather: the image's blocks add up to more than 2^31-1 bytes; use fewer, "
          "smaller images (or --image .png instead of .pfm)"};
  base::Pending blocks =
      base::startGatherv(std::span<const std::byte>(b.block), 0, comm, bound, b.gathered);
  if (rank == 0) {
    for (int tile : ownedTiles) {
      placeTile(grid, tile, bytesPerPixel, pixelsOf(tile), image);
      counts.pixelBytesReceived += tileBytes(grid, tile, bytesPerPixel);
    }
  }
  blocks.finish(bound);
  if (rank != 0) return counts;

  for (int r = 1; r < size; ++r) {
    const std::span<const std::byte> block = b.gathered.of(r);
    const size_t blockBytes = block.size();
    counts.bytesReceived += blockBytes;
    const std::byte* at = block.data();
    if (blockBytes < sizeof(BlockHeader))
      throw base::Error("gather: rank " + std::to_string(r) +
                        " sent a block shorter than its header");
    BlockHeader h;
    std::memcpy(&h, at, sizeof h);
    const std::span<const std::byte> data(at + sizeof h, blockBytes - sizeof h);
    const std::byte* pixels = data.data();
    if (!h.compressed && h.rawBytes != data.size())
      throw base::Error("gather: rank " + std::to_string(r) + " sent " +
                        std::to_string(data.size()) + " raw bytes, its header says " +
                        std::to_string(h.rawBytes));
    if (h.compressed > 2)
      throw base::Error("gather: rank " + std::to_string(r) + " sent a block of unknown encoding " +
                        std::to_string(h.compressed));
    if (h.compressed) {
      try {
        messaging::decompress(data, h.rawBytes, b.unpacked);
        pixels = b.unpacked.data();
        if (h.compressed == 2) {
          messaging::planeDeltaDecode(b.unpacked, 4, b.unfiltered);
          pixels = b.unfiltered.data();
        }
      } catch (const base::Error& e) {
        throw base::Error("gather: rank " + std::to_string(r) + ": " + e.what());
      }
    }
    size_t used = 0;
    for (int tile : tilesOf(r)) {
      const size_t bytes = tileBytes(grid, tile, bytesPerPixel);
      if (used + bytes > h.rawBytes)
        throw base::Error("gather: rank " + std::to_string(r) + " sent fewer pixel bytes (" +
                          std::to_string(h.rawBytes) + ") than its tiles need");
      placeTile(grid, tile, bytesPerPixel, pixels + used, image);
      used += bytes;
    }
    if (used != h.rawBytes)
      throw base::Error("gather: rank " + std::to_string(r) + " sent " +
                        std::to_string(h.rawBytes) + " pixel bytes for tiles that need " +
                        std::to_string(used));
    counts.pixelBytesReceived += used;
  }
  return counts;
}

}  // namespace dfb
