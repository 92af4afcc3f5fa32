#include "dfb/ImageGather.h"

#include <cstring>
#include <limits>
#include <string>

#include "dfb/BoundedWait.h"
#include "dfb/Error.h"

namespace dfb {
namespace {

struct BlockHeader {
  std::uint64_t rawBytes;
  std::uint32_t compressed;  // 0 raw, 1 Snappy, 2 plane-delta + Snappy
  std::uint32_t reserved;
};

}  // namespace

GatherCounts gatherImage(MPI_Comm comm, const TileGrid& grid, int bytesPerPixel, bool compress,
                         const std::vector<int>& ownedTiles,
                         const std::function<std::vector<int>(int rank)>& tilesOf,
                         const std::function<const std::byte*(int tile)>& pixelsOf,
                         std::byte* image, std::chrono::steady_clock::time_point deadline) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  GatherCounts counts;

  Bytes raw;
  for (int tile : ownedTiles) {
    const size_t bytes =
        static_cast<size_t>(grid.region(tile).pixelCount()) * static_cast<size_t>(bytesPerPixel);
    const std::byte* pixels = pixelsOf(tile);
    raw.insert(raw.end(), pixels, pixels + bytes);
  }

  BlockHeader header{raw.size(), 0, 0};
  Bytes body, filtered;
  if (compress && !raw.empty()) {
    if (bytesPerPixel == 4) {
      planeDeltaEncode(raw, 4, filtered);
      if (compressIfSmaller(filtered, body)) header.compressed = 2;
    } else if (compressIfSmaller(raw, body)) {
      header.compressed = 1;
    }
  }
  const Bytes& payload = header.compressed ? body : raw;
  // Appended rather than memcpy'd into a sized vector: GCC 12 at -O3 (Release) takes the
  // latter for a possible null dereference (-Wnull-dereference), which -Werror fails on.
  const auto* headerBytes = reinterpret_cast<const std::byte*>(&header);
  Bytes block(headerBytes, headerBytes + sizeof header);
  block.insert(block.end(), payload.begin(), payload.end());
  counts.bytesSent = rank == 0 ? 0 : block.size();

  constexpr std::uint64_t kMaxCount = std::numeric_limits<int>::max();
  if (block.size() > kMaxCount)
    throw Error("gather: rank " + std::to_string(rank) + " holds " + std::to_string(block.size()) +
                " bytes of the image, more than one MPI message carries (2^31-1)");
  const std::string late = "gather of the image: another rank did not join in time";
  int blockSize = static_cast<int>(block.size());
  std::vector<int> sizes(rank == 0 ? static_cast<size_t>(size) : 0);
  MPI_Request request;
  checkMpi(MPI_Igather(&blockSize, 1, MPI_INT, sizes.data(), 1, MPI_INT, 0, comm, &request),
           "MPI_Igather");
  waitWithDeadline(request, deadline, late);
  std::vector<int> offsets(sizes.size());
  Bytes all;
  if (rank == 0) {
    std::uint64_t total = 0;
    for (size_t r = 0; r < sizes.size(); ++r) {
      if (total > kMaxCount)
        throw Error(
            "gather: the image's blocks add up to more than 2^31-1 bytes; use fewer, "
            "smaller images (or --image .png instead of .pfm)");
      offsets[r] = static_cast<int>(total);
      total += static_cast<std::uint64_t>(sizes[r]);
    }
    all.resize(total);
  }
  checkMpi(MPI_Igatherv(block.data(), blockSize, MPI_BYTE, all.data(), sizes.data(), offsets.data(),
                        MPI_BYTE, 0, comm, &request),
           "MPI_Igatherv");
  waitWithDeadline(request, deadline, late);
  if (rank != 0) return counts;

  Bytes unpacked, unfiltered;
  for (int r = 0; r < size; ++r) {
    if (r != 0) counts.bytesReceived += static_cast<std::uint64_t>(sizes[static_cast<size_t>(r)]);
    const std::byte* at = all.data() + offsets[static_cast<size_t>(r)];
    if (static_cast<size_t>(sizes[static_cast<size_t>(r)]) < sizeof(BlockHeader))
      throw Error("gather: rank " + std::to_string(r) + " sent a block shorter than its header");
    BlockHeader h;
    std::memcpy(&h, at, sizeof h);
    const std::span<const std::byte> data(
        at + sizeof h, static_cast<size_t>(sizes[static_cast<size_t>(r)]) - sizeof h);
    const std::byte* pixels = data.data();
    if (!h.compressed && h.rawBytes != data.size())
      throw Error("gather: rank " + std::to_string(r) + " sent " + std::to_string(data.size()) +
                  " raw bytes, its header says " + std::to_string(h.rawBytes));
    if (h.compressed) {
      decompress(data, h.rawBytes, unpacked);
      pixels = unpacked.data();
      if (h.compressed == 2) {
        planeDeltaDecode(unpacked, 4, unfiltered);
        pixels = unfiltered.data();
      }
    }
    size_t used = 0;
    for (int tile : tilesOf(r)) {
      const Region region = grid.region(tile);
      const size_t rowBytes =
          static_cast<size_t>(region.width()) * static_cast<size_t>(bytesPerPixel);
      if (used + rowBytes * static_cast<size_t>(region.height()) > h.rawBytes)
        throw Error("gather: rank " + std::to_string(r) + " sent fewer pixel bytes (" +
                    std::to_string(h.rawBytes) + ") than its tiles need");
      for (int y = region.y0; y < region.y1; ++y) {
        std::memcpy(image + (static_cast<size_t>(y) * static_cast<size_t>(grid.width()) +
                             static_cast<size_t>(region.x0)) *
                                static_cast<size_t>(bytesPerPixel),
                    pixels + used, rowBytes);
        used += rowBytes;
      }
    }
    if (used != h.rawBytes)
      throw Error("gather: rank " + std::to_string(r) + " sent " + std::to_string(h.rawBytes) +
                  " pixel bytes for tiles that need " + std::to_string(used));
    counts.pixelBytesReceived += used;
  }
  return counts;
}

}  // namespace dfb
