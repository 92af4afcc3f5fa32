#include "renderers/scivis/bricks/BrickExchange.h"

#include <cstdint>
#include <map>
#include <string>

#include "base/Collectives.h"
#include "base/Error.h"

namespace renderers::scivis {
namespace {

// One brick on the wire: plain numbers, the same layout on every rank of a job.
struct WireBrick {
  std::int32_t id;
  float lo[3], hi[3];
};

}  // namespace

BrickDirectory exchangeBricks(const std::vector<BrickPlan>& mine, MPI_Comm comm,
                              std::chrono::milliseconds timeout) {
  int ranks = 1;
  MPI_Comm_size(comm, &ranks);
  std::vector<WireBrick> local;
  for (const BrickPlan& b : mine) {
    if (b.id < 0) throw base::Error("brick id " + std::to_string(b.id) + " is negative");
    local.push_back({b.id,
                     {b.bounds.lo.x, b.bounds.lo.y, b.bounds.lo.z},
                     {b.bounds.hi.x, b.bounds.hi.y, b.bounds.hi.z}});
  }
  std::vector<int> counts;
  const std::vector<WireBrick> all = base::allgatherv(
      local, comm,
      {.until = timeout,
       .late = "exchanging brick bounds: another render rank did not join within " +
               std::to_string(timeout.count()) + " ms"},
      &counts);

  std::map<int, std::pair<Box3, std::vector<int>>> byId;
  std::size_t first = 0;
  for (int r = 0; r < ranks; ++r) {
    const std::size_t n = static_cast<std::size_t>(counts[static_cast<std::size_t>(r)]);
    for (std::size_t i = first; i < first + n; ++i) {
      const WireBrick& w = all[i];
      const Box3 bounds{{w.lo[0], w.lo[1], w.lo[2]}, {w.hi[0], w.hi[1], w.hi[2]}};
      auto [it, fresh] = byId.try_emplace(w.id, bounds, std::vector<int>{});
      if (!fresh && !(it->second.first == bounds))
        throw base::Error("brick " + std::to_string(w.id) + ": render rank " + std::to_string(r) +
                          " gives it other bounds than render rank " +
                          std::to_string(it->second.second.front()) +
                          " (ranks holding one brick id must hold the same brick)");
      if (it->second.second.empty() || it->second.second.back() != r)
        it->second.second.push_back(r);
    }
    first += n;
  }
  if (byId.empty()) throw base::Error("no render rank holds any brick: nothing to render");
  BrickDirectory out;
  for (auto& [id, entry] : byId) {
    out.bricks.push_back({id, entry.first});
    out.holders.push_back(std::move(entry.second));
  }
  return out;
}

}  // namespace renderers::scivis
