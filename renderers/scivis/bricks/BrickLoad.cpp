#include "renderers/scivis/bricks/BrickLoad.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <new>
#include <string>

#include "base/Error.h"
#include "base/MemoryBudget.h"

namespace renderers::scivis {
namespace {

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
  // A face on a voxel plane, off by float rounding, is on it: the margins (2 below, 3 above)
  // hold more than such an offset, and a brick cut at plane z needs voxel z - 2, not z - 3.
  auto index = [&](float at, int a) {
    const double t = (double(at) - g.origin[a]) / g.spacing[a];
    return std::abs(t - std::round(t)) < 1e-3 ? std::round(t) : t;
  };
  bool empty = false;
  for (int a = 0; a < 3; ++a) {
    const double lo = std::floor(index(region.lo[a], a)) - 2;
    const double hi = std::ceil(index(region.hi[a], a)) + 3;
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

std::string volumeName(const VolumeDesc& v) {
  return v.where.empty() ? "volume '" + v.name + "'" : v.where;
}

bool hasIsosurface(const SceneDesc& desc, std::size_t volume) {
  for (const IsosurfaceDesc& iso : sciVisDesc(desc).isosurfaces)
    if (iso.volume == volume) return true;
  return false;
}

// What loadBrick holds of volume `i` for `plan` at most: the dense core with its macrocell
// ranges and, with a ghost shell, the shell both sparse (float voxels) and dense, as loadBrick
// may hold both while it chooses.
std::uint64_t brickVolumeBytes(const SceneDesc& desc, std::size_t i, const BrickPlan& plan,
                               const BrickReach& reach) {
  const VolumeSource& source = sciVisDesc(desc).volumes[i].source;
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

// loadBrick's work; `part` says what it is loading, for an allocation that fails on the way.
BrickContent loadBrickData(const SceneDesc& desc, const BrickPlan& plan, const GhostReach& ghosts,
                           std::string& part) {
  const SciVisDesc& parts = sciVisDesc(desc);
  BrickContent c;
  c.bounds = plan.bounds;
  const BrickReach reach = brickReach(desc, plan.bounds, ghosts);
  for (std::size_t i = 0; i < parts.volumes.size(); ++i) {
    const VolumeDesc& v = parts.volumes[i];
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
    for (const IsosurfaceDesc& iso : parts.isosurfaces)
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

VoxelBox neededVoxels(const SceneDesc& desc, std::size_t volume, const Box3& bounds,
                      const GhostReach& reach) {
  const GridGeometry& g = sciVisDesc(desc).volumes[volume].source.grid;
  VoxelBox core;
  if (!voxelsAround(g, bounds, core)) return {};
  const BrickReach r = brickReach(desc, bounds, reach);
  VoxelBox shell;
  if (r.beyond && hasIsosurface(desc, volume) && voxelsAround(g, r.region, shell, true))
    return shell;
  return core;
}

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
  const SciVisDesc& parts = sciVisDesc(desc);
  // Per volume, what the plans hold of it; particles and triangles: those the bricks reach
  // (plus, for triangles, the world-space copy of every mesh loadBrick makes on the way).
  std::vector<std::uint64_t> volumes(parts.volumes.size(), 0);
  std::uint64_t others = desc.bytes();
  std::vector<ParticlesDesc> converted;
  const std::vector<const ParticlesDesc*> sets = particleSets(desc, converted);
  const std::vector<WorldMesh> meshes = worldMeshes(desc);
  for (const BrickPlan& plan : plans) {
    const BrickReach reach = brickReach(desc, plan.bounds, ghosts);
    for (std::size_t i = 0; i < parts.volumes.size(); ++i)
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
    const VolumeDesc& v = parts.volumes[largest];
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

}  // namespace renderers::scivis
