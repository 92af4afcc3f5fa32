#include "renderers/scivis/render/VolumeMarch.h"

#include <immintrin.h>

#include <algorithm>
#include <bit>
#include <climits>
#include <cmath>
#include <string>

#include "base/Error.h"
#include "renderers/scivis/render/VolumeMarchSteps.h"

namespace renderers::scivis {
namespace {

constexpr float kInf = Box3::kInf;

using march::corners8;
using march::firstSample;
using march::lastBeforeExit;
using march::tableEntries8;

// Four samples of the ray at a time (SSE lanes, each computed as the scalar path does),
// composited one by one in order; those past the end or past opacity are dropped. Samples in
// empty macrocells have zero opacity: skipping them changes no bit.
template <class T>
std::uint32_t marchSse(const SciVisScene::VolumeLayer& v, const MarchRay& r, MarchColor& acc) {
  const VolumeField& field = *v.field;
  const std::uint8_t* empty = v.emptyMacrocells.data();
  const float t1 = r.t1, volumeEnd = r.volumeEnd, minTransmittance = r.minTransmittance;
  float k = firstSample(r);

  const __m128 lanes = _mm_setr_ps(0, 1, 2, 3), jitters = _mm_set1_ps(r.jitter),
               steps = _mm_set1_ps(r.step);
  const __m128 tableScale = _mm_set1_ps(v.tableScale), valueMin = _mm_set1_ps(v.valueMin);
  const __m128 zero = _mm_setzero_ps(),
               lastEntry = _mm_set1_ps(static_cast<float>(SciVisScene::kTableSize - 1));
  const __m128i lastLower = _mm_set1_epi32(SciVisScene::kTableSize - 2);
  const float* table = v.table.data();
  __m128 rgb = _mm_setr_ps(acc.rgb.x, acc.rgb.y, acc.rgb.z, 0);
  float transmittance = acc.transmittance, depth = acc.depth;
  std::uint32_t samples = 0;
  for (bool done = false; !done && transmittance > minTransmittance; k += 4) {
    alignas(16) float t[4];
    const __m128 ts = _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_set1_ps(k), lanes), jitters), steps);
    _mm_store_ps(t, ts);
    if (t[0] >= t1 || t[0] > volumeEnd) break;
    __m128 values;
    int macro0;
    const int inside = field.sample4<T>(
        _mm_add_ps(_mm_set1_ps(r.origin.x), _mm_mul_ps(_mm_set1_ps(r.dir.x), ts)),
        _mm_add_ps(_mm_set1_ps(r.origin.y), _mm_mul_ps(_mm_set1_ps(r.dir.y), ts)),
        _mm_add_ps(_mm_set1_ps(r.origin.z), _mm_mul_ps(_mm_set1_ps(r.dir.z), ts)), values, macro0);
    if (macro0 >= 0 && empty[macro0]) {
      const float last = lastBeforeExit(field, macro0, r, t[0]);
      if (last > k + 4) {
        samples += 1;
        k = last - 4;  // the loop's += 4 lands on `last`
        continue;
      }
    }
    // The transfer function, as the generic loop's lookup computes it: x = clamp(scaled, 0,
    // last entry), entry i = min(int(x), last - 1), weight x - i.
    __m128 x = _mm_mul_ps(_mm_sub_ps(values, valueMin), tableScale);
    x = _mm_andnot_ps(_mm_cmplt_ps(x, zero), x);
    const __m128 over = _mm_cmplt_ps(lastEntry, x);
    x = _mm_or_ps(_mm_and_ps(over, lastEntry), _mm_andnot_ps(over, x));
    __m128i i = _mm_cvttps_epi32(x);
    const __m128i high = _mm_cmpgt_epi32(i, lastLower);
    i = _mm_or_si128(_mm_and_si128(high, lastLower), _mm_andnot_si128(high, i));
    i = _mm_and_si128(i, _mm_cmpgt_epi32(i, _mm_set1_epi32(-1)));  // NaN data: entry 0
    alignas(16) int entry[4];
    alignas(16) float weight[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(entry), i);
    _mm_store_ps(weight, _mm_sub_ps(x, _mm_cvtepi32_ps(i)));
    for (int lane = 0; lane < 4; ++lane) {
      if (transmittance <= minTransmittance || t[lane] >= t1 || t[lane] > volumeEnd) {
        done = true;
        break;
      }
      ++samples;
      if (!(inside >> lane & 1)) continue;
      const float* e =
          table + SciVisScene::kTableEntryFloats * static_cast<std::size_t>(entry[lane]);
      const __m128 a = _mm_loadu_ps(e), d = _mm_loadu_ps(e + 4);
      const __m128 rgba = _mm_add_ps(a, _mm_mul_ps(_mm_set1_ps(weight[lane]), d));
      const float alpha = _mm_cvtss_f32(_mm_shuffle_ps(rgba, rgba, _MM_SHUFFLE(3, 3, 3, 3)));
      if (!(alpha > 0)) continue;
      // Accumulator::add, channel by channel.
      rgb = _mm_add_ps(rgb, _mm_mul_ps(rgba, _mm_set1_ps(transmittance * alpha)));
      transmittance *= 1.0f - alpha;
      if (depth == kInf && transmittance <= 0.5f) depth = t[lane];
    }
  }
  alignas(16) float sum[4];
  _mm_store_ps(sum, rgb);
  acc.rgb = {sum[0], sum[1], sum[2]};
  acc.transmittance = transmittance;
  acc.depth = depth;
  return samples;
}

