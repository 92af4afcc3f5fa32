#include "renderers/scivis/ShadingShell.h"

#include <algorithm>
#include <limits>

namespace renderers {

ShadingShell ShadingShell::load(const VolumeSource& source, const VoxelBox& box,
                                const VoxelBox& core, const std::vector<float>& isovalues) {
  ShadingShell s(source.grid, box);
  s.core_ = core;
  s.block_.assign(s.macroMin_.size(), -1);
  const VoxelBox& b = box;
  for (int mz = 0; mz < s.macroCells_.z; ++mz) {
    // One layer of macrocells: the voxel planes its cells interpolate between (a macrocell's far
    // face is the next one's near face, read twice).
    const int z0 = std::max((s.macroFirst_.z + mz) * kMacro, b.lo.z);
    const int z1 = std::min((s.macroFirst_.z + mz) * kMacro + kMacro, b.hi.z - 1);
    const Volume layer = loadVolume(source, {{b.lo.x, b.lo.y, z0}, {b.hi.x, b.hi.y, z1 + 1}});
    for (int my = 0; my < s.macroCells_.y; ++my)
      for (int mx = 0; mx < s.macroCells_.x; ++mx) {
        const std::size_t m =
            static_cast<std::size_t>(mx) +
            static_cast<std::size_t>(s.macroCells_.x) *
                (static_cast<std::size_t>(my) + static_cast<std::size_t>(s.macroCells_.y) * mz);
        const Index3 c0 = s.macroOrigin(static_cast<int>(m));
        // The voxels VolumeField's range of this macrocell covers over the same box.
        const int x0 = std::max(c0.x, b.lo.x), x1 = std::min(c0.x + kMacro, b.hi.x - 1);
        const int y0 = std::max(c0.y, b.lo.y), y1 = std::min(c0.y + kMacro, b.hi.y - 1);
        float lo = std::numeric_limits<float>::infinity(), hi = -lo;
        for (int z = z0; z <= z1; ++z)
          for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x) {
              const float v = layer.at(x, y, z);
              lo = std::min(lo, v), hi = std::max(hi, v);
            }
        s.macroMin_[m] = lo, s.macroMax_[m] = hi;
        const bool holdsIsovalue = std::any_of(isovalues.begin(), isovalues.end(),
                                               [&](float iso) { return iso >= lo && iso <= hi; });
        if (!holdsIsovalue) continue;
        // The voxels of the macrocell's cells the core does not hold (all 8 voxels of a cell
        // inside the core: the core's field interpolates the same values in the same cell);
        // their bounding box.
        Index3 first{x1, y1, z1}, last{x0, y0, z0};
        for (int z = z0; z < z1; ++z)
          for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
              const bool inCore = !core.empty() && x >= core.lo.x && y >= core.lo.y &&
                                  z >= core.lo.z && x + 1 < core.hi.x && y + 1 < core.hi.y &&
                                  z + 1 < core.hi.z;
              if (inCore) continue;
              first = {std::min(first.x, x), std::min(first.y, y), std::min(first.z, z)};
              last = {std::max(last.x, x + 1), std::max(last.y, y + 1), std::max(last.z, z + 1)};
            }
        if (first.x > last.x) continue;  // every cell in the core
        const Block block{s.voxels_.size(),
                          first,
                          {last.x - first.x + 1, last.y - first.y + 1, last.z - first.z + 1}};
        s.block_[m] = static_cast<std::int32_t>(s.blocks_.size());
        s.blocks_.push_back(block);
        for (int z = first.z; z <= last.z; ++z)
          for (int y = first.y; y <= last.y; ++y)
            for (int x = first.x; x <= last.x; ++x) s.voxels_.push_back(layer.at(x, y, z));
      }
  }
  s.voxels_.shrink_to_fit();
  return s;
}

std::size_t ShadingShell::bytes() const {
  return macroMin_.size() * 2 * sizeof(float) + block_.size() * sizeof(std::int32_t) +
         blocks_.size() * sizeof(Block) + voxels_.size() * sizeof(float);
}

}  // namespace renderers
