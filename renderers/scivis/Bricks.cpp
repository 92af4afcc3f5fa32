#include "renderers/scivis/Bricks.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <new>
#include <string>

#include "dfb/Error.h"
#include "dfb/MemoryBudget.h"
#include "messaging/BoundedWait.h"
#include "renderers/Error.h"

namespace renderers {
namespace {

void grow(Box3& b, Vec3 lo, Vec3 hi) {
  b.lo = {std::min(b.lo.x, lo.x), std::min(b.lo.y, lo.y), std::min(b.lo.z, lo.z)};
  b.hi = {std::max(b.hi.x, hi.x), std::max(b.hi.y, hi.y), std::max(b.hi.z, hi.z)};
}

Box3 expanded(const Box3& b, float margin) { return {b.lo - Vec3{margin}, b.hi + Vec3{margin}}; }

bool overlaps(const Box3& a, Vec3 lo, Vec3 hi) {
  return lo.x <= a.hi.x && hi.x >= a.lo.x && lo.y <= a.hi.y && hi.y >= a.lo.y && lo.z <= a.hi.z &&
         hi.z >= a.lo.z;
}

// Every particle set of the scene: its [[particles]] and the path tracer's sphere shapes.
std::vector<const ParticlesDesc*> particleSets(const SceneDesc& desc,
                                               std::vector<ParticlesDesc>& converted) {
  for (const Instance& inst : desc.instances) {
    const Shape& s = desc.shapes.at(inst.shape);
    if (!s.isSpheres()) continue;
    ParticlesDesc p;
    p.name = s.name;
    for (const Vec3& c : s.spheres.centers) p.centers.push_back(inst.transform.point(c));
    p.radii = s.spheres.radii;
    p.material = inst.material;
    converted.push_back(std::move(p));
  }
  std::vector<const ParticlesDesc*> out;
  for (const ParticlesDesc& p : desc.particles) out.push_back(&p);
  for (const ParticlesDesc& p : converted) out.push_back(&p);
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

// The voxels of `g` around `region`, two beyond it: the crossing test samples one step past a
// ray's end and gradients half a voxel around a hit. False: fewer than 2 voxels on an axis.
bool voxelsAround(const GridGeometry& g, const Box3& region, VoxelBox& box) {
  bool empty = false;
  for (int a = 0; a < 3; ++a) {
    const double lo = std::floor((double(region.lo[a]) - g.origin[a]) / g.spacing[a]) - 2;
    const double hi = std::ceil((double(region.hi[a]) - g.origin[a]) / g.spacing[a]) + 3;
    const int i0 = static_cast<int>(std::clamp(lo, 0.0, double(g.dims[a])));
    const int i1 = static_cast<int>(std::clamp(hi, 0.0, double(g.dims[a])));
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
  for (const IsosurfaceDesc& iso : desc.isosurfaces)
    if (iso.volume == volume) return true;
  return false;
}

// What loadBrick holds of volume `i` for `plan` at most: the dense core with its macrocell
// ranges and, with a ghost shell, the shell both sparse (float voxels) and dense, as loadBrick
// may hold both while it chooses.
std::uint64_t brickVolumeBytes(const SceneDesc& desc, std::size_t i, const BrickPlan& plan,
                               float ghost) {
  const VolumeSource& source = desc.volumes[i].source;
  // OpenVDB: while a box is sampled, the leaves of the grid that touch it are held too (as many
  // float voxels again, at most).
  const std::uint64_t width =
      voxelBytes(source.type) * (source.kind == VolumeSource::Kind::OpenVdb ? 2 : 1);
  auto dense = [&](const VoxelBox& b) {
    const std::uint64_t voxels = b.voxelCount();
    return dfb::bytesPlus(dfb::bytesTimes(voxels, width), voxels / 64);  // 8 bytes per 8³
  };
  std::uint64_t bytes = 0;
  VoxelBox core, shell;
  if (voxelsAround(source.grid, plan.bounds, core)) bytes = dense(core);
  if (ghost > 0 && hasIsosurface(desc, i) &&
      voxelsAround(source.grid, {plan.bounds.lo - Vec3{ghost}, plan.bounds.hi + Vec3{ghost}},
                   shell))
    bytes =
        dfb::bytesPlus(bytes, dfb::bytesPlus(dense(shell), dfb::bytesTimes(shell.voxelCount(), 4)));
  return bytes;
}

void split(const Box3& box, int count, int& nextId, std::vector<BrickPlan>& out) {
  if (count == 1) {
    out.push_back({nextId++, box});
    return;
  }
  const Vec3 size = box.hi - box.lo;
  const int axis = size.x >= size.y && size.x >= size.z ? 0 : (size.y >= size.z ? 1 : 2);
  const int left = count / 2;
  const float lo = box.lo[axis], hi = box.hi[axis];
  const float plane = lo + (hi - lo) * static_cast<float>(left) / static_cast<float>(count);
  Box3 a = box, b = box;
  (axis == 0 ? a.hi.x : axis == 1 ? a.hi.y : a.hi.z) = plane;
  (axis == 0 ? b.lo.x : axis == 1 ? b.lo.y : b.lo.z) = plane;
  split(a, left, nextId, out);
  split(b, count - left, nextId, out);
}

}  // namespace

Box3 sceneDomain(const SceneDesc& desc) {
  Box3 domain{Vec3{Box3::kInf}, Vec3{-Box3::kInf}};
  for (const VolumeDesc& v : desc.volumes) {
    Vec3 lo, hi;
    v.source.grid.bounds(v.source.grid.wholeBox(), lo, hi);
    grow(domain, lo, hi);
  }
  std::vector<ParticlesDesc> converted;
  for (const ParticlesDesc* p : particleSets(desc, converted))
    for (std::size_t i = 0; i < p->centers.size(); ++i)
      grow(domain, p->centers[i] - Vec3{p->radius(i)}, p->centers[i] + Vec3{p->radius(i)});
  for (const WorldMesh& m : worldMeshes(desc))
    for (const Vec3& v : m.mesh.positions) grow(domain, v, v);
  if (domain.empty()) throw Error("the scene is empty: nothing to cut into bricks");
  return domain;
}

std::vector<BrickPlan> splitScene(const SceneDesc& desc, int count) {
  if (count < 1) throw Error("--bricks must be at least 1");
  std::vector<BrickPlan> out;
  int nextId = 0;
  split(sceneDomain(desc), count, nextId, out);
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
  throw Error("ghost mode '" + name + "': choose reach (shading rays see what they reach) or " +
              "layer (one ghost layer of voxels)");
}

float ghostMargin(const SceneDesc& desc, float sceneExtent, GhostMode mode) {
  if (mode == GhostMode::Layer || desc.scivis.aoSamples <= 0) return 0.0f;
  return desc.scivis.aoDistance > 0 ? desc.scivis.aoDistance : 0.25f * sceneExtent;
}

namespace {

// loadBrick's work; `part` says what it is loading, for an allocation that fails on the way.
BrickContent loadBrickData(const SceneDesc& desc, const BrickPlan& plan, float ghost,
                           std::string& part) {
  BrickContent c;
  c.bounds = plan.bounds;
  const Box3 reach = expanded(plan.bounds, ghost);
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
    if (ghost > 0 && !isovalues.empty() && voxelsAround(g, reach, shell) && !(shell == core)) {
      ShadingShell sparse =
          ShadingShell::load(v.source, shell, haveCore ? core : VoxelBox{}, isovalues);
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
             overlaps(reach, centre - Vec3{r}, centre + Vec3{r});
    });
    if (!inside.centers.empty()) c.particles.push_back(std::move(inside));
    if (!near.centers.empty()) c.ghostParticles.push_back(std::move(near));
  }
  for (const WorldMesh& m : worldMeshes(desc)) {
    WorldMesh inside =
        selectTriangles(m, [&](Vec3 lo, Vec3 hi) { return overlaps(plan.bounds, lo, hi); });
    WorldMesh near = selectTriangles(m, [&](Vec3 lo, Vec3 hi) {
      return !overlaps(plan.bounds, lo, hi) && overlaps(reach, lo, hi);
    });
    if (!inside.mesh.triangles.empty()) c.meshes.push_back(std::move(inside));
    if (!near.mesh.triangles.empty()) c.ghostMeshes.push_back(std::move(near));
  }
  return c;
}

}  // namespace

BrickContent loadBrick(const SceneDesc& desc, const BrickPlan& plan, float ghost) {
  std::string part;
  try {
    return loadBrickData(desc, plan, ghost, part);
  } catch (const std::bad_alloc&) {
    throw Error(part + ": out of memory while loading brick " + std::to_string(plan.id) +
                "; this rank may hold " + dfb::memoryLimitText());
  }
}

void checkBrickMemory(const SceneDesc& desc, const std::vector<BrickPlan>& plans, float ghost) {
  // Per volume, what the plans hold of it; particles and triangles: those the bricks reach
  // (plus, for triangles, the world-space copy of every mesh loadBrick makes on the way).
  std::vector<std::uint64_t> volumes(desc.volumes.size(), 0);
  std::uint64_t others = desc.bytes();
  std::vector<ParticlesDesc> converted;
  const std::vector<const ParticlesDesc*> sets = particleSets(desc, converted);
  const std::vector<WorldMesh> meshes = worldMeshes(desc);
  for (const BrickPlan& plan : plans) {
    for (std::size_t i = 0; i < desc.volumes.size(); ++i)
      volumes[i] = dfb::bytesPlus(volumes[i], brickVolumeBytes(desc, i, plan, ghost));
    const Box3 reach = expanded(plan.bounds, ghost);
    for (const ParticlesDesc* p : sets) {
      const std::uint64_t each = sizeof(Vec3) + (p->radii.size() > 1 ? 4 : 0) +
                                 (p->attribute.empty() ? 0 : 4) + kBvhBytesPerPrimitive;
      std::uint64_t reached = 0;
      for (std::size_t i = 0; i < p->centers.size(); ++i)
        reached +=
            overlaps(reach, p->centers[i] - Vec3{p->radius(i)}, p->centers[i] + Vec3{p->radius(i)});
      others = dfb::bytesPlus(others, reached * each);
    }
    for (const WorldMesh& m : meshes) {
      // The world-space copy loadBrick makes of every mesh, and the triangles the brick reaches
      // with their share of the BVH.
      others = dfb::bytesPlus(others, m.mesh.positions.size() * sizeof(Vec3) +
                                          m.mesh.triangles.size() * sizeof(m.mesh.triangles[0]));
      std::uint64_t reached = 0;
      for (const auto& t : m.mesh.triangles) {
        const Vec3 a = m.mesh.positions[t[0]], b = m.mesh.positions[t[1]],
                   c = m.mesh.positions[t[2]];
        reached += overlaps(
            reach,
            {std::min({a.x, b.x, c.x}), std::min({a.y, b.y, c.y}), std::min({a.z, b.z, c.z})},
            {std::max({a.x, b.x, c.x}), std::max({a.y, b.y, c.y}), std::max({a.z, b.z, c.z})});
      }
      others = dfb::bytesPlus(others, reached * (3 * sizeof(Vec3) + sizeof(m.mesh.triangles[0]) +
                                                 kBvhBytesPerPrimitive));
    }
  }
  std::uint64_t total = others;
  std::size_t largest = 0;
  for (std::size_t i = 0; i < volumes.size(); ++i) {
    total = dfb::bytesPlus(total, volumes[i]);
    if (volumes[i] > volumes[largest]) largest = i;
  }
  const std::string problem = dfb::memoryProblem(total);
  if (problem.empty()) return;
  const std::string bricks =
      plans.size() == 1 && plans[0].bounds == Box3{}
          ? std::string("the whole scene")
          : std::to_string(plans.size()) + (plans.size() == 1 ? " brick" : " bricks");
  if (!volumes.empty() && volumes[largest] >= others) {
    const VolumeDesc& v = desc.volumes[largest];
    const Index3 n = v.source.grid.dims;
    throw Error(volumeName(v) + ": this rank holds " + std::to_string(volumes[largest]) +
                " bytes of this " + std::to_string(n.x) + "x" + std::to_string(n.y) + "x" +
                std::to_string(n.z) + " " + voxelTypeName(v.source.type) + " volume (" + bricks +
                ", ghost voxels and macrocells included); its data in all " + problem);
  }
  throw Error("the scene's particles and triangles: this rank holds " + std::to_string(others) +
              " bytes of them (" + bricks + "); its data in all " + problem);
}

namespace {

// The plans rank `rank` holds, and their ghost margin.
std::vector<BrickPlan> ownPlans(const SceneDesc& desc, int bricks, int replication, int rank,
                                int ranks, GhostMode ghosts, float& ghost) {
  const std::vector<BrickPlan> plans = splitScene(desc, bricks);
  if (replication < 1) throw Error("--replication must be at least 1");
  const Box3 domain = sceneDomain(desc);
  ghost = ghostMargin(desc, maxComponent(domain.hi - domain.lo), ghosts);
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
  float ghost = 0;
  const std::vector<BrickPlan> mine =
      ownPlans(desc, bricks, replication, rank, ranks, ghosts, ghost);
  checkBrickMemory(desc, mine, ghost);
}

std::vector<HeldBrick> loadOwnBricks(const SceneDesc& desc, int bricks, int replication, int rank,
                                     int ranks, GhostMode ghosts) {
  float ghost = 0;
  const std::vector<BrickPlan> mine =
      ownPlans(desc, bricks, replication, rank, ranks, ghosts, ghost);
  checkBrickMemory(desc, mine, ghost);
  std::vector<HeldBrick> out;
  for (const BrickPlan& plan : mine) out.push_back({plan.id, loadBrick(desc, plan, ghost)});
  return out;
}

namespace {

// One brick on the wire: plain numbers, the same layout on every rank of a job.
struct WireBrick {
  std::int32_t id;
  float lo[3], hi[3];
};

void finish(MPI_Request& request, std::chrono::milliseconds timeout) {
  messaging::waitWithDeadline(request, std::chrono::steady_clock::now() + timeout,
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
    if (b.id < 0) throw Error("brick id " + std::to_string(b.id) + " is negative");
    local.push_back({b.id,
                     {b.bounds.lo.x, b.bounds.lo.y, b.bounds.lo.z},
                     {b.bounds.hi.x, b.bounds.hi.y, b.bounds.hi.z}});
  }
  const int bytes = static_cast<int>(local.size() * sizeof(WireBrick));
  std::vector<int> counts(static_cast<std::size_t>(ranks)), offsets(counts.size());
  MPI_Request request;
  dfb::checkMpi(MPI_Iallgather(&bytes, 1, MPI_INT, counts.data(), 1, MPI_INT, comm, &request),
                "MPI_Iallgather");
  finish(request, timeout);
  int total = 0;
  for (std::size_t r = 0; r < counts.size(); ++r) offsets[r] = total, total += counts[r];
  std::vector<WireBrick> all(static_cast<std::size_t>(total) / sizeof(WireBrick));
  dfb::checkMpi(MPI_Iallgatherv(local.data(), bytes, MPI_BYTE, all.data(), counts.data(),
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
        throw Error("brick " + std::to_string(w.id) + ": render rank " + std::to_string(r) +
                    " gives it other bounds than render rank " +
                    std::to_string(it->second.second.front()) +
                    " (ranks holding one brick id must hold the same brick)");
      if (it->second.second.empty() || it->second.second.back() != r)
        it->second.second.push_back(r);
    }
  }
  if (byId.empty()) throw Error("no render rank holds any brick: nothing to render");
  BrickDirectory out;
  for (auto& [id, entry] : byId) {
    out.bricks.push_back({id, entry.first});
    out.holders.push_back(std::move(entry.second));
  }
  return out;
}

}  // namespace renderers
