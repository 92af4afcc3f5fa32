#pragma once
// One render rank's numbers of one frame (--stats), gathered to rank 0 and combined there into
// the frame's record.
#include <mpi.h>

#include <chrono>
#include <cstdint>
#include <vector>

#include "apps/Job.h"

namespace app {

// One render rank's numbers of one frame, gathered to rank 0 for the statistics.
struct RankFrame {
  double renderMs, compositeMs;
  // Pieces for the wall: bytes on the wire (after compression), bytes before, how many, how
  // many to other hosts; messages this rank's messenger compressed.
  std::uint64_t wallBytes, wallBytesRaw, wallPieces, wallPiecesToOtherHosts, messagesCompressed;
  std::uint64_t wallMessages;  // MPI messages to the wall node
  std::uint64_t tileBytes, tiles, samples;
  std::int64_t lastSetTileNs;
  std::uint64_t previewBytes;
  std::uint64_t wallPiecesDropped;  // for wall processes the wall lost (--connect)
  // A frame that showed a new time step (else 0): making the step's data (read, build; on the
  // prefetch thread), how long the frame waited for it and switching to it (the bricks'
  // exchange, renderers). Combined: the slowest rank's, but the switch the fastest's.
  double stepReadMs, stepBuildMs, stepWaitMs, stepSwitchMs;
};

// Collective over `comm`: every rank's numbers, on rank 0 (empty elsewhere).
std::vector<RankFrame> gatherRankFrames(const RankFrame& mine, MPI_Comm comm,
                                        std::chrono::milliseconds timeout);
// The slowest rank's times, the sums of the counts, the latest setTile.
FrameRecord combine(const std::vector<RankFrame>& all);

}  // namespace app
