#include "api/GhostExchange.h"

#include <algorithm>
#include <chrono>
#include <climits>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

#include "api/SceneStyle.h"
#include "base/BoundedWait.h"
#include "renderers/scivis/bricks/BrickPlan.h"
#include "renderers/scivis/io/SciVisDesc.h"

namespace dfbwall {
namespace {

using renderers::Index3;
using renderers::Volume;
using renderers::VoxelBox;
using renderers::scivis::HeldBrick;

// Point-to-point messages on the render ranks' communicator, matched in the order both sides
// post them (MPI's messages between two ranks with one tag do not overtake each other).
constexpr int kGhostTag = 0x6705;

// What every rank learns of each exchanged part.
struct PartRecord {
  int brick, volume, rank, type;
  int lo[3], hi[3];
  float boundsLo[3], boundsHi[3];
};

VoxelBox ownedBox(const PartRecord& r) {
  return {{r.lo[0], r.lo[1], r.lo[2]}, {r.hi[0], r.hi[1], r.hi[2]}};
}

VoxelBox intersection(const VoxelBox& a, const VoxelBox& b) {
  return {{std::max(a.lo.x, b.lo.x), std::max(a.lo.y, b.lo.y), std::max(a.lo.z, b.lo.z)},
          {std::min(a.hi.x, b.hi.x), std::min(a.hi.y, b.hi.y), std::min(a.hi.z, b.hi.z)}};
}

VoxelBox hull(const VoxelBox& a, const VoxelBox& b) {
  if (a.empty()) return b;
  return {{std::min(a.lo.x, b.lo.x), std::min(a.lo.y, b.lo.y), std::min(a.lo.z, b.lo.z)},
          {std::max(a.hi.x, b.hi.x), std::max(a.hi.y, b.hi.y), std::max(a.hi.z, b.hi.z)}};
}

bool holds(const VoxelBox& b, const Index3& p) {
  return p.x >= b.lo.x && p.x < b.hi.x && p.y >= b.lo.y && p.y < b.hi.y && p.z >= b.lo.z &&
         p.z < b.hi.z;
}

std::string text(const Index3& p) {
  return "(" + std::to_string(p.x) + ", " + std::to_string(p.y) + ", " + std::to_string(p.z) + ")";
}

// "brick 3 on render rank 1, voxels [(0, 0, 12), (48, 48, 24))"
std::string named(const PartRecord& r) {
  const VoxelBox b = ownedBox(r);
  return "brick " + std::to_string(r.brick) + " on render rank " + std::to_string(r.rank) +
         ", voxels [" + text(b.lo) + ", " + text(b.hi) + ")";
}

// Whether `b` touches `cell` face to face (along one axis they meet, along the others overlap).
bool adjacent(const VoxelBox& b, const VoxelBox& cell) {
  for (int a = 0; a < 3; ++a) {
    if (b.hi[a] != cell.lo[a] && b.lo[a] != cell.hi[a]) continue;
    bool across = true;
    for (int o = 0; o < 3; ++o)
      if (o != a) across = across && b.lo[o] < cell.hi[o] && cell.lo[o] < b.hi[o];
    if (across) return true;
  }
  return false;
}

// A part of the field no box holds, or nullopt when the boxes cover it: the first cell of the
// grid of every box's faces that no box holds.
std::optional<VoxelBox> gap(const std::vector<const PartRecord*>& parts, const Index3& dims) {
  std::vector<int> faces[3];
  for (int a = 0; a < 3; ++a) {
    faces[a] = {0, dims[a]};
    for (const PartRecord* r : parts) {
      faces[a].push_back(std::clamp(r->lo[a], 0, dims[a]));
      faces[a].push_back(std::clamp(r->hi[a], 0, dims[a]));
    }
    std::sort(faces[a].begin(), faces[a].end());
    faces[a].erase(std::unique(faces[a].begin(), faces[a].end()), faces[a].end());
  }
  for (std::size_t k = 0; k + 1 < faces[2].size(); ++k)
    for (std::size_t j = 0; j + 1 < faces[1].size(); ++j)
      for (std::size_t i = 0; i + 1 < faces[0].size(); ++i) {
        const Index3 p{faces[0][i], faces[1][j], faces[2][k]};
        if (std::none_of(parts.begin(), parts.end(),
                         [&](const PartRecord* r) { return holds(ownedBox(*r), p); }))
          return VoxelBox{p, {faces[0][i + 1], faces[1][j + 1], faces[2][k + 1]}};
      }
  return std::nullopt;
}

// The parts of one volume, one per brick (a replicated brick: its lowest rank's), must tile its
// field. Every rank checks the same records, so every rank throws the same InputError.
void checkTiling(const std::string& volume, const std::vector<const PartRecord*>& parts,
                 const Index3& dims) {
  const std::string where = "dfbwall: volume '" + volume + "', ghosts exchanged: ";
  for (std::size_t i = 0; i < parts.size(); ++i)
    for (std::size_t j = i + 1; j < parts.size(); ++j) {
      if (parts[i]->type != parts[j]->type)
        throw InputError(where + named(*parts[i]) + ", and " + named(*parts[j]) +
                         ", hold different voxel types (give one type for every part)");
      if (!intersection(ownedBox(*parts[i]), ownedBox(*parts[j])).empty())
        throw InputError(where + "the owned boxes of " + named(*parts[i]) + ", and " +
                         named(*parts[j]) + ", overlap (each voxel must be owned by one brick)");
    }
  std::uint64_t covered = 0;
  for (const PartRecord* r : parts) covered += ownedBox(*r).voxelCount();
  const std::uint64_t whole = static_cast<std::uint64_t>(dims.x) *
                              static_cast<std::uint64_t>(dims.y) *
                              static_cast<std::uint64_t>(dims.z);
  if (covered == whole) return;
  const std::optional<VoxelBox> hole = gap(parts, dims);
  if (!hole) return;  // (not reached: boxes inside the field that do not overlap and cover it all)
  std::string around;
  for (const PartRecord* r : parts)
    if (adjacent(ownedBox(*r), *hole)) around += (around.empty() ? "" : "; ") + named(*r);
  throw InputError(where + "voxels [" + text(hole->lo) + ", " + text(hole->hi) +
                   ") are in no brick's owned box (the owned boxes must cover the field's " +
                   text(dims) + " voxels); the boxes around them: " + around);
}

// Voxels laid out as a Volume holds them: `box`, x fastest, slices `stride` voxels apart.
struct Layout {
  std::byte* data;
  VoxelBox box;
  std::size_t stride, width;
  std::byte* at(int x, int y, int z) const {
    const auto sx = static_cast<std::size_t>(box.hi.x - box.lo.x);
    return data +
           (static_cast<std::size_t>(z - box.lo.z) * stride +
            static_cast<std::size_t>(y - box.lo.y) * sx + static_cast<std::size_t>(x - box.lo.x)) *
               width;
  }
};

Layout layoutOf(Volume& v) {
  return {v.voxels.data(), v.box, v.sliceStride(), renderers::voxelBytes(v.type)};
}
// Read only: held or borrowed voxels.
Layout layoutOf(const Volume& v) {
  return {const_cast<std::byte*>(v.data()), v.box, v.sliceStride(), renderers::voxelBytes(v.type)};
}
Layout layoutOf(std::vector<std::byte>& packed, const VoxelBox& region, std::size_t width) {
  const Index3 s = region.size();
  return {packed.data(), region, static_cast<std::size_t>(s.x) * static_cast<std::size_t>(s.y),
          width};
}

void copyRegion(const Layout& from, const VoxelBox& region, const Layout& to) {
  const std::size_t row = static_cast<std::size_t>(region.hi.x - region.lo.x) * from.width;
  for (int z = region.lo.z; z < region.hi.z; ++z)
    for (int y = region.lo.y; y < region.hi.y; ++y)
      std::memcpy(to.at(region.lo.x, y, z), from.at(region.lo.x, y, z), row);
}

const Volume& volumeOf(const std::vector<HeldBrick>& bricks, const OwnedPart& part) {
  for (const HeldBrick& b : bricks)
    if (b.id == part.brick) return b.content.volumes.at(part.volume);
  throw std::logic_error("dfbwall: ghost exchange for brick " + std::to_string(part.brick) +
                         ", which this rank does not hold");
}

}  // namespace

std::size_t exchangeGhosts(const Style& style, std::vector<HeldBrick>& bricks,
                           const std::vector<OwnedPart>& parts, MPI_Comm comm,
                           const base::Bound& bound) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  std::vector<PartRecord> mine;
  for (const OwnedPart& p : parts) {
    const Volume& v = volumeOf(bricks, p);
    PartRecord r{};
    r.brick = p.brick;
    r.volume = static_cast<int>(p.volume);
    r.rank = rank;
    r.type = static_cast<int>(v.type);
    for (int a = 0; a < 3; ++a) {
      r.lo[a] = p.owned.lo[a];
      r.hi[a] = p.owned.hi[a];
    }
    for (const HeldBrick& b : bricks)
      if (b.id == p.brick)
        for (int a = 0; a < 3; ++a) {
          r.boundsLo[a] = b.content.bounds.lo[a];
          r.boundsHi[a] = b.content.bounds.hi[a];
        }
    mine.push_back(r);
  }
  const std::vector<PartRecord> all = base::allgatherv(mine, comm, bound);
  if (all.empty()) return 0;

