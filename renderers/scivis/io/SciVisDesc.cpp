#include "renderers/scivis/io/SciVisDesc.h"

namespace renderers::scivis {

std::unique_ptr<SceneExtension> SciVisDesc::clone() const {
  return std::make_unique<SciVisDesc>(*this);
}

bool SciVisDesc::empty() const { return volumes.empty() && particles.empty(); }

std::vector<std::string> SciVisDesc::inputFiles() const {
  std::vector<std::string> files;
  for (const ParticlesDesc& p : particles)
    if (!p.file.empty()) files.push_back(p.file);
  for (const VolumeDesc& v : volumes) {
    if (v.source.kind == VolumeSource::Kind::RawFile) files.push_back(v.source.raw.path);
    if (v.source.kind == VolumeSource::Kind::OpenVdb) files.push_back(v.source.vdb.path);
    if (v.source.kind == VolumeSource::Kind::File) {
      files.push_back(v.source.file.path);
      const StoredArray& stored = v.source.file.stored;  // detached data files
      if (!stored.path.empty() && stored.path != v.source.file.path && stored.paths.empty())
        files.push_back(stored.path);
      for (const std::string& data : stored.paths) files.push_back(data);
      for (const FilePiece& piece : v.source.file.pieces) files.push_back(piece.path);
    }
  }
  return files;
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
