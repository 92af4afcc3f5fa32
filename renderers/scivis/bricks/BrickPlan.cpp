#include "renderers/scivis/bricks/BrickPlan.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "base/Error.h"

namespace renderers::scivis {
namespace {

Box3 expanded(const Box3& b, float margin) { return {b.lo - Vec3{margin}, b.hi + Vec3{margin}}; }

// How far off a brick's bounds its shading rays may start: SciVisRenderer leaves a surface by
// 1e-4 of the scene's extent and 0.05 of a volume step (both as SciVisScene computes them);
// four times that.
float startPad(const SceneDesc& desc, const Box3& domain) {
  float finest = 0;
  for (const VolumeDesc& v : sciVisDesc(desc).volumes) {
    const Vec3 h = v.source.grid.spacing;
    const float m = std::min(h.x, std::min(h.y, h.z));
    finest = finest > 0 ? std::min(finest, m) : m;
  }
  const float step = finest > 0 ? finest / sciVisDesc(desc).settings.samplingRate : 1.0f;
  const float extent = domain.empty() ? 0.0f : std::max(1e-3f, maxComponent(domain.hi - domain.lo));
  return 4.0f * (1e-4f * extent + 0.05f * step);
}

// Where the shadow rays of points in `bounds` go (one SweptBox per light of `reach`): from
// within `pad` of the bounds to a point light or out of the domain. None when the bounds hold
// the domain.
std::vector<SweptBox> shadowSweeps(const Box3& bounds, const GhostReach& reach, float pad) {
  std::vector<SweptBox> out;
  if (reach.lights.empty() || reach.domain.empty() ||
      (bounds.contains(reach.domain.lo) && bounds.contains(reach.domain.hi)))
    return out;
  const Box3 from = expanded(bounds, pad);
  Box3 all = reach.domain;
  grow(all, from.lo, from.hi);
  // A box moved this far along a unit direction has left every box holding it and the domain.
  const float across = length(all.hi - all.lo) * 1.001f + pad;
  for (const ResolvedLight& light : reach.lights) {
    if (light.kind == LightDesc::Kind::Directional) {
      const Vec3 d = length(light.direction) > 0 ? normalize(light.direction) : Vec3{};
      out.push_back({from, d, d, across});
    } else if (light.kind == LightDesc::Kind::Point) {
      const Box3 at = expanded({light.position, light.position}, pad);
      out.push_back({from, at.lo - from.lo, at.hi - from.hi, 1.0f});
    }
  }
  return out;
}

}  // namespace

BrickReach brickReach(const SceneDesc& desc, const Box3& bounds, const GhostReach& reach) {
  BrickReach r;
  const float pad = startPad(desc, reach.domain);
  r.sweeps = shadowSweeps(bounds, reach, pad);
  r.beyond = reach.margin > 0 || !r.sweeps.empty();
  r.around = r.beyond ? expanded(bounds, reach.margin + pad) : bounds;
  r.region = r.around;
  for (const SweptBox& s : r.sweeps) {
    const Box3 b = s.bounds();
    grow(r.region, b.lo, b.hi);
  }
  return r;
}

namespace {

// The axis to halve `size` along: the longest, and among axes within kNearlyLongest of it the
// one nearest the camera's up direction, then the one most across its view. Bricks stacked
// along up lie apart on screen for every camera that orbits about up (the usual way to turn a
// data set), so each rank rasterises and shades its own part of the image; bricks stacked along
// the view overlap there, and the farther one's rays are traced, or tested, behind the nearer
// one. (2 bricks of the 256^3 wavelet on 2 ranks at 2048^2 over a 135-degree orbit: contours'
// frames 0.57-0.69x of the x-split's, the volume's 0.67x.)
int splitAxis(Vec3 size, const CameraDesc& camera) {
  constexpr float kNearlyLongest = 0.9f;
  const float longest = std::max({size.x, size.y, size.z});
  const Vec3 up = normalize(camera.up), forward = normalize(camera.lookAt - camera.position);
  // Lower ranks better: nearer up, then more across the view.
  const auto rank = [&](int axis) {
    return std::pair{-std::abs(up[axis]), std::abs(forward[axis])};
  };
  int best = -1;
  for (int a = 0; a < 3; ++a)
    if (size[a] >= kNearlyLongest * longest && (best < 0 || rank(a) < rank(best))) best = a;
  return best < 0 ? 0 : best;
}

void split(const Box3& box, int count, const CameraDesc& camera, int& nextId,
           std::vector<BrickPlan>& out) {
  if (count == 1) {
    out.push_back({nextId++, box});
    return;
  }
  const int axis = splitAxis(box.hi - box.lo, camera);
  const int left = count / 2;
  const float lo = box.lo[axis], hi = box.hi[axis];
  const float plane = lo + (hi - lo) * static_cast<float>(left) / static_cast<float>(count);
  Box3 a = box, b = box;
  (axis == 0 ? a.hi.x : axis == 1 ? a.hi.y : a.hi.z) = plane;
  (axis == 0 ? b.lo.x : axis == 1 ? b.lo.y : b.lo.z) = plane;
  split(a, left, camera, nextId, out);
  split(b, count - left, camera, nextId, out);
}

}  // namespace

Box3 openAtDomainBoundary(const Box3& bounds, const Box3& domain) {
  constexpr float kInf = Box3::kInf;
  Box3 out = bounds;
  if (out.lo.x <= domain.lo.x) out.lo.x = -kInf;
  if (out.lo.y <= domain.lo.y) out.lo.y = -kInf;
  if (out.lo.z <= domain.lo.z) out.lo.z = -kInf;
  if (out.hi.x >= domain.hi.x) out.hi.x = kInf;
  if (out.hi.y >= domain.hi.y) out.hi.y = kInf;
  if (out.hi.z >= domain.hi.z) out.hi.z = kInf;
  return out;
}

std::vector<BrickPlan> splitScene(const SceneDesc& desc, int count) {
  if (count < 1) throw base::Error("--bricks must be at least 1");
  std::vector<BrickPlan> out;
  int nextId = 0;
  split(sceneDomain(desc), count, desc.camera, nextId, out);
  return out;
}

std::vector<int> brickHolders(int brick, int ranks, int replication) {
  const int k = std::clamp(replication, 1, ranks);
  std::vector<int> holders;
  for (int j = 0; j < k; ++j) holders.push_back((brick * k + j) % ranks);
  std::sort(holders.begin(), holders.end());
  return holders;
}

const char* ghostModeName(GhostMode mode) { return mode == GhostMode::Layer ? "layer" : "reach"; }

GhostMode ghostModeFromName(const std::string& name) {
  if (name == "reach") return GhostMode::Reach;
  if (name == "layer") return GhostMode::Layer;
  throw base::Error("ghost mode '" + name +
                    "': choose reach (shading rays see what they reach) or " +
                    "layer (one ghost layer of voxels)");
}

float ghostMargin(const SceneDesc& desc, float sceneExtent, GhostMode mode) {
  const SciVisSettings& settings = sciVisDesc(desc).settings;
  if (mode == GhostMode::Layer || settings.aoSamples <= 0) return 0.0f;
  return settings.aoDistance > 0 ? settings.aoDistance : 0.25f * sceneExtent;
}

GhostReach ghostReach(const SceneDesc& desc, GhostMode mode) {
  GhostReach reach;
  if (mode == GhostMode::Layer) return reach;
  reach.domain = sceneDomain(desc);
  reach.margin = ghostMargin(desc, maxComponent(reach.domain.hi - reach.domain.lo), mode);
  if (sciVisDesc(desc).settings.shadows)
    for (const ResolvedLight& light : resolveLights(desc))
      if (light.kind != LightDesc::Kind::Ambient) reach.lights.push_back(light);
  return reach;
}

// The plans rank `rank` holds.
std::vector<BrickPlan> ownPlans(const SceneDesc& desc, int bricks, int replication, int rank,
                                int ranks) {
  const std::vector<BrickPlan> plans = splitScene(desc, bricks);
  if (replication < 1) throw base::Error("--replication must be at least 1");
  std::vector<BrickPlan> mine;
  for (const BrickPlan& plan : plans) {
    const std::vector<int> h = brickHolders(plan.id, ranks, replication);
    if (std::find(h.begin(), h.end(), rank) != h.end()) mine.push_back(plan);
  }
  return mine;
}

}  // namespace renderers::scivis
