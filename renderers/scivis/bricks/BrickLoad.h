#pragma once
// Loading a brick's data: only its voxels (plus ghost layers), the particles and triangles that
// reach into it, and the ghost data its shading rays can reach, its memory checked first. Pure.
#include <vector>

#include "renderers/SceneDesc.h"
#include "renderers/scivis/bricks/BrickPlan.h"
#include "renderers/scivis/bricks/Bricks.h"
#include "renderers/scivis/scene/SciVisScene.h"

namespace renderers::scivis {

// The data of `plan`: per volume the voxels around its bounds and two beyond them (dense), and
// as far as `reach` goes, for shading rays, a ShadingShell (sparse: only macrocells holding an
// isovalue that those rays reach) or the dense bounding box when that is smaller; particles
// and mesh triangles reaching into the bounds (drawn, clipped to them) and, as ghost data,
// those that shading rays reach.
// An allocation that fails is reported as base::Error naming the volume (or the particles
// and triangles) it was loading.
BrickContent loadBrick(const SceneDesc& desc, const BrickPlan& plan, const GhostReach& reach);

// The voxels of volume `volume` that a brick with clip bounds `bounds` holds densely when it
// holds them as one box (what loadBrick holds when its shell is dense): around the bounds, two
// beyond them, and where the volume has isosurfaces and `reach` leaves the bounds, the whole
// macrocells of the region its shading rays reach. Empty when that is under 2 voxels on an axis.
// The data-distributed API's ghost exchange asks its neighbours for these (api/GhostExchange.h).
VoxelBox neededVoxels(const SceneDesc& desc, std::size_t volume, const Box3& bounds,
                      const GhostReach& reach);

// The memory budget of loading `plans` with `reach` (base/MemoryBudget.h): what loadBrick holds
// for them at most — dense voxel boxes with their ghost layers and macrocells, ghost shells
// counted both sparse and dense, the particles and triangles they reach — with the scene
// description itself. Throws base::Error before anything is loaded when that is more than
// this rank may hold, naming the volume that asks most (its file, line and field, e.g.
// "scene.toml:7:8: volume 'ct'.dims: ...") or the particles and triangles, and the bytes.
// loadOwnBricks and wholeScene check this themselves.
void checkBrickMemory(const SceneDesc& desc, const std::vector<BrickPlan>& plans,
                      const GhostReach& reach);
// The same for the bricks loadOwnBricks(desc, bricks, replication, rank, ranks, ghosts) loads,
// for a program that wants to know at setup, before the frames start.
void checkOwnBricksMemory(const SceneDesc& desc, int bricks, int replication, int rank, int ranks,
                          GhostMode ghosts = GhostMode::Reach);

// The whole scene as one brick: every volume loaded whole, every particle and mesh (its memory
// checked first).
BrickContent wholeScene(const SceneDesc& desc);

// One brick a rank holds: its id (every rank holding an id holds the same data) and its data;
// content.bounds are the brick's clip bounds.
struct HeldBrick {
  int id = 0;
  BrickContent content;
};

// --bricks N --replication K --ghost MODE: the bricks of `desc` that render rank `rank` of
// `ranks` holds, loaded (only their own voxels, particles and triangles, and `ghosts` around).
std::vector<HeldBrick> loadOwnBricks(const SceneDesc& desc, int bricks, int replication, int rank,
                                     int ranks, GhostMode ghosts = GhostMode::Reach);

}  // namespace renderers::scivis
