#pragma once
// The scivis renderer's common case, apart from its generic loop for speed: a ray through one
// visible volume without isosurfaces, nothing else on it before the volume ends. The march
// composites exactly the samples the generic loop composites, with the same arithmetic (the same
// bits): t_k = (k + jitter) step from the first k >= kStart with t_k >= t0, while t_k < t1,
// t_k <= volumeEnd and more than minTransmittance of the light gets through.
//
// Three kernels: SSE2 (every x86-64) takes 4 samples of one ray at a time (marchOneVolume); where
// the CPU runs AVX2 or AVX-512 (chosen at run time), packets of 8 or 16 rays take one sample of
// each at a time, one ray per lane (marchPacket: no serial compositing, no samples wasted past a
// ray's end; VolumeMarchAvx512.cpp holds the AVX-512 kernel).
// 8 samples of one ray at a time in AVX2 measured only about 10% faster than SSE's 4, so a ray
// alone marches with SSE everywhere. All compute every sample lane by lane as the scalar path
// does, without fused multiply-adds, and composite each ray in order, so they give the same
// image bit for bit; they differ only in the benchmark's sample count (a jump over an empty
// macrocell counts one sample, and the kernels jump from different places). Packets march
// voxels whose offsets fit 32 bits: AVX-512 packets float, uint8 and uint16 voxels (widened in
// the lanes), AVX2 packets float voxels; other rays march one by one.
#include <cstdint>

#include "renderers/Math.h"
#include "renderers/scivis/scene/SciVisScene.h"

namespace renderers::scivis {

enum class MarchKernel {
  Auto,  // the fastest the CPU runs
  Sse,
  Avx2,
  Avx512,
};

bool marchKernelAvailable(MarchKernel kernel);  // Auto and Sse: always
// `kernel`, or for Auto the fastest available one. Throws base::Error for one the CPU (or
// the build) lacks.
MarchKernel resolveMarchKernel(MarchKernel kernel);
const char* marchKernelName(MarchKernel kernel);

struct MarchRay {
  Vec3 origin, dir, invDir;  // dir unit length, invDir = 1 / dir
  float t0, t1;              // the piece of the ray to composite
  float kStart;              // the generic loop's first sample index
  float volumeEnd;           // where the volume's data ends on the ray, widened by a step
  float step, jitter, minTransmittance;
};

// Premultiplied RGB so far, the light still getting through, the distance where it first
// dropped to half (infinity until then).
struct MarchColor {
  Vec3 rgb;
  float transmittance = 1.0f;
  float depth = Box3::kInf;
};

// Composites the samples of `ray` through layer v (its field set) onto `color`, 4 at a time
// (SSE). Returns the samples taken (for benchmarks).
std::uint32_t marchOneVolume(const SciVisScene::VolumeLayer& v, const MarchRay& ray,
                             MarchColor& color);

// Rays marched together, one per SIMD lane: each lane composites its own ray exactly as
// marchOneVolume does (the same bits), and no lane wastes samples past its ray's end.
constexpr int kMarchPacket = 16;  // the widest packet of any kernel
// The rays of one packet of `kernel` (resolved): 8 for AVX2, 16 for AVX-512, 1 for SSE.
int marchPacketSize(MarchKernel kernel);
// Whether marchPacket() marches layer v's rays with `kernel` (resolved): AVX2 or AVX-512, float
// voxels.
bool marchesPackets(const SciVisScene::VolumeLayer& v, MarchKernel kernel);
// Rays 0 .. count - 1 (count <= marchPacketSize(kernel)) through layer v with `kernel`, where
// marchesPackets(v, kernel), each from nothing composited: colors[i] (written, not read) and
// samples[i] as marchOneVolume gives them for rays[i] and a MarchColor{}. `next` (nextCount
// rays): the rays of the packet to march after these, whose first voxels are asked for while
// these march (a hint, no value changes: rays take about 16 samples in a dense volume, and their
// first samples' cache misses were a tenth of the march at 512^3 at 512^2).
void marchPacket(const SciVisScene::VolumeLayer& v, MarchKernel kernel, const MarchRay* rays,
                 int count, MarchColor* colors, std::uint32_t* samples,
                 const MarchRay* next = nullptr, int nextCount = 0);

}  // namespace renderers::scivis