// min(int(f), last) in the lanes inside; the first held cell outside, so every lane reads held
// voxels.
AVX2_INLINE __m256i cellOf(__m256 f, int last, int first, __m256i inside) {
  const __m256i c = _mm256_min_epi32(_mm256_cvttps_epi32(f), _mm256_set1_epi32(last));
  return _mm256_blendv_epi8(_mm256_set1_epi32(first), c, inside);
}

AVX2_INLINE __m256 lerp(__m256 a, __m256 b, __m256 f) {
  return _mm256_add_ps(a, _mm256_mul_ps(f, _mm256_sub_ps(b, a)));
}

// The transfer function's colour and opacity of 8 lanes: the entries at[l] (floats from the
// table's start) interpolated with weight, as marchSse computes them.
AVX2_INLINE void tableLerp(const float* table, const int at[8], __m256 weight, __m256& r, __m256& g,
                           __m256& b, __m256& a) {
  __m256 c[2][4];
  tableEntries8(table, at, c);
  r = _mm256_add_ps(c[0][0], _mm256_mul_ps(weight, c[1][0]));
  g = _mm256_add_ps(c[0][1], _mm256_mul_ps(weight, c[1][1]));
  b = _mm256_add_ps(c[0][2], _mm256_mul_ps(weight, c[1][2]));
  a = _mm256_add_ps(c[0][3], _mm256_mul_ps(weight, c[1][3]));
}

// What every lane of a packet shares: the field's geometry and voxels, the transfer function.
struct Field8 {
  const VolumeField* field;
  const float* voxels;
  const std::uint8_t* empty;
  const float* table;
  int strideY, strideZ;
  bool prefetch;
  Index3 first, lastCell;
  __m256 gx, gy, gz, sx, sy, sz, lox, loy, loz, hix, hiy, hiz;
  __m256i strideYs, strideZs, firstX, firstY, firstZ;
  __m256i macroFirstX, macroFirstY, macroFirstZ, macroCellsX, macroCellsY;
  __m256 tableScale, valueMin;
};

AVX2_INLINE void setUp(Field8& f, const SciVisScene::VolumeLayer& v) {
  const FieldGeometry::Layout g = v.field->layout();
  f.field = v.field;
  f.voxels = reinterpret_cast<const float*>(v.field->volume().data());
  f.empty = v.emptyMacrocells.data();
  f.table = v.table.data();
  f.strideY = static_cast<int>(g.strideY), f.strideZ = static_cast<int>(g.strideZ);
  f.prefetch = v.field->volume().dataBytes() > march::kPrefetchAboveBytes;
  f.first = g.first, f.lastCell = g.lastCell;
  f.gx = _mm256_set1_ps(g.origin.x), f.gy = _mm256_set1_ps(g.origin.y);
  f.gz = _mm256_set1_ps(g.origin.z);
  f.sx = _mm256_set1_ps(g.invSpacing.x), f.sy = _mm256_set1_ps(g.invSpacing.y);
  f.sz = _mm256_set1_ps(g.invSpacing.z);
  f.lox = _mm256_set1_ps(g.lo.x), f.loy = _mm256_set1_ps(g.lo.y), f.loz = _mm256_set1_ps(g.lo.z);
  f.hix = _mm256_set1_ps(g.hi.x), f.hiy = _mm256_set1_ps(g.hi.y), f.hiz = _mm256_set1_ps(g.hi.z);
  f.strideYs = _mm256_set1_epi32(f.strideY), f.strideZs = _mm256_set1_epi32(f.strideZ);
  f.firstX = _mm256_set1_epi32(g.first.x), f.firstY = _mm256_set1_epi32(g.first.y);
  f.firstZ = _mm256_set1_epi32(g.first.z);
  f.macroFirstX = _mm256_set1_epi32(g.macroFirst.x);
  f.macroFirstY = _mm256_set1_epi32(g.macroFirst.y);
  f.macroFirstZ = _mm256_set1_epi32(g.macroFirst.z);
  f.macroCellsX = _mm256_set1_epi32(g.macroCells.x);
  f.macroCellsY = _mm256_set1_epi32(g.macroCells.y);
  f.tableScale = _mm256_set1_ps(v.tableScale), f.valueMin = _mm256_set1_ps(v.valueMin);
}

