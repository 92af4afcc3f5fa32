#pragma once
// Trilinear sampling of a Volume in world space, and its macrocells (min/max of blocks of
// voxels) for skipping space the transfer function makes invisible. Header-only: this is the
// renderer's innermost loop.
//
// A point can be sampled where all 8 voxels around it are held: inside the world box of the held
// voxel centres (`dataBounds`). Outside that the field is "not here" (a brick's neighbour has it).
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "renderers/scivis/Box.h"
#include "renderers/scivis/Volume.h"

namespace renderers {

class VolumeField {
 public:
  static constexpr int kMacroShift = 3;  // macrocells of 8 x 8 x 8 voxel cells

  explicit VolumeField(const Volume& volume);

  const Volume& volume() const { return *volume_; }
  const Box3& dataBounds() const { return bounds_; }
  float minSpacing() const {
    const Vec3 s = volume_->grid.spacing;
    return std::min(s.x, std::min(s.y, s.z));
  }

  // The trilinear value at world point p; false (value untouched) outside dataBounds().
  bool sample(Vec3 p, float& value) const {
    // Coordinates in voxels of the whole field, so a brick computes exactly the weights the
    // whole volume does at the same point (bit for bit), whatever part of the field it holds.
    float fx = (p.x - origin_.x) * invSpacing_.x, fy = (p.y - origin_.y) * invSpacing_.y,
          fz = (p.z - origin_.z) * invSpacing_.z;
    if (!(fx >= lo_.x && fy >= lo_.y && fz >= lo_.z && fx <= hi_.x && fy <= hi_.y && fz <= hi_.z))
      return false;
    // The last cell includes its far face.
    const int ix = std::min(static_cast<int>(fx), lastCell_.x);
    const int iy = std::min(static_cast<int>(fy), lastCell_.y);
    const int iz = std::min(static_cast<int>(fz), lastCell_.z);
    fx -= static_cast<float>(ix), fy -= static_cast<float>(iy), fz -= static_cast<float>(iz);
    const std::size_t i = static_cast<std::size_t>(ix - first_.x) +
                          static_cast<std::size_t>(iy - first_.y) * strideY_ +
                          static_cast<std::size_t>(iz - first_.z) * strideZ_;
    float c[8];
    gather(i, c);
    const float x00 = c[0] + fx * (c[1] - c[0]), x10 = c[2] + fx * (c[3] - c[2]);
    const float x01 = c[4] + fx * (c[5] - c[4]), x11 = c[6] + fx * (c[7] - c[6]);
    const float y0 = x00 + fy * (x10 - x00), y1 = x01 + fy * (x11 - x01);
    value = y0 + fz * (y1 - y0);
    return true;
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

  // Macrocells: the value range of the voxels a block of cells interpolates between.
  int macroIndex(Vec3 p) const;  // -1 outside dataBounds()
  float macroMin(int m) const { return macroMin_[static_cast<std::size_t>(m)]; }
  float macroMax(int m) const { return macroMax_[static_cast<std::size_t>(m)]; }
  Box3 macroBounds(int m) const;
  int macroCount() const { return static_cast<int>(macroMin_.size()); }

 private:
  void gather(std::size_t i, float c[8]) const {
    const std::size_t o[8] = {0, 1, strideY_, strideY_ + 1, strideZ_, strideZ_ + 1,
                              strideZ_ + strideY_, strideZ_ + strideY_ + 1};
    switch (volume_->type) {
      default:  // Float32 (the switch covers every type; GCC cannot tell)
      case VoxelType::Float32: {
        const float* v = reinterpret_cast<const float*>(volume_->voxels.data()) + i;
        for (int k = 0; k < 8; ++k) c[k] = v[o[k]];
        break;
      }
      case VoxelType::UInt8: {
        const std::uint8_t* v = reinterpret_cast<const std::uint8_t*>(volume_->voxels.data()) + i;
        for (int k = 0; k < 8; ++k) c[k] = v[o[k]];
        break;
      }
      case VoxelType::UInt16: {
        const std::uint16_t* v =
            reinterpret_cast<const std::uint16_t*>(volume_->voxels.data()) + i;
        for (int k = 0; k < 8; ++k) c[k] = v[o[k]];
        break;
      }
    }
  }

  const Volume* volume_;
  Vec3 origin_, invSpacing_;  // of the whole field's grid
  Vec3 lo_, hi_;              // the held voxels' first and last index, as floats
  Index3 first_, lastCell_;   // the first held voxel; the last cell's first voxel
  std::size_t strideY_ = 0, strideZ_ = 0;
  Box3 bounds_;
  Index3 macroFirst_, macroCells_;
  std::vector<float> macroMin_, macroMax_;
};

}  // namespace renderers
