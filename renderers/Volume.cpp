#include "renderers/Volume.h"

#include <sys/mman.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>

#include "base/Error.h"
#include "base/Parallel.h"

namespace renderers {

std::size_t voxelBytes(VoxelType type) {
  switch (type) {
    case VoxelType::Float32:
      return 4;
    case VoxelType::UInt8:
      return 1;
    case VoxelType::UInt16:
      return 2;
  }
  throw base::Error("unknown voxel type");
}

const char* voxelTypeName(VoxelType type) {
  switch (type) {
    case VoxelType::Float32:
      return "float32";
    case VoxelType::UInt8:
      return "uint8";
    case VoxelType::UInt16:
      return "uint16";
  }
  return "unknown";
}

std::size_t VoxelBox::voxelCount() const {
  if (empty()) return 0;
  const Index3 s = size();
  return static_cast<std::size_t>(s.x) * static_cast<std::size_t>(s.y) *
         static_cast<std::size_t>(s.z);
}

bool VoxelBox::contains(const VoxelBox& other) const {
  if (other.empty()) return true;
  return lo.x <= other.lo.x && lo.y <= other.lo.y && lo.z <= other.lo.z && other.hi.x <= hi.x &&
         other.hi.y <= hi.y && other.hi.z <= hi.z;
}

void GridGeometry::bounds(const VoxelBox& box, Vec3& lo, Vec3& hi) const {
  const Vec3 a = worldOf(static_cast<float>(box.lo.x), static_cast<float>(box.lo.y),
                         static_cast<float>(box.lo.z));
  const Vec3 b = worldOf(static_cast<float>(box.hi.x - 1), static_cast<float>(box.hi.y - 1),
                         static_cast<float>(box.hi.z - 1));
  // min/max: a negative spacing (a mirrored grid) still gives lo <= hi.
  lo = {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
  hi = {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}

std::string GridGeometry::problem() const {
  auto text = [](double v) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%g", v);
    return std::string(buffer);
  };
  for (int a = 0; a < 3; ++a) {
    const std::string axis = std::string(" along ") + "xyz"[a];
    const int n = dims[a];
    const float s = spacing[a], o = origin[a];
    if (n < 2) return "dims" + axis + " must be at least 2, not " + std::to_string(n);
    if (!(s >= std::numeric_limits<float>::min() && std::isfinite(1.0f / s)))
      return "spacing" + axis + ", " + text(s) + ", must be a positive normal float";
    const float extent = s * static_cast<float>(n - 1), far = o + extent;
    if (!std::isfinite(extent) || !std::isfinite(far))
      return "spacing" + axis +
             ": the grid's far corner, origin + spacing (dims - 1) = " + text(o) + " + " + text(s) +
             " x " + std::to_string(n - 1) + ", is beyond the float range";
    const float largest = std::max(std::fabs(o), std::fabs(far));
    const float step = std::nextafter(largest, INFINITY) - largest;
    if (s < 4 * step)
      return "spacing" + axis + ", " + text(s) +
             ", is below float precision at the grid's coordinates (up to " + text(largest) +
             ", where floats are " + text(step) +
             " apart): a voxel must span at least 4 of those steps";
  }
  return {};
}

namespace {

constexpr std::size_t kCacheLine = 64;

// Voxel n of the held voxels as a float; the buffer is not necessarily aligned for the type.
float valueAt(const std::byte* voxels, VoxelType type, std::size_t n) {
  switch (type) {
    case VoxelType::Float32: {
      float f;
      std::memcpy(&f, voxels + n * 4, 4);
      return f;
    }
    case VoxelType::UInt8:
      return static_cast<float>(static_cast<std::uint8_t>(voxels[n]));
    case VoxelType::UInt16: {
      std::uint16_t u;
      std::memcpy(&u, voxels + n * 2, 2);
      return static_cast<float>(u);
    }
  }
  return 0;
}

}  // namespace

float Volume::at(int i, int j, int k) const {
  const std::size_t n =
      static_cast<std::size_t>(k - box.lo.z) * sliceStride() +
      static_cast<std::size_t>(j - box.lo.y) * static_cast<std::size_t>(box.size().x) +
      static_cast<std::size_t>(i - box.lo.x);
  return valueAt(data(), type, n);
}

std::size_t Volume::sliceVoxels() const {
  const Index3 s = box.size();
  return box.empty() ? 0 : static_cast<std::size_t>(s.x) * static_cast<std::size_t>(s.y);
}

std::size_t slicePaddingFor(const VoxelBox& box, VoxelType type) {
  if (box.empty()) return 0;
  const Index3 s = box.size();
  const std::size_t sliceBytes =
      static_cast<std::size_t>(s.x) * static_cast<std::size_t>(s.y) * voxelBytes(type);
  return sliceBytes % 1024 == 0 ? kCacheLine / voxelBytes(type) : 0;
}

void Volume::spreadSlices() {
  const std::size_t padding = slicePaddingFor(box, type);
  if (slicePadding != 0 || padding == 0 || borrowed) return;
  const std::size_t width = voxelBytes(type), slice = sliceVoxels() * width;
  const std::size_t slices = static_cast<std::size_t>(box.size().z),
                    stride = slice + padding * width;
  if (voxels.size() != slice * slices) return;  // not dense voxels of the box: left as they are
  voxels.resize(stride * slices);
  // From the last slice down: each moves up, past slices already moved, never over one not yet.
  std::byte* buffer = voxels.data();
  for (std::size_t z = slices; z-- > 1;) {
    std::memmove(buffer + z * stride, buffer + z * slice, slice);
    std::memset(buffer + z * stride - padding * width, 0, padding * width);
  }
  std::memset(buffer + slices * stride - padding * width, 0, padding * width);
  slicePadding = padding;
}

std::vector<std::byte> allocateVoxelBytes(const VoxelBox& box, VoxelType type) {
  const std::size_t bytes = box.voxelCount() * voxelBytes(type);
  const std::size_t padded = bytes + slicePaddingFor(box, type) * voxelBytes(type) *
                                         static_cast<std::size_t>(box.empty() ? 0 : box.size().z);
  std::vector<std::byte> v;
  v.reserve(padded);  // allocated, not touched yet
  constexpr std::uintptr_t kHugePage = std::uintptr_t{2} << 20;
  if (padded >= 4 * kHugePage) {
    const auto begin = reinterpret_cast<std::uintptr_t>(v.data());
    const std::uintptr_t first = (begin + kHugePage - 1) & ~(kHugePage - 1);
    const std::uintptr_t last = (begin + padded) & ~(kHugePage - 1);
    // Advice only: where the kernel has no huge pages this fails and nothing changes.
    if (last > first) ::madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
  }
  v.resize(bytes);
  return v;
}

void Volume::updateRange() {
  const std::size_t count = box.voxelCount();
  if (count == 0 ||
      dataBytes() < sliceStride() * static_cast<std::size_t>(box.size().z) * voxelBytes(type)) {
    valueMin = valueMax = 0;
    return;
  }
  // One slice per task; NaN voxels (possible in float files) are left out so one bad voxel does
  // not make the whole range NaN.
  const std::size_t slab = sliceVoxels(), stride = sliceStride();
  const std::size_t slabs = static_cast<std::size_t>(box.size().z);
  std::vector<float> lo(slabs, std::numeric_limits<float>::infinity());
  std::vector<float> hi(slabs, -std::numeric_limits<float>::infinity());
  base::parallelFor(slabs, [&](std::size_t z) {
    float l = lo[z], h = hi[z];
    for (std::size_t n = z * stride, end = n + slab; n < end; ++n) {
      const float v = valueAt(data(), type, n);
      if (v < l) l = v;
      if (v > h) h = v;
    }
    lo[z] = l;
    hi[z] = h;
  });
  valueMin = *std::min_element(lo.begin(), lo.end());
  valueMax = *std::max_element(hi.begin(), hi.end());
  if (valueMin > valueMax) valueMin = valueMax = 0;  // every voxel NaN
}

}  // namespace renderers