// Up to 8 rays, one per lane, each where its march has got to.
struct Packet8 {
  const MarchRay* rays;
  int count;
  __m256 jitters, steps, t1s, ends, minTs, ox, oy, oz, dx, dy, dz;
  __m256 ks, red, green, blue, transmittance, depths;
  __m256 aheadX, aheadY, aheadZ;  // kPrefetchAhead steps along the ray, in cells
  __m256i counts;
  unsigned alive;  // lanes still marching
};

AVX2_INLINE void start(Packet8& p, const Field8& f, const MarchRay* rays, int count,
                       const MarchColor* colors) {
  alignas(32) float k[8], jitter[8], step[8], ox[8], oy[8], oz[8], dx[8], dy[8], dz[8], t1[8],
      end[8], minT[8], r[8], g[8], b[8], tr[8], depth[8];
  static const MarchRay none{};  // the lanes past `count`: never marching
  static const MarchColor black{};
  for (int l = 0; l < 8; ++l) {
    const MarchRay& ray = l < count ? rays[l] : none;
    const MarchColor& c = l < count ? colors[l] : black;
    k[l] = l < count ? firstSample(ray) : 0;
    jitter[l] = ray.jitter, step[l] = ray.step, t1[l] = ray.t1, end[l] = ray.volumeEnd;
    minT[l] = ray.minTransmittance;
    ox[l] = ray.origin.x, oy[l] = ray.origin.y, oz[l] = ray.origin.z;
    dx[l] = ray.dir.x, dy[l] = ray.dir.y, dz[l] = ray.dir.z;
    r[l] = c.rgb.x, g[l] = c.rgb.y, b[l] = c.rgb.z, tr[l] = c.transmittance, depth[l] = c.depth;
  }
  p.rays = rays, p.count = count;
  p.jitters = _mm256_load_ps(jitter), p.steps = _mm256_load_ps(step);
  p.t1s = _mm256_load_ps(t1), p.ends = _mm256_load_ps(end), p.minTs = _mm256_load_ps(minT);
  p.ox = _mm256_load_ps(ox), p.oy = _mm256_load_ps(oy), p.oz = _mm256_load_ps(oz);
  p.dx = _mm256_load_ps(dx), p.dy = _mm256_load_ps(dy), p.dz = _mm256_load_ps(dz);
  const __m256 ahead = _mm256_mul_ps(_mm256_set1_ps(march::kPrefetchAhead), p.steps);
  p.aheadX = _mm256_mul_ps(_mm256_mul_ps(ahead, p.dx), f.sx);
  p.aheadY = _mm256_mul_ps(_mm256_mul_ps(ahead, p.dy), f.sy);
  p.aheadZ = _mm256_mul_ps(_mm256_mul_ps(ahead, p.dz), f.sz);
  p.ks = _mm256_load_ps(k);
  p.red = _mm256_load_ps(r), p.green = _mm256_load_ps(g), p.blue = _mm256_load_ps(b);
  p.transmittance = _mm256_load_ps(tr), p.depths = _mm256_load_ps(depth);
  p.counts = _mm256_setzero_si256();
  // marchSse's loop test: light gets through.
  p.alive = static_cast<unsigned>(
                _mm256_movemask_ps(_mm256_cmp_ps(p.transmittance, p.minTs, _CMP_GT_OQ))) &
            ((1u << count) - 1);
}

