#include "renderers/scivis/bricks/Bricks.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <new>
#include <string>

#include "base/BoundedWait.h"
#include "base/Error.h"
#include "base/MemoryBudget.h"

namespace renderers {
namespace {

Box3 expanded(const Box3& b, float margin) { return {b.lo - Vec3{margin}, b.hi + Vec3{margin}}; }

bool overlaps(const Box3& a, Vec3 lo, Vec3 hi) {
  return lo.x <= a.hi.x && hi.x >= a.lo.x && lo.y <= a.hi.y && hi.y >= a.lo.y && lo.z <= a.hi.z &&
         hi.z >= a.lo.z;
}

// The boxes [from.lo + s dLo, from.hi + s dHi] for s in [0, sMax], together: every point a
// shadow ray from `from` passes on its way to a light. Towards a directional light d: dLo = dHi
// = d (the box swept along it); towards a point light in box L: dLo = L.lo - from.lo, dHi =
// L.hi - from.hi, sMax = 1 (each point of `from` joined to each of L: the convex hull).
struct SweptBox {
  Box3 from;
  Vec3 dLo, dHi;
  float sMax = 0;

  Box3 bounds() const {
    Box3 b = from;
    grow(b, from.lo + dLo * sMax, from.hi + dHi * sMax);
    return b;
  }
  // Whether [lo, hi] meets one of the boxes: per axis, two linear conditions on s.
  bool overlaps(Vec3 lo, Vec3 hi) const {
    float s0 = 0, s1 = sMax;
    // a + s b <= 0 for some s in [s0, s1].
    auto keep = [&](float a, float b) {
      if (b > 0)
        s1 = std::min(s1, -a / b);
      else if (b < 0)
        s0 = std::max(s0, -a / b);
      else if (a > 0)
        s1 = -1;
    };
    for (int a = 0; a < 3; ++a) {
      keep(from.lo[a] - hi[a], dLo[a]);   // the moving box's low face below hi
      keep(lo[a] - from.hi[a], -dHi[a]);  // its high face above lo
    }
    return s0 <= s1;
  }
};

// How far off a brick's bounds its shading rays may start: SciVisRenderer leaves a surface by
// 1e-4 of the scene's extent and 0.05 of a volume step (both as SciVisScene computes them);
// four times that.
float startPad(const SceneDesc& desc, const Box3& domain) {
  float finest = 0;
  for (const VolumeDesc& v : desc.volumes) {
    const Vec3 h = v.source.grid.spacing;
    const float m = std::min(h.x, std::min(h.y, h.z));
    finest = finest > 0 ? std::min(finest, m) : m;
  }
  const float step = finest > 0 ? finest / desc.scivis.samplingRate : 1.0f;
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

// The particles of `p` for which `keep(centre, radius)` holds, with their radii and attributes.
template <class Keep>
ParticlesDesc selectParticles(const ParticlesDesc& p, Keep keep) {
  ParticlesDesc out;
  out.name = p.name;
  out.material = p.material;
  out.colorMap = p.colorMap;
  const bool perParticle = p.radii.size() != 1;
  if (!perParticle) out.radii = p.radii;
  for (std::size_t i = 0; i < p.centers.size(); ++i) {
    if (!keep(p.centers[i], p.radius(i))) continue;
    out.centers.push_back(p.centers[i]);
    if (perParticle) out.radii.push_back(p.radii[i]);
    if (!p.attribute.empty()) out.attribute.push_back(p.attribute[i]);
  }
  return out;
}

// The triangles of `m` for which `keep(lo, hi)` of their bounds holds, positions compacted.
template <class Keep>
WorldMesh selectTriangles(const WorldMesh& m, Keep keep) {
  WorldMesh out;
  out.material = m.material;
  std::vector<std::uint32_t> remap(m.mesh.positions.size(), ~0u);
  for (const auto& t : m.mesh.triangles) {
    const Vec3 a = m.mesh.positions[t[0]], b = m.mesh.positions[t[1]], c = m.mesh.positions[t[2]];
    const Vec3 lo{std::min({a.x, b.x, c.x}), std::min({a.y, b.y, c.y}), std::min({a.z, b.z, c.z})};
    const Vec3 hi{std::max({a.x, b.x, c.x}), std::max({a.y, b.y, c.y}), std::max({a.z, b.z, c.z})};
    if (!keep(lo, hi)) continue;
    std::array<std::uint32_t, 3> tri;
    for (int k = 0; k < 3; ++k) {
      std::uint32_t& r = remap[t[static_cast<std::size_t>(k)]];
      if (r == ~0u) {
        r = static_cast<std::uint32_t>(out.mesh.positions.size());
        out.mesh.positions.push_back(m.mesh.positions[t[static_cast<std::size_t>(k)]]);
      }
      tri[static_cast<std::size_t>(k)] = r;
    }
    out.mesh.triangles.push_back(tri);
  }
  return out;
}

// The voxels of `g` around `region`, two beyond it: gradients look half a voxel around a hit
// and the brick's isosurface cells reach a cell past its bounds. False: fewer than 2 voxels on an
// axis. `whole`: widened to whole macrocells (their far faces included), so every macrocell has the
// value range and bounds it has in the whole field, and shading rays skip exactly the stretches
// they skip there.
bool voxelsAround(const GridGeometry& g, const Box3& region, VoxelBox& box, bool whole = false) {
  bool empty = false;
  for (int a = 0; a < 3; ++a) {
    const double lo = std::floor((double(region.lo[a]) - g.origin[a]) / g.spacing[a]) - 2;
    const double hi = std::ceil((double(region.hi[a]) - g.origin[a]) / g.spacing[a]) + 3;
    int i0 = static_cast<int>(std::clamp(lo, 0.0, double(g.dims[a])));
    int i1 = static_cast<int>(std::clamp(hi, 0.0, double(g.dims[a])));
    if (whole && i1 > i0) {
      constexpr int m = FieldGeometry::kMacro;
      i0 = i0 / m * m;
      i1 = std::min((i1 - 1 + m - 1) / m * m + 1, g.dims[a]);
    }
    (a == 0 ? box.lo.x : a == 1 ? box.lo.y : box.lo.z) = i0;
    (a == 0 ? box.hi.x : a == 1 ? box.hi.y : box.hi.z) = i1;
    empty = empty || i1 - i0 < 2;
  }
  return !empty;
}

// Where one brick's shading rays go beyond its bounds (from its GhostReach): ambient-occlusion
// rays within `around`, shadow rays along `sweeps`; `region` bounds both.
struct BrickReach {
  Box3 around, region;
  std::vector<SweptBox> sweeps;
  bool beyond = false;  // whether they leave the bounds at all
  bool reached(Vec3 lo, Vec3 hi) const {
    if (overlaps(around, lo, hi)) return true;
    for (const SweptBox& s : sweeps)
      if (s.overlaps(lo, hi)) return true;
    return false;
  }
};

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

std::string volumeName(const VolumeDesc& v) {
  return v.where.empty() ? "volume '" + v.name + "'" : v.where;
}

bool hasIsosurface(const SceneDesc& desc, std::size_t volume) {
  for (const IsosurfaceDesc& iso : desc.isosurfaces)
    if (iso.volume == volume) return true;
  return false;
}

// What loadBrick holds of volume `i` for `plan` at most: the dense core with its macrocell
// ranges and, with a ghost shell, the shell both sparse (float voxels) and dense, as loadBrick
// may hold both while it chooses.
std::uint64_t brickVolumeBytes(const SceneDesc& desc, std::size_t i, const BrickPlan& plan,
                               const BrickReach& reach) {
  const VolumeSource& source = desc.volumes[i].source;
  // OpenVDB: while a box is sampled, the leaves of the grid that touch it are held too (as many
  // float voxels again, at most).
  const std::uint64_t width =
      voxelBytes(source.type) * (source.kind == VolumeSource::Kind::OpenVdb ? 2 : 1);
  auto dense = [&](const VoxelBox& b) {
    const std::uint64_t voxels = b.voxelCount();
    return base::bytesPlus(base::bytesTimes(voxels, width), voxels / 64);  // 8 bytes per 8³
  };
  std::uint64_t bytes = 0;
  VoxelBox core, shell;
  if (voxelsAround(source.grid, plan.bounds, core)) bytes = dense(core);
  if (reach.beyond && hasIsosurface(desc, i) &&
      voxelsAround(source.grid, reach.region, shell, true))
    bytes = base::bytesPlus(bytes,
                            base::bytesPlus(dense(shell), base::bytesTimes(shell.voxelCount(), 4)));
  return bytes;
}

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
  if (mode == GhostMode::Layer || desc.scivis.aoSamples <= 0) return 0.0f;
  return desc.scivis.aoDistance > 0 ? desc.scivis.aoDistance : 0.25f * sceneExtent;
}

GhostReach ghostReach(const SceneDesc& desc, GhostMode mode) {
  GhostReach reach;
  if (mode == GhostMode::Layer) return reach;
  reach.domain = sceneDomain(desc);
  reach.margin = ghostMargin(desc, maxComponent(reach.domain.hi - reach.domain.lo), mode);
  if (desc.scivis.shadows)
    for (const ResolvedLight& light : resolveLights(desc))
      if (light.kind != LightDesc::Kind::Ambient) reach.lights.push_back(light);
  return reach;
}

namespace {

// loadBrick's work; `part` says what it is loading, for an allocation that fails on the way.
BrickContent loadBrickData(const SceneDesc& desc, const BrickPlan& plan, const GhostReach& ghosts,
                           std::string& part) {
  BrickContent c;
  c.bounds = plan.bounds;
  const BrickReach reach = brickReach(desc, plan.bounds, ghosts);
  for (std::size_t i = 0; i < desc.volumes.size(); ++i) {
    const VolumeDesc& v = desc.volumes[i];
    const GridGeometry& g = v.source.grid;
    part = volumeName(v) + ": its voxels";
    // Dense: the voxels camera rays and gradients use (the brick and one ghost layer).
    VoxelBox core;
    const bool haveCore = voxelsAround(g, plan.bounds, core);
    if (haveCore) {
      c.volumes.push_back(loadVolume(v.source, core));
    } else {
      Volume none;
      none.grid = g;
      none.type = v.source.type;
      c.volumes.push_back(std::move(none));
    }
    // Beyond, what shading rays can reach (only isosurfaces stop them in a volume): sparse, or
    // dense when the sparse shell would not be smaller (small fields, isosurfaces everywhere).
    std::vector<float> isovalues;
    for (const IsosurfaceDesc& iso : desc.isosurfaces)
      if (iso.volume == i) isovalues.push_back(iso.value);
    VoxelBox shell;
    c.shells.emplace_back();
    if (reach.beyond && !isovalues.empty() && voxelsAround(g, reach.region, shell, true) &&
        !(shell == core)) {
      // A macrocell is reached when a shading ray's sample can fall in it: when its bounds (a
      // hundredth of a voxel wider, for rounding) meet where the rays go.
      const Vec3 slack = g.spacing * 0.01f;
      ShadingShell sparse = ShadingShell::load(
          v.source, shell, haveCore ? core : VoxelBox{}, isovalues,
          [&](const Box3& m) { return reach.reached(m.lo - slack, m.hi + slack); });
      const std::size_t dense = shell.voxelCount() * voxelBytes(v.source.type);
      if (sparse.bytes() + c.volumes.back().bytes() < dense)
        c.shells.back() = std::move(sparse);
      else
        c.volumes.back() = loadVolume(v.source, shell);
    }
  }
  part = "its particles and triangles";
  std::vector<ParticlesDesc> converted;
  for (const ParticlesDesc* p : particleSets(desc, converted)) {
    ParticlesDesc inside = selectParticles(*p, [&](Vec3 centre, float r) {
      return overlaps(plan.bounds, centre - Vec3{r}, centre + Vec3{r});
    });
    ParticlesDesc near = selectParticles(*p, [&](Vec3 centre, float r) {
      return !overlaps(plan.bounds, centre - Vec3{r}, centre + Vec3{r}) &&
             reach.reached(centre - Vec3{r}, centre + Vec3{r});
    });
    if (!inside.centers.empty()) c.particles.push_back(std::move(inside));
    if (!near.centers.empty()) c.ghostParticles.push_back(std::move(near));
  }
  for (const WorldMesh& m : worldMeshes(desc)) {
    WorldMesh inside =
        selectTriangles(m, [&](Vec3 lo, Vec3 hi) { return overlaps(plan.bounds, lo, hi); });
    WorldMesh near = selectTriangles(m, [&](Vec3 lo, Vec3 hi) {
      return !overlaps(plan.bounds, lo, hi) && reach.reached(lo, hi);
    });
    if (!inside.mesh.triangles.empty()) c.meshes.push_back(std::move(inside));
    if (!near.mesh.triangles.empty()) c.ghostMeshes.push_back(std::move(near));
  }
  return c;
}

}  // namespace

BrickContent loadBrick(const SceneDesc& desc, const BrickPlan& plan, const GhostReach& reach) {
  std::string part;
  try {
    return loadBrickData(desc, plan, reach, part);
  } catch (const std::bad_alloc&) {
    throw base::Error(part + ": out of memory while loading brick " + std::to_string(plan.id) +
                      "; this rank may hold " + base::memoryLimitText());
  }
}

void checkBrickMemory(const SceneDesc& desc, const std::vector<BrickPlan>& plans,
                      const GhostReach& ghosts) {
  // Per volume, what the plans hold of it; particles and triangles: those the bricks reach
  // (plus, for triangles, the world-space copy of every mesh loadBrick makes on the way).
  std::vector<std::uint64_t> volumes(desc.volumes.size(), 0);
  std::uint64_t others = desc.bytes();
  std::vector<ParticlesDesc> converted;
  const std::vector<const ParticlesDesc*> sets = particleSets(desc, converted);
  const std::vector<WorldMesh> meshes = worldMeshes(desc);
  for (const BrickPlan& plan : plans) {
    const BrickReach reach = brickReach(desc, plan.bounds, ghosts);
    for (std::size_t i = 0; i < desc.volumes.size(); ++i)
      volumes[i] = base::bytesPlus(volumes[i], brickVolumeBytes(desc, i, plan, reach));
    for (const ParticlesDesc* p : sets) {
      const std::uint64_t each = sizeof(Vec3) + (p->radii.size() > 1 ? 4 : 0) +
                                 (p->attribute.empty() ? 0 : 4) + kBvhBytesPerPrimitive;
      std::uint64_t reached = 0;
      for (std::size_t i = 0; i < p->centers.size(); ++i)
        reached +=
            reach.reached(p->centers[i] - Vec3{p->radius(i)}, p->centers[i] + Vec3{p->radius(i)});
      others = base::bytesPlus(others, reached * each);
    }
    for (const WorldMesh& m : meshes) {
      // The world-space copy loadBrick makes of every mesh, and the triangles the brick reaches
      // with their share of the BVH.
      others = base::bytesPlus(others, m.mesh.positions.size() * sizeof(Vec3) +
                                           m.mesh.triangles.size() * sizeof(m.mesh.triangles[0]));
      std::uint64_t reached = 0;
      for (const auto& t : m.mesh.triangles) {
        const Vec3 a = m.mesh.positions[t[0]], b = m.mesh.positions[t[1]],
                   c = m.mesh.positions[t[2]];
        reached += reach.reached(
            {std::min({a.x, b.x, c.x}), std::min({a.y, b.y, c.y}), std::min({a.z, b.z, c.z})},
            {std::max({a.x, b.x, c.x}), std::max({a.y, b.y, c.y}), std::max({a.z, b.z, c.z})});
      }
      others = base::bytesPlus(others, reached * (3 * sizeof(Vec3) + sizeof(m.mesh.triangles[0]) +
                                                  kBvhBytesPerPrimitive));
    }
  }
  std::uint64_t total = others;
  std::size_t largest = 0;
  for (std::size_t i = 0; i < volumes.size(); ++i) {
    total = base::bytesPlus(total, volumes[i]);
    if (volumes[i] > volumes[largest]) largest = i;
  }
  const std::string problem = base::memoryProblem(total);
  if (problem.empty()) return;
  const std::string bricks =
      plans.size() == 1 && plans[0].bounds == Box3{}
          ? std::string("the whole scene")
          : std::to_string(plans.size()) + (plans.size() == 1 ? " brick" : " bricks");
  if (!volumes.empty() && volumes[largest] >= others) {
    const VolumeDesc& v = desc.volumes[largest];
    const Index3 n = v.source.grid.dims;
    throw base::Error(volumeName(v) + ": this rank holds " + std::to_string(volumes[largest]) +
                      " bytes of this " + std::to_string(n.x) + "x" + std::to_string(n.y) + "x" +
                      std::to_string(n.z) + " " + voxelTypeName(v.source.type) + " volume (" +
                      bricks + ", ghost voxels and macrocells included); its data in all " +
                      problem);
  }
  throw base::Error("the scene's particles and triangles: this rank holds " +
                    std::to_string(others) + " bytes of them (" + bricks + "); its data in all " +
                    problem);
}

BrickContent wholeScene(const SceneDesc& desc) {
  // One brick without bounds: every voxel, particle and triangle, nothing as ghost.
  const BrickPlan whole{0, Box3{}};
  checkBrickMemory(desc, {whole}, GhostReach{});
  return loadBrick(desc, whole, GhostReach{});
}

namespace {

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

}  // namespace

void checkOwnBricksMemory(const SceneDesc& desc, int bricks, int replication, int rank, int ranks,
                          GhostMode ghosts) {
  checkBrickMemory(desc, ownPlans(desc, bricks, replication, rank, ranks),
                   ghostReach(desc, ghosts));
}

std::vector<HeldBrick> loadOwnBricks(const SceneDesc& desc, int bricks, int replication, int rank,
                                     int ranks, GhostMode ghosts) {
  const std::vector<BrickPlan> mine = ownPlans(desc, bricks, replication, rank, ranks);
  const GhostReach reach = ghostReach(desc, ghosts);
  checkBrickMemory(desc, mine, reach);
  std::vector<HeldBrick> out;
  for (const BrickPlan& plan : mine) out.push_back({plan.id, loadBrick(desc, plan, reach)});
  return out;
}

namespace {

// One brick on the wire: plain numbers, the same layout on every rank of a job.
struct WireBrick {
  std::int32_t id;
  float lo[3], hi[3];
};

void finish(MPI_Request& request, std::chrono::milliseconds timeout) {
  base::waitWithDeadline(request, std::chrono::steady_clock::now() + timeout,
                         "exchanging brick bounds: another render rank did not join within " +
                             std::to_string(timeout.count()) + " ms");
}

}  // namespace

BrickDirectory exchangeBricks(const std::vector<BrickPlan>& mine, MPI_Comm comm,
                              std::chrono::milliseconds timeout) {
  int ranks = 1;
  MPI_Comm_size(comm, &ranks);
  std::vector<WireBrick> local;
  for (const BrickPlan& b : mine) {
    if (b.id < 0) throw base::Error("brick id " + std::to_string(b.id) + " is negative");
    local.push_back({b.id,
                     {b.bounds.lo.x, b.bounds.lo.y, b.bounds.lo.z},
                     {b.bounds.hi.x, b.bounds.hi.y, b.bounds.hi.z}});
  }
  const int bytes = static_cast<int>(local.size() * sizeof(WireBrick));
  std::vector<int> counts(static_cast<std::size_t>(ranks)), offsets(counts.size());
  MPI_Request request;
  base::checkMpi(MPI_Iallgather(&bytes, 1, MPI_INT, counts.data(), 1, MPI_INT, comm, &request),
                 "MPI_Iallgather");
  finish(request, timeout);
  int total = 0;
  for (std::size_t r = 0; r < counts.size(); ++r) offsets[r] = total, total += counts[r];
  std::vector<WireBrick> all(static_cast<std::size_t>(total) / sizeof(WireBrick));
  base::checkMpi(MPI_Iallgatherv(local.data(), bytes, MPI_BYTE, all.data(), counts.data(),
                                 offsets.data(), MPI_BYTE, comm, &request),
                 "MPI_Iallgatherv");
  finish(request, timeout);

  std::map<int, std::pair<Box3, std::vector<int>>> byId;
  for (int r = 0; r < ranks; ++r) {
    const std::size_t first =
        static_cast<std::size_t>(offsets[static_cast<std::size_t>(r)]) / sizeof(WireBrick);
    const std::size_t n =
        static_cast<std::size_t>(counts[static_cast<std::size_t>(r)]) / sizeof(WireBrick);
    for (std::size_t i = first; i < first + n; ++i) {
      const WireBrick& w = all[i];
      const Box3 bounds{{w.lo[0], w.lo[1], w.lo[2]}, {w.hi[0], w.hi[1], w.hi[2]}};
      auto [it, fresh] = byId.try_emplace(w.id, bounds, std::vector<int>{});
      if (!fresh && !(it->second.first == bounds))
        throw base::Error("brick " + std::to_string(w.id) + ": render rank " + std::to_string(r) +
                          " gives it other bounds than render rank " +
                          std::to_string(it->second.second.front()) +
                          " (ranks holding one brick id must hold the same brick)");
      if (it->second.second.empty() || it->second.second.back() != r)
        it->second.second.push_back(r);
    }
  }
  if (byId.empty()) throw base::Error("no render rank holds any brick: nothing to render");
  BrickDirectory out;
  for (auto& [id, entry] : byId) {
    out.bricks.push_back({id, entry.first});
    out.holders.push_back(std::move(entry.second));
  }
  return out;
}

}  // namespace renderers
