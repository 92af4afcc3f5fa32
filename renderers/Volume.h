#pragma once
// Structured scalar volumes: a regular grid of voxels (float32, uint8 or uint16) placed in the
// world by an origin and a spacing, of which a Volume holds any sub-box. A rank that renders one
// brick of a field holds only that brick's voxels plus its ghost layers, never the whole field.
//
// Coordinates: voxel (i, j, k) of the whole field sits at world point origin + spacing * (i, j, k)
// (vertex-centred, as VTK's image data). Boxes are half-open voxel index ranges over the whole
// field; voxels are stored x fastest, then y, then z, over the held box.
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "renderers/Math.h"

namespace renderers {

enum class VoxelType { Float32, UInt8, UInt16 };
std::size_t voxelBytes(VoxelType type);
const char* voxelTypeName(VoxelType type);  // "float32", "uint8", "uint16"

struct Index3 {
  int x = 0, y = 0, z = 0;
  constexpr int operator[](int a) const { return a == 0 ? x : (a == 1 ? y : z); }
  constexpr bool operator==(const Index3&) const = default;
};

// [lo, hi) in voxel indices of the whole field.
struct VoxelBox {
  Index3 lo, hi;
  bool empty() const { return hi.x <= lo.x || hi.y <= lo.y || hi.z <= lo.z; }
  std::size_t voxelCount() const;
  Index3 size() const { return {hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}; }
  bool contains(const VoxelBox& other) const;
  bool operator==(const VoxelBox&) const = default;
};

// The whole field's grid and where it sits in the world.
struct GridGeometry {
  Index3 dims;  // voxels per axis, each >= 2
  Vec3 origin;  // world position of voxel (0, 0, 0)
  Vec3 spacing{1.0f};
  VoxelBox wholeBox() const { return {{0, 0, 0}, dims}; }
  Vec3 worldOf(float i, float j, float k) const {
    return {origin.x + spacing.x * i, origin.y + spacing.y * j, origin.z + spacing.z * k};
  }
  // World-space bounds of the voxel centres of `box` (the region trilinear samples cover).
  void bounds(const VoxelBox& box, Vec3& lo, Vec3& hi) const;
  // Why the renderer cannot place this grid's voxels in float, or empty: each axis needs at
  // least 2 voxels, a normal positive spacing, a far corner (origin + spacing (dims - 1)) within
  // the float range, and voxels at least 4 float steps apart at the grid's coordinates (else
  // neighbours share positions and interpolating between them means nothing). Names the field:
  // "spacing along y, 1e-30, is below float precision ...". Every volume reader calls it.
  std::string problem() const;
};

// The voxels of one volume, held (`voxels`) or borrowed from the program that made them
// (`borrowed`, the data-distributed API's zero-copy bricks). Plain data: copyable (a copy of a
// borrowed volume borrows the same voxels), movable, no hidden state.
struct Volume {
  GridGeometry grid;
  VoxelBox box;  // the voxels (a sub-box of grid.wholeBox())
  VoxelType type = VoxelType::Float32;
  // x fastest, then y, then z: slices of sliceVoxels() voxels, sliceStride() voxels apart (each
  // slice followed by slicePadding voxels no one reads; none until spreadSlices()).
  std::vector<std::byte> voxels;
  // When set, the voxels are read here instead (dense, `voxels` empty): memory this Volume does
  // not own, kept alive by the pointer's owner (none: its lender's promise). Renderers read
  // data(), never `voxels`, so either works.
  std::shared_ptr<const std::byte> borrowed;
  std::size_t borrowedBytes = 0;
  std::size_t slicePadding = 0;
  float valueMin = 0, valueMax = 0;  // over the voxels

  // The value of voxel (i, j, k), given in whole-field indices inside `box`.
  float at(int i, int j, int k) const;
  const std::byte* data() const { return borrowed ? borrowed.get() : voxels.data(); }
  std::size_t dataBytes() const { return borrowed ? borrowedBytes : voxels.size(); }
  std::size_t bytes() const { return voxels.size(); }  // held: a borrowed volume holds none
  std::size_t sliceVoxels() const;
  std::size_t sliceStride() const { return sliceVoxels() + slicePadding; }
  // Recomputes valueMin / valueMax from the voxels.
  void updateRange();
  // Lays densely stored slices slicePaddingFor(box, type) voxels apart (nothing else changes: the
  // same values at the same indices). Where a slice is a multiple of 1 KiB (256², 512², any
  // power-of-two slice), the same rows of neighbouring slices map onto the same few sets of the
  // L1 cache (one way spans 4 KiB), and the march's 16 rays, crossing slices, evict each
  // other's voxels. In place when the buffer came from allocateVoxelBytes (its capacity holds
  // the padding); borrowed voxels are left as they are.
  void spreadSlices();
};

// The padding spreadSlices() puts after each slice of `box` voxels of `type`: one cache line
// where the slice's bytes are a multiple of 1 KiB, else none.
std::size_t slicePaddingFor(const VoxelBox& box, VoxelType type);

// Zeroed bytes for the dense voxels of `box` as `type` (Volume::voxels), with capacity for
// spreadSlices() to pad them without moving the buffer. Large buffers ask the kernel for
// transparent huge pages first (madvise): with 4 KiB pages the first-touch page faults were most
// of the time of making a 256³ volume here (0.29 s of CPU against 0.10 s).
std::vector<std::byte> allocateVoxelBytes(const VoxelBox& box, VoxelType type);

}  // namespace renderers
