#include "renderers/scivis/VolumeField.h"

#include <algorithm>
#include <limits>

#include "renderers/Error.h"
#include "renderers/Parallel.h"

namespace renderers {
FieldGeometry::FieldGeometry(const GridGeometry& grid, const VoxelBox& box)
    : grid_(grid), box_(box) {
  const Index3 n = box.size();
  if (n.x < 2 || n.y < 2 || n.z < 2)
    throw Error("a volume brick needs at least 2 voxels per axis to interpolate");
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
  strideZ_ = static_cast<std::size_t>(n.x) * static_cast<std::size_t>(n.y);
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

VolumeField::VolumeField(const Volume& volume)
    : FieldGeometry(volume.grid, volume.box), volume_(&volume) {
  strideZ_ = volume.sliceStride();
  const VoxelBox& b = volume.box;
  parallelFor(static_cast<std::size_t>(macroCells_.z), [&](std::size_t zIndex) {
    const int mz = static_cast<int>(zIndex);
    for (int my = 0; my < macroCells_.y; ++my)
      for (int mx = 0; mx < macroCells_.x; ++mx) {
        const std::size_t m =
            static_cast<std::size_t>(mx) +
            static_cast<std::size_t>(macroCells_.x) *
                (static_cast<std::size_t>(my) + static_cast<std::size_t>(macroCells_.y) * mz);
        const Index3 c0 = macroOrigin(static_cast<int>(m));
        float lo = std::numeric_limits<float>::infinity(), hi = -lo;
        for (int z = std::max(c0.z, b.lo.z); z <= std::min(c0.z + kMacro, b.hi.z - 1); ++z)
          for (int y = std::max(c0.y, b.lo.y); y <= std::min(c0.y + kMacro, b.hi.y - 1); ++y)
            for (int x = std::max(c0.x, b.lo.x); x <= std::min(c0.x + kMacro, b.hi.x - 1); ++x) {
              const float v = volume.at(x, y, z);
              lo = std::min(lo, v), hi = std::max(hi, v);
            }
        macroMin_[m] = lo, macroMax_[m] = hi;
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

}  // namespace renderers
