// The isosurface mesher (marching cubes): vertices on the level set, closed and consistently
// oriented surfaces (also through ambiguous faces), and the same triangles, bit for bit, from
// two bricks that polygonise a shared cell.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <vector>

#include "renderers/scivis/scene/Box.h"
#include "renderers/scivis/scene/Isosurfaces.h"

namespace renderers::scivis {
namespace {

// A field of n³ voxels over [-1, 1]³ held as floats, x fastest.
struct Field {
  GridGeometry grid;
  std::vector<float> values;
  float at(int x, int y, int z) const {
    return values[static_cast<std::size_t>(x) +
                  static_cast<std::size_t>(grid.dims.x) *
                      (static_cast<std::size_t>(y) + static_cast<std::size_t>(grid.dims.y) * z)];
  }
};

template <class F>
Field makeField(int n, F f) {
  Field out;
  out.grid.dims = {n, n, n};
  out.grid.origin = Vec3{-1.0f};
  out.grid.spacing = Vec3{2.0f / static_cast<float>(n - 1)};
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) out.values.push_back(f(x, y, z, out.grid.worldOf(x, y, z)));
  return out;
}

// The cells [lo, hi) cut into blocks of at most 8³ cells (as the scene cuts macrocells).
std::vector<CellBlock> blocksOf(Index3 lo, Index3 hi) {
  std::vector<CellBlock> out;
  for (int z = lo.z; z < hi.z; z += 8)
    for (int y = lo.y; y < hi.y; y += 8)
      for (int x = lo.x; x < hi.x; x += 8)
        out.push_back(
            {{{x, y, z}, {std::min(x + 8, hi.x), std::min(y + 8, hi.y), std::min(z + 8, hi.z)}},
             {},
             0});
  return out;
}

std::vector<IsoMesh> mesh(const Field& f, const std::vector<CellBlock>& blocks,
                          const std::vector<float>& isovalues) {
  return polygonise(f.grid, blocks, isovalues, [&](const CellBlock& b, float* out) {
    for (int z = b.cells.lo.z; z <= b.cells.hi.z; ++z)
      for (int y = b.cells.lo.y; y <= b.cells.hi.y; ++y)
        for (int x = b.cells.lo.x; x <= b.cells.hi.x; ++x) *out++ = f.at(x, y, z);
  });
}

// Per undirected edge of the mesh, how often it is walked each way; true when every edge not
// lying on the domain's border is walked once each way (closed, consistently oriented).
void expectClosedAndOriented(const IsoMesh& m, const Box3& domain) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::array<int, 2>> edges;
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[static_cast<std::size_t>(k)], b = t[(k + 1) % 3u];
      edges[{std::min(a, b), std::max(a, b)}][a < b ? 0 : 1] += 1;
    }
  auto onBorder = [&](Vec3 p, Vec3 q) {
    for (int a = 0; a < 3; ++a)
      if ((p[a] == domain.lo[a] && q[a] == domain.lo[a]) ||
          (p[a] == domain.hi[a] && q[a] == domain.hi[a]))
        return true;
    return false;
  };
  int inner = 0;
  for (const auto& [edge, count] : edges) {
    if (onBorder(m.positions[edge.first], m.positions[edge.second])) continue;
    ++inner;
    ASSERT_EQ(count[0], 1) << "edge " << edge.first << "-" << edge.second;
    ASSERT_EQ(count[1], 1) << "edge " << edge.first << "-" << edge.second;
  }
  EXPECT_GT(inner, 100);
}

TEST(Isosurfaces, ASphereIsClosedOnTheLevelSetAndFacesOutwards) {
  const int n = 41;
  const Field f = makeField(n, [](int, int, int, Vec3 p) { return length(p); });
  const float r = 0.6f, h = f.grid.spacing.x;
  const auto meshes = mesh(f, blocksOf({0, 0, 0}, {n - 1, n - 1, n - 1}), {r});
  ASSERT_EQ(meshes.size(), 1u);
  const IsoMesh& m = meshes[0];
  ASSERT_GT(m.triangles.size(), 1000u);
  // Vertices interpolate |p| linearly along an edge: at most h² / (8 r) off the sphere.
  for (const Vec3& p : m.positions) ASSERT_NEAR(length(p), r, h * h / (8 * r) + 1e-5f);
  expectClosedAndOriented(m, Box3{Vec3{-1}, Vec3{1}});
  // Higher values lie outside: every triangle's normal points away from the centre.
  for (const auto& t : m.triangles) {
    const Vec3 a = m.positions[t[0]], b = m.positions[t[1]], c = m.positions[t[2]];
    ASSERT_GE(dot(cross(b - a, c - a), a + b + c), 0.0f);
  }
  // No vertex twice (welded across blocks), and nothing closer than its edge allows.
  std::vector<std::array<float, 3>> sorted;
  for (const Vec3& p : m.positions) sorted.push_back({p.x, p.y, p.z});
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end());
}

