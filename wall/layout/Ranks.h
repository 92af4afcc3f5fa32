#pragma once
// Which ranks render and which drive displays. The job has R + W ranks: the first R render
// (rank 0 among them), the last W are wall ranks, wall process p being rank R + p.
#include <optional>
#include <string>
#include <vector>

#include "wall/layout/Layout.h"

namespace wall {

struct RankRoles {
  int renderRanks = 0;  // R: ranks 0 .. R-1
  int wallRanks = 0;    // W = layout.processCount: ranks R .. R+W-1
  int worldSize() const { return renderRanks + wallRanks; }
  int rankOfProcess(int process) const { return renderRanks + process; }
  // Wall process index of `rank`, or -1 for a render rank.
  int processOfRank(int rank) const { return rank >= renderRanks ? rank - renderRanks : -1; }
};

// The message for a rank count that does not fit the layout, or nothing when it fits. Without
// `renderRanks`, R = worldSize - W and it must be at least 1; with it (e.g. --render-ranks),
// worldSize must equal renderRanks + W exactly.
std::optional<std::string> checkRankCount(const Layout& layout, int worldSize,
                                          std::optional<int> renderRanks = std::nullopt);

// The roles for a rank count that passed checkRankCount; throws base::Error with its message
// otherwise.
RankRoles rankRoles(const Layout& layout, int worldSize,
                    std::optional<int> renderRanks = std::nullopt);

// Warnings (not errors: host names vary, and a test runs everything on one host) for displays of
// wall process `process` whose `host` differs from `processorName` (MPI_Get_processor_name).
std::vector<std::string> hostWarnings(const Layout& layout, int process,
                                      const std::string& processorName);

}  // namespace wall
