#pragma once
// The ghost shell of one volume for a brick's shading rays (--ghost reach), held sparsely.
//
// In a volume only isosurfaces stop shading rays, and they are triangles polygonised from the
// cells of macrocells whose value range holds an isovalue (SciVisScene, Isosurfaces.h). So a
// brick needs, as far as its shading rays reach, the value range of every macrocell and the
// voxels of just those macrocells whose range holds an isovalue (on the whole field's macrocell
// grid) — and of those only the voxels of cells its dense core does not hold: cells inside the
// core are read from the core. Everything else is the geometry of a dense VolumeField over the
// same box (FieldGeometry: the same box, macrocells, ranges and arithmetic), so sample() gives
// the same bits as the whole box held densely.
//
// Plain data (copyable); every const method is thread-safe. Voxels are kept as float32.
#include <cstdint>
#include <functional>
#include <vector>

#include "renderers/scivis/io/VolumeLoad.h"
#include "renderers/scivis/scene/VolumeField.h"

namespace renderers::scivis {

class ShadingShell : public FieldGeometry {
 public:
  ShadingShell() = default;  // empty: no shell (shading rays use the dense volume)

  // `box` of `source` (at least 2 voxels per axis), read one layer of macrocells at a time, so
  // no more than that layer of the box is ever held densely; per macrocell whose value range
  // holds one of `isovalues` and that shading rays reach (`reached(world bounds)` of it: the
  // box may be a region's bounding box, its shading rays reaching only part of it), the voxels
  // of the bounding box of its cells that shading rays reach and that do not lie inside `core`
  // (the brick's dense voxels, a sub-box of `box`; may be empty). A shading ray must not
  // sample a cell that is not reached.
  static ShadingShell load(const VolumeSource& source, const VoxelBox& box, const VoxelBox& core,
                           const std::vector<float>& isovalues,
                           const std::function<bool(const Box3&)>& reached);

  bool empty() const { return macroMin_.empty(); }
  std::size_t blockCount() const { return blocks_.size(); }
  std::size_t voxelCount() const { return voxels_.size(); }
  std::size_t bytes() const;  // ranges, block table and blocks

  // The dense core given to load (cells with all 8 voxels in it are read from there).
  const VoxelBox& core() const { return core_; }
  // Calls f(lo, size, voxels) for every block of voxels held: voxels [lo, lo + size) (whole-field
  // indices), x fastest (what the isosurface mesher reads).
  template <class F>
  void forEachBlock(F f) const {
    for (const Block& b : blocks_) f(b.lo, b.size, voxels_.data() + b.offset);
  }

  // The trilinear value at world point p, as VolumeField::sample over the dense box gives it
  // (cells inside the core from `core`, the dense field of the `core` box given to load); false
  // outside dataBounds(), in macrocells without voxels (no isovalue in their range, or not
  // reached), in cells not reached and where the value is missing (NaN).
  bool sample(Vec3 p, float& value, const VolumeField* core) const {
    Cell c;
    if (!locate(p, c)) return false;
    if (core && c.ix >= core_.lo.x && c.iy >= core_.lo.y && c.iz >= core_.lo.z &&
        c.ix + 1 < core_.hi.x && c.iy + 1 < core_.hi.y && c.iz + 1 < core_.hi.z)
      return core->sample(p, value);
    const std::int32_t b = block_[static_cast<std::size_t>(macroIndexOf(c))];
    if (b < 0) return false;
    const Block& k = blocks_[static_cast<std::size_t>(b)];
    if (c.ix < k.lo.x || c.iy < k.lo.y || c.iz < k.lo.z || c.ix + 1 >= k.lo.x + k.size.x ||
        c.iy + 1 >= k.lo.y + k.size.y || c.iz + 1 >= k.lo.z + k.size.z)
      return false;  // a cell shading rays do not reach
    const std::size_t sy = k.size.x, sz = sy * static_cast<std::size_t>(k.size.y);
    const float* v = voxels_.data() + k.offset + static_cast<std::size_t>(c.ix - k.lo.x) +
                     static_cast<std::size_t>(c.iy - k.lo.y) * sy +
                     static_cast<std::size_t>(c.iz - k.lo.z) * sz;
    const float corners[8] = {v[0],  v[1],      v[sy],      v[sy + 1],
                              v[sz], v[sz + 1], v[sz + sy], v[sz + sy + 1]};
    value = trilinear(corners, c.fx, c.fy, c.fz);
    return value == value;  // NaN: a missing value, as VolumeField::sample
  }

 private:
  // The voxels [lo, lo + size) of one macrocell, x fastest, at `offset` in voxels_.
  struct Block {
    std::size_t offset;
    Index3 lo, size;
  };

  ShadingShell(const GridGeometry& grid, const VoxelBox& box) : FieldGeometry(grid, box) {}

  VoxelBox core_;                    // cells with all 8 voxels in it are read from the core
  std::vector<std::int32_t> block_;  // per macrocell: its block, or -1
  std::vector<Block> blocks_;
  std::vector<float> voxels_;
};

}  // namespace renderers::scivis