// Random voxels: most cells are ambiguous somewhere, and every shared face must still be cut
// alike by its two cells.
TEST(Isosurfaces, NoiseMakesAClosedOrientedSurfaceThroughAmbiguousFaces) {
  const int n = 24;
  std::uint64_t state = 11;
  const Field f = makeField(n, [&](int, int, int, Vec3) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<float>(state >> 40) / static_cast<float>(1 << 24);
  });
  const auto meshes = mesh(f, blocksOf({0, 0, 0}, {n - 1, n - 1, n - 1}), {0.5f, 0.3f});
  ASSERT_EQ(meshes.size(), 2u);
  for (const IsoMesh& m : meshes) expectClosedAndOriented(m, Box3{Vec3{-1}, Vec3{1}});
}

// Two bricks overlapping in cells x in [10, 16) (blocks cut differently): the triangles of those
// cells are the same bits in both.
TEST(Isosurfaces, TwoBricksMakeTheSameTrianglesInASharedCell) {
  const int n = 33;
  const Field f = makeField(n, [](int, int, int, Vec3 p) {
    return std::sin(3 * p.x) * std::cos(4 * p.y) + 0.5f * std::sin(5 * p.z + p.x);
  });
  const auto a = mesh(f, blocksOf({0, 0, 0}, {16, n - 1, n - 1}), {0.1f});
  const auto b = mesh(f, blocksOf({10, 0, 0}, {n - 1, n - 1, n - 1}), {0.1f});
  const float x0 = f.grid.worldOf(10, 0, 0).x, x1 = f.grid.worldOf(16, 0, 0).x;
  auto shared = [&](const IsoMesh& m) {
    std::vector<std::array<float, 9>> out;
    for (const auto& t : m.triangles) {
      std::array<float, 9> v;
      float cx = 0;
      for (int k = 0; k < 3; ++k) {
        const Vec3 p = m.positions[t[static_cast<std::size_t>(k)]];
        v[3 * k] = p.x, v[3 * k + 1] = p.y, v[3 * k + 2] = p.z;
        cx += p.x / 3;
      }
      if (cx > x0 && cx < x1) out.push_back(v);
    }
    std::sort(out.begin(), out.end(), [](const auto& l, const auto& r) {
      return std::memcmp(l.data(), r.data(), sizeof l) < 0;
    });
    return out;
  };
  const auto sa = shared(a[0]), sb = shared(b[0]);
  ASSERT_GT(sa.size(), 50u);
  ASSERT_EQ(sa.size(), sb.size());
  EXPECT_EQ(std::memcmp(sa.data(), sb.data(), sa.size() * sizeof sa[0]), 0);
}

// Cells inside a block's skip box are left to another mesh: together the two are the whole.
TEST(Isosurfaces, SkippedCellsAreExactlyTheOtherMeshs) {
  const int n = 25;
  const Field f = makeField(n, [](int, int, int, Vec3 p) { return length(p - Vec3{0.1f}); });
  const auto whole = mesh(f, blocksOf({0, 0, 0}, {n - 1, n - 1, n - 1}), {0.7f});
  const VoxelBox inner{{5, 4, 3}, {15, 20, 12}};
  std::vector<CellBlock> outer = blocksOf({0, 0, 0}, {n - 1, n - 1, n - 1});
  for (CellBlock& b : outer) b.skip = inner;
  const auto rest = mesh(f, outer, {0.7f});
  const auto part = mesh(f, blocksOf(inner.lo, inner.hi), {0.7f});
  EXPECT_GT(part[0].triangles.size(), 0u);
  EXPECT_EQ(rest[0].triangles.size() + part[0].triangles.size(), whole[0].triangles.size());
}

}  // namespace
}  // namespace renderers::scivis
