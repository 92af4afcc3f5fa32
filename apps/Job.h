#pragma once
// What one run of dfbwall is, as every rank sees it after setup: the options, the layout (when
// there is a wall), and this rank's role.
#include <mpi.h>

#include <memory>
#include <optional>
#include <vector>

#include "apps/Options.h"
#include "dfb/Messenger.h"
#include "renderers/RenderScene.h"
#include "wall/Layout.h"
#include "wall/Ranks.h"

namespace app {

struct Job {
  Options options;
  std::optional<wall::Layout> layout;
  wall::RankRoles roles;  // without a wall: every rank renders
  int worldRank = 0;
  int canvasWidth = 0, canvasHeight = 0;
  renderers::RenderScene scene;  // render ranks only
  bool gatherMode() const { return options.mode == "gather"; }
  bool isWallRank() const { return roles.processOfRank(worldRank) >= 0; }
};

struct FrameRecord {
  std::uint32_t frame = 0;
  double frameMs = 0;                 // rank 0: from the start of this frame to the next one's
  double renderMs = 0;                // slowest render rank: begin() .. last setTile()
  double compositeMs = 0;             // slowest render rank: last setTile() .. frame complete
  std::uint64_t rank0PixelBytes = 0;  // final pixels into rank 0 (the gather)
  // Pieces sent to wall ranks by all render ranks: bytes on the wire (after compression, with
  // the messenger's envelope) and before compression; how many, how many to other hosts, and
  // how many messages the render ranks' messengers compressed.
  std::uint64_t wallBytesSent = 0, wallBytesRaw = 0;
  std::uint64_t wallPieces = 0, wallPiecesToOtherHosts = 0, messagesCompressed = 0;
  std::uint64_t tileBytesSent = 0;  // tile inputs between render ranks
  std::uint64_t tilesRendered = 0;
  std::uint64_t samples = 0;
  std::int64_t lastSetTileNs = 0;  // steady_clock, latest over render ranks
  // steady_clock time the last display had every piece (wall ranks, filled on rank 0 at the end
  // of the run); minus lastSetTileNs it is the compositing time. One host's clock: on a cluster
  // the difference also holds the hosts' clock offset.
  std::int64_t displaysCompleteNs = 0;
};

// Where one rank's time went over the whole run, in milliseconds summed over tiles or frames,
// and its peak resident memory. Render ranks fill the first stages, wall ranks the last.
struct RankTotals {
  static constexpr int kStages = 12;
  static constexpr const char* kStageNames[kStages] = {
      "render",       "tile_unpack",  "tile_operation", "tone_map",  "cut",     "send",
      "gather_relay", "piece_unpack", "assemble",       "wall_wait", "barrier", "present"};
  double stageMs[kStages] = {};
  double peakRssKiB = 0;
  double role = 0;  // 0: render, 1: wall (a double so the whole struct gathers as doubles)
};

// Render ranks: renders the frames, feeds the wall (route or gather), writes --image on rank 0.
// Returns the records (complete on rank 0).
std::vector<FrameRecord> runRenderRank(const Job& job, dfb::Messenger& messenger,
                                       MPI_Comm renderComm, RankTotals& totals);
// Wall ranks: assembles, swaps and presents the frames of this process's displays.
// Returns, per frame, the steady_clock time its last piece arrived on this rank.
std::vector<std::int64_t> runWallRank(const Job& job, dfb::Messenger& messenger, MPI_Comm wallComm,
                                      RankTotals& totals);

// The peak resident set of this process (VmHWM), in KiB; 0 where /proc is missing.
double peakRssKiB();

// --dry-run on rank 0: canvas, displays, roles, and per display its tiles and their owners.
void printDryRun(const Job& job);
// --stats FILE.json on rank 0.
// `ranks` has every rank's totals, by world rank.
void writeStats(const Job& job, const std::vector<FrameRecord>& frames,
                const std::vector<RankTotals>& ranks);
// --image on rank 0: PNG from RGBA8 or PFM from linear RGBA float.
void writePfm(const std::string& path, const float* rgba, int width, int height);

}  // namespace app
