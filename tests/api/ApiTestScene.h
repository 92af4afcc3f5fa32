#pragma once
// The scene the API tests render: a wavelet field cut by the program into slabs with ghost
// layers, particles, a camera (shared by tests/api/*MpiTest.cpp).
#include <algorithm>
#include <vector>

#include "api/DataDistributed.h"
#include "renderers/scivis/io/VolumeLoad.h"

namespace apitest {

constexpr int kN = 33;  // voxels per axis of the field

// The whole field, as the program would have it (here made once per rank, for the test).
inline const renderers::Volume& field() {
  static const renderers::Volume v = [] {
    renderers::VolumeSource s;
    s.kind = renderers::VolumeSource::Kind::Wavelet;
    s.grid.dims = {kN, kN, kN};
    s.grid.origin = {-1, -1, -1};
    s.grid.spacing = renderers::Vec3{2.0f / (kN - 1)};
    return renderers::scivis::loadVolume(s, s.grid.wholeBox());
  }();
  return v;
}

inline dfbwall::Style style() {
  dfbwall::Style st;
  dfbwall::VolumeStyle v;
  v.grid.dims = {kN, kN, kN};
  v.grid.origin = {-1, -1, -1};
  const float h = 2.0f / (kN - 1);
  v.grid.spacing = {h, h, h};
  v.maxOpacity = 0.2f;
  st.volumes.push_back(v);
  st.isosurfaces.push_back({0, 190, {0.9f, 0.5f, 0.2f}, 0.5f});
  st.isosurfaces.push_back({0, 240, {0.9f, 0.9f, 0.9f}, 1});
  st.aoSamples = 1;
  st.aoDistance = 0.15f;  // under the 3 ghost voxels (0.1875) each brick carries
  st.seed = 11;
  return st;
}

// Brick `b` of `count` slabs along x (count 1: the whole field), with 2 + 3 ghost voxels, and
// the particles whose centres lie in its slab (a particle reaching over the border is drawn by
// both: each clipped to its own bounds).
inline dfbwall::Brick brick(int b, int count, std::vector<float>& storage) {
  const float h = 2.0f / (kN - 1);
  const int x0 = (kN - 1) * b / count, x1 = (kN - 1) * (b + 1) / count;  // planes of the bounds
  dfbwall::Brick out;
  out.id = b;
  out.boundsLo = {-1 + h * x0, -1, -1};
  out.boundsHi = {-1 + h * x1, 1, 1};
  // AO looks 0.15 (2.4 voxels) beyond the bounds: 2 + 3 ghost voxels cover it and the seams.
  const int lo = std::max(0, x0 - 5), hi = std::min(kN, x1 + 6);
  storage.clear();
  for (int z = 0; z < kN; ++z)
    for (int y = 0; y < kN; ++y)
      for (int x = lo; x < hi; ++x) storage.push_back(field().at(x, y, z));
  dfbwall::VolumePart part;
  part.lo = {lo, 0, 0};
  part.hi = {hi, kN, kN};
  part.voxels = storage.data();
  out.volumes.push_back(part);
  const dfbwall::Vec3f centres[] = {{-0.6f, 0.5f, -0.2f}, {0.02f, -0.4f, 0.1f}, {0.7f, 0.1f, 0.3f}};
  for (const auto& c : centres)
    if (c[0] >= out.boundsLo[0] - 0.2f && c[0] <= out.boundsHi[0] + 0.2f)
      out.particles.centers.push_back(c);
  out.particles.radii = {0.15f};
  return out;
}

inline dfbwall::Camera camera() {
  dfbwall::Camera c;
  c.position = {1.6f, 1.1f, -2.4f};
  c.fovY = 40;
  return c;
}

}  // namespace apitest
