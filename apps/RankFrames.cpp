#include "apps/RankFrames.h"

#include <algorithm>

#include "base/BoundedWait.h"
#include "base/Error.h"

namespace app {

std::vector<RankFrame> gatherRankFrames(const RankFrame& mine, MPI_Comm comm,
                                        std::chrono::milliseconds timeout) {
  int rank = 0, size = 0;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  std::vector<RankFrame> all(rank == 0 ? static_cast<size_t>(size) : 0);
  MPI_Request request;
  base::checkMpi(MPI_Igather(&mine, sizeof mine, MPI_BYTE, all.data(), sizeof mine, MPI_BYTE, 0,
                             comm, &request),
                 "MPI_Igather");
  base::waitWithDeadline(request, std::chrono::steady_clock::now() + timeout,
                         "frame statistics: another render rank did not send them in time");
  return all;
}

FrameRecord combine(const std::vector<RankFrame>& all) {
  FrameRecord r;
  for (const RankFrame& f : all) {
    r.renderMs = std::max(r.renderMs, f.renderMs);
    // The paper's compositing overhead: from the slowest rank's last tile to the finished
    // frame, i.e. that rank's own last setTile -> complete. (The maximum over ranks would be the
    // time the fastest rank waited for the others.)
    if (f.lastSetTileNs >= r.lastSetTileNs) r.compositeMs = f.compositeMs;
    r.wallBytesSent += f.wallBytes;
    r.wallBytesRaw += f.wallBytesRaw;
    r.wallPieces += f.wallPieces;
    r.wallPiecesDropped += f.wallPiecesDropped;
    r.wallPiecesToOtherHosts += f.wallPiecesToOtherHosts;
    r.wallMessages += f.wallMessages;
    r.messagesCompressed += f.messagesCompressed;
    r.tileBytesSent += f.tileBytes;
    r.previewBytes += f.previewBytes;
    r.tilesRendered += f.tiles;
    r.samples += f.samples;
    r.lastSetTileNs = std::max(r.lastSetTileNs, f.lastSetTileNs);
  }
  return r;
}

}  // namespace app
