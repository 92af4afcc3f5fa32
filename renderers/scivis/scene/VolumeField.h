#pragma once
// Trilinear sampling of a Volume in world space, and its macrocells (min/max of blocks of
// voxels) for skipping space the transfer function makes invisible. Header-only: this is the
// renderer's innermost loop.
//
// A point can be sampled where all 8 voxels around it are held: inside the world box of the held
// voxel centres (`dataBounds`). Outside that the field is "not here" (a brick's neighbour has it).
//
// Missing values: float volumes may hold NaN voxels (a file's fill values, land in an ocean
// model). A point whose cell touches one samples as "no data" (sample() false, sample4() lane
// off): it renders as empty space and no isosurface is crossed there. Macrocell ranges leave
// NaN voxels out (a macrocell of NaN only has min +inf, max -inf: it holds nothing).
#include <emmintrin.h>  // SSE2, which every x86-64 has: sample4()

#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "renderers/Volume.h"
#include "renderers/scivis/scene/Box.h"

namespace renderers::scivis {

// Where a held box of a field lies and how world points map onto it: cells, macrocells on the
// whole field's grid and their value ranges. The part of a field that does not depend on how
// the voxels are stored, shared by the dense VolumeField and the sparse ShadingShell, so both
// locate a point with the same arithmetic (the same bits).
class FieldGeometry {
 public:
  static constexpr int kMacroShift = 3;  // macrocells of 8 x 8 x 8 voxel cells
  static constexpr int kMacro = 1 << kMacroShift;

  const GridGeometry& grid() const { return grid_; }
  const VoxelBox& box() const { return box_; }
  const Box3& dataBounds() const { return bounds_; }
  float minSpacing() const {
    const Vec3 s = grid_.spacing;
    return std::min(s.x, std::min(s.y, s.z));
  }

  // Where a world point falls: its cell (whole-field voxel indices of the cell's first voxel,
  // the offset of that voxel in the held data) and the position inside the cell.
  struct Cell {
    std::size_t offset;
    int ix, iy, iz;
    float fx, fy, fz;
  };

  // The cell of world point p; false outside dataBounds(). sample() is locate() then
  // interpolate(): loops that look at the cell first (its macrocell) get the same bits.
  bool locate(Vec3 p, Cell& c) const {
    // Coordinates in voxels of the whole field, so a brick computes exactly the weights the
    // whole volume does at the same point (bit for bit), whatever part of the field it holds.
    float fx = (p.x - origin_.x) * invSpacing_.x, fy = (p.y - origin_.y) * invSpacing_.y,
          fz = (p.z - origin_.z) * invSpacing_.z;
    if (!(fx >= lo_.x && fy >= lo_.y && fz >= lo_.z && fx <= hi_.x && fy <= hi_.y && fz <= hi_.z))
      return false;
    // The last cell includes its far face.
    c.ix = std::min(static_cast<int>(fx), lastCell_.x);
    c.iy = std::min(static_cast<int>(fy), lastCell_.y);
    c.iz = std::min(static_cast<int>(fz), lastCell_.z);
    c.fx = fx - static_cast<float>(c.ix), c.fy = fy - static_cast<float>(c.iy);
    c.fz = fz - static_cast<float>(c.iz);
    c.offset = static_cast<std::size_t>(c.ix - first_.x) +
               static_cast<std::size_t>(c.iy - first_.y) * strideY_ +
               static_cast<std::size_t>(c.iz - first_.z) * strideZ_;
    return true;
  }

  // The trilinear value at (fx, fy, fz) of a cell whose corner values are c: c0 c1 along x,
  // then y (c2 c3), then z (c4 .. c7).
  static float trilinear(const float c[8], float fx, float fy, float fz) {
    const float x00 = c[0] + fx * (c[1] - c[0]), x10 = c[2] + fx * (c[3] - c[2]);
    const float x01 = c[4] + fx * (c[5] - c[4]), x11 = c[6] + fx * (c[7] - c[6]);
    const float y0 = x00 + fy * (x10 - x00), y1 = x01 + fy * (x11 - x01);
    return y0 + fz * (y1 - y0);
  }

  // The numbers locate() and macroIndexOf() work with, for vectorised copies of them
  // (VolumeMarch.cpp), which must round as they do.
  struct Layout {
    Vec3 origin, invSpacing, lo, hi;
    Index3 first, lastCell, macroFirst, macroCells;
    std::size_t strideY, strideZ;
  };
  Layout layout() const {
    return {origin_,   invSpacing_, lo_,         hi_,      first_,
            lastCell_, macroFirst_, macroCells_, strideY_, strideZ_};
  }

