#include "renderers/scivis/io/SciVisDesc.h"

#include <algorithm>

namespace renderers::scivis {

std::unique_ptr<SceneExtension> SciVisDesc::clone() const {
  return std::make_unique<SciVisDesc>(*this);
}

bool SciVisDesc::empty() const { return volumes.empty() && particles.empty(); }

std::vector<std::string> SciVisDesc::inputFiles() const {
  std::vector<std::string> files;
  for (const ParticlesDesc& p : particles)
    if (!p.file.empty()) files.push_back(p.file);
  const auto add = [&files](const VolumeSource& source) {
    if (source.kind == VolumeSource::Kind::RawFile) files.push_back(source.raw.path);
    if (source.kind == VolumeSource::Kind::OpenVdb) files.push_back(source.vdb.path);
    if (source.kind == VolumeSource::Kind::File) {
      files.push_back(source.file.path);
      const StoredArray& stored = source.file.stored;  // detached data files
      if (!stored.path.empty() && stored.path != source.file.path && stored.paths.empty())
        files.push_back(stored.path);
      for (const std::string& data : stored.paths) files.push_back(data);
      for (const FilePiece& piece : source.file.pieces) files.push_back(piece.path);
    }
  };
  for (const VolumeDesc& v : volumes) {
    if (v.steps.empty()) add(v.source);
    // A time dimension names one file for every step: once is enough.
    std::string last;
    for (const VolumeSource& step : v.steps)
      if (step.file.path != last) add(step), last = step.file.path;
  }
  return files;
}

std::uint32_t timeSteps(const SceneDesc& desc) {
  std::size_t steps = 1;
  for (const VolumeDesc& v : sciVisDesc(desc).volumes) steps = std::max(steps, v.steps.size());
  return static_cast<std::uint32_t>(steps);
}

float playbackFps(const SceneDesc& desc) {
  for (const VolumeDesc& v : sciVisDesc(desc).volumes)
    if (!v.steps.empty()) return v.fps;
  return 0;
}

std::shared_ptr<const SceneDesc> sceneAtStep(const SceneDesc& desc, std::uint32_t step) {
  auto out = std::make_shared<SceneDesc>(desc);
  for (VolumeDesc& v : sciVisDesc(*out).volumes)
    if (!v.steps.empty()) v.source = v.steps.at(step % v.steps.size());
  return out;
}

std::uint64_t SciVisDesc::bytes() const {
  std::uint64_t total = 0;
  for (const ParticlesDesc& p : particles) total += p.bytes();
  return total;
}

SciVisDesc& sciVisDesc(SceneDesc& desc) {
  if (auto* own = dynamic_cast<SciVisDesc*>(desc.extensions.find(kSciVisName))) return *own;
  return static_cast<SciVisDesc&>(desc.extensions.set(kSciVisName, std::make_unique<SciVisDesc>()));
}

const SciVisDesc& sciVisDesc(const SceneDesc& desc) {
  static const SciVisDesc none;
  const auto* own = dynamic_cast<const SciVisDesc*>(desc.extensions.find(kSciVisName));
  return own ? *own : none;
}

}  // namespace renderers::scivis
