#pragma once
// No work behind a nearer brick's opaque surface (sort-last, BrickFrameDriver): what every rank
// knows of every brick's opaque isosurfaces, small enough to exchange once with the bounds, so a
// farther brick's rank can tell, ray by ray and without waiting for anyone, that a nearer brick
// certainly composites alpha 1 in front of it; then its own fragment adds nothing (the
// compositor multiplies it by 1 - 1 = 0) and the ray is not traced. Exact, bit for bit.
//
// Why it is certain: marching-cubes triangles (Isosurfaces.h) separate a brick's cells into the
// side above and the side below each isovalue, and a cell whose 8 voxels are all strictly below
// (above) holds no triangle, not even touching it. So a ray whose piece in the brick starts in
// such a cell and ends in one strictly on the other side crosses the isosurface inside the piece,
// and with watertight triangles (Embree's robust mode) the brick's renderer finds that hit. The
// summary holds, per isovalue and per face of each brick, the cells along the face (two cells
// deep) that lie wholly on one side, eroded by a cell in the face's plane, so a rounded entry or
// exit point still lies in such a region and the crossing is at least a cell away from both ends
// of the piece (far beyond float rounding of Embree's hit distance).
//
// When it applies (exactFor): one sample per pixel a frame, no visible volume and every material
// opaque, so every fragment's alpha is exactly 0 or 1 and the first opaque one in depth order
// makes the composited alpha exactly 1.
#include <mpi.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <vector>

#include "renderers/SceneDesc.h"
#include "renderers/scivis/bricks/Bricks.h"
#include "renderers/scivis/scene/SciVisScene.h"

namespace renderers::scivis {

class BrickOcclusion {
 public:
  // Whether an opaque crossing makes a fragment's alpha exactly 1 for `desc`: no volume drawn,
  // every material's opacity 1, at least one isosurface (else there is nothing to find).
  static bool exactFor(const SceneDesc& desc);

  BrickOcclusion();
  ~BrickOcclusion();
  BrickOcclusion(BrickOcclusion&&) noexcept;
  BrickOcclusion& operator=(BrickOcclusion&&) noexcept;

  // Collective over `comm`: every rank summarises the bricks it holds (`held`: id and content;
  // a brick held twice is summarised by each holder alike) and gets every brick's summary, in
  // the order of `bricks` (the directory's, ascending ids). One base::allgatherv, each of its
  // waits bounded by `timeout`.
  static BrickOcclusion exchange(const SceneDesc& desc, const std::vector<BrickPlan>& bricks,
                                 const std::vector<std::pair<int, const BrickContent*>>& held,
                                 MPI_Comm comm, std::chrono::milliseconds timeout);
  // The summary of one brick's content (what exchange() sends): pure, for tests.
  static std::vector<std::uint8_t> summarise(const SceneDesc& desc, const BrickContent& content);

  // Whether origin + t dir enters brick `brick` before `before` (at `before` too when
  // `winsTie`) and its piece [t0, t1] there (t0 < t1: the ray clipped to the brick's bounds by
  // clipToBox from [0, inf), as the brick's renderer clips it) certainly crosses an isosurface
  // inside the brick. False when unsure. One pass over the slabs gives the piece and the faces
  // it enters and leaves by.
  bool hides(int brick, Vec3 origin, Vec3 dir, Vec3 invDir, float before, bool winsTie) const;
  std::size_t bytes() const;  // the summaries held

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace renderers::scivis