AVX2_INLINE __m256 laneMask(unsigned bits) {
  return _mm256_castsi256_ps(
      _mm256_cmpgt_epi32(_mm256_and_si256(_mm256_set1_epi32(static_cast<int>(bits)),
                                          _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128)),
                         _mm256_setzero_si256()));
}

// The held cell (relative to the first) of coordinate c + ahead, clamped to the held cells.
AVX2_INLINE __m256i cellAhead(__m256 c, __m256 ahead, int first, int last, __m256i firsts) {
  const __m256i i =
      _mm256_min_epi32(_mm256_cvttps_epi32(_mm256_add_ps(c, ahead)), _mm256_set1_epi32(last));
  return _mm256_sub_epi32(_mm256_max_epi32(i, _mm256_set1_epi32(first)), firsts);
}

// Asks for the voxels of cell (fx, fy, fz) + ahead of `lanes`, as the AVX-512 kernel does
// (VolumeMarchAvx512.cpp): a hint only, no value changes.
AVX2_INLINE void prefetchCells(const Field8& f, __m256 fx, __m256 fy, __m256 fz, __m256 aheadX,
                               __m256 aheadY, __m256 aheadZ, unsigned lanes) {
  const __m256i offset = _mm256_add_epi32(
      cellAhead(fx, aheadX, f.first.x, f.lastCell.x, f.firstX),
      _mm256_add_epi32(
          _mm256_mullo_epi32(cellAhead(fy, aheadY, f.first.y, f.lastCell.y, f.firstY), f.strideYs),
          _mm256_mullo_epi32(cellAhead(fz, aheadZ, f.first.z, f.lastCell.z, f.firstZ),
                             f.strideZs)));
  alignas(32) int at[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(at), offset);
  for (; lanes; lanes &= lanes - 1) {
    const float* v = f.voxels + at[std::countr_zero(lanes)];
    for (const float* row : {v, v + f.strideY, v + f.strideZ, v + f.strideZ + f.strideY})
      _mm_prefetch(reinterpret_cast<const char*>(row), _MM_HINT_T0);
  }
}

// The first kPrefetchAhead samples' voxels of the packet that marches next, as the AVX-512
// kernel asks for them (prefetchStarts there).
AVX2_INLINE void prefetchStarts(const Field8& f, const MarchRay* rays, int count) {
  alignas(32) float x[8], y[8], z[8], ex[8], ey[8], ez[8];
  for (int l = 0; l < 8; ++l) {
    const MarchRay& r = rays[l < count ? l : 0];
    const float t = std::max(r.t0, (r.kStart + r.jitter) * r.step);
    x[l] = r.origin.x + r.dir.x * t, y[l] = r.origin.y + r.dir.y * t;
    z[l] = r.origin.z + r.dir.z * t;
    ex[l] = r.step * r.dir.x, ey[l] = r.step * r.dir.y, ez[l] = r.step * r.dir.z;
  }
  const __m256 fx = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(x), f.gx), f.sx);
  const __m256 fy = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(y), f.gy), f.sy);
  const __m256 fz = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(z), f.gz), f.sz);
  const __m256 sx = _mm256_mul_ps(_mm256_load_ps(ex), f.sx);
  const __m256 sy = _mm256_mul_ps(_mm256_load_ps(ey), f.sy);
  const __m256 sz = _mm256_mul_ps(_mm256_load_ps(ez), f.sz);
  for (int j = 0; j < static_cast<int>(march::kPrefetchAhead); ++j) {
    const __m256 a = _mm256_set1_ps(static_cast<float>(j));
    prefetchCells(f, fx, fy, fz, _mm256_mul_ps(a, sx), _mm256_mul_ps(a, sy), _mm256_mul_ps(a, sz),
                  0xffu);
  }
}