  // Macrocells: the value range of the voxels a block of cells interpolates between.
  int macroIndex(Vec3 p) const;  // -1 outside dataBounds()
  // The macrocell of a located cell: what macroIndex() gives for the same point.
  int macroIndexOf(const Cell& c) const {
    return (c.ix >> kMacroShift) - macroFirst_.x +
           macroCells_.x * ((c.iy >> kMacroShift) - macroFirst_.y +
                            macroCells_.y * ((c.iz >> kMacroShift) - macroFirst_.z));
  }
  float macroMin(int m) const { return macroMin_[static_cast<std::size_t>(m)]; }
  float macroMax(int m) const { return macroMax_[static_cast<std::size_t>(m)]; }
  Box3 macroBounds(int m) const;
  int macroCount() const { return static_cast<int>(macroMin_.size()); }
  // The first voxel (whole-field indices) of macrocell m.
  Index3 macroOrigin(int m) const;

 protected:
  FieldGeometry() = default;
  // The geometry of `box` of `grid` (at least 2 voxels per axis; throws base::Error
  // otherwise), voxels stored x fastest, then y, then z, slices `sliceStride` voxels apart (0:
  // dense, box.size().x * box.size().y); macrocell ranges all zero.
  FieldGeometry(const GridGeometry& grid, const VoxelBox& box, std::size_t sliceStride = 0);

  GridGeometry grid_;
  VoxelBox box_;
  Vec3 origin_, invSpacing_;  // of the whole field's grid
  Vec3 lo_, hi_;              // the held voxels' first and last index, as floats
  Index3 first_, lastCell_;   // the first held voxel; the last cell's first voxel
  std::size_t strideY_ = 0, strideZ_ = 0;
  Box3 bounds_;
  Index3 macroFirst_, macroCells_;
  std::vector<float> macroMin_, macroMax_;
};

// A field whose held box is stored densely: a Volume (which must outlive it).
class VolumeField : public FieldGeometry {
 public:
  explicit VolumeField(const Volume& volume);

  const Volume& volume() const { return *volume_; }

  // The trilinear value in cell c, with the voxels read as T (the volume's voxel type).
  template <class T>
  float interpolate(const Cell& cell) const {
    const T* v = reinterpret_cast<const T*>(volume_->data()) + cell.offset;
    const float c[8] = {static_cast<float>(v[0]),
                        static_cast<float>(v[1]),
                        static_cast<float>(v[strideY_]),
                        static_cast<float>(v[strideY_ + 1]),
                        static_cast<float>(v[strideZ_]),
                        static_cast<float>(v[strideZ_ + 1]),
                        static_cast<float>(v[strideZ_ + strideY_]),
                        static_cast<float>(v[strideZ_ + strideY_ + 1])};
    return trilinear(c, cell.fx, cell.fy, cell.fz);
  }

  // The trilinear value at world point p; false outside dataBounds() and where the value is
  // missing (NaN; `value` is then NaN too).
  bool sample(Vec3 p, float& value) const {
    Cell c;
    if (!locate(p, c)) return false;
    switch (volume_->type) {
      default:  // Float32 (the switch covers every type; GCC cannot tell)
      case VoxelType::Float32:
        value = interpolate<float>(c);
        break;
      case VoxelType::UInt8:
        value = interpolate<std::uint8_t>(c);
        break;
      case VoxelType::UInt16:
        value = interpolate<std::uint16_t>(c);
        break;
    }
    return value == value;  // NaN: missing
  }

