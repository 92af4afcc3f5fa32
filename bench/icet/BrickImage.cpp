#include "bench/icet/BrickImage.h"

#include <algorithm>
#include <functional>

#include "base/Error.h"
#include "base/Parallel.h"
#include "dfb/Tile.h"
#include "renderers/Camera.h"
#include "renderers/Rng.h"

namespace icetbench {

using namespace renderers;
using namespace renderers::scivis;

namespace {
constexpr int kTileSize = 64;  // the DFB's default tile: the same plan on both sides
}

BrickImage::BrickImage(std::shared_ptr<const SceneDesc> desc, const RenderSettings& settings,
                       int brick, int bricks, bool opaque, dfb::ToneMapSettings toneMap)
    : desc_(std::move(desc)), settings_(settings), opaque_(opaque), toneMap_(toneMap) {
  // What BrickFrameDriver's constructor does for a brick this rank holds.
  const std::vector<BrickPlan> plans = splitScene(*desc_, bricks);
  plan_ = plans.at(static_cast<std::size_t>(brick));
  const Box3 domain = sceneDomain(*desc_);
  const float extent = maxComponent(domain.hi - domain.lo);
  depthScale_ = extent;
  scene_ = std::make_unique<SciVisScene>(desc_, loadBrick(*desc_, plan_, ghostReach(*desc_)));
  renderer_ = std::make_unique<SciVisRenderer>(*scene_, settings_, SciVisOptions{false});
  const std::size_t pixels =
      static_cast<std::size_t>(settings.width) * static_cast<std::size_t>(settings.height);
  color_.assign(4 * pixels, 0.0f);
  if (opaque_) {
    rgba8_.assign(pixels, 0);
    depth_.assign(pixels, 1.0f);
  }
}

void BrickImage::render(const dfb::FrameInfo& frame, const CameraDesc& cameraDesc,
                        const BrickFrameDriver& planner) {
  const Camera camera(cameraDesc, settings_.width, settings_.height);
  renderer_->beginFrame(frame, cameraDesc);
  // The planner's bricks are by ascending id: find this one among them.
  const std::vector<BrickPlan>& all = planner.bricks();
  const int index = static_cast<int>(
      std::find_if(all.begin(), all.end(), [&](const BrickPlan& b) { return b.id == plan_.id; }) -
      all.begin());
  const dfb::TileGrid grid(settings_.width, settings_.height, kTileSize);
  std::vector<int> mine;
  for (int t = 0; t < grid.tileCount(); ++t) {
    const std::vector<int> needed = planner.bricksOfTile(cameraDesc, grid.region(t), 0);
    if (std::find(needed.begin(), needed.end(), index) != needed.end()) mine.push_back(t);
  }
  if (mine.empty()) {
    viewport_ = {0, 0, 0, 0};
    return;
  }
  // The valid rectangle: every tile inside it is rendered or cleared (IceT reads all of it).
  int x0 = settings_.width, y0 = settings_.height, x1 = 0, y1 = 0;
  for (int t : mine) {
    const dfb::Region r = grid.region(t);
    x0 = std::min(x0, r.x0), y0 = std::min(y0, r.y0), x1 = std::max(x1, r.x1),
    y1 = std::max(y1, r.y1);
  }
  viewport_ = {x0, y0, x1 - x0, y1 - y0};
  std::vector<int> inside;
  for (int t = 0; t < grid.tileCount(); ++t) {
    const dfb::Region r = grid.region(t);
    if (r.x0 >= x0 && r.x1 <= x1 && r.y0 >= y0 && r.y1 <= y1) inside.push_back(t);
  }
  const std::size_t width = static_cast<std::size_t>(settings_.width);
  base::parallelFor(inside.size(), [&](std::size_t i) {
    const int t = inside[i];
    const dfb::Region region = grid.region(t);
    const bool rendered = std::binary_search(mine.begin(), mine.end(), t);
    dfb::Tile tile;
    if (rendered) renderer_->render(region, 0, 0, 1, tile);
    for (int y = region.y0; y < region.y1; ++y)
      for (int x = region.x0; x < region.x1; ++x) {
        const std::size_t p = static_cast<std::size_t>(y) * width + static_cast<std::size_t>(x);
        float* out = &color_[4 * p];
        if (rendered) {
          const std::size_t q = static_cast<std::size_t>(y - region.y0) * region.width() +
                                static_cast<std::size_t>(x - region.x0);
          std::copy_n(&tile.color[4 * q], 4, out);
        } else {
          std::fill_n(out, 4, 0.0f);
        }
        if (!opaque_) continue;
        rgba8_[p] = dfb::toneMapPixel(out, toneMap_);
        depth_[p] = 1.0f;
        if (out[3] <= 0.0f) continue;
        // Opaque fragments from disjoint convex bricks: the nearest brick whose ray hits
        // something wins, so the brick's entry distance along the sample's ray is a depth that
        // z-compositing orders exactly as the DFB's per-pixel sort does.
        const Sampler sampler(settings_.seed, x, y, 0, 0);
        Vec3 origin, dir;
        camera.ray(static_cast<float>(x) + sampler.get(0), static_cast<float>(y) + sampler.get(1),
                   0.5f, 0.5f, origin, dir);
        float a = 0, b = Box3::kInf;
        if (clipToBox(plan_.bounds, origin, reciprocal(dir), a, b))
          depth_[p] = a / (a + depthScale_);
      }
  });
}

std::vector<int> visibilityOrder(const std::vector<BrickPlan>& bricks, Vec3 eye) {
  std::function<std::vector<int>(const std::vector<int>&)> order =
      [&](const std::vector<int>& ids) -> std::vector<int> {
    if (ids.size() <= 1) return ids;
    for (int axis = 0; axis < 3; ++axis)
      for (int candidate : ids) {
        const float plane = bricks[static_cast<std::size_t>(candidate)].bounds.hi[axis];
        std::vector<int> below, above;
        for (int id : ids) {
          const Box3& b = bricks[static_cast<std::size_t>(id)].bounds;
          if (b.hi[axis] <= plane)
            below.push_back(id);
          else if (b.lo[axis] >= plane)
            above.push_back(id);
        }
        if (below.empty() || above.empty() || below.size() + above.size() != ids.size()) continue;
        std::vector<int> first = order(eye[axis] < plane ? below : above);
        const std::vector<int> second = order(eye[axis] < plane ? above : below);
        first.insert(first.end(), second.begin(), second.end());
        return first;
      }
    throw base::Error("bricks that no plane separates: not a k-d split");
  };
  std::vector<int> all;
  for (const BrickPlan& b : bricks) all.push_back(b.id);
  return order(all);
}

}  // namespace icetbench
