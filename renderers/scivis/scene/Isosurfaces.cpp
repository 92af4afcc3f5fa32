#include "renderers/scivis/scene/Isosurfaces.h"

#include <algorithm>
#include <bit>
#include <unordered_map>

#include "base/Parallel.h"

namespace renderers::scivis {
namespace {

// Cube corners c = x + 2 y + 4 z (the order trilinear() takes them in). Edge e runs along axis
// e / 4 from the corner whose two other coordinates are the bits of e % 4 (lower axis first).
int otherAxis(int axis, int which) {
  return which == 0 ? (axis == 0 ? 1 : 0) : (axis == 2 ? 1 : 2);
}

int edgeStart(int e) {
  const int a = e / 4;
  return ((e & 1) << otherAxis(a, 0)) | (((e >> 1) & 1) << otherAxis(a, 1));
}

int edgeBetween(int c, int d) {
  const int lo = std::min(c, d), a = std::countr_zero(static_cast<unsigned>(c ^ d));
  return a * 4 + ((lo >> otherAxis(a, 0)) & 1) + 2 * ((lo >> otherAxis(a, 1)) & 1);
}

// The two faces edge e lies on, as bits (face 2 a + s: the face at coordinate s of axis a).
int faces(int e) {
  const int a = e / 4, b0 = otherAxis(a, 0), b1 = otherAxis(a, 1);
  return (1 << (2 * b0 + (e & 1))) | (1 << (2 * b1 + ((e >> 1) & 1)));
}

// Per case (bit c set: corner c above): its triangles as edge triples.
struct CaseTable {
  static constexpr int kMaxTriangles = 12;
  std::int8_t edges[256][3 * kMaxTriangles];
  std::uint8_t triangles[256];
  bool unfanned = false;

  CaseTable() {
    for (int mask = 0; mask < 256; ++mask) build(mask);
    // Orient: in case 1 (corner 0 above) the values grow towards corner 0.
    const auto mid = [](int e) {
      const int a = e / 4, c = edgeStart(e);
      Vec3 p{float(c & 1), float((c >> 1) & 1), float((c >> 2) & 1)};
      (a == 0 ? p.x : a == 1 ? p.y : p.z) = 0.5f;
      return p;
    };
    const Vec3 p0 = mid(edges[1][0]), p1 = mid(edges[1][1]), p2 = mid(edges[1][2]);
    if (dot(cross(p1 - p0, p2 - p0), Vec3{-1, -1, -1}) < 0)
      for (int mask = 0; mask < 256; ++mask)
        for (int t = 0; t < triangles[mask]; ++t)
          std::swap(edges[mask][3 * t + 1], edges[mask][3 * t + 2]);
  }

