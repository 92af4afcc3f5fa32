#include "renderers/SceneExtension.h"

#include <utility>

namespace renderers {

SceneExtensions::SceneExtensions(const SceneExtensions& other) {
  for (const auto& [name, extension] : other.byName_) byName_.emplace(name, extension->clone());
}

SceneExtensions& SceneExtensions::operator=(const SceneExtensions& other) {
  if (this != &other) *this = SceneExtensions(other);
  return *this;
}

const SceneExtension* SceneExtensions::find(const std::string& name) const {
  const auto it = byName_.find(name);
  return it == byName_.end() ? nullptr : it->second.get();
}

SceneExtension* SceneExtensions::find(const std::string& name) {
  const auto it = byName_.find(name);
  return it == byName_.end() ? nullptr : it->second.get();
}

SceneExtension& SceneExtensions::set(const std::string& name,
                                     std::unique_ptr<SceneExtension> extension) {
  std::unique_ptr<SceneExtension>& slot = byName_[name];
  slot = std::move(extension);
  return *slot;
}

std::vector<std::string> SceneExtensions::drawnBy() const {
  std::vector<std::string> names;
  for (const auto& [name, extension] : byName_)
    if (!extension->empty()) names.push_back(name);
  return names;
}

std::vector<std::string> SceneExtensions::inputFiles() const {
  std::vector<std::string> files;
  for (const auto& [name, extension] : byName_)
    for (std::string& file : extension->inputFiles()) files.push_back(std::move(file));
  return files;
}

std::uint64_t SceneExtensions::bytes() const {
  std::uint64_t total = 0;
  for (const auto& [name, extension] : byName_) total += extension->bytes();
  return total;
}

}  // namespace renderers
