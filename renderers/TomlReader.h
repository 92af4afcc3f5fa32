#pragma once
// Reading TOML++ tables with errors that name the file, the line and the field: every scene
// reader (SceneToml.cpp, scivis/io/VolumeToml.cpp) goes through this one class, so a misspelt key
// or a wrong type is reported the same way everywhere.
#include <toml++/toml.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <initializer_list>
#include <new>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "base/Error.h"
#include "base/MemoryBudget.h"
#include "renderers/Math.h"
#include "renderers/SceneDesc.h"

namespace renderers {

class TomlReader {
 public:
  explicit TomlReader(std::string path) : path_(std::move(path)) {}

  [[noreturn]] void fail(const toml::node& at, const std::string& what) const {
    throw base::Error(path_ + ":" + std::to_string(at.source().begin.line) + ": " + what);
  }

  const toml::table& table(const toml::node& n, const std::string& what) const {
    if (!n.is_table()) fail(n, what + " must be a table");
    return *n.as_table();
  }

  // Rejects keys outside `known`: a misspelt field would otherwise be silently ignored.
  void onlyKeys(const toml::table& t, const std::string& what,
                std::initializer_list<std::string_view> known) const {
    onlyKeys(t, what, std::vector<std::string_view>(known));
  }
  void onlyKeys(const toml::table& t, const std::string& what,
                const std::vector<std::string_view>& known) const {
    for (const auto& [key, value] : t) {
      bool ok = false;
      for (auto k : known) ok = ok || key.str() == k;
      if (!ok) fail(value, "unknown field '" + std::string(key.str()) + "' in " + what);
    }
  }

  const toml::node* get(const toml::table& t, std::string_view key) const { return t.get(key); }

  // "FILE:LINE: what", for errors found after reading (VolumeDesc::where).
  std::string where(const toml::node& at, const std::string& what) const {
    return path_ + ":" + std::to_string(at.source().begin.line) + ": " + what;
  }

  // The memory budget (dfb/MemoryBudget.h): fails naming `at` when `bytes` (all this rank will
  // hold once `what` is loaded: what it holds already included) exceed what it may hold.
  void budget(const toml::node& at, const std::string& what, std::uint64_t bytes) const {
    if (std::string problem = base::memoryProblem(bytes); !problem.empty())
      fail(at, what + " " + problem);
  }

  // Runs `load` (reading the thing `what` at `at` names); an allocation that fails in it is
  // reported as that thing's error, not as a bare std::bad_alloc.
  template <class Load>
  auto loading(const toml::node& at, const std::string& what, Load&& load) const {
    try {
      return load();
    } catch (const std::bad_alloc&) {
      fail(at, what + ": out of memory while loading it; this rank may hold " +
                   base::memoryLimitText());
    } catch (const std::length_error&) {
      fail(at, what + ": out of memory while loading it (a size beyond what a container holds)");
    }
  }

  // The tables of an array of tables ([[key]] entries); none when `key` is absent.
  std::vector<const toml::table*> arrayOfTables(const toml::table& t, std::string_view key) const {
    std::vector<const toml::table*> out;
    if (const toml::node* n = t.get(key)) {
      const toml::array* a = n->as_array();
      if (!a)
        fail(*n, std::string(key) + " must be an array of tables ([[" + std::string(key) + "]])");
      for (const toml::node& e : *a) out.push_back(&table(e, std::string(key) + " entry"));
    }
    return out;
  }

  bool boolean(const toml::table& t, std::string_view key, const std::string& what,
               bool fallback) const {
    const toml::node* n = t.get(key);
    if (!n) return fallback;
    if (!n->is_boolean()) fail(*n, what + "." + std::string(key) + " must be true or false");
    return *n->value<bool>();
  }

  const std::string& path() const { return path_; }

  // A number as messages show it: "1e+30", "0.25".
  static std::string text(double v) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%g", v);
    return buffer;
  }

  const toml::node& require(const toml::table& t, std::string_view key,
                            const std::string& what) const {
    const toml::node* n = t.get(key);
    if (!n) fail(t, what + ": missing field '" + std::string(key) + "'");
    return *n;
  }

  float number(const toml::node& n, const std::string& what) const {
    if (auto v = n.value<double>(); v && (n.is_integer() || n.is_floating_point())) {
      // nan and inf are valid TOML, and a float that overflows becomes inf: neither is a size,
      // a position or a colour.
      const float f = static_cast<float>(*v);
      if (!std::isfinite(f)) fail(n, what + " must be a finite number, got " + std::to_string(*v));
      return f;
    }
    fail(n, what + " must be a number");
  }

  float number(const toml::table& t, std::string_view key, const std::string& what,
               float fallback) const {
    const toml::node* n = t.get(key);
    return n ? number(*n, what + "." + std::string(key)) : fallback;
  }

  std::string string(const toml::node& n, const std::string& what) const {
    if (!n.is_string()) fail(n, what + " must be a string");
    return std::string(*n.value<std::string_view>());
  }

  Vec3 vec3(const toml::node& n, const std::string& what) const {
    const toml::array* a = n.as_array();
    if (!a || a->size() != 3) fail(n, what + " must be an array of 3 numbers");
    return {number((*a)[0], what), number((*a)[1], what), number((*a)[2], what)};
  }

  Vec3 vec3(const toml::table& t, std::string_view key, const std::string& what,
            Vec3 fallback) const {
    const toml::node* n = t.get(key);
    return n ? vec3(*n, what + "." + std::string(key)) : fallback;
  }

  std::uint32_t index(const toml::node& n, const std::string& what) const {
    auto v = n.value<std::int64_t>();
    if (!n.is_integer() || !v || *v < 0) fail(n, what + " must be a non-negative integer");
    return static_cast<std::uint32_t>(*v);
  }

  // scale, then rotate = [axis x, y, z, degrees], then translate.
  Affine transform(const toml::table& t, const std::string& what) const {
    Affine m;
    if (const toml::node* s = t.get("scale")) {
      m = s->is_array() ? scaling(vec3(*s, what + ".scale"))
                        : scaling(Vec3{number(*s, what + ".scale")});
    }
    if (const toml::node* r = t.get("rotate")) {
      const toml::array* a = r->as_array();
      if (!a || a->size() != 4) fail(*r, what + ".rotate must be [axis x, y, z, degrees]");
      const Vec3 axis{number((*a)[0], what), number((*a)[1], what), number((*a)[2], what)};
      if (length(axis) <= 0) fail(*r, what + ".rotate: the axis must not be zero");
      m = rotation(axis, number((*a)[3], what + ".rotate")) * m;
    }
    if (t.get("translate")) m = translation(vec3(t, "translate", what, {})) * m;
    // Instances are drawn through the inverse: a transform that flattens (a zero scale) or whose
    // determinant leaves the float range has none.
    const float det = dot(m.vx, cross(m.vy, m.vz));
    if (!(std::isfinite(det) && std::fabs(det) >= 1e-30f))
      fail(t.get("scale") ? *t.get("scale") : t,
           what + ".scale makes a degenerate transform (determinant " + text(det) +
               "): every axis must be scaled by a non-zero amount within the float range");
    return m;
  }

  std::uint32_t material(const SceneDesc& d, const toml::table& t, const std::string& owner) const {
    const toml::node& n = require(t, "material", owner);
    const std::string name = string(n, owner + ".material");
    const int i = d.findMaterial(name);
    if (i < 0) fail(n, "material '" + name + "' of " + owner + " is not defined");
    return static_cast<std::uint32_t>(i);
  }

 private:
  std::string path_;
};

}  // namespace renderers
