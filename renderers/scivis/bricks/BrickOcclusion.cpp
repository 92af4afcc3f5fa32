#include "renderers/scivis/bricks/BrickOcclusion.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <string>

#include "base/Collectives.h"
#include "base/Error.h"

namespace renderers::scivis {
namespace {

// A cell's side of an isovalue: wholly below, wholly above (strictly, every voxel), or neither.
enum Side : std::uint8_t { kUnsure = 0, kBelow = 1, kAbove = 2 };

// One face of a brick (axis a, low or high side): per cell (u, v) along it, in-plane axes
// u = a + 1, v = a + 2 (mod 3), the side of the isovalue that the cell and the next one inwards
// lie on, eroded by a cell in the plane (a cell counts only when its 8 neighbours agree).
struct FaceMap {
  std::int32_t u0 = 0, nu = 0, v0 = 0, nv = 0;  // cell indices of the whole field
  std::vector<std::uint8_t> sides;              // nu * nv, u fastest

  // `perCell`: 1 / spacing. A product instead of a quotient may land a point a rounding away
  // in the neighbouring cell, which the erosion makes the same side or unsure, never the other.
  Side at(Vec3 p, int axis, const Vec3& origin, const Vec3& perCell) const {
    if (nu == 0 || nv == 0) return kUnsure;
    const int u = axis == 2 ? 0 : axis + 1, v = axis == 0 ? 2 : axis - 1;
    const float fu = (p[u] - origin[u]) * perCell[u], fv = (p[v] - origin[v]) * perCell[v];
    if (!(fu == fu) || !(fv == fv)) return kUnsure;
    // Clamped to the face: a point a rounding beyond it lands on the border, which is unsure.
    const float cu =
        std::clamp(std::floor(fu), static_cast<float>(u0), static_cast<float>(u0 + nu - 1));
    const float cv =
        std::clamp(std::floor(fv), static_cast<float>(v0), static_cast<float>(v0 + nv - 1));
    const std::size_t i = static_cast<std::size_t>(static_cast<int>(cv) - v0) * nu +
                          static_cast<std::size_t>(static_cast<int>(cu) - u0);
    return static_cast<Side>(sides[i]);
  }
};

// One isosurface of one brick: the grid its cells lie on and its 6 faces (-x, +x, -y, +y, -z, +z).
struct IsoFaces {
  Vec3 origin, spacing{1.0f}, perCell{1.0f};  // perCell = 1 / spacing
  std::array<FaceMap, 6> faces;
};

struct BrickSummary {
  std::vector<IsoFaces> isos;  // per SciVisDesc::isosurfaces entry
};

// The side of `iso` that cell (i, j, k) lies on (all 8 voxels strictly below or above; a voxel
// not held or NaN: unsure). Marching cubes puts a vertex only on an edge whose voxels straddle
// the isovalue (value >= iso counts as above), so such a cell holds no part of the surface.
Side cellSide(const Volume& v, int i, int j, int k, float iso) {
  if (i < v.box.lo.x || j < v.box.lo.y || k < v.box.lo.z || i + 1 >= v.box.hi.x ||
      j + 1 >= v.box.hi.y || k + 1 >= v.box.hi.z)
    return kUnsure;
  float lo = 0, hi = 0;
  for (int c = 0; c < 8; ++c) {
    const float x = v.at(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
    if (!(x == x)) return kUnsure;
    lo = c == 0 ? x : std::min(lo, x), hi = c == 0 ? x : std::max(hi, x);
  }
  return hi < iso ? kBelow : (lo > iso ? kAbove : kUnsure);
}

IsoFaces summariseIso(const Volume& volume, const Box3& bounds, float iso) {
  IsoFaces out;
  const GridGeometry& g = volume.grid;
  out.origin = g.origin, out.spacing = g.spacing;
  if (volume.box.empty()) return out;
  // The cells meeting the brick's (closed) bounds, per axis; none when the bounds reach beyond
  // the grid's voxel centres (a point on such a face may lie in no cell at all). A bound on the
  // first or last voxel plane may miss it by float rounding of the spacing: a thousandth of a
  // cell is taken as on it (such a point is clamped into the border cell, which it touches).
  constexpr double kSlack = 1e-3;
  int lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    const double l = (double(bounds.lo[a]) - g.origin[a]) / g.spacing[a];
    const double h = (double(bounds.hi[a]) - g.origin[a]) / g.spacing[a];
    if (!(l >= -kSlack) || !(h <= double(g.dims[a] - 1) + kSlack) || !(l <= h)) return out;
    lo[a] = std::clamp(static_cast<int>(std::floor(l)), 0, g.dims[a] - 2);
    hi[a] = std::clamp(static_cast<int>(std::ceil(h)) - 1, lo[a], g.dims[a] - 2);
  }
  for (int f = 0; f < 6; ++f) {
    const int a = f / 2, u = (a + 1) % 3, v = (a + 2) % 3;
    const bool high = f % 2 == 1;
    // Two cells deep, so a point on the face has a cell of solid side behind it.
    if (hi[a] - lo[a] < 1) continue;
    const int layer0 = high ? hi[a] : lo[a], layer1 = high ? hi[a] - 1 : lo[a] + 1;
    FaceMap& map = out.faces[static_cast<std::size_t>(f)];
    map.u0 = lo[u], map.nu = hi[u] - lo[u] + 1, map.v0 = lo[v], map.nv = hi[v] - lo[v] + 1;
    std::vector<std::uint8_t> raw(static_cast<std::size_t>(map.nu) * map.nv);
    for (int cv = 0; cv < map.nv; ++cv)
      for (int cu = 0; cu < map.nu; ++cu) {
        int c[3];
        c[u] = lo[u] + cu, c[v] = lo[v] + cv, c[a] = layer0;
        const Side s0 = cellSide(volume, c[0], c[1], c[2], iso);
        c[a] = layer1;
        const Side s1 = s0 == kUnsure ? kUnsure : cellSide(volume, c[0], c[1], c[2], iso);
        raw[static_cast<std::size_t>(cv) * map.nu + cu] = s0 == s1 ? s0 : kUnsure;
      }
    map.sides.assign(raw.size(), kUnsure);
    for (int cv = 1; cv + 1 < map.nv; ++cv)
      for (int cu = 1; cu + 1 < map.nu; ++cu) {
        const std::uint8_t s = raw[static_cast<std::size_t>(cv) * map.nu + cu];
        bool agree = s != kUnsure;
        for (int dv = -1; dv <= 1 && agree; ++dv)
          for (int du = -1; du <= 1 && agree; ++du)
            agree = raw[static_cast<std::size_t>(cv + dv) * map.nu + (cu + du)] == s;
        if (agree) map.sides[static_cast<std::size_t>(cv) * map.nu + cu] = s;
      }
  }
  return out;
}

// The wire form: per isosurface the grid (6 floats), then per face u0, nu, v0, nv and the sides.
template <typename T>
void put(std::vector<std::uint8_t>& out, const T& value) {
  const auto* p = reinterpret_cast<const std::uint8_t*>(&value);
  out.insert(out.end(), p, p + sizeof(T));
}
template <typename T>
T take(const std::vector<std::uint8_t>& in, std::size_t& at) {
  if (at + sizeof(T) > in.size()) throw base::Error("brick occlusion summary: truncated");
  T value;
  std::memcpy(&value, in.data() + at, sizeof(T));
  at += sizeof(T);
  return value;
}

BrickSummary parse(const std::vector<std::uint8_t>& in, std::size_t& at, std::size_t isos) {
  BrickSummary s;
  s.isos.resize(isos);
  for (IsoFaces& iso : s.isos) {
    float g[6];
    for (float& x : g) x = take<float>(in, at);
    iso.origin = {g[0], g[1], g[2]}, iso.spacing = {g[3], g[4], g[5]};
    iso.perCell = {1.0f / g[3], 1.0f / g[4], 1.0f / g[5]};
    for (FaceMap& f : iso.faces) {
      f.u0 = take<std::int32_t>(in, at), f.nu = take<std::int32_t>(in, at);
      f.v0 = take<std::int32_t>(in, at), f.nv = take<std::int32_t>(in, at);
      if (f.nu < 0 || f.nv < 0) throw base::Error("brick occlusion summary: a negative face size");
      const std::size_t n = static_cast<std::size_t>(f.nu) * static_cast<std::size_t>(f.nv);
      if (at + n > in.size()) throw base::Error("brick occlusion summary: truncated");
      f.sides.assign(in.begin() + static_cast<std::ptrdiff_t>(at),
                     in.begin() + static_cast<std::ptrdiff_t>(at + n));
      at += n;
    }
  }
  return s;
}

}  // namespace

struct BrickOcclusion::Impl {
  std::vector<Box3> bounds;             // per directory brick
  std::vector<BrickSummary> summaries;  // the same; empty isos: nothing known
  std::size_t bytes = 0;
};

BrickOcclusion::BrickOcclusion() : impl_(std::make_unique<Impl>()) {}
BrickOcclusion::~BrickOcclusion() = default;
BrickOcclusion::BrickOcclusion(BrickOcclusion&&) noexcept = default;
BrickOcclusion& BrickOcclusion::operator=(BrickOcclusion&&) noexcept = default;

bool BrickOcclusion::exactFor(const SceneDesc& desc) {
  if (sciVisDesc(desc).isosurfaces.empty()) return false;
  for (const VolumeDesc& v : sciVisDesc(desc).volumes)
    if (v.visible) return false;
  for (const Material& m : desc.materials)
    if (m.opacity != 1.0f) return false;
  return true;
}

std::vector<std::uint8_t> BrickOcclusion::summarise(const SceneDesc& desc,
                                                    const BrickContent& content) {
  std::vector<std::uint8_t> out;
  for (const IsosurfaceDesc& iso : sciVisDesc(desc).isosurfaces) {
    const IsoFaces faces =
        iso.volume < content.volumes.size()
            ? summariseIso(content.volumes[iso.volume], content.bounds, iso.value)
            : IsoFaces{};
    for (int a = 0; a < 3; ++a) put(out, faces.origin[a]);
    for (int a = 0; a < 3; ++a) put(out, faces.spacing[a]);
    for (const FaceMap& f : faces.faces) {
      put(out, f.u0), put(out, f.nu), put(out, f.v0), put(out, f.nv);
      out.insert(out.end(), f.sides.begin(), f.sides.end());
    }
  }
  return out;
}

BrickOcclusion BrickOcclusion::exchange(
    const SceneDesc& desc, const std::vector<BrickPlan>& bricks,
    const std::vector<std::pair<int, const BrickContent*>>& held, MPI_Comm comm,
    std::chrono::milliseconds timeout) {
  // Mine: per held brick its id, the summary's length and the summary.
  std::vector<std::uint8_t> local;
  for (const auto& [id, content] : held) {
    const std::vector<std::uint8_t> s = summarise(desc, *content);
    put(local, static_cast<std::int32_t>(id));
    put(local, static_cast<std::uint64_t>(s.size()));
    local.insert(local.end(), s.begin(), s.end());
  }
  if (local.size() > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw base::Error("brick occlusion summaries of one rank exceed 2 GB");
  const std::vector<std::uint8_t> all = base::allgatherv(
      local, comm,
      {.until = timeout,
       .late = "exchanging brick occlusion summaries: another render rank did not join within " +
               std::to_string(timeout.count()) + " ms",
       .tooLarge = "brick occlusion summaries of the job exceed 2 GB"});

  BrickOcclusion out;
  Impl& m = *out.impl_;
  m.summaries.resize(bricks.size());
  for (const BrickPlan& b : bricks) m.bounds.push_back(b.bounds);
  std::vector<bool> known(bricks.size(), false);
  std::size_t at = 0;
  while (at < all.size()) {
    const int id = take<std::int32_t>(all, at);
    const std::size_t size = static_cast<std::size_t>(take<std::uint64_t>(all, at));
    if (size > all.size() - at) throw base::Error("brick occlusion summary: truncated");
    const auto it =
        std::find_if(bricks.begin(), bricks.end(), [&](const BrickPlan& p) { return p.id == id; });
    const std::size_t end = at + size;
    if (it != bricks.end() && !known[static_cast<std::size_t>(it - bricks.begin())]) {
      const std::size_t i = static_cast<std::size_t>(it - bricks.begin());
      std::size_t pos = at;
      m.summaries[i] = parse(all, pos, sciVisDesc(desc).isosurfaces.size());
      known[i] = true;
      m.bytes += size;
    }
    at = end;
  }
  return out;
}

std::size_t BrickOcclusion::bytes() const { return impl_->bytes; }

bool BrickOcclusion::hides(int brick, Vec3 origin, Vec3 dir, Vec3 invDir, float before,
                           bool winsTie) const {
  const Impl& m = *impl_;
  if (brick < 0 || static_cast<std::size_t>(brick) >= m.summaries.size()) return false;
  const BrickSummary& s = m.summaries[static_cast<std::size_t>(brick)];
  if (s.isos.empty()) return false;
  // clipToBox's slabs, keeping the faces that set the entry and the exit. NaN slabs (a ray on
  // a face's plane) are skipped as clipToBox skips them, so from [0, inf) its t0 is `entry` when
  // that is >= 0, and its t1 is `exit`.
  const Box3& box = m.bounds[static_cast<std::size_t>(brick)];
  float entry = -Box3::kInf, exit = Box3::kInf;
  int entryFace = -1, exitFace = -1;
  for (int a = 0; a < 3; ++a) {
    const float lo = (box.lo[a] - origin[a]) * invDir[a], hi = (box.hi[a] - origin[a]) * invDir[a];
    const bool flip = lo > hi;
    const float near = flip ? hi : lo, far = flip ? lo : hi;
    if (near > entry) entry = near, entryFace = 2 * a + (flip ? 1 : 0);
    if (far < exit) exit = far, exitFace = 2 * a + (flip ? 0 : 1);
  }
  // A ray starting inside the brick (the camera in it) does not enter by a face.
  if (entryFace < 0 || exitFace < 0 || !(entry >= 0)) return false;
  const float t0 = entry, t1 = exit;
  if (!(t0 < t1) || !(t0 < before || (t0 == before && winsTie))) return false;
  const Vec3 p0 = origin + dir * t0, p1 = origin + dir * t1;
  for (const IsoFaces& iso : s.isos) {
    const Side in = iso.faces[static_cast<std::size_t>(entryFace)].at(p0, entryFace / 2, iso.origin,
                                                                      iso.perCell);
    if (in == kUnsure) continue;
    const Side out =
        iso.faces[static_cast<std::size_t>(exitFace)].at(p1, exitFace / 2, iso.origin, iso.perCell);
    if (out != kUnsure && out != in) return true;
  }
  return false;
}

}  // namespace renderers::scivis
