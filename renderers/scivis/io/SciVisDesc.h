#pragma once
// What the scivis renderer draws, as plain data next to the meshes of SceneDesc: volumes (where
// their voxels come from, not the voxels), isosurfaces of them, particle sets, lights and the
// renderer's settings. Read from TOML (scivis/SciVisToml.cpp) or made by the built-in scenes
// (scivis/BuiltinScenes.h); a SceneDesc holds them as its "scivis" extension (sciVisDesc()).
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "renderers/Math.h"
#include "renderers/SceneDesc.h"
#include "renderers/SceneExtension.h"
#include "renderers/TransferFunction.h"
#include "renderers/VolumeSource.h"

namespace renderers::scivis {

struct VolumeDesc {
  std::string name;
  VolumeSource source;
  TransferFunction transfer;
  bool visible = true;  // false: only for isosurfaces (no volume rendering of it)
  // Where its size was given, for errors found after reading (the memory budget of a brick):
  // "scene.toml:7:8: volume 'ct'.dims"; empty when not read from a file.
  std::string where;
  // A time series (file = "step-%03d.nrrd" or a glob, or time_steps along the file's time
  // dimension): every step's source, resolved, with step 0's grid and type; `source` is the
  // step shown. Empty: one step, `source`.
  std::vector<VolumeSource> steps;
  float fps = 0;  // playback rate of `steps`; 0: one step a frame
};

// One level set of a volume: a surface at `value`, shaded with a material, possibly transparent.
struct IsosurfaceDesc {
  std::uint32_t volume = 0;  // index into SciVisDesc::volumes
  float value = 0;
  std::uint32_t material = 0;  // index into SceneDesc::materials (its color and opacity)
};

// Spheres: one radius for all or one per particle; coloured by `attribute` through `colorMap`
// when attributes are given, else by the material's colour.
struct ParticlesDesc {
  std::string name;
  std::string file;  // the particle file they were read from; empty when inline or generated
  std::vector<Vec3> centers;
  std::vector<float> radii;      // 1 (shared) or centers.size()
  std::vector<float> attribute;  // empty or centers.size()
  TransferFunction colorMap;     // colour by attribute (its opacity is not used)
  std::uint32_t material = 0;    // index into SceneDesc::materials
  float radius(std::size_t i) const { return radii.size() == 1 ? radii[0] : radii[i]; }
  std::size_t bytes() const {
    return centers.size() * sizeof(Vec3) + (radii.size() + attribute.size()) * sizeof(float);
  }
};

struct LightDesc {
  enum class Kind { Directional, Point, Ambient };
  Kind kind = Kind::Directional;
  Vec3 direction{0, -1, 0};  // directional: the way the light travels
  Vec3 position{};           // point
  Vec3 color{1.0f};
  float intensity = 1.0f;  // point lights fall off with 1 / distance²
};

struct SciVisSettings {
  int aoSamples = 0;          // ambient-occlusion rays per surface hit and sample; 0: none
  float aoDistance = 0;       // world distance AO rays look; 0: 1/4 of the scene's extent
  float samplingRate = 1.0f;  // volume samples per voxel spacing along a ray
  bool shadows = true;        // shadow rays towards directional and point lights
  // A ray stops once less than this fraction of light gets through (early ray termination).
  // The error it allows is at most this much of the background (and of anything behind): 1e-3
  // is below an 8-bit step. (VTK's fixed-point ray caster stops at 1/128.)
  float minTransmittance = 1e-3f;
};

// The scivis parts of a scene (the path tracer draws its meshes and spheres; the scivis
// renderer draws those too).
struct SciVisDesc final : SceneExtension {
  std::vector<VolumeDesc> volumes;
  std::vector<IsosurfaceDesc> isosurfaces;
  std::vector<ParticlesDesc> particles;
  std::vector<LightDesc> lights;  // empty: an ambient light and a headlight (SciVisScene.h)
  SciVisSettings settings;

  std::unique_ptr<SceneExtension> clone() const override;
  bool empty() const override;                           // no volumes and no particles
  std::vector<std::string> inputFiles() const override;  // particle and volume files
  std::uint64_t bytes() const override;                  // the particles' bytes
};

// The time steps of `desc`'s series (every series volume has the same count; 1: none) and
// their playback rate (steps a second; 0: one a frame).
std::uint32_t timeSteps(const SceneDesc& desc);
float playbackFps(const SceneDesc& desc);
// `desc` showing time step `step` (< timeSteps): each series volume's source is that step's.
std::shared_ptr<const SceneDesc> sceneAtStep(const SceneDesc& desc, std::uint32_t step);

// The name SceneDesc::extensions holds SciVisDesc under: the renderer's.
inline constexpr const char* kSciVisName = "scivis";

// `desc`'s scivis parts, added (empty) when it has none.
SciVisDesc& sciVisDesc(SceneDesc& desc);
// `desc`'s scivis parts; empty ones when it has none.
const SciVisDesc& sciVisDesc(const SceneDesc& desc);

}  // namespace renderers::scivis
