#include "renderers/RendererRegistry.h"

#include <deque>
#include <mutex>
#include <utility>

namespace renderers {
namespace {

struct Registered {
  std::string name;
  RendererFactory factory;
};

struct Registry {
  std::mutex mutex;
  std::deque<Registered> renderers;  // a deque: entries never move, findRenderer's pointers hold
};

Registry& registry() {
  static Registry r;
  return r;
}

}  // namespace

void registerRenderer(const std::string& name, RendererFactory factory) {
  Registry& r = registry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  for (Registered& e : r.renderers)
    if (e.name == name) {
      e.factory = std::move(factory);
      return;
    }
  r.renderers.push_back({name, std::move(factory)});
}

const RendererFactory* findRenderer(const std::string& name) {
  Registry& r = registry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  for (const Registered& e : r.renderers)
    if (e.name == name) return &e.factory;
  return nullptr;
}

std::vector<std::string> registeredRenderers() {
  Registry& r = registry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  std::vector<std::string> names;
  for (const Registered& e : r.renderers) names.push_back(e.name);
  return names;
}

}  // namespace renderers
