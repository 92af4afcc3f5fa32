#include "apps/RankFrames.h"

#include <algorithm>

#include "base/Collectives.h"

namespace app {

std::vector<RankFrame> gatherRankFrames(const RankFrame& mine, MPI_Comm comm,
                                        std::chrono::milliseconds timeout) {
  return base::gather(mine, 0, comm,
                      {.until = timeout,
                       .late = "frame statistics: another render rank did not send them in time"});
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
    r.stepReadMs = std::max(r.stepReadMs, f.stepReadMs);
    r.stepBuildMs = std::max(r.stepBuildMs, f.stepBuildMs);
    r.stepWaitMs = std::max(r.stepWaitMs, f.stepWaitMs);
    // The least: the other ranks' switch includes waiting in the bricks' exchange for the rank
    // whose step came last (its wait is stepWaitMs).
    r.stepSwitchMs = &f == &all.front() ? f.stepSwitchMs : std::min(r.stepSwitchMs, f.stepSwitchMs);
  }
  return r;
}

}  // namespace app
