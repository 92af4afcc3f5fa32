#pragma once
// Ghosts the session exchanges itself (Ghosts::Exchange, api/DataDistributed.h): a brick gives
// only the voxels it owns; at each scene version every render rank works out which voxels each
// exchanged brick's renderer reads (renderers::scivis::neededVoxels, the rule `dfbwall --ghost
// reach` loads files by) and the ranks send each other exactly the parts of their owned boxes
// that another brick needs, point to point over the render ranks' communicator.
#include <mpi.h>

#include <cstddef>
#include <vector>

#include "api/DataDistributed.h"
#include "base/Collectives.h"
#include "renderers/Volume.h"
#include "renderers/scivis/bricks/BrickLoad.h"

namespace dfbwall {

// A volume part given with Ghosts::Exchange: the held brick `brick` (by id) holds at least the
// voxels of `owned` of volume `volume`.
struct OwnedPart {
  int brick = 0;
  std::size_t volume = 0;
  renderers::VoxelBox owned;
};

// Collective over `comm` (every render rank, at every scene version, with or without parts):
// grows each of `parts`' volumes in `bricks` to the voxels its renderer reads, the ghosts
// received from the bricks that own them. Returns the bytes this rank received from others.
// Throws InputError alike on every rank when the owned boxes of a volume overlap, leave a gap
// in its field, or differ in voxel type (naming the bricks, their boxes and render ranks);
// base::DeadlineError when a rank does not join within `bound`.
std::size_t exchangeGhosts(const Style& style, std::vector<renderers::scivis::HeldBrick>& bricks,
                           const std::vector<OwnedPart>& parts, MPI_Comm comm,
                           const base::Bound& bound);

}  // namespace dfbwall
