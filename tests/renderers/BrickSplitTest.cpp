// How splitScene cuts a domain: the longest axis first; among nearly equal axes the camera's up
// axis, then the one across its view, so bricks lie apart on screen as the camera orbits.
#include <gtest/gtest.h>

#include <memory>

#include "renderers/scivis/bricks/BrickPlan.h"
#include "renderers/scivis/io/SciVisDesc.h"

namespace renderers::scivis {
namespace {

// A scene of one volume of `dims` voxels at unit spacing, seen by a camera with `up` looking
// from `position` at the origin.
SceneDesc sceneOf(Index3 dims, Vec3 up, Vec3 position) {
  SceneDesc desc;
  VolumeDesc v;
  v.name = "v";
  v.source.grid.dims = dims;
  v.source.grid.origin = {0, 0, 0};
  v.source.grid.spacing = {1, 1, 1};
  sciVisDesc(desc).volumes.push_back(v);
  desc.camera.position = position;
  desc.camera.lookAt = {0, 0, 0};
  desc.camera.up = up;
  return desc;
}

// The axes along which `bricks` differ from the domain (the cut axes).
std::vector<int> cutAxes(const std::vector<BrickPlan>& bricks, const Box3& domain) {
  std::vector<int> axes;
  for (int a = 0; a < 3; ++a)
    for (const BrickPlan& b : bricks)
      if (b.bounds.lo[a] != domain.lo[a] || b.bounds.hi[a] != domain.hi[a]) {
        axes.push_back(a);
        break;
      }
  return axes;
}

TEST(BrickSplit, ACubeIsCutAcrossTheCamerasUpAxis) {
  for (int up = 0; up < 3; ++up) {
    const auto unit = [](int axis, float length) {
      return Vec3{axis == 0 ? length : 0, axis == 1 ? length : 0, axis == 2 ? length : 0};
    };
    const Vec3 upDir = unit(up, 1), from = unit((up + 1) % 3, 10);  // looking along another axis
    const SceneDesc desc = sceneOf({33, 33, 33}, upDir, from);
    const std::vector<BrickPlan> two = splitScene(desc, 2);
    ASSERT_EQ(two.size(), 2u);
    EXPECT_EQ(cutAxes(two, sceneDomain(desc)), std::vector<int>{up}) << "up axis " << up;
  }
}

TEST(BrickSplit, AmongTheOtherAxesTheOneAcrossTheViewIsCutNext) {
  // Up y, looking along z: 4 bricks are cut along y, then along x (a 2 x 2 grid on screen).
  const SceneDesc desc = sceneOf({33, 33, 33}, {0, 1, 0}, {0, 0, 10});
  EXPECT_EQ(cutAxes(splitScene(desc, 4), sceneDomain(desc)), (std::vector<int>{0, 1}));
  const SceneDesc sideways = sceneOf({33, 33, 33}, {0, 1, 0}, {10, 0, 0});
  EXPECT_EQ(cutAxes(splitScene(sideways, 4), sceneDomain(sideways)), (std::vector<int>{1, 2}));
}

TEST(BrickSplit, AClearlyLongestAxisIsCutWhateverTheCamera) {
  // x a third longer than y (the up axis): x is cut, so bricks stay compact.
  const SceneDesc desc = sceneOf({45, 33, 33}, {0, 1, 0}, {0, 0, 10});
  EXPECT_EQ(cutAxes(splitScene(desc, 2), sceneDomain(desc)), std::vector<int>{0});
  // Within 10% the up axis wins.
  const SceneDesc nearly = sceneOf({35, 33, 33}, {0, 1, 0}, {0, 0, 10});
  EXPECT_EQ(cutAxes(splitScene(nearly, 2), sceneDomain(nearly)), std::vector<int>{1});
}

TEST(BrickSplit, BricksTileTheDomainWithEqualShares) {
  const SceneDesc desc = sceneOf({41, 33, 37}, {0.3f, 1, 0.1f}, {2, 3, 10});
  const Box3 domain = sceneDomain(desc);
  const Vec3 size = domain.hi - domain.lo;
  const float whole = size.x * size.y * size.z;
  const std::vector<BrickPlan> bricks = splitScene(desc, 3);
  ASSERT_EQ(bricks.size(), 3u);
  float sum = 0;
  for (std::size_t i = 0; i < bricks.size(); ++i) {
    EXPECT_EQ(bricks[i].id, static_cast<int>(i));
    EXPECT_TRUE(domain.contains(bricks[i].bounds.lo) && domain.contains(bricks[i].bounds.hi));
    const Vec3 s = bricks[i].bounds.hi - bricks[i].bounds.lo;
    EXPECT_NEAR(s.x * s.y * s.z, whole / 3, whole * 1e-5f);
    sum += s.x * s.y * s.z;
  }
  EXPECT_NEAR(sum, whole, whole * 1e-5f);
}

}  // namespace
}  // namespace renderers::scivis
