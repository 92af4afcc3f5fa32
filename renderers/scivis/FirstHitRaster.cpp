#include "renderers/scivis/FirstHitRaster.h"

#include <immintrin.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include "renderers/Parallel.h"

#include "renderers/scivis/Avx512Warnings.h"

namespace renderers {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
// How far a triangle's screen box is widened: a pixel's ray and the projection of the point it
// hits agree to far less than this (float rounding of canvas coordinates below 2^14).
constexpr float kMargin = 1.0f / 32.0f;
constexpr std::size_t kChunk = 65536;   // triangles per binning task
constexpr std::uint32_t kPrefetch = 8;  // triangle records fetched ahead in a query

struct PixelBox {
  int x0, y0, x1, y1;  // inclusive; empty when x0 > x1 or y0 > y1
};

// The pixels whose sample point may lie in the projection of (a, b, c), clamped to the canvas.
inline PixelBox pixelsOf(float ax, float ay, float bx, float by, float cx, float cy, int width,
                         int height) {
  const float minX = std::min(ax, std::min(bx, cx)) - kMargin;
  const float maxX = std::max(ax, std::max(bx, cx)) + kMargin;
  const float minY = std::min(ay, std::min(by, cy)) - kMargin;
  const float maxY = std::max(ay, std::max(by, cy)) + kMargin;
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

struct Vec {
  float x, y, z;
};

inline Vec minus(Vec a, Vec b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec at(const float* vertices, std::uint32_t i) {
  const float* p = vertices + 3 * std::size_t{i};
  return {p[0], p[1], p[2]};
}
inline Vec crossOf(Vec a, Vec b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline bool before(Vec a, Vec b) {
  return a.x < b.x || (a.x == b.x && (a.y < b.y || (a.y == b.y && a.z < b.z)));
}

// The plane through the camera at `o` and the edge from p to q, as its normal (p - o) x (q - p):
// the same as (p - o) x (q - o), but from the short edge vector, not from two long, nearly
// parallel ones whose cross product cancels (that moved the edges of small, far triangles by a
// fraction of a pixel, and let through or caught rays near them). Computed from the endpoints
// in one order (the first by coordinates) and negated for the other, so the two triangles
// sharing an edge get exactly opposite normals: watertight, also across bricks (whose meshes
// number their vertices differently but place them alike).
inline Vec edgePlane(Vec p, Vec q, Vec o) {
  if (before(q, p)) {
    const Vec c = crossOf(minus(q, o), minus(p, q));
    return {-c.x, -c.y, -c.z};
  }
  return crossOf(minus(p, o), minus(q, p));
}
inline float dotOf(Vec a, Vec b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

using Setup = FirstHitRaster::Setup;

// The rays of one 4 x 4 pixel block, lane k = pixel (k % 4, k / 4) of the block (an inactive
// lane: t0 = inf, t1 = -inf), and the best hit of each so far.
struct alignas(64) Block {
  float dx[16], dy[16], dz[16], t0[16], t1[16];
  float t[16], s[16], e1[16], e2[16];
  std::uint32_t id[16];
};

// Each lane against the listed triangles (global indices into `setups`) in order, one lane at a
// time.
void blockScalar(const Setup* setups, const std::uint32_t* list, std::size_t count, Block& b) {
  for (int k = 0; k < 16; ++k) {
    const float x = b.dx[k], y = b.dy[k], z = b.dz[k];
    float bestT = kInf, bestS = 0, bestE1 = 0, bestE2 = 0;
    std::uint32_t bestId = FirstHitRaster::kNone;
    for (std::size_t j = 0; j < count; ++j) {
      const Setup& g = setups[list[j]];
      const float e0 = g.c0[0] * x + g.c0[1] * y + g.c0[2] * z;
      const float e1 = g.c1[0] * x + g.c1[1] * y + g.c1[2] * z;
      const float e2 = g.c2[0] * x + g.c2[1] * y + g.c2[2] * z;
      const bool inside = (e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0);
      const float s = e0 + e1 + e2;
      if (!inside || s == 0) continue;
      const float t = g.det / (g.n[0] * x + g.n[1] * y + g.n[2] * z);
      if (t >= b.t0[k] && t <= b.t1[k] && t < bestT)
        bestT = t, bestS = s, bestE1 = e1, bestE2 = e2, bestId = list[j];
    }
    b.t[k] = bestT, b.s[k] = bestS, b.e1[k] = bestE1, b.e2[k] = bestE2, b.id[k] = bestId;
  }
}

#define AVX512_INLINE \
  __attribute__((target("avx512f,avx512dq,avx512bw,avx512vl"), always_inline)) inline

// c . d in 16 lanes, as blockScalar() sums it.
AVX512_INLINE __m512 edge16(const float* c, __m512 x, __m512 y, __m512 z) {
  return _mm512_add_ps(
      _mm512_add_ps(_mm512_mul_ps(_mm512_set1_ps(c[0]), x), _mm512_mul_ps(_mm512_set1_ps(c[1]), y)),
      _mm512_mul_ps(_mm512_set1_ps(c[2]), z));
}

// blockScalar() with the 16 lanes together, the same operations in the same order (so the
// same bits); the block's best hits stay in registers over all its triangles.
__attribute__((target("avx512f,avx512dq,avx512bw,avx512vl"))) void block16(
    const Setup* setups, const std::uint32_t* list, std::size_t count, Block& b) {
  const __m512 x = _mm512_load_ps(b.dx), y = _mm512_load_ps(b.dy), z = _mm512_load_ps(b.dz);
  const __m512 t0 = _mm512_load_ps(b.t0), t1 = _mm512_load_ps(b.t1);
  const __m512 zero = _mm512_setzero_ps();
  __m512 bestT = _mm512_set1_ps(kInf), bestS = zero, bestE1 = zero, bestE2 = zero;
  __m512i bestId = _mm512_set1_epi32(-1);
  for (std::size_t j = 0; j < count; ++j) {
    const Setup& g = setups[list[j]];
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
    if (!take) continue;
    const __m512 t = _mm512_maskz_div_ps(take, _mm512_set1_ps(g.det), edge16(g.n, x, y, z));
    take = _mm512_mask_cmp_ps_mask(take, t, t0, _CMP_GE_OQ);
    take = _mm512_mask_cmp_ps_mask(take, t, t1, _CMP_LE_OQ);
    take = _mm512_mask_cmp_ps_mask(take, t, bestT, _CMP_LT_OQ);
    bestT = _mm512_mask_mov_ps(bestT, take, t);
    bestS = _mm512_mask_mov_ps(bestS, take, s);
    bestE1 = _mm512_mask_mov_ps(bestE1, take, e1);
    bestE2 = _mm512_mask_mov_ps(bestE2, take, e2);
    bestId = _mm512_mask_mov_epi32(bestId, take, _mm512_set1_epi32(static_cast<int>(list[j])));
  }
  _mm512_store_ps(b.t, bestT), _mm512_store_ps(b.s, bestS);
  _mm512_store_ps(b.e1, bestE1), _mm512_store_ps(b.e2, bestE2);
  _mm512_store_si512(reinterpret_cast<__m512i*>(b.id), bestId);
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
  const Vec origin{originX_, originY_, originZ_};
  simd_ = simd && avx512Available();

  // Every vertex on the canvas (Camera::ray() inverted); one behind or beside the camera's
  // plane: no raster this frame.
  screen_.resize(meshes.size());
  std::atomic<bool> behind{false};
  const float w = static_cast<float>(width), h = static_cast<float>(height);
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    const Mesh& mesh = meshes[m];
    std::vector<Vertex2>& screen = screen_[m];
    screen.resize(mesh.vertexCount);
    parallelFor((mesh.vertexCount + kChunk - 1) / kChunk, [&](std::size_t c) {
      const std::size_t end = std::min(mesh.vertexCount, (c + 1) * kChunk);
      for (std::size_t i = c * kChunk; i < end; ++i) {
        const float* p = mesh.vertices + 3 * i;
        const Vec3 v{p[0] - cam.origin.x, p[1] - cam.origin.y, p[2] - cam.origin.z};
        if (!inFrontOfCamera(v, cam.forward)) {
          behind.store(true, std::memory_order_relaxed);
          return;
        }
        const float depth = dot(v, cam.forward);
        const float sx = dot(v, cam.right) / depth, sy = dot(v, cam.up) / depth;
        screen[i] = {(sx / cam.halfWidth + 1.0f) * 0.5f * w,
                     (1.0f - sy / cam.halfHeight) * 0.5f * h};
      }
    });
    if (behind.load()) {
      clear();
      return false;
    }
  }

  // Per triangle its edge planes through the camera and its pixels (made once a frame, in
  // triangle order: the queries then read one record per triangle instead of its indices and
  // vertices). Binning: count per chunk and cell, offsets, then each chunk writes its
  // triangles, so every cell lists its triangles in ascending global index whatever the
  // threads did.
  setup_.resize(total);
  const std::size_t cells = static_cast<std::size_t>(cellsX_) * static_cast<std::size_t>(cellsY_);
  const std::size_t chunks = (total + kChunk - 1) / kChunk;
  std::vector<std::uint32_t>& counts = counts_;  // kept: a fresh one page-faulted every frame
  counts.assign(chunks * cells, 0);
  const auto cellsOf = [&](const Setup& t, std::size_t g, auto&& visit) {
    if (t.x0 > t.x1) return;
    for (int cy = t.y0 / kCell; cy <= t.y1 / kCell; ++cy)
      for (int cx = t.x0 / kCell; cx <= t.x1 / kCell; ++cx)
        visit(static_cast<std::size_t>(cy) * static_cast<std::size_t>(cellsX_) +
                  static_cast<std::size_t>(cx),
              static_cast<std::uint32_t>(g));
  };
  parallelFor(chunks, [&](std::size_t c) {
    std::uint32_t* count = counts.data() + c * cells;
    const std::size_t begin = c * kChunk, end = std::min(total, begin + kChunk);
    std::size_t m = static_cast<std::size_t>(
        std::upper_bound(firstTriangle_.begin(), firstTriangle_.end(), begin) -
        firstTriangle_.begin() - 1);
    for (std::size_t g = begin; g < end; ++g) {
      while (g >= firstTriangle_[m] + meshes[m].triangleCount) ++m;
      const Mesh& mesh = meshes[m];
      const std::uint32_t* tri = mesh.triangles + 3 * (g - firstTriangle_[m]);
      const Vertex2 a = screen_[m][tri[0]], b = screen_[m][tri[1]], d = screen_[m][tri[2]];
      const PixelBox box = pixelsOf(a.x, a.y, b.x, b.y, d.x, d.y, width, height);
      Setup& t = setup_[g];
      if (box.x0 > box.x1 || box.y0 > box.y1) {
        t.x0 = 1, t.x1 = 0;
        continue;
      }
      const Vec a3 = at(mesh.vertices, tri[0]), b3 = at(mesh.vertices, tri[1]);
      const Vec c3 = at(mesh.vertices, tri[2]);
      const Vec c0 = edgePlane(b3, c3, origin), c1 = edgePlane(c3, a3, origin);
      const Vec c2 = edgePlane(a3, b3, origin);
      // The plane's normal from the edges (well conditioned; the triple product of the three
      // long vectors from the camera is not: it lost 1e-3 of t at a few units' distance).
      const Vec n = crossOf(minus(b3, a3), minus(c3, a3));
      const Vec pa = minus(a3, origin);
      t = {{c0.x, c0.y, c0.z},
           {c1.x, c1.y, c1.z},
           {c2.x, c2.y, c2.z},
           {n.x, n.y, n.z},
           dotOf(pa, n),
           static_cast<std::int16_t>(box.x0),
           static_cast<std::int16_t>(box.y0),
           static_cast<std::int16_t>(box.x1),
           static_cast<std::int16_t>(box.y1)};
      cellsOf(t, g, [&](std::size_t cell, std::uint32_t) { ++count[cell]; });
    }
  });
  cellStart_.assign(cells + 1, 0);
  std::size_t running = 0;
  for (std::size_t cell = 0; cell < cells; ++cell) {
    cellStart_[cell] = static_cast<std::uint32_t>(running);
    for (std::size_t c = 0; c < chunks; ++c) {
      std::uint32_t& n = counts[c * cells + cell];
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
  cellTriangles_.resize(running);
  parallelFor(chunks, [&](std::size_t c) {
    std::uint32_t* next = counts.data() + c * cells;
    const std::size_t begin = c * kChunk, end = std::min(total, begin + kChunk);
    for (std::size_t g = begin; g < end; ++g)
      cellsOf(setup_[g], g,
              [&](std::size_t cell, std::uint32_t id) { cellTriangles_[next[cell]++] = id; });
  });
  meshes_ = meshes;
  ready_ = true;
  return true;
}

void FirstHitRaster::firstHits(int x0, int x1, int y0, int y1, std::size_t stride, const float* dx,
                               const float* dy, const float* dz, const float* t0, const float* t1,
                               Hit* out) const {
  const std::size_t count = static_cast<std::size_t>(y1 - y0) * stride;
  for (std::size_t i = 0; i < count; ++i) out[i] = Hit{};
  if (!ready_ || x0 >= x1 || y0 >= y1) return;
  constexpr int kBlocks = kCell / 4;  // 4 x 4 pixel blocks per cell side
  thread_local std::vector<std::uint32_t> lists[kBlocks * kBlocks];
  alignas(64) Block block;
  const int cx0 = x0 / kCell, cx1 = (x1 - 1) / kCell, cy0 = y0 / kCell, cy1 = (y1 - 1) / kCell;
  for (int cy = cy0; cy <= cy1; ++cy)
    for (int cx = cx0; cx <= cx1; ++cx) {
      // This cell's part of the query. Each pixel lies in one cell, and a cell lists its
      // triangles in ascending index, so a pixel meets its triangles in that order and a tie in
      // t keeps the lower index.
      const int ox = cx * kCell, oy = cy * kCell;
      const int ax = std::max(x0, ox), bx = std::min(x1 - 1, ox + kCell - 1);
      const int ay = std::max(y0, oy), by = std::min(y1 - 1, oy + kCell - 1);
      const std::size_t cell = static_cast<std::size_t>(cy) * static_cast<std::size_t>(cellsX_) +
                               static_cast<std::size_t>(cx);
      for (auto& list : lists) list.clear();
      const std::uint32_t end = cellStart_[cell + 1];
      for (std::uint32_t k = cellStart_[cell]; k < end; ++k) {
        // The records are read in the cell's order, scattered over the frame's: fetch ahead.
        if (k + kPrefetch < end) __builtin_prefetch(&setup_[cellTriangles_[k + kPrefetch]]);
        const std::uint32_t g = cellTriangles_[k];
        const Setup& setup = setup_[g];
        const int bx0 = std::max<int>(setup.x0, ax), bx1 = std::min<int>(setup.x1, bx);
        const int by0 = std::max<int>(setup.y0, ay), by1 = std::min<int>(setup.y1, by);
        if (bx0 > bx1 || by0 > by1) continue;
        for (int by4 = (by0 - oy) / 4; by4 <= (by1 - oy) / 4; ++by4)
          for (int bx4 = (bx0 - ox) / 4; bx4 <= (bx1 - ox) / 4; ++bx4)
            lists[by4 * kBlocks + bx4].push_back(g);
      }
      for (int b = 0; b < kBlocks * kBlocks; ++b) {
        const std::vector<std::uint32_t>& list = lists[b];
        if (list.empty()) continue;
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
        }
        if (simd_)
          block16(setup_.data(), list.data(), list.size(), block);
        else
          blockScalar(setup_.data(), list.data(), list.size(), block);
        for (int k = 0; k < 16; ++k) {
          const std::uint32_t g = block.id[k];
          if (g == kNone) continue;  // also every lane off the query
          const int px = px0 + k % 4, py = py0 + k / 4;
          Hit& h =
              out[static_cast<std::size_t>(py - y0) * stride + static_cast<std::size_t>(px - x0)];
          const std::size_t mesh = static_cast<std::size_t>(
              std::upper_bound(firstTriangle_.begin(), firstTriangle_.end(), std::size_t{g}) -
              firstTriangle_.begin() - 1);
          h.t = block.t[k];
          h.u = block.e1[k] / block.s[k];
          h.v = block.e2[k] / block.s[k];
          h.mesh = meshes_[mesh].id;
          h.triangle = static_cast<std::uint32_t>(g - firstTriangle_[mesh]);
        }
      }
    }
}

}  // namespace renderers
