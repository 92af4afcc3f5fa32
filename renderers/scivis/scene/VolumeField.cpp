#include "renderers/scivis/scene/VolumeField.h"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

#include "base/Error.h"
#include "base/Parallel.h"

namespace renderers::scivis {
FieldGeometry::FieldGeometry(const GridGeometry& grid, const VoxelBox& box, std::size_t sliceStride)
    : grid_(grid), box_(box) {
  const Index3 n = box.size();
  if (n.x < 2 || n.y < 2 || n.z < 2)
    throw base::Error("a volume brick needs at least 2 voxels per axis to interpolate");
  const GridGeometry& g = grid;
  const VoxelBox& b = box;
  origin_ = g.origin;
  invSpacing_ = {1.0f / g.spacing.x, 1.0f / g.spacing.y, 1.0f / g.spacing.z};
  first_ = b.lo;
  lastCell_ = {b.hi.x - 2, b.hi.y - 2, b.hi.z - 2};
  lo_ = {static_cast<float>(b.lo.x), static_cast<float>(b.lo.y), static_cast<float>(b.lo.z)};
  hi_ = {static_cast<float>(b.hi.x - 1), static_cast<float>(b.hi.y - 1),
         static_cast<float>(b.hi.z - 1)};
  strideY_ = static_cast<std::size_t>(n.x);
  strideZ_ =
      sliceStride > 0 ? sliceStride : static_cast<std::size_t>(n.x) * static_cast<std::size_t>(n.y);
  bounds_.lo = g.worldOf(lo_.x, lo_.y, lo_.z);
  bounds_.hi = g.worldOf(hi_.x, hi_.y, hi_.z);

  // Macrocells lie on the whole field's grid: macrocell (mx, my, mz) covers the cells
  // [8 mx, 8 mx + 8) and so the voxels [8 mx, 8 mx + 8] (its far face included). Those of the
  // held box are numbered from the one holding its first cell.
  macroFirst_ = {b.lo.x / kMacro, b.lo.y / kMacro, b.lo.z / kMacro};
  macroCells_ = {lastCell_.x / kMacro - macroFirst_.x + 1, lastCell_.y / kMacro - macroFirst_.y + 1,
                 lastCell_.z / kMacro - macroFirst_.z + 1};
  const std::size_t count = static_cast<std::size_t>(macroCells_.x) * macroCells_.y * macroCells_.z;
  macroMin_.assign(count, 0.0f);
  macroMax_.assign(count, 0.0f);
}

Index3 FieldGeometry::macroOrigin(int m) const {
  const int mx = m % macroCells_.x, my = (m / macroCells_.x) % macroCells_.y,
            mz = m / (macroCells_.x * macroCells_.y);
  return {(macroFirst_.x + mx) * kMacro, (macroFirst_.y + my) * kMacro,
          (macroFirst_.z + mz) * kMacro};
}

namespace {

// The voxels (held indices, both ends included) each macrocell's range covers along one axis:
// macrocell m of `cells` on the whole field's grid from macrocell `first`, its far face included.
struct MacroSpans {
  std::vector<int> from, to;
  MacroSpans(int first, int cells, int lo, int hi) {  // lo, hi: the held voxels [lo, hi)
    for (int m = 0; m < cells; ++m) {
      const int c0 = (first + m) * FieldGeometry::kMacro;
      from.push_back(std::max(c0, lo) - lo);
      to.push_back(std::min(c0 + FieldGeometry::kMacro, hi - 1) - lo);
    }
  }
};

// Each macrocell's value range over one slab of macrocells (mz), NaN voxels left out: a row's
// spans first (independent short chains of min / max, which the core overlaps), then the rows'
// ranges over each macrocell's rows. (Volume::at() voxel by voxel, one chain a macrocell, took a
// third of the time of loading a 512³ float volume.)
template <class T>
void slabRanges(const T* voxels, std::size_t strideY, std::size_t strideZ, const MacroSpans& x,
                const MacroSpans& y, int z0, int z1, float* lo, float* hi) {
  const std::size_t cellsX = x.from.size(), rows = static_cast<std::size_t>(y.to.back()) + 1;
  constexpr float kInf = std::numeric_limits<float>::infinity();
  std::vector<float> rowLo(rows * cellsX, kInf), rowHi(rows * cellsX, -kInf);
  for (int z = z0; z <= z1; ++z)
    for (std::size_t r = 0; r < rows; ++r) {
      const T* row = voxels + static_cast<std::size_t>(z) * strideZ + r * strideY;
      float* l = &rowLo[r * cellsX];
      float* h = &rowHi[r * cellsX];
      for (std::size_t m = 0; m < cellsX; ++m) {
        float a = l[m], b = h[m];
        for (int i = x.from[m]; i <= x.to[m]; ++i) {
          const float v = static_cast<float>(row[i]);
          a = std::min(a, v), b = std::max(b, v);
        }
        l[m] = a, h[m] = b;
      }
    }
  for (std::size_t my = 0; my < y.from.size(); ++my)
    for (std::size_t m = 0; m < cellsX; ++m) {
      float a = kInf, b = -kInf;
      for (int r = y.from[my]; r <= y.to[my]; ++r) {
        a = std::min(a, rowLo[static_cast<std::size_t>(r) * cellsX + m]);
        b = std::max(b, rowHi[static_cast<std::size_t>(r) * cellsX + m]);
      }
      lo[my * cellsX + m] = a, hi[my * cellsX + m] = b;
    }
}

}  // namespace

VolumeField::VolumeField(const Volume& volume)
    : FieldGeometry(volume.grid, volume.box, volume.sliceStride()), volume_(&volume) {
  const VoxelBox& b = volume.box;
  const MacroSpans x(macroFirst_.x, macroCells_.x, b.lo.x, b.hi.x);
  const MacroSpans y(macroFirst_.y, macroCells_.y, b.lo.y, b.hi.y);
  const MacroSpans z(macroFirst_.z, macroCells_.z, b.lo.z, b.hi.z);
  const std::size_t slab = static_cast<std::size_t>(macroCells_.x) * macroCells_.y;
  base::parallelFor(static_cast<std::size_t>(macroCells_.z), [&](std::size_t mz) {
    float* lo = &macroMin_[mz * slab];
    float* hi = &macroMax_[mz * slab];
    const int z0 = z.from[mz], z1 = z.to[mz];
    const std::byte* voxels = volume.data();
    switch (volume.type) {
      case VoxelType::Float32:
        slabRanges(reinterpret_cast<const float*>(voxels), strideY_, strideZ_, x, y, z0, z1, lo,
                   hi);
        break;
      case VoxelType::UInt8:
        slabRanges(reinterpret_cast<const std::uint8_t*>(voxels), strideY_, strideZ_, x, y, z0, z1,
                   lo, hi);
        break;
      case VoxelType::UInt16:
        slabRanges(reinterpret_cast<const std::uint16_t*>(voxels), strideY_, strideZ_, x, y, z0, z1,
                   lo, hi);
        break;
    }
  });
}

int FieldGeometry::macroIndex(Vec3 p) const {
  const float fx = (p.x - origin_.x) * invSpacing_.x, fy = (p.y - origin_.y) * invSpacing_.y,
              fz = (p.z - origin_.z) * invSpacing_.z;
  if (!(fx >= lo_.x && fy >= lo_.y && fz >= lo_.z && fx <= hi_.x && fy <= hi_.y && fz <= hi_.z))
    return -1;
  const int mx = std::min(static_cast<int>(fx), lastCell_.x) / kMacro - macroFirst_.x;
  const int my = std::min(static_cast<int>(fy), lastCell_.y) / kMacro - macroFirst_.y;
  const int mz = std::min(static_cast<int>(fz), lastCell_.z) / kMacro - macroFirst_.z;
  return mx + macroCells_.x * (my + macroCells_.y * mz);
}

Box3 FieldGeometry::macroBounds(int m) const {
  const int mx = m % macroCells_.x, my = (m / macroCells_.x) % macroCells_.y,
            mz = m / (macroCells_.x * macroCells_.y);
  const GridGeometry& g = grid_;
  // Clamped to the held voxels: outside them the field is not here at all.
  auto lo = [&](int cell, int first) { return static_cast<float>(std::max(cell * kMacro, first)); };
  auto hi = [&](int cell, int last) {
    return static_cast<float>(std::min((cell + 1) * kMacro, last));
  };
  Box3 b;
  b.lo = g.worldOf(lo(macroFirst_.x + mx, first_.x), lo(macroFirst_.y + my, first_.y),
                   lo(macroFirst_.z + mz, first_.z));
  b.hi = g.worldOf(hi(macroFirst_.x + mx, lastCell_.x + 1), hi(macroFirst_.y + my, lastCell_.y + 1),
                   hi(macroFirst_.z + mz, lastCell_.z + 1));
  return b;
}

}  // namespace renderers::scivis