  // sample() at four points at once (their x, y, z in the lanes), for loops that take several
  // samples of a ray together: the same arithmetic lane by lane, so the same bits. Returns the
  // lanes inside dataBounds() with a value (not NaN) as a 4-bit mask (their values in `value`,
  // the others garbage) and the macrocell of lane 0 (-1 when outside).
  template <class T>
  int sample4(__m128 px, __m128 py, __m128 pz, __m128& value, int& macro0) const {
    const __m128 fx =
        _mm_mul_ps(_mm_sub_ps(px, _mm_set1_ps(origin_.x)), _mm_set1_ps(invSpacing_.x));
    const __m128 fy =
        _mm_mul_ps(_mm_sub_ps(py, _mm_set1_ps(origin_.y)), _mm_set1_ps(invSpacing_.y));
    const __m128 fz =
        _mm_mul_ps(_mm_sub_ps(pz, _mm_set1_ps(origin_.z)), _mm_set1_ps(invSpacing_.z));
    __m128 in =
        _mm_and_ps(_mm_cmpge_ps(fx, _mm_set1_ps(lo_.x)), _mm_cmple_ps(fx, _mm_set1_ps(hi_.x)));
    in = _mm_and_ps(
        in, _mm_and_ps(_mm_cmpge_ps(fy, _mm_set1_ps(lo_.y)), _mm_cmple_ps(fy, _mm_set1_ps(hi_.y))));
    in = _mm_and_ps(
        in, _mm_and_ps(_mm_cmpge_ps(fz, _mm_set1_ps(lo_.z)), _mm_cmple_ps(fz, _mm_set1_ps(hi_.z))));
    const int mask = _mm_movemask_ps(in);
    macro0 = -1;
    value = _mm_setzero_ps();
    if (mask == 0) return 0;
    const __m128i inside = _mm_castps_si128(in);
    // min(int(f), last) inside; the first held cell outside, so every lane reads held voxels.
    auto cellOf = [&](__m128 f, int last, int first) {
      const __m128i i = _mm_cvttps_epi32(f), l = _mm_set1_epi32(last);
      const __m128i over = _mm_cmpgt_epi32(i, l);
      const __m128i c = _mm_or_si128(_mm_and_si128(over, l), _mm_andnot_si128(over, i));
      return _mm_or_si128(_mm_and_si128(inside, c),
                          _mm_andnot_si128(inside, _mm_set1_epi32(first)));
    };
    const __m128i ix = cellOf(fx, lastCell_.x, first_.x), iy = cellOf(fy, lastCell_.y, first_.y),
                  iz = cellOf(fz, lastCell_.z, first_.z);
    const __m128 wx = _mm_sub_ps(fx, _mm_cvtepi32_ps(ix)), wy = _mm_sub_ps(fy, _mm_cvtepi32_ps(iy)),
                 wz = _mm_sub_ps(fz, _mm_cvtepi32_ps(iz));
    alignas(16) int cx[4], cy[4], cz[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(cx), ix);
    _mm_store_si128(reinterpret_cast<__m128i*>(cy), iy);
    _mm_store_si128(reinterpret_cast<__m128i*>(cz), iz);
    if (mask & 1) macro0 = macroIndexOf(Cell{0, cx[0], cy[0], cz[0], 0, 0, 0});
    // Per lane (c0 c1 c2 c3) and (c4 c5 c6 c7), transposed to one corner per register.
    __m128 lo[4], hi[4];
    const T* voxels = reinterpret_cast<const T*>(volume_->data());
    for (int lane = 0; lane < 4; ++lane) {
      const T* v = voxels + static_cast<std::size_t>(cx[lane] - first_.x) +
                   static_cast<std::size_t>(cy[lane] - first_.y) * strideY_ +
                   static_cast<std::size_t>(cz[lane] - first_.z) * strideZ_;
      corners(v, lo[lane], hi[lane]);
    }
    _MM_TRANSPOSE4_PS(lo[0], lo[1], lo[2], lo[3]);
    _MM_TRANSPOSE4_PS(hi[0], hi[1], hi[2], hi[3]);
    auto lerp = [](__m128 a, __m128 b, __m128 f) {
      return _mm_add_ps(a, _mm_mul_ps(f, _mm_sub_ps(b, a)));
    };
    const __m128 x00 = lerp(lo[0], lo[1], wx), x10 = lerp(lo[2], lo[3], wx);
    const __m128 x01 = lerp(hi[0], hi[1], wx), x11 = lerp(hi[2], hi[3], wx);
    value = lerp(lerp(x00, x10, wy), lerp(x01, x11, wy), wz);
    return mask & _mm_movemask_ps(_mm_cmpord_ps(value, value));  // NaN lanes: missing
  }

  // Central differences of the trilinear field, `h` world units apart; zero where a neighbour
  // point is not held.
  Vec3 gradient(Vec3 p, float h) const {
    Vec3 g;
    for (int axis = 0; axis < 3; ++axis) {
      const Vec3 d{axis == 0 ? h : 0.0f, axis == 1 ? h : 0.0f, axis == 2 ? h : 0.0f};
      float plus = 0, minus = 0, centre = 0, slope = 0;
      const bool hasPlus = sample(p + d, plus), hasMinus = sample(p - d, minus);
      if (hasPlus && hasMinus)
        slope = (plus - minus) / (2 * h);
      else if (hasPlus && sample(p, centre))  // one-sided at the data's edge
        slope = (plus - centre) / h;
      else if (hasMinus && sample(p, centre))
        slope = (centre - minus) / h;
      (axis == 0 ? g.x : axis == 1 ? g.y : g.z) = slope;
    }
    return g;
  }

 private:
  // The cell's 8 voxels from its first, v: (c0 c1 c2 c3) and (c4 c5 c6 c7) in interpolate()'s
  // order.
  void corners(const float* v, __m128& lo, __m128& hi) const {
    lo = _mm_loadh_pi(_mm_loadl_pi(_mm_setzero_ps(), reinterpret_cast<const __m64*>(v)),
                      reinterpret_cast<const __m64*>(v + strideY_));
    hi = _mm_loadh_pi(_mm_loadl_pi(_mm_setzero_ps(), reinterpret_cast<const __m64*>(v + strideZ_)),
                      reinterpret_cast<const __m64*>(v + strideZ_ + strideY_));
  }
  template <class T>
  void corners(const T* v, __m128& lo, __m128& hi) const {
    lo = _mm_setr_ps(static_cast<float>(v[0]), static_cast<float>(v[1]),
                     static_cast<float>(v[strideY_]), static_cast<float>(v[strideY_ + 1]));
    hi = _mm_setr_ps(static_cast<float>(v[strideZ_]), static_cast<float>(v[strideZ_ + 1]),
                     static_cast<float>(v[strideZ_ + strideY_]),
                     static_cast<float>(v[strideZ_ + strideY_ + 1]));
  }

  const Volume* volume_;
};

}  // namespace renderers::scivis
