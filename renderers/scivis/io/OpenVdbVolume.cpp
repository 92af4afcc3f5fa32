#include "renderers/scivis/io/OpenVdbVolume.h"

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <mutex>

#include "base/Error.h"
#include "base/Parallel.h"

namespace renderers::scivis {
namespace {

void initializeOpenVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

openvdb::Coord coordOf(Index3 i) { return openvdb::Coord(i.x, i.y, i.z); }

// The metadata (no voxels) of the named float grid, or of the first float grid.
openvdb::GridBase::Ptr findGrid(openvdb::io::File& file, const std::string& path,
                                const std::string& name) {
  openvdb::GridPtrVecPtr grids = file.readAllGridMetadata();
  std::string names;
  for (const openvdb::GridBase::Ptr& g : *grids) {
    names += (names.empty() ? "'" : ", '") + g->getName() + "' (" + g->valueType() + ")";
    if (name.empty() ? g->valueType() == "float" : g->getName() == name) {
      if (g->valueType() != "float")
        throw base::Error(path + ": OpenVDB grid '" + name + "' holds " + g->valueType() +
                          " values; only float grids are volumes");
      return g;
    }
  }
  throw base::Error(path + ": " +
                    (name.empty() ? std::string("no float grid") : "no grid named '" + name + "'") +
                    " in the file (grids: " + (names.empty() ? std::string("none") : names) + ")");
}

// The active voxels' index bounding box, from the file's statistics when present (no voxels
// read), else from the grid's tree.
openvdb::CoordBBox activeBox(openvdb::io::File& file, const openvdb::GridBase& meta) {
  auto lo = meta.getMetadata<openvdb::Vec3IMetadata>(openvdb::GridBase::META_FILE_BBOX_MIN);
  auto hi = meta.getMetadata<openvdb::Vec3IMetadata>(openvdb::GridBase::META_FILE_BBOX_MAX);
  if (lo && hi) return {openvdb::Coord(lo->value()), openvdb::Coord(hi->value())};
  return file.readGrid(meta.getName())->evalActiveVoxelBoundingBox();
}

void resolve(VolumeSource& source) {
  const std::string& path = source.vdb.path;
  openvdb::io::File file(path);
  file.open();
  openvdb::GridBase::Ptr meta = findGrid(file, path, source.vdb.gridName);
  const openvdb::CoordBBox box = activeBox(file, *meta);
  if (box.empty())
    throw base::Error(path + ": OpenVDB grid '" + meta->getName() + "' has no active voxels");
  const openvdb::math::Transform& t = meta->transform();
  const openvdb::Vec3d o = t.indexToWorld(box.min());
  const openvdb::Vec3d axes[3] = {t.indexToWorld(box.min().offsetBy(1, 0, 0)) - o,
                                  t.indexToWorld(box.min().offsetBy(0, 1, 0)) - o,
                                  t.indexToWorld(box.min().offsetBy(0, 0, 1)) - o};
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      // The dense grid is axis-aligned: a rotated or sheared index space would need resampling.
      if (a != b && std::abs(axes[a][b]) > 1e-6 * std::abs(axes[a][a]))
        throw base::Error(
            path + ": OpenVDB grid '" + meta->getName() +
            "' has a rotated or sheared transform; only axis-aligned grids are volumes");
    }
    if (!(axes[a][a] > 0))
      throw base::Error(path + ": OpenVDB grid '" + meta->getName() +
                        "' has a non-positive voxel size");
  }
  const openvdb::Coord extent = box.dim();
  for (int a = 0; a < 3; ++a) {
    if (extent[a] > (1 << 30))
      throw base::Error(path + ": OpenVDB grid '" + meta->getName() +
                        "' is too large to be a dense volume");
  }
  source.vdb.gridName = meta->getName();
  source.vdb.indexOrigin = {box.min().x(), box.min().y(), box.min().z()};
  // A flat grid still gets two voxels per axis (the second one holds the background value).
  source.grid.dims = {std::max(extent.x(), 2), std::max(extent.y(), 2), std::max(extent.z(), 2)};
  source.grid.origin = {static_cast<float>(o.x()), static_cast<float>(o.y()),
                        static_cast<float>(o.z())};
  source.grid.spacing = {static_cast<float>(axes[0][0]), static_cast<float>(axes[1][1]),
                         static_cast<float>(axes[2][2])};
  source.type = VoxelType::Float32;
}

Volume sample(const VolumeSource& source, const VoxelBox& box) {
  const std::string& path = source.vdb.path;
  openvdb::io::File file(path);
  file.open();
  // The box in the file's index space, half a voxel wider so that clipping to it keeps the
  // voxels on its faces, then in world space for readGrid (the transform is axis-aligned).
  openvdb::GridBase::Ptr meta = findGrid(file, path, source.vdb.gridName);
  const openvdb::Coord lo = coordOf(source.vdb.indexOrigin) + coordOf(box.lo);
  const openvdb::Coord hi = coordOf(source.vdb.indexOrigin) + coordOf(box.hi) - openvdb::Coord(1);
  const openvdb::math::Transform& t = meta->transform();
  const openvdb::Vec3d a = t.indexToWorld(lo.asVec3d() - openvdb::Vec3d(0.5));
  const openvdb::Vec3d b = t.indexToWorld(hi.asVec3d() + openvdb::Vec3d(0.5));
  const openvdb::BBoxd world(openvdb::math::minComponent(a, b), openvdb::math::maxComponent(a, b));
  // Reads only the leaf nodes that touch the box.
  openvdb::FloatGrid::Ptr grid =
      openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid(source.vdb.gridName, world));
  if (!grid)
    throw base::Error(path + ": OpenVDB grid '" + source.vdb.gridName + "' is not a float grid");

  Volume v;
  v.grid = source.grid;
  v.box = box;
  v.type = VoxelType::Float32;
  v.voxels = allocateVoxelBytes(box, v.type);
  const Index3 s = box.size();
  std::byte* out = v.voxels.data();
  base::parallelFor(
      static_cast<std::size_t>(s.y) * static_cast<std::size_t>(s.z), [&](std::size_t row) {
        auto accessor =
            grid->getConstAccessor();  // one per task: accessors cache, so are not shared
        const int j = lo.y() + static_cast<int>(row % static_cast<std::size_t>(s.y));
        const int k = lo.z() + static_cast<int>(row / static_cast<std::size_t>(s.y));
        std::byte* dst = out + row * static_cast<std::size_t>(s.x) * sizeof(float);
        for (int i = lo.x(); i <= hi.x(); ++i, dst += sizeof(float)) {
          const float value = accessor.getValue(openvdb::Coord(i, j, k));
          std::memcpy(dst, &value, sizeof value);
        }
      });
  v.updateRange();
  return v;
}

}  // namespace

void resolveOpenVdbGrid(VolumeSource& source) {
  initializeOpenVdb();
  try {
    resolve(source);
  } catch (const openvdb::Exception& e) {
    throw base::Error(source.vdb.path + ": cannot read the OpenVDB file: " + e.what());
  }
}

Volume loadOpenVdbBox(const VolumeSource& source, const VoxelBox& box) {
  initializeOpenVdb();
  try {
    return sample(source, box);
  } catch (const openvdb::Exception& e) {
    throw base::Error(source.vdb.path + ": cannot read the OpenVDB file: " + e.what());
  }
}

}  // namespace renderers::scivis
