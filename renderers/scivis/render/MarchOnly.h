#pragma once
// Which ray pieces the one-volume march takes (SciVisRenderer::marchOnly() once the scene has
// only the one visible volume on the ray) and the MarchRay each becomes: one at a time, and 16
// at a time in AVX-512 lanes (MarchOnlyAvx512.cpp) with the same operations, bit for bit. The
// scalar version cost the bench about as much per camera ray as 3 march samples.
#include <cmath>

#include "renderers/scivis/render/SciVisRenderer.h"
#include "renderers/scivis/render/VolumeMarch.h"
#include "renderers/scivis/scene/Box.h"

namespace renderers::scivis {

// The march takes a piece of t0 < t1 whose [t0 - step, t1 + step] meets `dataBounds` (the
// field's); `step`: the scene's volume step. False: it takes none (`ray` unchanged).
inline bool marchRayOf(const SciVisRenderer::RayPiece& r, Vec3 invDir, const Box3& dataBounds,
                       float step, float minTransmittance, MarchRay& ray) {
  if (!(r.t0 < r.t1)) return false;
  float volumeStart = r.t0 - step, volumeEnd = r.t1 + step;
  if (!clipToBox(dataBounds, r.origin, invDir, volumeStart, volumeEnd)) return false;
  const float jitter = r.sampler.get(2);
  ray = {r.origin,  r.dir,
         invDir,    r.t0,
         r.t1,      std::ceil(volumeStart / step - jitter),
         volumeEnd, step,
         jitter,    minTransmittance};
  return true;
}

// marchRayOf(rays[l], reciprocal(rays[l].dir), ...) for l = 0 .. 15: the pieces it takes as a
// mask (bit l: rays[l]), their MarchRays in out[0 .. n - 1] in order, n the mask's bit count
// (out holds 16). Where the CPU runs AVX-512 F, DQ, BW and VL.
unsigned marchOnly16(const SciVisRenderer::RayPiece* rays, const Box3& dataBounds, float step,
                     float minTransmittance, MarchRay* out);

}  // namespace renderers::scivis