// One sample of every ray still marching.
AVX2_INLINE void advance(Packet8& p, const Field8& f) {
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
  const __m256 ts = _mm256_mul_ps(_mm256_add_ps(p.ks, p.jitters), p.steps);
  p.alive &= static_cast<unsigned>(_mm256_movemask_ps(
      _mm256_and_ps(_mm256_cmp_ps(ts, p.t1s, _CMP_LT_OQ), _mm256_cmp_ps(ts, p.ends, _CMP_LE_OQ))));
  if (!p.alive) return;
  // VolumeField::locate(), lane by lane.
  const __m256 fx =
      _mm256_mul_ps(_mm256_sub_ps(_mm256_add_ps(p.ox, _mm256_mul_ps(p.dx, ts)), f.gx), f.sx);
  const __m256 fy =
      _mm256_mul_ps(_mm256_sub_ps(_mm256_add_ps(p.oy, _mm256_mul_ps(p.dy, ts)), f.gy), f.sy);
  const __m256 fz =
      _mm256_mul_ps(_mm256_sub_ps(_mm256_add_ps(p.oz, _mm256_mul_ps(p.dz, ts)), f.gz), f.sz);
  __m256 in =
      _mm256_and_ps(_mm256_cmp_ps(fx, f.lox, _CMP_GE_OQ), _mm256_cmp_ps(fx, f.hix, _CMP_LE_OQ));
  in = _mm256_and_ps(in, _mm256_and_ps(_mm256_cmp_ps(fy, f.loy, _CMP_GE_OQ),
                                       _mm256_cmp_ps(fy, f.hiy, _CMP_LE_OQ)));
  in = _mm256_and_ps(in, _mm256_and_ps(_mm256_cmp_ps(fz, f.loz, _CMP_GE_OQ),
                                       _mm256_cmp_ps(fz, f.hiz, _CMP_LE_OQ)));
  const unsigned inside = static_cast<unsigned>(_mm256_movemask_ps(in)) & p.alive;
  // Every marching lane takes (and counts) this sample; all but those that jump then step on.
  const unsigned taken = p.alive;
  unsigned stepped = 0xffu;
  if (inside) {
    const __m256i insideLanes = _mm256_castps_si256(in);
    const __m256i ix = cellOf(fx, f.lastCell.x, f.first.x, insideLanes),
                  iy = cellOf(fy, f.lastCell.y, f.first.y, insideLanes),
                  iz = cellOf(fz, f.lastCell.z, f.first.z, insideLanes);
    const __m256 wx = _mm256_sub_ps(fx, _mm256_cvtepi32_ps(ix)),
                 wy = _mm256_sub_ps(fy, _mm256_cvtepi32_ps(iy)),
                 wz = _mm256_sub_ps(fz, _mm256_cvtepi32_ps(iz));
    const __m256i offset = _mm256_add_epi32(
        _mm256_sub_epi32(ix, f.firstX),
        _mm256_add_epi32(_mm256_mullo_epi32(_mm256_sub_epi32(iy, f.firstY), f.strideYs),
                         _mm256_mullo_epi32(_mm256_sub_epi32(iz, f.firstZ), f.strideZs)));
    alignas(32) int offsets[8];
    _mm256_store_si256(reinterpret_cast<__m256i*>(offsets), offset);
    if (f.prefetch) prefetchCells(f, fx, fy, fz, p.aheadX, p.aheadY, p.aheadZ, inside);
    __m256 c[8];
    corners8(f.voxels, offsets, f.strideY, f.strideZ, c);
    // VolumeField::interpolate(): along x, then y, then z.
    const __m256 x00 = lerp(c[0], c[1], wx), x10 = lerp(c[2], c[3], wx);
    const __m256 x01 = lerp(c[4], c[5], wx), x11 = lerp(c[6], c[7], wx);
    const __m256 values = lerp(lerp(x00, x10, wy), lerp(x01, x11, wy), wz);
    // The transfer function as marchSse computes it.
    const __m256 lastEntry = _mm256_set1_ps(static_cast<float>(SciVisScene::kTableSize - 1));
    const __m256i lastLower = _mm256_set1_epi32(SciVisScene::kTableSize - 2);
    __m256 x = _mm256_mul_ps(_mm256_sub_ps(values, f.valueMin), f.tableScale);
    // vmaxps / vminps give their second operand unless the first is greater / less (NaN
    // compares false): the clamps of marchSse, NaN and -0 kept, in one instruction each.
    x = _mm256_min_ps(lastEntry, _mm256_max_ps(zero, x));
    __m256i i = _mm256_min_epi32(_mm256_cvttps_epi32(x), lastLower);
    i = _mm256_max_epi32(i, _mm256_setzero_si256());  // NaN's 0x80000000: entry 0
    const __m256 weight = _mm256_sub_ps(x, _mm256_cvtepi32_ps(i));
    alignas(32) int entry[8];
    static_assert(SciVisScene::kTableEntryFloats == 1 << 3, "entry i starts at float 8 i");
    _mm256_store_si256(reinterpret_cast<__m256i*>(entry), _mm256_slli_epi32(i, 3));
    __m256 r, g, b, opacity;
    tableLerp(f.table, entry, weight, r, g, b, opacity);
    const unsigned composited =
        static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(opacity, zero, _CMP_GT_OQ))) &
        inside;
    if (composited) {
      // Accumulator::add in the lanes that composite.
      const __m256 lanes = laneMask(composited);
      const __m256 w = _mm256_mul_ps(p.transmittance, opacity);
      p.red = _mm256_blendv_ps(p.red, _mm256_add_ps(p.red, _mm256_mul_ps(r, w)), lanes);
      p.green = _mm256_blendv_ps(p.green, _mm256_add_ps(p.green, _mm256_mul_ps(g, w)), lanes);
      p.blue = _mm256_blendv_ps(p.blue, _mm256_add_ps(p.blue, _mm256_mul_ps(b, w)), lanes);
      p.transmittance = _mm256_blendv_ps(
          p.transmittance, _mm256_mul_ps(p.transmittance, _mm256_sub_ps(one, opacity)), lanes);
      const __m256 reached = _mm256_and_ps(
          lanes, _mm256_and_ps(_mm256_cmp_ps(p.depths, _mm256_set1_ps(kInf), _CMP_EQ_OQ),
                               _mm256_cmp_ps(p.transmittance, _mm256_set1_ps(0.5f), _CMP_LE_OQ)));
      p.depths = _mm256_blendv_ps(p.depths, ts, reached);
      p.alive &= static_cast<unsigned>(
          _mm256_movemask_ps(_mm256_cmp_ps(p.transmittance, p.minTs, _CMP_GT_OQ)));
    }
    // A lane that sees nothing here and lies in an empty macrocell jumps to where marchSse
    // would (the samples in between would see nothing either).
    if (const unsigned dark = inside & ~composited) {
      // Their macrocells (FieldGeometry::macroIndexOf).
      const __m256i macros = _mm256_add_epi32(
          _mm256_sub_epi32(_mm256_srai_epi32(ix, FieldGeometry::kMacroShift), f.macroFirstX),
          _mm256_mullo_epi32(
              f.macroCellsX,
              _mm256_add_epi32(
                  _mm256_sub_epi32(_mm256_srai_epi32(iy, FieldGeometry::kMacroShift),
                                   f.macroFirstY),
                  _mm256_mullo_epi32(
                      f.macroCellsY,
                      _mm256_sub_epi32(_mm256_srai_epi32(iz, FieldGeometry::kMacroShift),
                                       f.macroFirstZ)))));
      alignas(32) int macro[8];
      _mm256_store_si256(reinterpret_cast<__m256i*>(macro), macros);
      alignas(32) float t[8], k[8];
      bool jumped = false;
      for (unsigned lanes = dark; lanes; lanes &= lanes - 1) {
        const int l = std::countr_zero(lanes);
        if (!f.empty[macro[l]]) continue;
        if (!jumped) _mm256_store_ps(t, ts), _mm256_store_ps(k, p.ks), jumped = true;
        const float last = lastBeforeExit(*f.field, macro[l], p.rays[l], t[l]);
        if (last > k[l] + 1) {
          k[l] = last;  // this lane's next sample
          stepped &= ~(1u << l);
        }
      }
      if (jumped) p.ks = _mm256_load_ps(k);
    }
  }
  p.counts = _mm256_sub_epi32(p.counts, _mm256_castps_si256(laneMask(taken)));
  p.ks = _mm256_add_ps(p.ks, _mm256_and_ps(one, laneMask(stepped)));
}