  // The surface crosses each face in segments between its crossed edges. Walking the face
  // counter-clockwise seen from outside, each edge where the walk goes up (below to above) is
  // joined to the next edge, where it comes down: the segment cuts off the corners above
  // between them, so an ambiguous face keeps its two corners above apart; both cells sharing a
  // face see the same corners and cut it alike. A segment runs from its down edge to its up
  // edge, and a cube edge is walked one way by one of its faces and the other way by the other,
  // so each crossed edge has one segment leaving and one arriving: the segments form closed
  // loops, fanned into triangles.
  void build(int mask) {
    const auto above = [&](int c) { return (mask >> c & 1) != 0; };
    int next[12];
    std::fill(next, next + 12, -1);
    for (int a = 0; a < 3; ++a)
      for (int s = 0; s < 2; ++s) {
        const int b0 = otherAxis(a, 0), b1 = otherAxis(a, 1);
        int cycle[4] = {s << a, (s << a) | (1 << b0), (s << a) | (1 << b0) | (1 << b1),
                        (s << a) | (1 << b1)};
        // (b0, b1) order turns about +a for a = 0, 2 and about -a for a = 1; outward is +a on
        // the far side.
        const bool counterClockwise = (a == 1 ? -1 : 1) == (s ? 1 : -1);
        if (!counterClockwise) std::swap(cycle[1], cycle[3]);
        int crossing[4], up[4], n = 0;
        for (int k = 0; k < 4; ++k) {
          const int c = cycle[k], d = cycle[(k + 1) % 4];
          if (above(c) == above(d)) continue;
          crossing[n] = edgeBetween(c, d), up[n] = above(d), ++n;
        }
        for (int i = 0; i < n; ++i)
          if (up[i]) next[crossing[(i + 1) % n]] = crossing[i];
      }
    triangles[mask] = 0;
    bool done[12] = {};
    for (int start = 0; start < 12; ++start) {
      if (next[start] < 0 || done[start]) continue;
      int loop[12], length = 0;
      for (int e = start; !done[e]; e = next[e]) done[e] = true, loop[length++] = e;
      // The fan's apex: one whose chords cross the cell's inside. A chord between two edges of
      // one face would lie in that face, and the neighbouring cell could draw it too (a seam
      // edge with four triangles).
      int apex = -1;
      for (int s = 0; s < length && apex < 0; ++s) {
        bool ok = true;
        for (int j = 2; j + 1 < length && ok; ++j)
          ok = (faces(loop[s]) & faces(loop[(s + j) % length])) == 0;
        if (ok) apex = s;
      }
      if (apex < 0) {
        unfanned = true;
        apex = 0;
      }
      for (int i = 1; i + 1 < length; ++i) {
        std::int8_t* t = &edges[mask][3 * triangles[mask]++];
        t[0] = static_cast<std::int8_t>(loop[apex]);
        t[1] = static_cast<std::int8_t>(loop[(apex + i) % length]);
        t[2] = static_cast<std::int8_t>(loop[(apex + i + 1) % length]);
      }
    }
  }
};

const CaseTable& caseTable() {
  static const CaseTable table;
  return table;
}

// One block's mesh of one isovalue: vertices that lie on the block's border carry their edge's
// key, to be welded with the neighbouring blocks' ones.
struct BlockMesh {
  std::vector<Vec3> positions;
  std::vector<std::uint64_t> borderKey;  // per vertex; ~0: inside the block
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

void polygoniseBlock(const GridGeometry& grid, const CellBlock& block, const float* voxels,
                     float iso, std::vector<std::int32_t>& vertexOf, BlockMesh& out) {
  const CaseTable& table = caseTable();
  const Index3 lo = block.cells.lo, n = block.cells.size();
  const int vx = n.x + 1, vy = n.y + 1, vz = n.z + 1;
  const std::size_t sy = static_cast<std::size_t>(vx), sz = sy * static_cast<std::size_t>(vy);
  vertexOf.assign(sz * static_cast<std::size_t>(vz) * 3, -1);
  const VoxelBox& skip = block.skip;
  auto vertex = [&](int x, int y, int z, int e) -> std::uint32_t {
    const int a = e / 4, c = edgeStart(e);
    const int lx = x + (c & 1), ly = y + ((c >> 1) & 1), lz = z + ((c >> 2) & 1);
    const std::size_t at = static_cast<std::size_t>(lx) + static_cast<std::size_t>(ly) * sy +
                           static_cast<std::size_t>(lz) * sz;
    std::int32_t& v = vertexOf[at * 3 + static_cast<std::size_t>(a)];
    if (v >= 0) return static_cast<std::uint32_t>(v);
    const std::size_t stride = a == 0 ? 1 : a == 1 ? sy : sz;
    const float va = voxels[at], vb = voxels[at + stride];
    float t = (iso - va) / (vb - va);
    if (!(t >= 0.0f)) t = 0.0f;  // NaN too
    if (t > 1.0f) t = 1.0f;
    const int gx = lo.x + lx, gy = lo.y + ly, gz = lo.z + lz;
    out.positions.push_back(grid.worldOf(static_cast<float>(gx) + (a == 0 ? t : 0.0f),
                                         static_cast<float>(gy) + (a == 1 ? t : 0.0f),
                                         static_cast<float>(gz) + (a == 2 ? t : 0.0f)));
    const int l[3] = {lx, ly, lz}, size[3] = {n.x, n.y, n.z};
    bool border = false;
    for (int b = 0; b < 3; ++b) border = border || (b != a && (l[b] == 0 || l[b] == size[b]));
    out.borderKey.push_back(
        border ? ((static_cast<std::uint64_t>(gz) * static_cast<std::uint64_t>(grid.dims.y) +
                   static_cast<std::uint64_t>(gy)) *
                      static_cast<std::uint64_t>(grid.dims.x) +
                  static_cast<std::uint64_t>(gx)) *
                         3 +
                     static_cast<std::uint64_t>(a)
               : ~std::uint64_t{0});
    v = static_cast<std::int32_t>(out.positions.size() - 1);
    return static_cast<std::uint32_t>(v);
  };
  for (int z = 0; z < n.z; ++z)
    for (int y = 0; y < n.y; ++y) {
      const float* row =
          voxels + static_cast<std::size_t>(y) * sy + static_cast<std::size_t>(z) * sz;
      for (int x = 0; x < n.x; ++x) {
        const float* v = row + x;
        const float c[8] = {v[0],  v[1],      v[sy],      v[sy + 1],
                            v[sz], v[sz + 1], v[sz + sy], v[sz + sy + 1]};
        int mask = 0;
        bool missing = false;  // a NaN voxel (a missing value): no surface in this cell
        for (int k = 0; k < 8; ++k) {
          mask |= (c[k] >= iso ? 1 : 0) << k;
          missing = missing || c[k] != c[k];
        }
        if (mask == 0 || mask == 255 || missing) continue;
        const int gx = lo.x + x, gy = lo.y + y, gz = lo.z + z;
        if (!skip.empty() && gx >= skip.lo.x && gx < skip.hi.x && gy >= skip.lo.y &&
            gy < skip.hi.y && gz >= skip.lo.z && gz < skip.hi.z)
          continue;
        const std::int8_t* e = table.edges[mask];
        for (int t = 0; t < table.triangles[mask]; ++t, e += 3)
          out.triangles.push_back(
              {vertex(x, y, z, e[0]), vertex(x, y, z, e[1]), vertex(x, y, z, e[2])});
      }
    }
}

}  // namespace

std::vector<IsoMesh> polygonise(const GridGeometry& grid, const std::vector<CellBlock>& blocks,
                                const std::vector<float>& isovalues, const BlockReader& read) {
  const std::size_t levels = isovalues.size();
  std::vector<BlockMesh> parts(blocks.size() * levels);
  base::parallelFor(blocks.size(), [&](std::size_t b) {
    const CellBlock& block = blocks[b];
    if (block.cells.empty()) return;
    const Index3 n = block.cells.size();
    std::vector<float> voxels(static_cast<std::size_t>(n.x + 1) *
                              static_cast<std::size_t>(n.y + 1) *
                              static_cast<std::size_t>(n.z + 1));
    read(block, voxels.data());
    std::vector<std::int32_t> vertexOf;
    for (std::size_t i = 0; i < levels; ++i)
      polygoniseBlock(grid, block, voxels.data(), isovalues[i], vertexOf, parts[b * levels + i]);
  });
  // Welding, in block order: a border vertex another block made already is that one.
  std::vector<IsoMesh> out(levels);
  for (std::size_t i = 0; i < levels; ++i) {
    IsoMesh& mesh = out[i];
    std::size_t vertices = 0, triangles = 0;
    for (std::size_t b = 0; b < blocks.size(); ++b)
      vertices += parts[b * levels + i].positions.size(),
          triangles += parts[b * levels + i].triangles.size();
    mesh.positions.reserve(vertices);
    mesh.triangles.reserve(triangles);
    std::unordered_map<std::uint64_t, std::uint32_t> border;
    std::vector<std::uint32_t> remap;
    for (std::size_t b = 0; b < blocks.size(); ++b) {
      BlockMesh& part = parts[b * levels + i];
      remap.resize(part.positions.size());
      for (std::size_t v = 0; v < part.positions.size(); ++v) {
        const auto next = static_cast<std::uint32_t>(mesh.positions.size());
        if (part.borderKey[v] != ~std::uint64_t{0}) {
          const auto [it, fresh] = border.try_emplace(part.borderKey[v], next);
          if (!fresh) {
            remap[v] = it->second;
            continue;
          }
        }
        remap[v] = next;
        mesh.positions.push_back(part.positions[v]);
      }
      for (const auto& t : part.triangles)
        mesh.triangles.push_back({remap[t[0]], remap[t[1]], remap[t[2]]});
      part = BlockMesh{};
    }
    mesh.positions.shrink_to_fit();
  }
  return out;
}

}  // namespace renderers::scivis
