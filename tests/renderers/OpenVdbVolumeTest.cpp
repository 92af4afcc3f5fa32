// OpenVDB volumes: a grid written with OpenVDB's own API comes back through loadVolume with its
// geometry, its values, its background in inactive voxels, and the same values in any brick.
#include <gtest/gtest.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <unistd.h>

#include <filesystem>

#include "base/Error.h"
#include "renderers/scivis/io/VolumeLoad.h"

namespace renderers::scivis {
namespace {

namespace fs = std::filesystem;

float valueOf(int i, int j, int k) { return static_cast<float>(i * 10000 + j * 100 + k); }

// Active voxels over index box [-3, 28] x [0, 20] x [2, 18] (several 8³ leaves) except a hole
// at (5, 5, 5); voxel size 0.5, translated by (1, 2, 3). An int grid shares the file.
std::string writeVdb() {
  openvdb::initialize();
  // One folder a process: two test processes never write one file.
  const fs::path dir =
      fs::path(::testing::TempDir()) / ("dfbwall-vdb-tests-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string path = (dir / "field.vdb").string();
  auto labels = openvdb::Int32Grid::create(0);
  labels->setName("labels");
  labels->tree().setValue(openvdb::Coord(0, 0, 0), 7);
  auto density = openvdb::FloatGrid::create(-1.0f);
  density->setName("density");
  auto transform = openvdb::math::Transform::createLinearTransform(0.5);
  transform->postTranslate(openvdb::Vec3d(1, 2, 3));
  density->setTransform(transform);
  auto accessor = density->getAccessor();
  for (int k = 2; k <= 18; ++k)
    for (int j = 0; j <= 20; ++j)
      for (int i = -3; i <= 28; ++i)
        if (!(i == 5 && j == 5 && k == 5))
          accessor.setValue(openvdb::Coord(i, j, k), valueOf(i, j, k));
  openvdb::io::File file(path);
  file.write({labels, density});
  file.close();
  return path;
}

VolumeSource vdbSource(const std::string& path, const std::string& grid = "") {
  VolumeSource s;
  s.kind = VolumeSource::Kind::OpenVdb;
  s.vdb.path = path;
  s.vdb.gridName = grid;
  return s;
}

std::string errorOf(VolumeSource s) {
  try {
    resolveOpenVdbGrid(s);
  } catch (const base::Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(OpenVdbVolume, RoundTripThroughLoadVolume) {
  VolumeSource s = vdbSource(writeVdb());
  resolveOpenVdbGrid(s);
  EXPECT_EQ(s.vdb.gridName, "density");  // the float grid, not the int one
  EXPECT_EQ(s.vdb.indexOrigin, (Index3{-3, 0, 2}));
  EXPECT_EQ(s.grid.dims, (Index3{32, 21, 17}));
  EXPECT_EQ(s.grid.spacing, (Vec3{0.5f}));
  EXPECT_EQ(s.grid.origin, (Vec3{1 - 1.5f, 2, 3 + 1}));
  EXPECT_EQ(s.type, VoxelType::Float32);

  const Volume whole = loadVolume(s, s.grid.wholeBox());
  EXPECT_EQ(whole.type, VoxelType::Float32);
  EXPECT_EQ(whole.at(0, 0, 0), valueOf(-3, 0, 2));
  EXPECT_EQ(whole.at(31, 20, 16), valueOf(28, 20, 18));
  EXPECT_EQ(whole.at(8, 5, 3), -1.0f);  // the hole at index (5, 5, 5): the background
  EXPECT_EQ(whole.valueMin, valueOf(-3, 0, 2));
  EXPECT_EQ(whole.valueMax, valueOf(28, 20, 18));

  // Bricks read their own part of the file and give the same voxels.
  for (const VoxelBox& b : {VoxelBox{{7, 4, 2}, {9, 7, 4}}, VoxelBox{{0, 0, 0}, {32, 1, 17}},
                            VoxelBox{{13, 9, 8}, {29, 18, 17}}}) {
    const Volume part = loadVolume(s, b);
    ASSERT_EQ(part.box, b);
    for (int k = b.lo.z; k < b.hi.z; ++k)
      for (int j = b.lo.y; j < b.hi.y; ++j)
        for (int i = b.lo.x; i < b.hi.x; ++i)
          ASSERT_EQ(part.at(i, j, k), whole.at(i, j, k)) << i << ", " << j << ", " << k;
  }
}

TEST(OpenVdbVolume, LoadVolumeResolvesAnUnresolvedSource) {
  const VolumeSource s = vdbSource(writeVdb(), "density");
  const Volume v = loadVolume(s, {{1, 1, 1}, {3, 3, 3}});
  EXPECT_EQ(v.grid.dims, (Index3{32, 21, 17}));
  EXPECT_EQ(v.at(2, 1, 1), valueOf(-1, 1, 3));
}

TEST(OpenVdbVolume, ErrorsNameTheFileAndTheGrid) {
  const std::string path = writeVdb();
  EXPECT_EQ(errorOf(vdbSource(path, "labels")),
            path + ": OpenVDB grid 'labels' holds int32 values; only float grids are volumes");
  EXPECT_EQ(errorOf(vdbSource(path, "temperature")),
            path +
                ": no grid named 'temperature' in the file (grids: 'density' (float), 'labels' "
                "(int32))");
  const std::string missing = (fs::path(::testing::TempDir()) / "missing.vdb").string();
  const std::string e = errorOf(vdbSource(missing));
  EXPECT_EQ(e.rfind(missing + ": cannot read the OpenVDB file: ", 0), 0u) << e;
}

}  // namespace
}  // namespace renderers::scivis
