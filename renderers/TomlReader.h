#pragma once
// Reading scene TOML (scene files, camera paths) into renderer types through
// base::TomlDiagnostics, so a misspelt key or a wrong type reads as it does in a layout.
// Problems are collected, not thrown: a wrong field is reported and reading goes on with its
// default; a problem an entry (the camera, a mesh, a volume) cannot be read past ends that entry
// alone, and the rest of the file is still checked. The caller throws them all at the end.
#include <toml++/toml.h>

#include <cstdint>
#include <initializer_list>
#include <new>
#include <set>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "base/MemoryBudget.h"
#include "base/TomlDiagnostics.h"
#include "renderers/Math.h"
#include "renderers/SceneDesc.h"

namespace renderers {

class TomlReader {
 public:
  explicit TomlReader(base::TomlDiagnostics& diagnostics) : diagnostics_(diagnostics) {}

  base::TomlDiagnostics& diagnostics() { return diagnostics_; }
  const std::string& path() const { return diagnostics_.file(); }

  // Records a problem; reading goes on.
  void problem(const toml::node& at, const std::string& field, const std::string& message);
  // Records a problem and ends the entry being read (see entry()).
  [[noreturn]] void fail(const toml::node& at, const std::string& field,
                         const std::string& message);
  // Ends the entry without a message: what it rests on was reported already.
  [[noreturn]] void skip();
  // Ends the entry if it has had a problem: checks past this point would judge stand-ins.
  void settle();
  // Problems so far: a check of a value runs only if reading it added none.
  std::size_t problems() const { return diagnostics_.count(); }

  // Reads one entry with `read`; a fail() inside ends that entry alone. Returns whether it read
  // without a problem.
  template <class Read>
  bool entry(Read&& read) {
    const std::size_t outer = entryStart_;
    entryStart_ = diagnostics_.count();
    bool clean = true;
    try {
      read();
    } catch (const Abandon&) {
      clean = false;
    }
    clean = clean && diagnostics_.count() == entryStart_;
    entryStart_ = outer;
    return clean;
  }

  // Entries that failed, by kind and name: a reference to one is not reported again.
  void markFailed(std::string_view kind, const std::string& name);
  bool failed(std::string_view kind, const std::string& name) const;

  // Reports keys outside `known`: a misspelt field would otherwise be silently ignored.
  void onlyKeys(const toml::table& t, const std::string& what,
                std::initializer_list<std::string_view> known);
  void onlyKeys(const toml::table& t, const std::string& what,
                std::span<const std::string_view> known);
  // The field `key` of `t`, or nullptr with "WHAT.KEY: missing" recorded (what: empty at the top).
  const toml::node* need(const toml::table& t, std::string_view key, const std::string& what);
  const toml::table* table(const toml::node& n, const std::string& field);
  // The tables of an array of tables ([[key]] entries); none when `key` is absent.
  std::vector<const toml::table*> arrayOfTables(const toml::table& t, std::string_view key);

  // Typed readers: the value, or `fallback` with the problem recorded (nothing recorded for an
  // absent node: need() reported it). Numbers are finite floats.
  float number(const toml::node* n, const std::string& field, float fallback = 0);
  float number(const toml::node& n, const std::string& field, float fallback = 0) {
    return number(&n, field, fallback);
  }
  float number(const toml::table& t, std::string_view key, const std::string& what,
               float fallback) {
    return number(t.get(key), field(what, key), fallback);
  }
  bool boolean(const toml::table& t, std::string_view key, const std::string& what, bool fallback);
  std::string string(const toml::node* n, const std::string& field);
  std::string string(const toml::node& n, const std::string& field) { return string(&n, field); }
  Vec3 vec3(const toml::node* n, const std::string& field, Vec3 fallback = {});
  Vec3 vec3(const toml::node& n, const std::string& field) { return vec3(&n, field); }
  Vec3 vec3(const toml::table& t, std::string_view key, const std::string& what, Vec3 fallback) {
    return vec3(t.get(key), field(what, key), fallback);
  }
  // An array of exactly `count` numbers (`shape` shows it: "[low, high]") as floats into `out`;
  // false, with the problems recorded, otherwise.
  bool floats(const toml::node& n, const std::string& field, std::size_t count,
              std::string_view shape, float* out);
  // A non-negative integer that fits 32 bits.
  std::uint32_t index(const toml::node* n, const std::string& field);
  std::uint32_t index(const toml::node& n, const std::string& field) { return index(&n, field); }

  // scale, then rotate = [axis x, y, z, degrees], then translate.
  Affine transform(const toml::table& t, const std::string& what);
  // The material `t` names for `owner`.
  std::uint32_t material(const SceneDesc& d, const toml::table& t, const std::string& owner);
  // Ends the entry: `name` (of a `kind`: "material") is not defined. Names the closest defined
  // one; says nothing when the entry defining it failed (that was reported).
  [[noreturn]] void notDefined(const toml::node& at, const std::string& field,
                               std::string_view kind, const std::string& name,
                               const std::vector<std::string>& defined);

  // "FILE:LINE:COLUMN: FIELD", for problems found after reading (VolumeDesc::where).
  std::string where(const toml::node& at, const std::string& field) const;

  // The memory budget (base/MemoryBudget.h): fails at `at` when `bytes` (all this rank will hold
  // once `field` is loaded, what it holds already included) exceed what it may hold. `size`
  // says what is loaded: "1024 bytes", "100 particles".
  void budget(const toml::node& at, const std::string& field, const std::string& size,
              std::uint64_t bytes);

  // Runs `load` (reading what `field` at `at` names); an allocation that fails in it is reported
  // as that field's problem, not as a bare std::bad_alloc.
  template <class Load>
  auto loading(const toml::node& at, const std::string& field, Load&& load) {
    try {
      return load();
    } catch (const std::bad_alloc&) {
      fail(at, field,
           "out of memory while loading it; this rank may hold " + base::memoryLimitText());
    } catch (const std::length_error&) {
      fail(at, field, "out of memory while loading it (a size beyond what a container holds)");
    }
  }

  // A number as messages show it: "1e+30", "0.25".
  static std::string text(double v);
  // "WHAT.KEY", or "KEY" at the top of the file (`what` empty).
  static std::string field(const std::string& what, std::string_view key);

 private:
  struct Abandon {};  // unwinds to entry(); never leaves it

  base::TomlDiagnostics& diagnostics_;
  std::size_t entryStart_ = 0;
  std::set<std::pair<std::string, std::string>> failed_;
};

}  // namespace renderers
