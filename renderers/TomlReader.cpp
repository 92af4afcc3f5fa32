#include "renderers/TomlReader.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <span>

namespace renderers {
namespace {

// A TOML number as the float the renderer keeps; false, with the problem recorded, when float
// cannot hold it (1e39 would become inf).
bool toFloat(base::TomlDiagnostics& d, const toml::node& at, double v, const std::string& field,
             float& out) {
  out = static_cast<float>(v);
  if (std::isfinite(out)) return true;
  d.add(at, field,
        "expected a finite number, got " + TomlReader::text(v) + " (beyond the float range)");
  return false;
}

}  // namespace

void TomlReader::problem(const toml::node& at, const std::string& field,
                         const std::string& message) {
  diagnostics_.add(at, field, message);
}

void TomlReader::fail(const toml::node& at, const std::string& field, const std::string& message) {
  diagnostics_.add(at, field, message);
  throw Abandon{};
}

void TomlReader::skip() { throw Abandon{}; }

void TomlReader::settle() {
  if (diagnostics_.count() != entryStart_) throw Abandon{};
}

void TomlReader::markFailed(std::string_view kind, const std::string& name) {
  failed_.emplace(std::string(kind), name);
}

bool TomlReader::failed(std::string_view kind, const std::string& name) const {
  return failed_.count({std::string(kind), name}) > 0;
}

void TomlReader::onlyKeys(const toml::table& t, const std::string& what,
                          std::initializer_list<std::string_view> known) {
  diagnostics_.unknownKeys(t, what, std::span(known.begin(), known.size()));
}

void TomlReader::onlyKeys(const toml::table& t, const std::string& what,
                          std::span<const std::string_view> known) {
  diagnostics_.unknownKeys(t, what, known);
}

const toml::node* TomlReader::need(const toml::table& t, std::string_view key,
                                   const std::string& what) {
  if (const toml::node* n = t.get(key)) return n;
  diagnostics_.add(t, field(what, key), "missing");
  return nullptr;
}

const toml::table* TomlReader::table(const toml::node& n, const std::string& field) {
  return diagnostics_.table(n, field);
}

std::vector<const toml::table*> TomlReader::arrayOfTables(const toml::table& t,
                                                          std::string_view key) {
  std::vector<const toml::table*> out;
  const toml::node* n = t.get(key);
  if (!n) return out;
  const std::string name(key);
  const toml::array* a = n->as_array();
  if (!a) {
    problem(*n, name,
            "expected [[" + name + "]] tables (an array of tables), got " + base::tomlTypeName(*n));
    return out;
  }
  for (const toml::node& e : *a) {
    if (const toml::table* entry = e.as_table())
      out.push_back(entry);
    else
      problem(e, name, "expected a table ([[" + name + "]]), got " + base::tomlTypeName(e));
  }
  return out;
}

float TomlReader::number(const toml::node* n, const std::string& field, float fallback) {
  if (!n) return fallback;
  const std::optional<double> v = diagnostics_.number(*n, field);
  float out = 0;
  return v && toFloat(diagnostics_, *n, *v, field, out) ? out : fallback;
}

bool TomlReader::boolean(const toml::table& t, std::string_view key, const std::string& what,
                         bool fallback) {
  const toml::node* n = t.get(key);
  return n ? diagnostics_.boolean(*n, field(what, key)).value_or(fallback) : fallback;
}

std::string TomlReader::string(const toml::node* n, const std::string& field) {
  return n ? diagnostics_.string(*n, field).value_or("") : "";
}

bool TomlReader::floats(const toml::node& n, const std::string& field, std::size_t count,
                        std::string_view shape, float* out) {
  const std::optional<std::vector<double>> v = diagnostics_.numbers(n, field, count, shape);
  if (!v) return false;
  const toml::array& a = *n.as_array();
  bool ok = true;
  for (std::size_t i = 0; i < count; ++i)
    ok = toFloat(diagnostics_, a[i], (*v)[i], field, out[i]) && ok;
  return ok;
}

Vec3 TomlReader::vec3(const toml::node* n, const std::string& field, Vec3 fallback) {
  float f[3];
  return n && floats(*n, field, 3, "[x, y, z]", f) ? Vec3{f[0], f[1], f[2]} : fallback;
}

std::uint32_t TomlReader::index(const toml::node* n, const std::string& field) {
  if (!n) return 0;
  const std::optional<std::int64_t> v = diagnostics_.integer(*n, field);
  if (!v) return 0;
  if (*v < 0 || *v > std::numeric_limits<std::uint32_t>::max()) {
    problem(*n, field,
            "expected an integer from 0 to " +
                std::to_string(std::numeric_limits<std::uint32_t>::max()) + ", got " +
                std::to_string(*v));
    return 0;
  }
  return static_cast<std::uint32_t>(*v);
}

Affine TomlReader::transform(const toml::table& t, const std::string& what) {
  Affine m;
  if (const toml::node* s = t.get("scale")) {
    m = s->is_array() ? scaling(vec3(s, what + ".scale", Vec3{1.0f}))
                      : scaling(Vec3{number(s, what + ".scale", 1.0f)});
  }
  if (const toml::node* r = t.get("rotate")) {
    const std::string field = what + ".rotate";
    float f[4];
    if (floats(*r, field, 4, "[axis x, y, z, degrees]", f)) {
      const Vec3 axis{f[0], f[1], f[2]};
      if (length(axis) > 0)
        m = rotation(axis, f[3]) * m;
      else
        problem(*r, field, "the axis must not be zero");
    }
  }
  if (t.get("translate")) m = translation(vec3(t, "translate", what, {})) * m;
  settle();  // a wrong field above stands in as the identity: its determinant says nothing
  // Instances are drawn through the inverse: a transform that flattens (a zero scale) or whose
  // determinant leaves the float range has none.
  const float det = dot(m.vx, cross(m.vy, m.vz));
  if (!(std::isfinite(det) && std::fabs(det) >= 1e-30f))
    fail(t.get("scale") ? *t.get("scale") : t, what + ".scale",
         "makes a degenerate transform (determinant " + text(det) +
             "): every axis must be scaled by a non-zero amount within the float range");
  return m;
}

std::uint32_t TomlReader::material(const SceneDesc& d, const toml::table& t,
                                   const std::string& owner) {
  const std::string field = owner + ".material";
  const toml::node* n = need(t, "material", owner);
  if (!n || !n->is_string()) {
    string(n, field);  // reports a wrong type (need() reported a missing one)
    return 0;
  }
  const std::string name = string(n, field);
  const int i = d.findMaterial(name);
  if (i < 0) {
    std::vector<std::string> defined;
    for (const Material& m : d.materials) defined.push_back(m.name);
    notDefined(*n, field, "material", name, defined);
  }
  return static_cast<std::uint32_t>(i);
}

void TomlReader::notDefined(const toml::node& at, const std::string& field, std::string_view kind,
                            const std::string& name, const std::vector<std::string>& defined) {
  if (failed(kind, name)) skip();
  std::string message = std::string(kind) + " '" + name + "' is not defined";
  const std::vector<std::string_view> names(defined.begin(), defined.end());
  if (const auto best = base::closestKey(name, names))
    message += " (did you mean '" + std::string(*best) + "'?)";
  fail(at, field, message);
}

std::string TomlReader::where(const toml::node& at, const std::string& field) const {
  const toml::source_position& p = at.source().begin;
  return base::SourceLocation{path(), static_cast<int>(p.line), static_cast<int>(p.column)}.text() +
         ": " + field;
}

void TomlReader::budget(const toml::node& at, const std::string& field, const std::string& size,
                        std::uint64_t bytes) {
  if (std::string problem = base::memoryProblem(bytes); !problem.empty())
    fail(at, field, "loading it (" + size + ") " + problem);
}

std::string TomlReader::field(const std::string& what, std::string_view key) {
  return what.empty() ? std::string(key) : what + "." + std::string(key);
}

std::string TomlReader::text(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", v);
  return buffer;
}

}  // namespace renderers