  // Which voxels the renderer reads around each brick: the style's scene without its data (a
  // fixed value range needs no collective; the range does not change what rays reach).
  Style fixed = style;
  for (VolumeStyle& v : fixed.volumes) v.autoRange = false;
  const renderers::SceneDesc desc = sceneDesc(fixed, {}, comm, std::chrono::milliseconds(0));
  const renderers::scivis::GhostReach reach = renderers::scivis::ghostReach(desc);

  // The source of each brick's owned voxels: its first record (all is in rank order).
  std::vector<std::size_t> sources;
  for (std::size_t v = 0; v < style.volumes.size(); ++v) {
    std::vector<const PartRecord*> unique;
    for (std::size_t i = 0; i < all.size(); ++i) {
      if (all[i].volume != static_cast<int>(v)) continue;
      const auto same = std::find_if(unique.begin(), unique.end(),
                                     [&](const PartRecord* r) { return r->brick == all[i].brick; });
      if (same == unique.end()) {
        unique.push_back(&all[i]);
        sources.push_back(i);
      } else if (!(ownedBox(**same) == ownedBox(all[i]))) {
        throw InputError("dfbwall: volume '" + style.volumes[v].name +
                         "', ghosts exchanged: brick " + std::to_string(all[i].brick) +
                         " owns different boxes on two ranks: " + named(**same) + ", and " +
                         named(all[i]) + " (the same id must be the same data)");
      }
    }
    if (!unique.empty()) {
      const FieldGrid& g = style.volumes[v].grid;
      checkTiling(style.volumes[v].name, unique, {g.dims[0], g.dims[1], g.dims[2]});
    }
  }

