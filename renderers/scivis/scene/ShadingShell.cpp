#include "renderers/scivis/scene/ShadingShell.h"

#include <algorithm>
#include <limits>

namespace renderers::scivis {

ShadingShell ShadingShell::load(const VolumeSource& source, const VoxelBox& box,
                                const VoxelBox& core, const std::vector<float>& isovalues,
                                const std::function<bool(const Box3&)>& reached) {
  ShadingShell s(source.grid, box);
  s.core_ = core;
  s.block_.assign(s.macroMin_.size(), -1);
  const VoxelBox& b = box;
  // One layer of macrocells at a time: the voxel planes its cells interpolate between (a
  // macrocell's far face is the next one's near face, read twice).
  auto layerBox = [&](int mz) {
    const int z0 = std::max((s.macroFirst_.z + mz) * kMacro, b.lo.z);
    const int z1 = std::min((s.macroFirst_.z + mz) * kMacro + kMacro, b.hi.z - 1);
    return VoxelBox{{b.lo.x, b.lo.y, z0}, {b.hi.x, b.hi.y, z1 + 1}};
  };
  auto index = [&](int mx, int my, int mz) {
    return static_cast<std::size_t>(mx) +
           static_cast<std::size_t>(s.macroCells_.x) *
               (static_cast<std::size_t>(my) + static_cast<std::size_t>(s.macroCells_.y) * mz);
  };
  // First pass: ranges, and which voxels each block needs. The voxels are copied in a second
  // pass into storage of exactly their size, so loading never holds more than the shell and
  // one layer (a growing buffer would leave up to twice the shell in the process's peak).
  std::size_t total = 0;
  for (int mz = 0; mz < s.macroCells_.z; ++mz) {
    const VoxelBox lb = layerBox(mz);
    const Volume layer = loadVolume(source, lb);
    for (int my = 0; my < s.macroCells_.y; ++my)
      for (int mx = 0; mx < s.macroCells_.x; ++mx) {
        const std::size_t m = index(mx, my, mz);
        const Index3 c0 = s.macroOrigin(static_cast<int>(m));
        // The voxels VolumeField's range of this macrocell covers over the same box.
        const int x0 = std::max(c0.x, b.lo.x), x1 = std::min(c0.x + kMacro, b.hi.x - 1);
        const int y0 = std::max(c0.y, b.lo.y), y1 = std::min(c0.y + kMacro, b.hi.y - 1);
        const int z0 = lb.lo.z, z1 = lb.hi.z - 1;
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
        if (!holdsIsovalue || !reached(s.macroBounds(static_cast<int>(m)))) continue;
        // The voxels of the macrocell's cells the core does not hold (all 8 voxels of a cell
        // inside the core: the core's field interpolates the same values in the same cell) and
        // shading rays reach; their bounding box (voxels first..last).
        const GridGeometry& g = source.grid;
        Index3 first{x1, y1, z1}, last{x0, y0, z0};
        for (int z = z0; z < z1; ++z)
          for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
              const bool inCore = !core.empty() && x >= core.lo.x && y >= core.lo.y &&
                                  z >= core.lo.z && x + 1 < core.hi.x && y + 1 < core.hi.y &&
                                  z + 1 < core.hi.z;
              if (inCore) continue;
              const auto i = [](int v) { return static_cast<float>(v); };
              if (!reached({g.worldOf(i(x), i(y), i(z)), g.worldOf(i(x + 1), i(y + 1), i(z + 1))}))
                continue;
              first = {std::min(first.x, x), std::min(first.y, y), std::min(first.z, z)};
              last = {std::max(last.x, x + 1), std::max(last.y, y + 1), std::max(last.z, z + 1)};
            }
        if (first.x > last.x) continue;  // every cell in the core
        const Index3 size{last.x - first.x + 1, last.y - first.y + 1, last.z - first.z + 1};
        s.block_[m] = static_cast<std::int32_t>(s.blocks_.size());
        s.blocks_.push_back({total, first, size});
        total += static_cast<std::size_t>(size.x) * static_cast<std::size_t>(size.y) *
                 static_cast<std::size_t>(size.z);
      }
  }
  s.blocks_.shrink_to_fit();
  // Second pass: the blocks' voxels, layer by layer.
  s.voxels_.assign(total, 0.0f);
  for (int mz = 0; mz < s.macroCells_.z; ++mz) {
    bool any = false;
    for (int my = 0; my < s.macroCells_.y && !any; ++my)
      for (int mx = 0; mx < s.macroCells_.x && !any; ++mx) any = s.block_[index(mx, my, mz)] >= 0;
    if (!any) continue;
    const Volume layer = loadVolume(source, layerBox(mz));
    for (int my = 0; my < s.macroCells_.y; ++my)
      for (int mx = 0; mx < s.macroCells_.x; ++mx) {
        const std::int32_t k = s.block_[index(mx, my, mz)];
        if (k < 0) continue;
        const Block& block = s.blocks_[static_cast<std::size_t>(k)];
        float* out = s.voxels_.data() + block.offset;
        for (int z = block.lo.z; z < block.lo.z + block.size.z; ++z)
          for (int y = block.lo.y; y < block.lo.y + block.size.y; ++y)
            for (int x = block.lo.x; x < block.lo.x + block.size.x; ++x) *out++ = layer.at(x, y, z);
      }
  }
  return s;
}

std::size_t ShadingShell::bytes() const {
  return macroMin_.size() * 2 * sizeof(float) + block_.size() * sizeof(std::int32_t) +
         blocks_.size() * sizeof(Block) + voxels_.size() * sizeof(float);
}

}  // namespace renderers::scivis
