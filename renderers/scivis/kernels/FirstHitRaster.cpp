#include "renderers/scivis/kernels/FirstHitRaster.h"

#include <immintrin.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>

#include "base/Parallel.h"

#include "renderers/scivis/kernels/Avx512.h"

namespace renderers::scivis {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
// How far a triangle's screen box is widened: a pixel's ray and the projection of the point it
// hits agree to far less than this (float rounding of canvas coordinates below 2^14).
constexpr float kMargin = 1.0f / 32.0f;
constexpr std::size_t kChunk = 65536;        // triangles per task making the clusters' keys
constexpr int kBuckets = 4096;               // depth buckets a frame's clusters are sorted in
constexpr std::uint32_t kClusterSize = 16;   // triangles a cluster
constexpr std::size_t kClusterChunk = 4096;  // clusters per binning task
// The per-chunk rows of counts (depth buckets, screen cells) are this many entries longer than
// they hold: the offsets pass walks one entry of every row in turn, and rows a power of two of
// bytes apart (16 KiB of buckets, 64 KiB of cells at 2048²) all fell into the same cache sets,
// so each of those reads missed.
constexpr std::size_t kCountRowPad = 64 / sizeof(std::uint32_t);
// A triangle's least depth is its vertices' least less this share of it (so every hit the ray
// test finds on it lies deeper); a cluster's, its points' less twice that, so it lies below
// each of its triangles' whatever the rounding.
constexpr float kNearMargin = 1e-4f;
inline float triangleNear(float least) { return least - kNearMargin * least; }
inline float clusterNear(float least) { return least - 2 * kNearMargin * least; }

struct PixelBox {
  int x0, y0, x1, y1;  // inclusive; empty when x0 > x1 or y0 > y1
};

// The pixels whose sample point may lie in [minX, maxX] x [minY, maxY] (canvas coordinates),
// clamped to the canvas.
inline PixelBox pixelsIn(float minX, float maxX, float minY, float maxY, int width, int height) {
  minX -= kMargin, maxX += kMargin, minY -= kMargin, maxY += kMargin;
  // Clamped in float first: a vertex near the camera's plane projects far off the canvas. NaN
  // (never made by prepare()) would give an empty box.
  const float w = static_cast<float>(width), h = static_cast<float>(height);
  PixelBox box;
  box.x0 = static_cast<int>(std::floor(std::clamp(minX, -1.0f, w)));
  box.x1 = static_cast<int>(std::floor(std::clamp(maxX, -1.0f, w)));
  box.y0 = static_cast<int>(std::floor(std::clamp(minY, -1.0f, h)));
  box.y1 = static_cast<int>(std::floor(std::clamp(maxY, -1.0f, h)));
  box.x0 = std::max(box.x0, 0), box.y0 = std::max(box.y0, 0);
  box.x1 = std::min(box.x1, width - 1), box.y1 = std::min(box.y1, height - 1);
  return box;
}

// The pixels whose sample point may lie in the projection of (a, b, c).
inline PixelBox pixelsOf(float ax, float ay, float bx, float by, float cx, float cy, int width,
                         int height) {
  return pixelsIn(std::min(ax, std::min(bx, cx)), std::max(ax, std::max(bx, cx)),
                  std::min(ay, std::min(by, cy)), std::max(ay, std::max(by, cy)), width, height);
}

struct Vec {
  float x, y, z;
};

inline Vec minus(Vec a, Vec b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec crossOf(Vec a, Vec b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
// Without branches: which way an edge runs is as good as random, so a branch would often be
// mispredicted.
inline bool before(Vec a, Vec b) {
  return (a.x < b.x) | ((a.x == b.x) & ((a.y < b.y) | ((a.y == b.y) & (a.z < b.z))));
}
inline Vec select(bool first, Vec a, Vec b) {
  return {first ? a.x : b.x, first ? a.y : b.y, first ? a.z : b.z};
}

// The plane through the camera at `o` and the edge from p to q, as its normal (p - o) x (q - p):
// the same as (p - o) x (q - o), but from the short edge vector, not from two long, nearly
// parallel ones whose cross product cancels (that moved the edges of small, far triangles by a
// fraction of a pixel, and let through or caught rays near them). Computed from the endpoints
// in one order (the first by coordinates) and negated for the other, so the two triangles
// sharing an edge get exactly opposite normals: watertight, also across bricks (whose meshes
// number their vertices differently but place them alike).
inline Vec edgePlane(Vec p, Vec q, Vec o) {
  const bool reversed = before(q, p);
  const Vec from = select(reversed, q, p), to = select(reversed, p, q);
  const Vec c = crossOf(minus(from, o), minus(to, from));
  return select(reversed, Vec{-c.x, -c.y, -c.z}, c);
}
inline float dotOf(Vec a, Vec b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

using Setup = FirstHitRaster::Setup;

// The rays of one 4 x 4 pixel block, lane k = pixel (k % 4, k / 4) of the block (a lane off the
// query: t0 = inf, t1 = -inf), each ray's direction's share along the camera's axis (cos: depth
// = t cos), the best hit of each so far (`at`: its global triangle index, kNone: no hit), and
// the greatest depth at which a triangle could still change one of them.
struct alignas(64) Block {
  float dx[16], dy[16], dz[16], t0[16], t1[16], cos[16];
  float t[16], s[16], e1[16], e2[16];
  std::uint32_t at[16];
  float reach;
};

// max over the lanes of min(t, t1) cos: a triangle wholly deeper than that hits no lane nearer
// than what the lane holds (or within its interval; see the kernels' depth test).
float reachOf(const Block& b) {
  float reach = -kInf;
  for (int k = 0; k < 16; ++k) reach = std::max(reach, std::min(b.t[k], b.t1[k]) * b.cos[k]);
  return reach;
}

// Whether hit distance t (finite) of triangle `at` beats lane k's best: nearer, or as near and
// the lower index, so the answer does not depend on the order the triangles come in.
inline bool beats(float t, std::uint32_t at, const Block& b, int k) {
  return t < b.t[k] || (t == b.t[k] && at < b.at[k]);
}

// Triangle record `at` against each lane of the block, one lane at a time. True when a lane's
// best hit changed.
bool testScalar(const Setup& g, std::uint32_t at, Block& b) {
  bool changed = false;
  for (int k = 0; k < 16; ++k) {
    const float x = b.dx[k], y = b.dy[k], z = b.dz[k];
    const float e0 = g.c0[0] * x + g.c0[1] * y + g.c0[2] * z;
    const float e1 = g.c1[0] * x + g.c1[1] * y + g.c1[2] * z;
    const float e2 = g.c2[0] * x + g.c2[1] * y + g.c2[2] * z;
    const bool inside = (e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0);
    const float s = e0 + e1 + e2;
    if (!inside || s == 0) continue;
    const float t = g.det / (g.n[0] * x + g.n[1] * y + g.n[2] * z);
    if (t >= b.t0[k] && t * b.cos[k] >= g.near && t <= b.t1[k] && t < kInf && beats(t, at, b, k)) {
      b.t[k] = t, b.s[k] = s, b.e1[k] = e1, b.e2[k] = e2, b.at[k] = at;
      changed = true;
    }
  }
  return changed;
}

// c . d in 16 lanes, as testScalar() sums it.
AVX512_INLINE __m512 edge16(const float* c, __m512 x, __m512 y, __m512 z) {
  return _mm512_add_ps(
      _mm512_add_ps(_mm512_mul_ps(_mm512_set1_ps(c[0]), x), _mm512_mul_ps(_mm512_set1_ps(c[1]), y)),
      _mm512_mul_ps(_mm512_set1_ps(c[2]), z));
}

// testScalar() with the 16 lanes together, the same operations in the same order (so the same
// bits).
AVX512_TARGET bool test16(const Setup& g, std::uint32_t at, Block& b) {
  const __m512 x = _mm512_load_ps(b.dx), y = _mm512_load_ps(b.dy), z = _mm512_load_ps(b.dz);
  const __m512 zero = _mm512_setzero_ps();
  const __m512 e0 = edge16(g.c0, x, y, z), e1 = edge16(g.c1, x, y, z), e2 = edge16(g.c2, x, y, z);
  const __mmask16 positive = _mm512_mask_cmp_ps_mask(
      _mm512_mask_cmp_ps_mask(_mm512_cmp_ps_mask(e0, zero, _CMP_GE_OQ), e1, zero, _CMP_GE_OQ), e2,
      zero, _CMP_GE_OQ);
  const __mmask16 negative = _mm512_mask_cmp_ps_mask(
      _mm512_mask_cmp_ps_mask(_mm512_cmp_ps_mask(e0, zero, _CMP_LE_OQ), e1, zero, _CMP_LE_OQ), e2,
      zero, _CMP_LE_OQ);
  const __m512 s = _mm512_add_ps(_mm512_add_ps(e0, e1), e2);
  __mmask16 take =
      _mm512_mask_cmp_ps_mask(static_cast<__mmask16>(positive | negative), s, zero, _CMP_NEQ_OQ);
  if (!take) return false;
  const __m512 t = _mm512_maskz_div_ps(take, _mm512_set1_ps(g.det), edge16(g.n, x, y, z));
  take = _mm512_mask_cmp_ps_mask(take, t, _mm512_load_ps(b.t0), _CMP_GE_OQ);
  take = _mm512_mask_cmp_ps_mask(take, _mm512_mul_ps(t, _mm512_load_ps(b.cos)),
                                 _mm512_set1_ps(g.near), _CMP_GE_OQ);
  take = _mm512_mask_cmp_ps_mask(take, t, _mm512_load_ps(b.t1), _CMP_LE_OQ);
  take = _mm512_mask_cmp_ps_mask(take, t, _mm512_set1_ps(kInf), _CMP_LT_OQ);
  const __m512 bestT = _mm512_load_ps(b.t);
  // As near as a lane's best: the lower index wins (a ray through an edge two triangles share).
  const __mmask16 tie = _mm512_mask_cmp_ps_mask(take, t, bestT, _CMP_EQ_OQ);
  take = _mm512_mask_cmp_ps_mask(take, t, bestT, _CMP_LT_OQ) |
         _mm512_mask_cmplt_epu32_mask(tie, _mm512_set1_epi32(static_cast<int>(at)),
                                      _mm512_load_si512(b.at));
  if (!take) return false;
  _mm512_mask_store_ps(b.t, take, t);
  _mm512_mask_store_ps(b.s, take, s);
  _mm512_mask_store_ps(b.e1, take, e1);
  _mm512_mask_store_ps(b.e2, take, e2);
  _mm512_mask_store_epi32(b.at, take, _mm512_set1_epi32(static_cast<int>(at)));
  return true;
}

bool avx512Available() {
  return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
         __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vl");
}

}  // namespace

void FirstHitRaster::clear() {
  ready_ = false;
  meshes_.clear();
}

int FirstHitRaster::bucketOf(float distance) const {
  // Monotone in `distance` (a subtraction, a product by a non-negative number, a clamp), which
  // is all the queries' early stop needs.
  // NaN (an infinite depth times a zero scale: all depths alike, or nothing binned) is bucket 0.
  const float x = (distance - bucketFrom_) * bucketScale_;
  if (!(x > 0.0f)) return 0;
  return x < static_cast<float>(kBuckets - 1) ? static_cast<int>(x) : kBuckets - 1;
}

bool FirstHitRaster::prepare(const Camera& camera, int width, int height,
                             const std::vector<Mesh>& meshes, bool simd) {
  clear();
  Camera::Pinhole cam;
  if (!camera.pinhole(cam) || width <= 0 || height <= 0) return false;
  std::size_t total = 0;
  firstTriangle_.assign(meshes.size(), 0);
  for (std::size_t m = 0; m < meshes.size(); ++m)
    firstTriangle_[m] = total, total += meshes[m].triangleCount;
  // Pixel boxes are kept in 16 bits.
  if (total >= kNone || width > 32767 || height > 32767) return false;
  width_ = width, height_ = height;
  cellsX_ = (width + kCell - 1) / kCell, cellsY_ = (height + kCell - 1) / kCell;
  originX_ = cam.origin.x, originY_ = cam.origin.y, originZ_ = cam.origin.z;
  simd_ = simd && avx512Available();

  forwardX_ = cam.forward.x, forwardY_ = cam.forward.y, forwardZ_ = cam.forward.z;
  if (!sameMeshes(meshes)) makeClusters(meshes, total);

  // Every cluster's points on the canvas (Camera::ray() inverted) with their depths along the
  // camera's axis, the pixels the cluster may cover (its points' span) and its least depth
  // (clusterNear). A point behind or beside the camera's plane: no raster this frame.
  const std::size_t clusterCount = clusters_.size();
  const std::size_t chunks = (clusterCount + kClusterChunk - 1) / kClusterChunk;
  clusterScreen_.resize(clusterPoints_.size() / 3);
  placed_.resize(clusterCount);
  std::atomic<bool> behind{false};
  const float w = static_cast<float>(width), h = static_cast<float>(height);
  std::vector<float> chunkNearest(chunks, kInf), chunkFarthest(chunks, 0.0f);
  base::parallelFor(chunks, [&](std::size_t c) {
    const std::size_t begin = c * kClusterChunk,
                      end = std::min(clusterCount, begin + kClusterChunk);
    float lo = kInf, hi = 0;
    for (std::size_t i = begin; i < end; ++i) {
      const Cluster& cluster = clusters_[i];
      float minX = kInf, maxX = -kInf, minY = kInf, maxY = -kInf, least = kInf;
      for (std::uint32_t k = cluster.points; k < cluster.points + cluster.pointCount; ++k) {
        const float* p = clusterPoints_.data() + 3 * std::size_t{k};
        const Vec3 v{p[0] - cam.origin.x, p[1] - cam.origin.y, p[2] - cam.origin.z};
        if (!inFrontOfCamera(v, cam.forward)) {
          behind.store(true, std::memory_order_relaxed);
          return;
        }
        const float depth = dot(v, cam.forward);
        const float sx = dot(v, cam.right) / depth, sy = dot(v, cam.up) / depth;
        const Vertex2 s{(sx / cam.halfWidth + 1.0f) * 0.5f * w,
                        (1.0f - sy / cam.halfHeight) * 0.5f * h, depth};
        clusterScreen_[k] = s;
        minX = std::min(minX, s.x), maxX = std::max(maxX, s.x);
        minY = std::min(minY, s.y), maxY = std::max(maxY, s.y);
        least = std::min(least, depth), hi = std::max(hi, depth);
      }
      lo = std::min(lo, least);
      const PixelBox box = pixelsIn(minX, maxX, minY, maxY, width, height);
      placed_[i] = {cluster.first,
                    cluster.points,
                    cluster.count,
                    clusterNear(least),
                    {static_cast<std::int16_t>(box.x0), static_cast<std::int16_t>(box.y0),
                     static_cast<std::int16_t>(box.x1), static_cast<std::int16_t>(box.y1)}};
    }
    chunkNearest[c] = lo, chunkFarthest[c] = hi;
  });
  if (behind.load()) {
    clear();
    return false;
  }
  float nearest = kInf, farthest = 0;
  for (std::size_t c = 0; c < chunks; ++c)
    nearest = std::min(nearest, chunkNearest[c]), farthest = std::max(farthest, chunkFarthest[c]);
  bucketFrom_ = nearest < kInf ? nearest : 0.0f;
  bucketScale_ = farthest > nearest ? static_cast<float>(kBuckets) / (farthest - nearest) : 0.0f;

  // A cluster's depth bucket, -1 for one that covers no pixel (left out).
  const auto bucketOfPlaced = [&](const Placed& placed) {
    return placed.box.x0 > placed.box.x1 || placed.box.y0 > placed.box.y1 ? -1
                                                                          : bucketOf(placed.near);
  };
  std::vector<std::uint32_t>& counts = counts_;  // kept: a fresh one page-faulted every frame
  const std::size_t bucketRow = kBuckets + kCountRowPad;
  counts.assign(chunks * bucketRow, 0);
  base::parallelFor(chunks, [&](std::size_t c) {
    std::uint32_t* count = counts.data() + c * bucketRow;
    const std::size_t begin = c * kClusterChunk,
                      end = std::min(clusterCount, begin + kClusterChunk);
    for (std::size_t i = begin; i < end; ++i)
      if (const int bucket = bucketOfPlaced(placed_[i]); bucket >= 0) ++count[bucket];
  });
  // The clusters sorted by depth bucket, ascending within one (counted per chunk and bucket, so
  // the order does not depend on the threads).
  std::size_t binned = 0;
  for (int bucket = 0; bucket < kBuckets; ++bucket)
    for (std::size_t c = 0; c < chunks; ++c) {
      std::uint32_t& n = counts[c * bucketRow + static_cast<std::size_t>(bucket)];
      const std::uint32_t here = n;
      n = static_cast<std::uint32_t>(binned);  // now: where chunk c writes this bucket's next
      binned += here;
    }
  order_.resize(binned);
  base::parallelFor(chunks, [&](std::size_t c) {
    std::uint32_t* next = counts.data() + c * bucketRow;
    const std::size_t begin = c * kClusterChunk,
                      end = std::min(clusterCount, begin + kClusterChunk);
    for (std::size_t i = begin; i < end; ++i)
      if (const int bucket = bucketOfPlaced(placed_[i]); bucket >= 0)
        order_[next[bucket]++] = placed_[i];
  });

  // Binning in that order: count per chunk (of order_) and cell, offsets, then each chunk
  // writes its clusters, so every cell lists them nearest bucket first.
  const std::size_t cells = static_cast<std::size_t>(cellsX_) * static_cast<std::size_t>(cellsY_);
  const std::size_t orderChunks = (binned + kClusterChunk - 1) / kClusterChunk;
  const std::size_t cellRow = cells + kCountRowPad;
  counts.assign(orderChunks * cellRow, 0);
  const auto cellsOf = [&](const ScreenBox& t, auto&& visit) {
    for (int cy = t.y0 / kCell; cy <= t.y1 / kCell; ++cy)
      for (int cx = t.x0 / kCell; cx <= t.x1 / kCell; ++cx)
        visit(static_cast<std::size_t>(cy) * static_cast<std::size_t>(cellsX_) +
              static_cast<std::size_t>(cx));
  };
  base::parallelFor(orderChunks, [&](std::size_t c) {
    std::uint32_t* count = counts.data() + c * cellRow;
    const std::size_t begin = c * kClusterChunk, end = std::min(binned, begin + kClusterChunk);
    for (std::size_t i = begin; i < end; ++i)
      cellsOf(order_[i].box, [&](std::size_t cell) { ++count[cell]; });
  });
  cellStart_.assign(cells + 1, 0);
  std::size_t running = 0;
  for (std::size_t cell = 0; cell < cells; ++cell) {
    cellStart_[cell] = static_cast<std::uint32_t>(running);
    for (std::size_t c = 0; c < orderChunks; ++c) {
      std::uint32_t& n = counts[c * cellRow + cell];
      const std::uint32_t here = n;
      n = static_cast<std::uint32_t>(running);  // now: where chunk c writes this cell's next
      running += here;
    }
  }
  if (running >= kNone) {
    clear();
    return false;
  }
  cellStart_[cells] = static_cast<std::uint32_t>(running);
  cellClusters_.resize(running);
  base::parallelFor(orderChunks, [&](std::size_t c) {
    std::uint32_t* next = counts.data() + c * cellRow;
    const std::size_t begin = c * kClusterChunk, end = std::min(binned, begin + kClusterChunk);
    for (std::size_t i = begin; i < end; ++i)
      cellsOf(order_[i].box, [&](std::size_t cell) { cellClusters_[next[cell]++] = order_[i]; });
  });
  meshes_ = meshes;
  ready_ = true;
  return true;
}

std::size_t FirstHitRaster::meshOf(std::size_t triangle) const {
  return static_cast<std::size_t>(
      std::upper_bound(firstTriangle_.begin(), firstTriangle_.end(), triangle) -
      firstTriangle_.begin() - 1);
}

bool FirstHitRaster::sameMeshes(const std::vector<Mesh>& meshes) const {
  return std::equal(meshes.begin(), meshes.end(), clusteredMeshes_.begin(), clusteredMeshes_.end(),
                    [](const Mesh& a, const Mesh& b) {
                      return a.vertices == b.vertices && a.vertexCount == b.vertexCount &&
                             a.triangles == b.triangles && a.triangleCount == b.triangleCount;
                    });
}

void FirstHitRaster::makeClusters(const std::vector<Mesh>& meshes, std::size_t total) {
  // The triangles in Morton order of their centroids (over the meshes' bounds, 2^10 steps an
  // axis), cut into runs of kClusterSize: neighbours in space, so a cluster's box is small.
  float lo[3] = {kInf, kInf, kInf}, hi[3] = {-kInf, -kInf, -kInf};
  for (const Mesh& mesh : meshes)
    for (std::size_t i = 0; i < mesh.vertexCount; ++i)
      for (int a = 0; a < 3; ++a)
        lo[a] = std::min(lo[a], mesh.vertices[3 * i + a]),
        hi[a] = std::max(hi[a], mesh.vertices[3 * i + a]);
  float scale[3];
  for (int a = 0; a < 3; ++a) scale[a] = hi[a] > lo[a] ? 1023.0f / (hi[a] - lo[a]) : 0.0f;
  const auto spread = [](std::uint64_t v) {  // bit i to bit 3i
    v &= 0x3ff;
    v = (v | (v << 16)) & 0x30000ff;
    v = (v | (v << 8)) & 0x300f00f;
    v = (v | (v << 4)) & 0x30c30c3;
    return (v | (v << 2)) & 0x9249249;
  };
  std::vector<std::uint64_t> keys(total);
  const std::size_t chunks = (total + kChunk - 1) / kChunk;
  // The key's top two bits keep one mesh's triangles together (a cluster holds one mesh's; more
  // meshes than four only make more clusters cut at a mesh's end).
  base::parallelFor(chunks, [&](std::size_t c) {
    const std::size_t begin = c * kChunk, end = std::min(total, begin + kChunk);
    std::size_t m = meshOf(begin);
    for (std::size_t g = begin; g < end; ++g) {
      while (g >= firstTriangle_[m] + meshes[m].triangleCount) ++m;
      const std::uint32_t* tri = meshes[m].triangles + 3 * (g - firstTriangle_[m]);
      std::uint64_t code = 0;
      for (int a = 0; a < 3; ++a) {
        const float centre =
            (meshes[m].vertices[3 * tri[0] + a] + meshes[m].vertices[3 * tri[1] + a] +
             meshes[m].vertices[3 * tri[2] + a]) /
            3.0f;
        const float q = std::clamp((centre - lo[a]) * scale[a], 0.0f, 1023.0f);
        code |= spread(static_cast<std::uint64_t>(q)) << a;
      }
      keys[g] = (std::uint64_t{m & 3} << 62) | code << 32 | g;
    }
  });
  base::parallelSort(keys);  // the keys are distinct (each holds its triangle): one order
  clustered_.resize(total);
  for (std::size_t i = 0; i < total; ++i) clustered_[i] = static_cast<std::uint32_t>(keys[i]);
  // Runs of up to kClusterSize triangles of one mesh.
  clusters_.clear();
  for (std::size_t i = 0; i < total;) {
    const std::uint32_t m = static_cast<std::uint32_t>(meshOf(clustered_[i]));
    Cluster cluster{static_cast<std::uint32_t>(i), 0, m, 0, 0};
    for (; i < total && cluster.count < kClusterSize && meshOf(clustered_[i]) == m; ++i)
      ++cluster.count;
    clusters_.push_back(cluster);
  }
  // Each cluster's own copy of its triangles' vertices (a vertex shared by clusters is copied
  // to each: a query then reads one cluster's points together), in the order its triangles
  // first name them, and its triangles' corners as indices into them. Clusters are independent,
  // so in parallel: their distinct vertices found (and corners set) first, then, placed by the
  // counts' running sum, copied.
  const auto eachCluster = [&](const auto& body) {
    base::parallelFor(
        (clusters_.size() + kClusterChunk - 1) / kClusterChunk, [&](std::size_t chunk) {
          const std::size_t end = std::min(clusters_.size(), (chunk + 1) * kClusterChunk);
          for (std::size_t i = chunk * kClusterChunk; i < end; ++i) body(clusters_[i]);
        });
  };
  // A cluster's distinct vertex ids from 3 x its first triangle on (at most 3 a triangle).
  std::vector<std::uint32_t> distinct(3 * total);
  clusterCorners_.resize(3 * total);
  eachCluster([&](Cluster& cluster) {
    const Mesh& mesh = meshes[cluster.mesh];
    // The triangles' corners first: loads that do not wait for each other (a cluster's
    // triangles lie far apart in the mesh).
    std::uint32_t corners[3 * kClusterSize];
    for (std::uint32_t t = 0; t < cluster.count; ++t)
      std::copy_n(
          mesh.triangles + 3 * (clustered_[cluster.first + t] - firstTriangle_[cluster.mesh]), 3,
          corners + 3 * t);
    std::uint32_t* held = distinct.data() + 3 * std::size_t{cluster.first};
    std::uint32_t count = 0;
    for (std::uint32_t corner = 0; corner < 3 * cluster.count; ++corner) {
      // A scan of all held rather than a search that stops at the match: the stop was a
      // mispredicted branch nearly every corner. The held ids are distinct: one match at most.
      std::uint32_t at = count;
      for (std::uint32_t h = 0; h < count; ++h) at = held[h] == corners[corner] ? h : at;
      if (at == count) held[count++] = corners[corner];
      clusterCorners_[3 * std::size_t{cluster.first} + corner] = static_cast<std::uint8_t>(at);
    }
    cluster.pointCount = count;
  });
  std::size_t points = 0;
  for (Cluster& cluster : clusters_)
    cluster.points = static_cast<std::uint32_t>(points), points += cluster.pointCount;
  clusterPoints_.resize(3 * points);
  eachCluster([&](const Cluster& cluster) {
    const float* vertices = meshes[cluster.mesh].vertices;
    const std::uint32_t* held = distinct.data() + 3 * std::size_t{cluster.first};
    float* to = clusterPoints_.data() + 3 * std::size_t{cluster.points};
    for (std::uint32_t p = 0; p < cluster.pointCount; ++p)
      std::copy_n(vertices + 3 * std::size_t{held[p]}, 3, to + 3 * std::size_t{p});
  });
  clusteredMeshes_ = meshes;
}

FirstHitRaster::Setup FirstHitRaster::setupOf(const float* pa, const float* pb, const float* pc,
                                              float near) const {
  const Vec origin{originX_, originY_, originZ_};
  const Vec a{pa[0], pa[1], pa[2]}, b{pb[0], pb[1], pb[2]}, c{pc[0], pc[1], pc[2]};
  const Vec c0 = edgePlane(b, c, origin), c1 = edgePlane(c, a, origin);
  const Vec c2 = edgePlane(a, b, origin);
  // The plane's normal from the edges (well conditioned; the triple product of the three long
  // vectors from the camera is not: it lost 1e-3 of t at a few units' distance).
  const Vec n = crossOf(minus(b, a), minus(c, a));
  return {{c0.x, c0.y, c0.z}, {c1.x, c1.y, c1.z},         {c2.x, c2.y, c2.z},
          {n.x, n.y, n.z},    dotOf(minus(a, origin), n), near};
}

void FirstHitRaster::firstHits(int x0, int x1, int y0, int y1, std::size_t stride, const float* dx,
                               const float* dy, const float* dz, const float* t0, const float* t1,
                               Hit* out) const {
  const std::size_t count = static_cast<std::size_t>(y1 - y0) * stride;
  for (std::size_t i = 0; i < count; ++i) out[i] = Hit{};
  if (!ready_ || x0 >= x1 || y0 >= y1) return;
  constexpr int kBlocks = kCell / 4;  // 4 x 4 pixel blocks per cell side
  alignas(64) Block blocks[kBlocks * kBlocks];
  const auto test = simd_ ? test16 : testScalar;
  const int cx0 = x0 / kCell, cx1 = (x1 - 1) / kCell, cy0 = y0 / kCell, cy1 = (y1 - 1) / kCell;
  for (int cy = cy0; cy <= cy1; ++cy)
    for (int cx = cx0; cx <= cx1; ++cx) {
      // This cell's part of the query, its rays in blocks.
      const int ox = cx * kCell, oy = cy * kCell;
      const int ax = std::max(x0, ox), bx = std::min(x1 - 1, ox + kCell - 1);
      const int ay = std::max(y0, oy), by = std::min(y1 - 1, oy + kCell - 1);
      float reach = -kInf;  // the greatest of the blocks' reaches
      for (int b = 0; b < kBlocks * kBlocks; ++b) {
        Block& block = blocks[b];
        const int px0 = ox + 4 * (b % kBlocks), py0 = oy + 4 * (b / kBlocks);
        for (int k = 0; k < 16; ++k) {
          const int px = px0 + k % 4, py = py0 + k / 4;
          const bool on = px >= ax && px <= bx && py >= ay && py <= by;
          const std::size_t i =
              on ? static_cast<std::size_t>(py - y0) * stride + static_cast<std::size_t>(px - x0)
                 : 0;
          block.dx[k] = on ? dx[i] : 0.0f, block.dy[k] = on ? dy[i] : 0.0f;
          block.dz[k] = on ? dz[i] : 1.0f;
          block.t0[k] = on ? t0[i] : kInf, block.t1[k] = on ? t1[i] : -kInf;
          block.cos[k] = on ? dx[i] * forwardX_ + dy[i] * forwardY_ + dz[i] * forwardZ_ : 1.0f;
          block.t[k] = kInf, block.at[k] = kNone;
        }
        block.reach = reachOf(block);
        reach = std::max(reach, block.reach);
      }
      // Canvas coordinates beyond which a triangle's pixels miss this cell's part (its box's
      // margin and a pixel's width beyond).
      const float spanX0 = static_cast<float>(ax) - 1.0f, spanX1 = static_cast<float>(bx) + 2.0f;
      const float spanY0 = static_cast<float>(ay) - 1.0f, spanY1 = static_cast<float>(by) + 2.0f;
      // The cell's clusters nearest bucket first: past the bucket of the cell's reach, none can
      // change a hit.
      int lastBucket = bucketOf(reach);
      const std::size_t cell = static_cast<std::size_t>(cy) * static_cast<std::size_t>(cellsX_) +
                               static_cast<std::size_t>(cx);
      const std::uint32_t end = reach > -kInf ? cellStart_[cell + 1] : cellStart_[cell];
      for (std::uint32_t k = cellStart_[cell]; k < end; ++k) {
        const Placed& placed = cellClusters_[k];
        if (placed.near > reach) {
          if (bucketOf(placed.near) > lastBucket) break;
          continue;
        }
        const Vertex2* screen = clusterScreen_.data() + placed.points;
        const float* points = clusterPoints_.data() + 3 * std::size_t{placed.points};
        for (std::uint32_t j = placed.first; j < placed.first + placed.count; ++j) {
          // The triangle's pixels and least depth, as the cluster's were made. Most of a
          // cluster's triangles lie in other cells: out first, before rounding to pixels.
          const std::uint8_t* tri = clusterCorners_.data() + 3 * std::size_t{j};
          const Vertex2 va = screen[tri[0]], vb = screen[tri[1]], vc = screen[tri[2]];
          if (std::max(va.x, std::max(vb.x, vc.x)) < spanX0 ||
              std::min(va.x, std::min(vb.x, vc.x)) > spanX1 ||
              std::max(va.y, std::max(vb.y, vc.y)) < spanY0 ||
              std::min(va.y, std::min(vb.y, vc.y)) > spanY1)
            continue;
          const float near = triangleNear(std::min(va.depth, std::min(vb.depth, vc.depth)));
          if (near > reach) continue;
          const PixelBox box = pixelsOf(va.x, va.y, vb.x, vb.y, vc.x, vc.y, width_, height_);
          const int bx0 = std::max(box.x0, ax), bx1 = std::min(box.x1, bx);
          const int by0 = std::max(box.y0, ay), by1 = std::min(box.y1, by);
          if (bx0 > bx1 || by0 > by1) continue;
          Setup setup;
          bool made = false, changed = false;
          for (int by4 = (by0 - oy) / 4; by4 <= (by1 - oy) / 4; ++by4)
            for (int bx4 = (bx0 - ox) / 4; bx4 <= (bx1 - ox) / 4; ++bx4) {
              Block& block = blocks[by4 * kBlocks + bx4];
              if (near > block.reach) continue;
              if (!made)
                setup =
                    setupOf(points + 3 * tri[0], points + 3 * tri[1], points + 3 * tri[2], near),
                made = true;
              if (!test(setup, clustered_[j], block)) continue;
              block.reach = reachOf(block);
              changed = true;
            }
          if (changed) {
            reach = -kInf;
            for (const Block& block : blocks) reach = std::max(reach, block.reach);
            lastBucket = bucketOf(reach);
          }
        }
      }
      for (int b = 0; b < kBlocks * kBlocks; ++b) {
        const Block& block = blocks[b];
        const int px0 = ox + 4 * (b % kBlocks), py0 = oy + 4 * (b / kBlocks);
        for (int k = 0; k < 16; ++k) {
          if (block.at[k] == kNone) continue;  // also every lane off the query
          const std::size_t g = block.at[k];
          const int px = px0 + k % 4, py = py0 + k / 4;
          Hit& h =
              out[static_cast<std::size_t>(py - y0) * stride + static_cast<std::size_t>(px - x0)];
          const std::size_t mesh = meshOf(g);
          h.t = block.t[k];
          h.u = block.e1[k] / block.s[k];
          h.v = block.e2[k] / block.s[k];
          h.mesh = meshes_[mesh].id;
          h.triangle = static_cast<std::uint32_t>(g - firstTriangle_[mesh]);
        }
      }
    }
}

}  // namespace renderers::scivis