  // What each part must hold: what its renderer reads, and what it owns.
  std::vector<VoxelBox> need(all.size());
  for (std::size_t i = 0; i < all.size(); ++i) {
    const PartRecord& r = all[i];
    const renderers::scivis::Box3 bounds{
        renderers::Vec3{r.boundsLo[0], r.boundsLo[1], r.boundsLo[2]},
        renderers::Vec3{r.boundsHi[0], r.boundsHi[1], r.boundsHi[2]}};
    need[i] = hull(
        renderers::scivis::neededVoxels(desc, static_cast<std::size_t>(r.volume), bounds, reach),
        ownedBox(r));
  }
  struct Transfer {
    std::size_t to, from;
    VoxelBox region;
  };
  std::vector<Transfer> transfers;
  for (std::size_t i = 0; i < all.size(); ++i)
    for (std::size_t s : sources)
      if (all[s].volume == all[i].volume && all[s].brick != all[i].brick) {
        const VoxelBox region = intersection(need[i], ownedBox(all[s]));
        if (region.empty()) continue;
        const std::uint64_t bytes =
            region.voxelCount() *
            renderers::voxelBytes(static_cast<renderers::VoxelType>(all[s].type));
        if (bytes > static_cast<std::uint64_t>(INT_MAX))
          throw InputError("dfbwall: ghosts exchanged: " + named(all[i]) + " needs " +
                           std::to_string(bytes) + " bytes from " + named(all[s]) +
                           ", over one message's 2^31 - 1: use smaller bricks");
        transfers.push_back({i, s, region});
      }

