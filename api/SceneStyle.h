#pragma once
// The API's plain structs (api/DataDistributed.h) turned into the renderer's: a Style into the
// SceneDesc every render rank shares, a Brick into the BrickContent one rank holds.
#include <mpi.h>

#include <chrono>
#include <cstdint>
#include <vector>

#include "api/DataDistributed.h"
#include "renderers/SceneDesc.h"
#include "renderers/scivis/bricks/BrickLoad.h"

namespace dfbwall {

// Copies the brick's data. Throws std::runtime_error naming the brick and the field for data
// that does not fit the style (a voxel box outside its field, radii that do not match, ...).
renderers::scivis::BrickContent brickContent(const Style& style, const Brick& brick);

// Materials: 0 the particles, 1 the meshes, 2 + i isosurface i. Collective over `renderComm`
// when a volume asks for autoRange (the value range over every rank's voxels, one allreduce).
renderers::SceneDesc sceneDesc(const Style& style,
                               const std::vector<renderers::scivis::HeldBrick>& mine,
                               MPI_Comm renderComm, std::chrono::milliseconds timeout);

// FNV-1a over a canonical serialisation of every field of the style (sizes and string lengths
// included, floats by their bits, little-endian integers): the same on every rank for the same
// style, whatever the platform's padding. The render ranks compare it at every scene version.
std::uint64_t styleHash(const Style& style);

}  // namespace dfbwall