AVX2_INLINE void finish(const Packet8& p, MarchColor* colors, std::uint32_t* samples) {
  alignas(32) float r[8], g[8], b[8], tr[8], depth[8];
  alignas(32) std::uint32_t taken[8];
  _mm256_store_ps(r, p.red);
  _mm256_store_ps(g, p.green);
  _mm256_store_ps(b, p.blue);
  _mm256_store_ps(tr, p.transmittance);
  _mm256_store_ps(depth, p.depths);
  _mm256_store_si256(reinterpret_cast<__m256i*>(taken), p.counts);
  for (int l = 0; l < p.count; ++l) {
    colors[l].rgb = {r[l], g[l], b[l]};
    colors[l].transmittance = tr[l];
    colors[l].depth = depth[l];
    samples[l] = taken[l];
  }
}

// Up to 8 rays, one per AVX2 lane, one sample of each per step. Each lane computes its ray's
// samples as marchSse does (the same operations in the same order, no fused multiply-adds) and
// composites its own ray front to back, so every ray gets marchSse's colour bit for bit; lanes
// that composite nothing in a step (outside the data, no opacity, ended) keep their colour by a
// blend. A lane whose sample lies in an empty macrocell jumps, alone, as marchSse does. (Two
// packets stepped in turn, for the core to overlap their chains of dependent steps, measured
// no faster.)
__attribute__((target("avx2"))) void marchPacketAvx2(const SciVisScene::VolumeLayer& v,
                                                     const MarchRay* rays, int count,
                                                     MarchColor* colors, std::uint32_t* samples,
                                                     const MarchRay* next, int nextCount) {
  Field8 f;
  setUp(f, v);
  Packet8 p;
  start(p, f, rays, count, colors);
  if (f.prefetch && nextCount > 0) prefetchStarts(f, next, nextCount);
  while (p.alive) advance(p, f);
  finish(p, colors, samples);
}