  // This rank's parts, grown: their owned voxels first.
  std::vector<std::size_t> local(all.size(), parts.size());
  for (std::size_t i = 0, k = 0; i < all.size(); ++i)
    if (all[i].rank == rank) local[i] = k++;
  std::vector<const Volume*> held(parts.size());
  std::vector<Volume> grown(parts.size());
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (local[i] == parts.size()) continue;
    const std::size_t k = local[i];
    held[k] = &volumeOf(bricks, parts[k]);
    Volume& g = grown[k];
    g.grid = held[k]->grid;
    g.type = held[k]->type;
    g.box = need[i];
    g.voxels = renderers::allocateVoxelBytes(g.box, g.type);
    copyRegion(layoutOf(*held[k]), parts[k].owned, layoutOf(g));
  }

  // The ghosts: copied from this rank's own bricks, or sent and received in the order of
  // `transfers`, which every rank lists alike.
  std::vector<std::vector<std::byte>> buffers;
  std::vector<MPI_Request> requests;
  struct Landing {
    std::size_t buffer, part;
    VoxelBox region;
  };
  std::vector<Landing> landings;
  std::size_t received = 0;
  for (const Transfer& t : transfers) {
    const int from = all[t.from].rank, to = all[t.to].rank;
    const std::size_t width =
        renderers::voxelBytes(static_cast<renderers::VoxelType>(all[t.from].type));
    const int bytes = static_cast<int>(t.region.voxelCount() * width);
    if (from == rank && to == rank) {
      copyRegion(layoutOf(*held[local[t.from]]), t.region, layoutOf(grown[local[t.to]]));
    } else if (from == rank) {
      buffers.emplace_back(static_cast<std::size_t>(bytes));
      copyRegion(layoutOf(*held[local[t.from]]), t.region,
                 layoutOf(buffers.back(), t.region, width));
      requests.emplace_back();
      base::checkMpi(
          MPI_Isend(buffers.back().data(), bytes, MPI_BYTE, to, kGhostTag, comm, &requests.back()),
          "MPI_Isend");
    } else if (to == rank) {
      buffers.emplace_back(static_cast<std::size_t>(bytes));
      landings.push_back({buffers.size() - 1, local[t.to], t.region});
      requests.emplace_back();
      base::checkMpi(MPI_Irecv(buffers.back().data(), bytes, MPI_BYTE, from, kGhostTag, comm,
                               &requests.back()),
                     "MPI_Irecv");
      received += static_cast<std::size_t>(bytes);
    }
  }
  try {
    const auto deadline = bound.deadline();
    for (MPI_Request& r : requests)
      base::waitWithDeadline(r, deadline, bound.late, bound.maxSleep, bound.unless);
  } catch (...) {
    // MPI may still write them: kept for the rest of the process (base/Collectives.h).
    base::collectives::keepWhilePosted(std::move(buffers), std::move(requests));
    throw;
  }
  for (const Landing& l : landings) {
    const std::size_t width = renderers::voxelBytes(grown[l.part].type);
    copyRegion(layoutOf(buffers[l.buffer], l.region, width), l.region, layoutOf(grown[l.part]));
  }
  for (std::size_t k = 0; k < parts.size(); ++k) {
    grown[k].updateRange();
    for (HeldBrick& b : bricks)
      if (b.id == parts[k].brick) b.content.volumes[parts[k].volume] = std::move(grown[k]);
  }
  return received;
}

}  // namespace dfbwall
