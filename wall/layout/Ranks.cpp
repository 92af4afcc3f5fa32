#include "wall/layout/Ranks.h"

#include "base/Error.h"

namespace wall {

std::optional<std::string> checkRankCount(const Layout& layout, int worldSize,
                                          std::optional<int> renderRanks) {
  const int w = layout.processCount;
  const std::string head = layout.file + ": the layout has " + std::to_string(w) + " wall process" +
                           (w == 1 ? "" : "es") + ", so ";
  if (renderRanks) {
    if (*renderRanks < 1)
      return layout.file + ": at least 1 render rank is needed, got " +
             std::to_string(*renderRanks);
    if (worldSize != *renderRanks + w)
      return head + "mpirun -np must be " + std::to_string(*renderRanks) + " render ranks + " +
             std::to_string(w) + " = " + std::to_string(*renderRanks + w) + ", but it is " +
             std::to_string(worldSize);
    return std::nullopt;
  }
  if (worldSize - w < 1)
    return head + "mpirun -np must be at least " + std::to_string(w + 1) +
           " (1 or more render ranks + " + std::to_string(w) + " wall ranks), but it is " +
           std::to_string(worldSize);
  return std::nullopt;
}

RankRoles rankRoles(const Layout& layout, int worldSize, std::optional<int> renderRanks) {
  if (auto problem = checkRankCount(layout, worldSize, renderRanks)) throw base::Error(*problem);
  return RankRoles{worldSize - layout.processCount, layout.processCount};
}

std::vector<std::string> hostWarnings(const Layout& layout, int process,
                                      const std::string& processorName) {
  std::vector<std::string> out;
  for (int i : layout.displaysOfProcess(process)) {
    const Display& d = layout.displays[static_cast<size_t>(i)];
    if (d.host.empty() || d.host == processorName) continue;
    out.push_back(layout.file + ":" + std::to_string(d.lines.table) + ": warning: display '" +
                  d.name + "' expects host '" + d.host + "', but wall process " +
                  std::to_string(process) + " runs on '" + processorName +
                  "'; place it with a hostfile or rankfile (see README)");
  }
  return out;
}

}  // namespace wall
