#include "renderers/scivis/BuiltinScenes.h"

#include <string>
#include <utility>

#include "renderers/TransferFunction.h"
#include "renderers/scivis/io/Particles.h"
#include "renderers/scivis/io/SciVisDesc.h"

namespace renderers::scivis {
namespace {

Material diffuse(const std::string& name, Vec3 color) {
  return {name, MaterialType::Diffuse, color, {}, 0, 1.5f};
}

}  // namespace

SceneDesc waveletScene(int resolution) {
  SceneDesc d;
  SciVisDesc& s = sciVisDesc(d);
  VolumeDesc v;
  v.name = "wavelet";
  v.source.kind = VolumeSource::Kind::Wavelet;
  v.source.grid.dims = {resolution, resolution, resolution};
  const float spacing = 2.0f / static_cast<float>(resolution - 1);
  v.source.grid.spacing = Vec3{spacing};
  v.source.grid.origin = Vec3{-1.0f};
  // The field spans about 37..277; a faint cool-warm haze shows its lobes, and two isosurfaces
  // show its shape: a glassy outer one and an opaque core.
  v.transfer = transferFunctionPreset("cool-warm", 37.0f, 277.0f, 0.0f);
  v.transfer.opacities = {{37.0f, 0.0f}, {190.0f, 0.0f}, {277.0f, 0.04f}};
  s.volumes.push_back(std::move(v));
  Material glass = {"outer", MaterialType::Diffuse, {0.55f, 0.7f, 1.0f}, {}, 0, 1.5f};
  glass.opacity = 0.18f;
  glass.specular = 0.4f;
  Material core = {"core", MaterialType::Diffuse, {1.0f, 0.55f, 0.2f}, {}, 0, 1.5f};
  core.specular = 0.3f;
  d.materials = {glass, core};
  s.isosurfaces = {{0, 160.0f, 0}, {0, 215.0f, 1}};
  d.camera = {{2.3f, 1.5f, 2.9f}, {0, -0.05f, 0}, {0, 1, 0}, 38.0f, 0, 0};
  d.environment.kind = Environment::Kind::Gradient;
  d.environment.bottom = {0.02f, 0.02f, 0.03f};
  d.environment.top = {0.12f, 0.14f, 0.22f};
  s.settings.aoSamples = 1;
  s.settings.aoDistance = 0.3f;
  return d;
}

SceneDesc particleScene(std::size_t count) {
  SceneDesc d;
  SciVisDesc& s = sciVisDesc(d);
  d.materials = {diffuse("particle", {0.8f, 0.8f, 0.8f})};
  d.materials[0].specular = 0.25f;
  ParticlesDesc p = clusteredParticles(count, 7, Vec3{}, 2.0f, 0.0045f);
  p.name = "halos";
  p.colorMap = transferFunctionPreset("viridis", 0.0f, 1.0f);
  s.particles.push_back(std::move(p));
  d.camera = {{0.4f, 0.9f, 3.0f}, {0, 0, 0}, {0, 1, 0}, 45.0f, 0, 0};
  d.environment.kind = Environment::Kind::Constant;
  d.environment.color = {0.01f, 0.01f, 0.015f};
  s.settings.aoSamples = 1;
  s.settings.aoDistance = 0.08f;
  return d;
}

}  // namespace renderers::scivis