// Whether every voxel offset of the field fits the packet kernel's 32-bit lane arithmetic.
bool offsetsFitInt(const VolumeField& field) {
  return field.volume().dataBytes() / voxelBytes(field.volume().type) <=
         static_cast<std::size_t>(INT_MAX);
}

}  // namespace

bool marchKernelAvailable(MarchKernel kernel) {
  switch (kernel) {
    case MarchKernel::Avx2:
      return __builtin_cpu_supports("avx2");
    case MarchKernel::Avx512:
      return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
             __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vl");
    default:
      return true;
  }
}

MarchKernel resolveMarchKernel(MarchKernel kernel) {
  if (kernel == MarchKernel::Auto) {
    for (MarchKernel best : {MarchKernel::Avx512, MarchKernel::Avx2})
      if (marchKernelAvailable(best)) return best;
    return MarchKernel::Sse;
  }
  if (!marchKernelAvailable(kernel))
    throw base::Error(std::string("this CPU cannot run the ") + marchKernelName(kernel) +
                      " volume march");
  return kernel;
}

int marchPacketSize(MarchKernel kernel) {
  switch (kernel) {
    case MarchKernel::Avx2:
      return 8;
    case MarchKernel::Avx512:
      return 16;
    default:
      return 1;
  }
}

bool marchesPackets(const SciVisScene::VolumeLayer& v, MarchKernel kernel) {
  if (!v.field || !offsetsFitInt(*v.field)) return false;
  // AVX-512 widens integer voxels in its lanes; AVX2 packets take float voxels only.
  return kernel == MarchKernel::Avx512 ||
         (kernel == MarchKernel::Avx2 && v.field->volume().type == VoxelType::Float32);
}

void marchPacket(const SciVisScene::VolumeLayer& v, MarchKernel kernel, const MarchRay* rays,
                 int count, MarchColor* colors, std::uint32_t* samples, const MarchRay* next,
                 int nextCount) {
  count = std::min(count, marchPacketSize(kernel));
  nextCount = std::min(nextCount, marchPacketSize(kernel));
  if (count <= 0) return;
  if (kernel == MarchKernel::Avx512)
    return march::marchPacketAvx512(v, rays, count, colors, samples, next, nextCount);
  std::fill(colors, colors + count, MarchColor{});
  marchPacketAvx2(v, rays, count, colors, samples, next, nextCount);
}

const char* marchKernelName(MarchKernel kernel) {
  switch (kernel) {
    case MarchKernel::Sse:
      return "sse";
    case MarchKernel::Avx2:
      return "avx2";
    case MarchKernel::Avx512:
      return "avx512";
    default:
      return "auto";
  }
}

std::uint32_t marchOneVolume(const SciVisScene::VolumeLayer& v, const MarchRay& ray,
                             MarchColor& color) {
  const VoxelType type = v.field->volume().type;
  switch (type) {
    default:
    case VoxelType::Float32:
      return marchSse<float>(v, ray, color);
    case VoxelType::UInt8:
      return marchSse<std::uint8_t>(v, ray, color);
    case VoxelType::UInt16:
      return marchSse<std::uint16_t>(v, ray, color);
  }
}

}  // namespace renderers::scivis
