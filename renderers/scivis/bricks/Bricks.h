#pragma once
// Data-parallel bricks of a scivis scene: the scene's domain cut by a k-d split, which ranks hold
// which brick, and loading one brick's data — only its voxels (plus ghost layers), the particles
// and triangles that reach into it, and the ghost data its shading rays can reach. Every function
// but exchangeBricks is pure.
//
// Who holds what is never planned globally: each rank says which bricks it holds (from
// loadOwnBricks, or a program's own data through api/DataDistributed.h) and exchangeBricks
// tells every rank every brick's bounds and holders, once per scene change.
#include <mpi.h>

#include <chrono>
#include <string>
#include <vector>

#include "renderers/SceneDesc.h"
#include "renderers/scivis/scene/SciVisScene.h"

namespace renderers {

struct BrickPlan {
  int id = 0;
  Box3 bounds;  // bricks tile the domain; camera rays are clipped to them
};

// sceneDomain (the bounds of everything in the scene): SciVisScene.h.
// `bounds` with the faces it shares with `domain`'s boundary pushed to infinity: where a brick's
// camera rays take first hits from the raster (FirstHitRaster.h) as the unbricked scene, which
// clips no ray at the domain's boundary, does; between bricks the split stays `bounds`'.
Box3 openAtDomainBoundary(const Box3& bounds, const Box3& domain);

// `count` bricks: the domain halved (in brick counts) along its longest axis, recursively, at
// the plane that gives each side its share of the volume; where axes are nearly as long (within
// 10%), along the one nearest the scene camera's up direction, then across its view, so the
// bricks' screen footprints overlap least. Ids are 0 .. count-1 in k-d order.
std::vector<BrickPlan> splitScene(const SceneDesc& desc, int count);

// The ranks holding brick `brick`: `replication` consecutive slots of brick * replication, wrapped
// over `ranks` (so every rank holds about count * replication / ranks bricks).
std::vector<int> brickHolders(int brick, int ranks, int replication);

// How much ghost data a brick loads around its bounds (--ghost).
enum class GhostMode {
  // Everything its shading rays can reach: within the ambient-occlusion distance, and the
  // brick swept towards each light that casts shadows, to the domain's boundary. A brick shades
  // its points exactly as the whole scene does, at the price of those regions (held sparsely).
  Reach,
  // One ghost layer: only the voxels that interpolation, gradients and the brick's isosurface
  // cells need at the brick's faces, no ghost particles or triangles. Shading rays see the
  // brick's own data and that layer (as OSPRay's distributed renderer), so AO and shadows near
  // brick faces differ (seams), and no shadow falls from one brick into another.
  Layer,
};
// "reach" / "layer"; ghostModeFromName throws base::Error naming the choices otherwise.
const char* ghostModeName(GhostMode mode);
GhostMode ghostModeFromName(const std::string& name);

// How far a brick's ambient-occlusion rays reach beyond its bounds (world units; the voxel
// layer comes on top): with GhostMode::Reach the ambient-occlusion distance when AO is on,
// else 0.
float ghostMargin(const SceneDesc& desc, float sceneExtent, GhostMode mode = GhostMode::Reach);

// Where a brick's shading rays go beyond its bounds: AO rays up to `margin`, shadow rays from
// the brick towards each of `lights` until they leave `domain`. Load-time only: live settings
// change neither lights nor isovalues.
struct GhostReach {
  float margin = 0;
  std::vector<ResolvedLight> lights;  // directional and point lights, when shadows are on
  Box3 domain{Vec3{Box3::kInf}, Vec3{-Box3::kInf}};  // sceneDomain(): nothing beyond it
};
// The reach of every brick of `desc` with `mode` (GhostMode::Layer: nothing).
GhostReach ghostReach(const SceneDesc& desc, GhostMode mode = GhostMode::Reach);

// The data of `plan`: per volume the voxels around its bounds and two beyond them (dense), and
// as far as `reach` goes, for shading rays, a ShadingShell (sparse: only macrocells holding an
// isovalue that those rays reach) or the dense bounding box when that is smaller; particles
// and mesh triangles reaching into the bounds (drawn, clipped to them) and, as ghost data,
// those that shading rays reach.
// An allocation that fails is reported as base::Error naming the volume (or the particles
// and triangles) it was loading.
BrickContent loadBrick(const SceneDesc& desc, const BrickPlan& plan, const GhostReach& reach);

// The memory budget of loading `plans` with `reach` (dfb/MemoryBudget.h): what loadBrick holds
// for them at most — dense voxel boxes with their ghost layers and macrocells, ghost shells
// counted both sparse and dense, the particles and triangles they reach — with the scene
// description itself. Throws base::Error before anything is loaded when that is more than
// this rank may hold, naming the volume that asks most (its file, line and field, e.g.
// "scene.toml:7: volume 'ct'.dims: ...") or the particles and triangles, and the bytes.
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

// Every brick of the job, by ascending id, and the ranks of `comm` holding each (ascending).
struct BrickDirectory {
  std::vector<BrickPlan> bricks;
  std::vector<std::vector<int>> holders;  // per entry of `bricks`
};

// Collective over `comm`: every rank gives the bricks it holds (id and clip bounds), every rank
// gets the whole directory (one MPI_Iallgatherv, bounded by `timeout`). Throws base::Error
// when ranks disagree about a brick's bounds, an id is negative, or no rank holds any brick.
BrickDirectory exchangeBricks(const std::vector<BrickPlan>& mine, MPI_Comm comm,
                              std::chrono::milliseconds timeout);

}  // namespace renderers
