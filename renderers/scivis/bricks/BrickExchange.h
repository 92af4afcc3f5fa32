#pragma once
// The brick directory every render rank agrees on: which ranks hold which brick, and its bounds.
//
// Who holds what is never planned globally: each rank says which bricks it holds (from
// loadOwnBricks, or a program's own data through api/DataDistributed.h) and exchangeBricks
// tells every rank every brick's bounds and holders, once per scene change.
#include <mpi.h>

#include <chrono>
#include <vector>

#include "renderers/scivis/bricks/Bricks.h"

namespace renderers::scivis {

// Every brick of the job, by ascending id, and the ranks of `comm` holding each (ascending).
struct BrickDirectory {
  std::vector<BrickPlan> bricks;
  std::vector<std::vector<int>> holders;  // per entry of `bricks`
};

// Collective over `comm`: every rank gives the bricks it holds (id and clip bounds), every rank
// gets the whole directory (one base::allgatherv, bounded by `timeout`). Throws base::Error
// when ranks disagree about a brick's bounds, an id is negative, or no rank holds any brick.
BrickDirectory exchangeBricks(const std::vector<BrickPlan>& mine, MPI_Comm comm,
                              std::chrono::milliseconds timeout);

}  // namespace renderers::scivis
