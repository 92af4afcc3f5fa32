// The volume march's AVX-512 kernel: packets of 16 rays, one per lane, one sample of each at a
// time. Every lane computes its ray's samples with the operations and the order of marchSse
// and the AVX2 packets (VolumeMarch.cpp), without fused multiply-adds (this file is built with
// -ffp-contract=off), so every ray gets the same colour bit for bit. What AVX-512 changes is
// the machinery around the arithmetic: twice the lanes per instruction, 32 vector registers (the
// AVX2 packet spills its state) and mask registers instead of blends. The voxels and the table
// entries are loaded as the AVX2 kernel loads them, 8 lanes at a time (AVX-512 gathers of the
// same x-pairs and entries measured slower on this machine's AMD EPYC: most of the march's time
// went to the gathers).
#include <immintrin.h>

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "renderers/scivis/kernels/Transpose16.h"
#include "renderers/scivis/render/VolumeMarch.h"
#include "renderers/scivis/render/VolumeMarchSteps.h"

#include "renderers/scivis/kernels/Avx512.h"

namespace renderers::scivis::march {
namespace {

constexpr float kInf = Box3::kInf;

AVX512_INLINE __m512 lerp(__m512 a, __m512 b, __m512 f) {
  return _mm512_add_ps(a, _mm512_mul_ps(f, _mm512_sub_ps(b, a)));
}

// lerp(entry, next, f) from a transfer-function entry and its difference to the next.
AVX512_INLINE __m512 fromEntry(__m512 entry, __m512 difference, __m512 f) {
  return _mm512_add_ps(entry, _mm512_mul_ps(f, difference));
}

// min(int(f), last) in the lanes inside; the first held cell outside, so every lane reads held
// voxels.
AVX512_INLINE __m512i cellOf(__m512 f, int last, int first, __mmask16 inside) {
  const __m512i c = _mm512_min_epi32(_mm512_cvttps_epi32(f), _mm512_set1_epi32(last));
  return _mm512_mask_blend_epi32(inside, _mm512_set1_epi32(first), c);
}

// A register of 16 lanes from two of 8.
AVX512_INLINE __m512 join(__m256 lo, __m256 hi) {
  return _mm512_insertf32x8(_mm512_castps256_ps512(lo), hi, 1);
}

// A lane's 8 cell corners as floats in VolumeField::interpolate()'s order, from integer voxels:
// the x-pairs of rows (y, z), (y + 1, z), (y, z + 1), (y + 1, z + 1), widened exactly as
// static_cast<float> does.
AVX512_INLINE __m256 laneCorners(const std::uint16_t* v, int strideY, int strideZ) {
  std::uint32_t pair[4];
  std::memcpy(&pair[0], v, 4);
  std::memcpy(&pair[1], v + strideY, 4);
  std::memcpy(&pair[2], v + strideZ, 4);
  std::memcpy(&pair[3], v + strideZ + strideY, 4);
  const __m128i w = _mm_setr_epi32(static_cast<int>(pair[0]), static_cast<int>(pair[1]),
                                   static_cast<int>(pair[2]), static_cast<int>(pair[3]));
  return _mm256_cvtepi32_ps(_mm256_cvtepu16_epi32(w));
}

AVX512_INLINE __m256 laneCorners(const std::uint8_t* v, int strideY, int strideZ) {
  std::uint16_t pair[4];
  std::memcpy(&pair[0], v, 2);
  std::memcpy(&pair[1], v + strideY, 2);
  std::memcpy(&pair[2], v + strideZ, 2);
  std::memcpy(&pair[3], v + strideZ + strideY, 2);
  const __m128i w =
      _mm_setr_epi16(static_cast<short>(pair[0]), static_cast<short>(pair[1]),
                     static_cast<short>(pair[2]), static_cast<short>(pair[3]), 0, 0, 0, 0);
  return _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(w));
}

// The 8 corners of the cells at offsets[l] (voxel indices) of 16 lanes, a register per corner.
template <class T>
AVX512_INLINE void corners16(const std::byte* bytes, const int offsets[16], int strideY,
                             int strideZ, __m512 c[8]) {
  const T* voxels = reinterpret_cast<const T*>(bytes);
  __m256 half[2][8];
  if constexpr (std::is_same_v<T, float>) {
    corners8(voxels, offsets, strideY, strideZ, half[0]);
    corners8(voxels, offsets + 8, strideY, strideZ, half[1]);
  } else {
    for (int h = 0; h < 2; ++h) {
      __m256 rows[8];
      for (int l = 0; l < 8; ++l)
        rows[l] = laneCorners(voxels + offsets[8 * h + l], strideY, strideZ);
      transpose8(rows, half[h]);
    }
  }
  for (int n = 0; n < 8; ++n) c[n] = join(half[0][n], half[1][n]);
}

// Transfer-function entries at[l] (8 floats from at[l]) of 16 lanes, a register per float:
// out[0 .. 3] the entry's RGBA, out[4 .. 7] its difference to the next
// (SciVisScene::VolumeLayer::table). Each lane's 8 floats are one 256-bit load (lanes l and
// l + 8 share a register), then an 8x8 transpose in each half.
AVX512_INLINE void tableEntries16(const float* table, const int at[16], __m512 out[8]) {
  __m512 q[8], t[8], u[8];
  for (int j = 0; j < 8; ++j)
    q[j] = _mm512_insertf32x8(_mm512_castps256_ps512(_mm256_loadu_ps(table + at[j])),
                              _mm256_loadu_ps(table + at[j + 8]), 1);
  for (int j = 0; j < 8; j += 2)
    t[j] = _mm512_unpacklo_ps(q[j], q[j + 1]), t[j + 1] = _mm512_unpackhi_ps(q[j], q[j + 1]);
  for (int j = 0; j < 8; j += 4) {
    u[j] = _mm512_shuffle_ps(t[j], t[j + 2], 0x44);
    u[j + 1] = _mm512_shuffle_ps(t[j], t[j + 2], 0xee);
    u[j + 2] = _mm512_shuffle_ps(t[j + 1], t[j + 3], 0x44);
    u[j + 3] = _mm512_shuffle_ps(t[j + 1], t[j + 3], 0xee);
  }
  // Blocks (128 bits) 0 and 2 of u[k] and u[k + 4] make value k; blocks 1 and 3 value k + 4.
  const __m512i even = _mm512_setr_epi32(0, 1, 2, 3, 16, 17, 18, 19, 8, 9, 10, 11, 24, 25, 26, 27);
  const __m512i odd = _mm512_setr_epi32(4, 5, 6, 7, 20, 21, 22, 23, 12, 13, 14, 15, 28, 29, 30, 31);
  for (int k = 0; k < 4; ++k) {
    out[k] = _mm512_permutex2var_ps(u[k], even, u[k + 4]);
    out[k + 4] = _mm512_permutex2var_ps(u[k], odd, u[k + 4]);
  }
}

// What every lane of a packet shares: the field's geometry and voxels, the transfer function.
struct Field16 {
  const VolumeField* field;
  const std::byte* voxels;
  const std::uint8_t* empty;
  const float* table;
  int strideY, strideZ;
  bool prefetch;  // whether the voxels are too many for the caches (prefetchCells)
  Index3 first, lastCell;
  __m512 gx, gy, gz, sx, sy, sz, lox, loy, loz, hix, hiy, hiz;
  __m512i strideYs, strideZs, firstX, firstY, firstZ;
  __m512i macroFirstX, macroFirstY, macroFirstZ, macroCellsX, macroCellsY;
  __m512 tableScale, valueMin;
};

AVX512_INLINE void setUp(Field16& f, const SciVisScene::VolumeLayer& v) {
  const FieldGeometry::Layout g = v.field->layout();
  f.field = v.field;
  f.voxels = v.field->volume().data();
  f.empty = v.emptyMacrocells.data();
  f.table = v.table.data();
  f.strideY = static_cast<int>(g.strideY), f.strideZ = static_cast<int>(g.strideZ);
  f.prefetch = v.field->volume().dataBytes() > kPrefetchAboveBytes;
  f.first = g.first, f.lastCell = g.lastCell;
  f.gx = _mm512_set1_ps(g.origin.x), f.gy = _mm512_set1_ps(g.origin.y);
  f.gz = _mm512_set1_ps(g.origin.z);
  f.sx = _mm512_set1_ps(g.invSpacing.x), f.sy = _mm512_set1_ps(g.invSpacing.y);
  f.sz = _mm512_set1_ps(g.invSpacing.z);
  f.lox = _mm512_set1_ps(g.lo.x), f.loy = _mm512_set1_ps(g.lo.y), f.loz = _mm512_set1_ps(g.lo.z);
  f.hix = _mm512_set1_ps(g.hi.x), f.hiy = _mm512_set1_ps(g.hi.y), f.hiz = _mm512_set1_ps(g.hi.z);
  f.strideYs = _mm512_set1_epi32(static_cast<int>(g.strideY));
  f.strideZs = _mm512_set1_epi32(static_cast<int>(g.strideZ));
  f.firstX = _mm512_set1_epi32(g.first.x), f.firstY = _mm512_set1_epi32(g.first.y);
  f.firstZ = _mm512_set1_epi32(g.first.z);
  f.macroFirstX = _mm512_set1_epi32(g.macroFirst.x);
  f.macroFirstY = _mm512_set1_epi32(g.macroFirst.y);
  f.macroFirstZ = _mm512_set1_epi32(g.macroFirst.z);
  f.macroCellsX = _mm512_set1_epi32(g.macroCells.x);
  f.macroCellsY = _mm512_set1_epi32(g.macroCells.y);
  f.tableScale = _mm512_set1_ps(v.tableScale), f.valueMin = _mm512_set1_ps(v.valueMin);
}

// Up to 16 rays, one per lane, each where its march has got to.
struct Packet16 {
  const MarchRay* rays;
  int count;
  __m512 jitters, steps, t1s, ends, minTs, ox, oy, oz, dx, dy, dz;
  __m512 ks, red, green, blue, transmittance, depths;
  __m512 aheadX, aheadY, aheadZ;  // kPrefetchAhead steps along the ray, in cells
  __m512i counts;
  __mmask16 alive;  // lanes still marching
};

// MarchRay's floats in its order: a ray is one 512-bit load, and 16 of them transposed are a
// register per field.
static_assert(sizeof(MarchRay) == 16 * sizeof(float));
enum RayFloat : int {
  kOx = 0,
  kOy,
  kOz,
  kDx,
  kDy,
  kDz,
  kT0 = 9,
  kT1,
  kKStart,
  kVolumeEnd,
  kStep,
  kJitter,
  kMinT,
};
static_assert(offsetof(MarchRay, dir) == kDx * sizeof(float) &&
              offsetof(MarchRay, t0) == kT0 * sizeof(float) &&
              offsetof(MarchRay, kStart) == kKStart * sizeof(float) &&
              offsetof(MarchRay, minTransmittance) == kMinT * sizeof(float));

// firstSample() lane by lane: the same operations, its loops run while any lane still steps.
AVX512_INLINE __m512 firstSamples(const __m512 ray[16], __mmask16 lanes) {
  const __m512 one = _mm512_set1_ps(1.0f), t0 = ray[kT0], step = ray[kStep];
  const __m512 jitter = ray[kJitter], kStart = ray[kKStart];
  const __m512 c = _mm512_roundscale_ps(_mm512_sub_ps(_mm512_div_ps(t0, step), jitter),
                                        _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC);
  // std::max(kStart, c): c where kStart < c, else kStart (NaN c too).
  __m512 k = _mm512_maskz_max_ps(lanes, c, kStart);
  for (__mmask16 down = lanes;;) {
    down = _mm512_mask_cmp_ps_mask(down, k, kStart, _CMP_GT_OQ);
    down = _mm512_mask_cmp_ps_mask(
        down, _mm512_mul_ps(_mm512_add_ps(_mm512_sub_ps(k, one), jitter), step), t0, _CMP_GE_OQ);
    if (!down) break;
    k = _mm512_mask_sub_ps(k, down, k, one);
  }
  for (__mmask16 up = lanes;;) {
    up = _mm512_mask_cmp_ps_mask(up, _mm512_mul_ps(_mm512_add_ps(k, jitter), step), t0, _CMP_LT_OQ);
    if (!up) break;
    k = _mm512_mask_add_ps(k, up, k, one);
  }
  return k;
}

// Rays 0 .. count - 1 in the lanes, nothing composited yet; the lanes past `count` march none.
AVX512_INLINE void start(Packet16& p, const Field16& f, const MarchRay* rays, int count) {
  __m512 ray[16];
  for (int l = 0; l < 16; ++l)
    ray[l] = l < count ? _mm512_loadu_ps(reinterpret_cast<const float*>(rays + l))
                       : _mm512_setzero_ps();  // MarchRay{}
  lanes::transpose16(ray);
  const __mmask16 lanes = static_cast<__mmask16>((1u << count) - 1);
  p.rays = rays, p.count = count;
  p.jitters = ray[kJitter], p.steps = ray[kStep];
  p.t1s = ray[kT1], p.ends = ray[kVolumeEnd], p.minTs = ray[kMinT];
  p.ox = ray[kOx], p.oy = ray[kOy], p.oz = ray[kOz];
  p.dx = ray[kDx], p.dy = ray[kDy], p.dz = ray[kDz];
  const __m512 ahead = _mm512_mul_ps(_mm512_set1_ps(kPrefetchAhead), p.steps);
  p.aheadX = _mm512_mul_ps(_mm512_mul_ps(ahead, p.dx), f.sx);
  p.aheadY = _mm512_mul_ps(_mm512_mul_ps(ahead, p.dy), f.sy);
  p.aheadZ = _mm512_mul_ps(_mm512_mul_ps(ahead, p.dz), f.sz);
  p.ks = firstSamples(ray, lanes);
  const MarchColor black{};
  p.red = _mm512_set1_ps(black.rgb.x), p.green = _mm512_set1_ps(black.rgb.y);
  p.blue = _mm512_set1_ps(black.rgb.z), p.transmittance = _mm512_set1_ps(black.transmittance);
  p.depths = _mm512_set1_ps(black.depth);
  p.counts = _mm512_setzero_si512();
  // marchSse's loop test: light gets through.
  p.alive = _mm512_mask_cmp_ps_mask(lanes, p.transmittance, p.minTs, _CMP_GT_OQ);
}

// The held cell (relative to the first) of coordinate c + ahead, clamped to the held cells.
AVX512_INLINE __m512i cellAhead(__m512 c, __m512 ahead, int first, int last, __m512i firsts) {
  const __m512i i =
      _mm512_min_epi32(_mm512_cvttps_epi32(_mm512_add_ps(c, ahead)), _mm512_set1_epi32(last));
  return _mm512_sub_epi32(_mm512_max_epi32(i, _mm512_set1_epi32(first)), firsts);
}

// Asks for the voxels of cell (fx, fy, fz) + ahead of every lane, clamped to the held cells (the
// march asks for those kPrefetchAhead samples on, Packet16::ahead*): the march reads cells far
// apart in memory (a ray crosses a z slice every few samples), and a load that misses the cache
// stalls the packet's whole step. Only a hint: no value changes. Measured 7% faster on the 256³
// bench, 20% on 512³ at 512² (fewer rays per voxel, fewer shared cache lines; at 1024² it measured
// about even). Every lane asks, marching or not (its cell is a held one): a loop over the marching
// lanes only mispredicted its exit nearly every step.
template <class T>
AVX512_INLINE void prefetchCells(const Field16& f, __m512 fx, __m512 fy, __m512 fz, __m512 aheadX,
                                 __m512 aheadY, __m512 aheadZ) {
  const __m512i offset = _mm512_add_epi32(
      cellAhead(fx, aheadX, f.first.x, f.lastCell.x, f.firstX),
      _mm512_add_epi32(
          _mm512_mullo_epi32(cellAhead(fy, aheadY, f.first.y, f.lastCell.y, f.firstY), f.strideYs),
          _mm512_mullo_epi32(cellAhead(fz, aheadZ, f.first.z, f.lastCell.z, f.firstZ),
                             f.strideZs)));
  alignas(64) int at[16];
  _mm512_store_si512(at, offset);
  const T* voxels = reinterpret_cast<const T*>(f.voxels);
#pragma GCC unroll 16
  for (int l = 0; l < 16; ++l) {
    const T* v = voxels + at[l];
    for (const T* row : {v, v + f.strideY, v + f.strideZ, v + f.strideZ + f.strideY})
      _mm_prefetch(reinterpret_cast<const char*>(row), _MM_HINT_T0);
  }
}

// Asks for the voxels of the first kPrefetchAhead samples of rays 0 .. count - 1 (the packet
// that marches next), from about where each ray's march starts (its first sample lies within a
// step of it): no step asks for them, and in a dense volume a ray takes only about 16 samples.
// Asked while the packet before marches, they are in the cache when it starts (asking when their
// own packet starts gains half as much: docs/benchmarks.md, "Measurements behind the code").
template <class T>
AVX512_INLINE void prefetchStarts(const Field16& f, const MarchRay* rays, int count) {
  __m512 ray[16];
  for (int l = 0; l < 16; ++l)
    ray[l] = _mm512_loadu_ps(reinterpret_cast<const float*>(rays + (l < count ? l : 0)));
  lanes::transpose16(ray);
  const __m512 steps = ray[kStep];
  const __m512 ts =
      _mm512_max_ps(ray[kT0], _mm512_mul_ps(_mm512_add_ps(ray[kKStart], ray[kJitter]), steps));
  const __m512 fx = _mm512_mul_ps(
      _mm512_sub_ps(_mm512_add_ps(ray[kOx], _mm512_mul_ps(ray[kDx], ts)), f.gx), f.sx);
  const __m512 fy = _mm512_mul_ps(
      _mm512_sub_ps(_mm512_add_ps(ray[kOy], _mm512_mul_ps(ray[kDy], ts)), f.gy), f.sy);
  const __m512 fz = _mm512_mul_ps(
      _mm512_sub_ps(_mm512_add_ps(ray[kOz], _mm512_mul_ps(ray[kDz], ts)), f.gz), f.sz);
  const __m512 ex = _mm512_mul_ps(_mm512_mul_ps(steps, ray[kDx]), f.sx);
  const __m512 ey = _mm512_mul_ps(_mm512_mul_ps(steps, ray[kDy]), f.sy);
  const __m512 ez = _mm512_mul_ps(_mm512_mul_ps(steps, ray[kDz]), f.sz);
  for (int j = 0; j < static_cast<int>(kPrefetchAhead); ++j) {
    const __m512 a = _mm512_set1_ps(static_cast<float>(j));
    prefetchCells<T>(f, fx, fy, fz, _mm512_mul_ps(a, ex), _mm512_mul_ps(a, ey),
                     _mm512_mul_ps(a, ez));
  }
}

// One sample of every ray still marching.
template <class T>
AVX512_INLINE void advance(Packet16& p, const Field16& f) {
  const __m512 zero = _mm512_setzero_ps(), one = _mm512_set1_ps(1.0f);
  const __m512 ts = _mm512_mul_ps(_mm512_add_ps(p.ks, p.jitters), p.steps);
  p.alive = _mm512_mask_cmp_ps_mask(p.alive, ts, p.t1s, _CMP_LT_OQ) &
            _mm512_cmp_ps_mask(ts, p.ends, _CMP_LE_OQ);
  if (!p.alive) return;
  // VolumeField::locate(), lane by lane.
  const __m512 fx =
      _mm512_mul_ps(_mm512_sub_ps(_mm512_add_ps(p.ox, _mm512_mul_ps(p.dx, ts)), f.gx), f.sx);
  const __m512 fy =
      _mm512_mul_ps(_mm512_sub_ps(_mm512_add_ps(p.oy, _mm512_mul_ps(p.dy, ts)), f.gy), f.sy);
  const __m512 fz =
      _mm512_mul_ps(_mm512_sub_ps(_mm512_add_ps(p.oz, _mm512_mul_ps(p.dz, ts)), f.gz), f.sz);
  // Six independent compares, their masks and-ed as a tree: a chain of masked compares, each
  // waiting for the one before, made the march's longest path (the cell, then the loads) longer.
  const __mmask16 inX =
      _mm512_cmp_ps_mask(fx, f.lox, _CMP_GE_OQ) & _mm512_cmp_ps_mask(fx, f.hix, _CMP_LE_OQ);
  const __mmask16 inY =
      _mm512_cmp_ps_mask(fy, f.loy, _CMP_GE_OQ) & _mm512_cmp_ps_mask(fy, f.hiy, _CMP_LE_OQ);
  const __mmask16 inZ =
      _mm512_cmp_ps_mask(fz, f.loz, _CMP_GE_OQ) & _mm512_cmp_ps_mask(fz, f.hiz, _CMP_LE_OQ);
  const __mmask16 in = inX & inY & inZ;
  const __mmask16 inside = in & p.alive;
  // Every marching lane takes (and counts) this sample; all but those that jump then step on.
  const __mmask16 taken = p.alive;
  __mmask16 stepped = 0xffff;
  if (inside) {
    const __m512i ix = cellOf(fx, f.lastCell.x, f.first.x, in),
                  iy = cellOf(fy, f.lastCell.y, f.first.y, in),
                  iz = cellOf(fz, f.lastCell.z, f.first.z, in);
    const __m512 wx = _mm512_sub_ps(fx, _mm512_cvtepi32_ps(ix)),
                 wy = _mm512_sub_ps(fy, _mm512_cvtepi32_ps(iy)),
                 wz = _mm512_sub_ps(fz, _mm512_cvtepi32_ps(iz));
    const __m512i offset = _mm512_add_epi32(
        _mm512_sub_epi32(ix, f.firstX),
        _mm512_add_epi32(_mm512_mullo_epi32(_mm512_sub_epi32(iy, f.firstY), f.strideYs),
                         _mm512_mullo_epi32(_mm512_sub_epi32(iz, f.firstZ), f.strideZs)));
    // The 8 corners in VolumeField::interpolate()'s order, 8 lanes at a time.
    alignas(64) int offsets[16];
    _mm512_store_si512(offsets, offset);
    if (f.prefetch) prefetchCells<T>(f, fx, fy, fz, p.aheadX, p.aheadY, p.aheadZ);
    __m512 c[8];
    corners16<T>(f.voxels, offsets, f.strideY, f.strideZ, c);
    // VolumeField::interpolate(): along x, then y, then z.
    const __m512 x00 = lerp(c[0], c[1], wx), x10 = lerp(c[2], c[3], wx);
    const __m512 x01 = lerp(c[4], c[5], wx), x11 = lerp(c[6], c[7], wx);
    const __m512 values = lerp(lerp(x00, x10, wy), lerp(x01, x11, wy), wz);
    // The transfer function as marchSse computes it: x = clamp(scaled, 0, last entry) (NaN
    // stays NaN), entry i = min(int(x), last - 1), NaN's entry 0, weight x - i.
    const __m512 lastEntry = _mm512_set1_ps(static_cast<float>(SciVisScene::kTableSize - 1));
    const __m512i lastLower = _mm512_set1_epi32(SciVisScene::kTableSize - 2);
    __m512 x = _mm512_mul_ps(_mm512_sub_ps(values, f.valueMin), f.tableScale);
    // vmaxps / vminps give their second operand unless the first is greater / less (NaN
    // compares false): max(0, x) is x < 0 ? 0 : x and min(last, x) is x > last ? last : x, NaN
    // and -0 kept as the compare and blend of marchSse keep them.
    x = _mm512_min_ps(lastEntry, _mm512_max_ps(zero, x));
    __m512i i = _mm512_min_epi32(_mm512_cvttps_epi32(x), lastLower);
    i = _mm512_max_epi32(i, _mm512_setzero_si512());  // NaN's 0x80000000: entry 0
    const __m512 weight = _mm512_sub_ps(x, _mm512_cvtepi32_ps(i));
    // Entry i: RGBA and the difference to entry i + 1, 8 lanes at a time.
    alignas(64) int entry[16];
    static_assert(SciVisScene::kTableEntryFloats == 1 << 3, "entry i starts at float 8 i");
    _mm512_store_si512(entry, _mm512_slli_epi32(i, 3));
    __m512 e[8];
    tableEntries16(f.table, entry, e);
    // entry + weight x difference: the bits of lerp(entry, next, weight).
    const __m512 opacity = fromEntry(e[3], e[7], weight);
    const __mmask16 composited = _mm512_mask_cmp_ps_mask(inside, opacity, zero, _CMP_GT_OQ);
    if (composited) {
      // Accumulator::add in the lanes that composite.
      const __m512 w = _mm512_mul_ps(p.transmittance, opacity);
      p.red = _mm512_mask_add_ps(p.red, composited, p.red,
                                 _mm512_mul_ps(fromEntry(e[0], e[4], weight), w));
      p.green = _mm512_mask_add_ps(p.green, composited, p.green,
                                   _mm512_mul_ps(fromEntry(e[1], e[5], weight), w));
      p.blue = _mm512_mask_add_ps(p.blue, composited, p.blue,
                                  _mm512_mul_ps(fromEntry(e[2], e[6], weight), w));
      p.transmittance = _mm512_mask_mul_ps(p.transmittance, composited, p.transmittance,
                                           _mm512_sub_ps(one, opacity));
      const __mmask16 reached =
          _mm512_mask_cmp_ps_mask(composited, p.depths, _mm512_set1_ps(kInf), _CMP_EQ_OQ) &
          _mm512_cmp_ps_mask(p.transmittance, _mm512_set1_ps(0.5f), _CMP_LE_OQ);
      p.depths = _mm512_mask_mov_ps(p.depths, reached, ts);
      p.alive &= _mm512_cmp_ps_mask(p.transmittance, p.minTs, _CMP_GT_OQ);
    }
    // A lane that sees nothing here and lies in an empty macrocell jumps to where marchSse
    // would (the samples in between would see nothing either).
    if (const unsigned dark = inside & ~composited) {
      // Their macrocells (FieldGeometry::macroIndexOf).
      const __m512i macros = _mm512_add_epi32(
          _mm512_sub_epi32(_mm512_srai_epi32(ix, FieldGeometry::kMacroShift), f.macroFirstX),
          _mm512_mullo_epi32(
              f.macroCellsX,
              _mm512_add_epi32(
                  _mm512_sub_epi32(_mm512_srai_epi32(iy, FieldGeometry::kMacroShift),
                                   f.macroFirstY),
                  _mm512_mullo_epi32(
                      f.macroCellsY,
                      _mm512_sub_epi32(_mm512_srai_epi32(iz, FieldGeometry::kMacroShift),
                                       f.macroFirstZ)))));
      alignas(64) int macro[16];
      _mm512_store_si512(macro, macros);
      alignas(64) float t[16], k[16];
      bool jumped = false;
      for (unsigned lanes = dark; lanes; lanes &= lanes - 1) {
        const int l = std::countr_zero(lanes);
        if (!f.empty[macro[l]]) continue;
        if (!jumped) _mm512_store_ps(t, ts), _mm512_store_ps(k, p.ks), jumped = true;
        const float last = lastBeforeExit(*f.field, macro[l], p.rays[l], t[l]);
        if (last > k[l] + 1) {
          k[l] = last;  // this lane's next sample
          stepped &= static_cast<__mmask16>(~(1u << l));
        }
      }
      if (jumped) p.ks = _mm512_load_ps(k);
    }
  }
  p.counts = _mm512_mask_add_epi32(p.counts, taken, p.counts, _mm512_set1_epi32(1));
  p.ks = _mm512_mask_add_ps(p.ks, stepped, p.ks, one);
}

AVX512_INLINE void finish(const Packet16& p, MarchColor* colors, std::uint32_t* samples) {
  alignas(64) float r[16], g[16], b[16], tr[16], depth[16];
  alignas(64) std::uint32_t taken[16];
  _mm512_store_ps(r, p.red);
  _mm512_store_ps(g, p.green);
  _mm512_store_ps(b, p.blue);
  _mm512_store_ps(tr, p.transmittance);
  _mm512_store_ps(depth, p.depths);
  _mm512_store_si512(taken, p.counts);
  for (int l = 0; l < p.count; ++l) {
    colors[l].rgb = {r[l], g[l], b[l]};
    colors[l].transmittance = tr[l];
    colors[l].depth = depth[l];
    samples[l] = taken[l];
  }
}

template <class T>
AVX512_TARGET void marchPacket16(const SciVisScene::VolumeLayer& v, const MarchRay* rays, int count,
                                 MarchColor* colors, std::uint32_t* samples, const MarchRay* next,
                                 int nextCount) {
  Field16 f;
  setUp(f, v);
  Packet16 p;
  start(p, f, rays, count);
  if (f.prefetch && nextCount > 0) prefetchStarts<T>(f, next, nextCount);
  while (p.alive) advance<T>(p, f);
  finish(p, colors, samples);
}

}  // namespace

void marchPacketAvx512(const SciVisScene::VolumeLayer& v, const MarchRay* rays, int count,
                       MarchColor* colors, std::uint32_t* samples, const MarchRay* next,
                       int nextCount) {
  switch (v.field->volume().type) {
    default:
    case VoxelType::Float32:
      return marchPacket16<float>(v, rays, count, colors, samples, next, nextCount);
    case VoxelType::UInt8:
      return marchPacket16<std::uint8_t>(v, rays, count, colors, samples, next, nextCount);
    case VoxelType::UInt16:
      return marchPacket16<std::uint16_t>(v, rays, count, colors, samples, next, nextCount);
  }
}

}  // namespace renderers::scivis::march
