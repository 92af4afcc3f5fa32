#pragma once
// Isosurfaces as triangles: marching cubes over blocks of a scalar field's cells, vertices
// welded per edge (an indexed mesh), so rays find isosurfaces as they find any triangle.
//
// Every triangle lies in one cell and depends only on that cell's 8 voxel values and the
// isovalue: its vertices lie on the cell's edges, each computed from the edge's two voxels in
// the edge's own direction (low index first), and a cell's triangles come from one case table.
// So two bricks that polygonise the same cell make the same triangles, bit for bit, and the
// surface is closed across cells: an ambiguous face (two diagonal corners above, two below) is
// split the same way by both cells that share it (the corners above are kept apart). A cell with
// a NaN voxel (a missing value, see VolumeField.h) has no triangles: nothing is crossed there.
//
// Why here and not a library: VTK's filters need VTK's data model (a large dependency for one
// algorithm), and OpenVDB's volumeToMesh is a dual mesher over sparse trees whose quads span
// four cells and whose border depends on background values, so bricks would not make matching
// triangles. The case table is generated (not transcribed) from the rule above.
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "renderers/Volume.h"

namespace renderers::scivis {

struct IsoMesh {
  std::vector<Vec3> positions;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  std::size_t bytes() const {
    return positions.size() * sizeof(Vec3) + triangles.size() * sizeof(triangles[0]);
  }
};

// A block of cells to polygonise: cell (i, j, k) spans voxels i..i+1, j..j+1, k..k+1 (whole-field
// indices). Cells inside `skip` are left out (another mesh has them).
struct CellBlock {
  VoxelBox cells;  // [lo, hi) in cells
  VoxelBox skip;   // may be empty
  int source = 0;  // for the caller's voxel reader
};

// The voxels a block's cells read: (hi - lo + 1) per axis from cells.lo, x fastest, as floats.
using BlockReader = std::function<void(const CellBlock& block, float* voxels)>;

// One mesh per isovalue over `blocks` (cells of `grid`), triangles oriented so that their
// geometric normal (v1 - v0) x (v2 - v0) points towards higher values. Blocks are polygonised in
// parallel; the result does not depend on the thread count (vertices and triangles come in
// block order, then cell order). A voxel above the isovalue is one with value >= isovalue (NaN:
// below).
std::vector<IsoMesh> polygonise(const GridGeometry& grid, const std::vector<CellBlock>& blocks,
                                const std::vector<float>& isovalues, const BlockReader& read);

}  // namespace renderers::scivis
