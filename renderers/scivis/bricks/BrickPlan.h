#pragma once
// Planning the bricks of a scivis scene: the k-d split of its domain, which ranks hold which brick,
// and how far beyond its bounds a brick's shading rays reach (the ghost data it loads). Pure.
#include <algorithm>
#include <string>
#include <vector>

#include "renderers/SceneDesc.h"
#include "renderers/scivis/bricks/Bricks.h"
#include "renderers/scivis/scene/SciVisScene.h"

namespace renderers::scivis {

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

// The plans rank `rank` holds.
std::vector<BrickPlan> ownPlans(const SceneDesc& desc, int bricks, int replication, int rank,
                                int ranks);

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

// One brick's reach, for loading its ghost data and counting its memory (BrickLoad.cpp).

// Whether `a` meets the box [lo, hi] (touching counts).
inline bool overlaps(const Box3& a, Vec3 lo, Vec3 hi) {
  return lo.x <= a.hi.x && hi.x >= a.lo.x && lo.y <= a.hi.y && hi.y >= a.lo.y && lo.z <= a.hi.z &&
         hi.z >= a.lo.z;
}

// The boxes [from.lo + s dLo, from.hi + s dHi] for s in [0, sMax], together: every point a
// shadow ray from `from` passes on its way to a light. Towards a directional light d: dLo = dHi
// = d (the box swept along it); towards a point light in box L: dLo = L.lo - from.lo, dHi =
// L.hi - from.hi, sMax = 1 (each point of `from` joined to each of L: the convex hull).
struct SweptBox {
  Box3 from;
  Vec3 dLo, dHi;
  float sMax = 0;

  Box3 bounds() const {
    Box3 b = from;
    grow(b, from.lo + dLo * sMax, from.hi + dHi * sMax);
    return b;
  }
  // Whether [lo, hi] meets one of the boxes: per axis, two linear conditions on s.
  bool overlaps(Vec3 lo, Vec3 hi) const {
    float s0 = 0, s1 = sMax;
    // a + s b <= 0 for some s in [s0, s1].
    auto keep = [&](float a, float b) {
      if (b > 0)
        s1 = std::min(s1, -a / b);
      else if (b < 0)
        s0 = std::max(s0, -a / b);
      else if (a > 0)
        s1 = -1;
    };
    for (int a = 0; a < 3; ++a) {
      keep(from.lo[a] - hi[a], dLo[a]);   // the moving box's low face below hi
      keep(lo[a] - from.hi[a], -dHi[a]);  // its high face above lo
    }
    return s0 <= s1;
  }
};

// Where one brick's shading rays go beyond its bounds (from its GhostReach): ambient-occlusion
// rays within `around`, shadow rays along `sweeps`; `region` bounds both.
struct BrickReach {
  Box3 around, region;
  std::vector<SweptBox> sweeps;
  bool beyond = false;  // whether they leave the bounds at all
  bool reached(Vec3 lo, Vec3 hi) const {
    if (overlaps(around, lo, hi)) return true;
    for (const SweptBox& s : sweeps)
      if (s.overlaps(lo, hi)) return true;
    return false;
  }
};
// The reach of the brick with `bounds`.
BrickReach brickReach(const SceneDesc& desc, const Box3& bounds, const GhostReach& reach);

}  // namespace renderers::scivis
