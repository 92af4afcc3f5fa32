#include "renderers/SceneSections.h"

#include <mutex>
#include <utility>

namespace renderers {
namespace {

struct Registry {
  std::mutex mutex;
  std::vector<SceneSections> sections;
};

Registry& registry() {
  static Registry r;
  return r;
}

}  // namespace

void registerSceneSections(SceneSections sections) {
  Registry& r = registry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  for (SceneSections& s : r.sections)
    if (s.keys == sections.keys) {
      s = std::move(sections);
      return;
    }
  r.sections.push_back(std::move(sections));
}

std::vector<SceneSections> registeredSceneSections() {
  Registry& r = registry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  return r.sections;
}

}  // namespace renderers
