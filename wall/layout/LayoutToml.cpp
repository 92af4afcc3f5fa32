// TOML → Layout: syntax, types, unknown keys and the [grid] shorthand. Semantic checks (sizes,
// names, overlaps, process gaps) live in LayoutValidate.cpp and run on the result.
#include <toml++/toml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>

#include "base/Error.h"
#include "base/TomlDiagnostics.h"
#include "wall/layout/Layout.h"
#include "wall/layout/LayoutChecks.h"
#include "wall/layout/RoomToml.h"

namespace wall {
namespace {

constexpr std::array<std::string_view, 4> kTopKeys = {"display", "grid", "description", "viewer"};
constexpr std::array<std::string_view, 11> kDisplayKeys = {
    "name",       "origin",      "size",         "process",  "host", "monitor",
    "fullscreen", "bottom_left", "bottom_right", "top_left", "eye"};
constexpr std::array<std::string_view, 10> kGridKeys = {
    "columns",        "rows",       "display_size", "bezel_px",    "bezel_mm",
    "pixel_pitch_mm", "fullscreen", "monitor",      "process_per", "room"};

int lineOf(const toml::node& n) { return static_cast<int>(n.source().begin.line); }
int columnOf(const toml::node& n) { return static_cast<int>(n.source().begin.column); }

// Records where `n` was written as the place of one field of `d`.
void mark(Display& d, int Display::Places::*field, const toml::node& n) {
  d.lines.*field = lineOf(n);
  d.columns.*field = columnOf(n);
}

// "display 'a'.size", or the field alone at the top of the file.
std::string fieldOf(const std::string& subject, std::string_view field) {
  return subject.empty() ? std::string(field) : subject + "." + std::string(field);
}

std::optional<int> readInt(const toml::node& n, base::TomlDiagnostics& r,
                           const std::string& subject, std::string_view field) {
  const std::optional<std::int64_t> v = r.integer(n, fieldOf(subject, field));
  if (!v) return std::nullopt;
  if (*v < std::numeric_limits<int>::min() || *v > std::numeric_limits<int>::max()) {
    r.add(n, fieldOf(subject, field), std::to_string(*v) + " is out of range");
    return std::nullopt;
  }
  return static_cast<int>(*v);
}

std::optional<double> readNumber(const toml::node& n, base::TomlDiagnostics& r,
                                 const std::string& subject, std::string_view field) {
  return r.number(n, fieldOf(subject, field));
}

// An array of exactly N integers or numbers, e.g. origin = [x, y].
template <typename T, size_t N>
std::optional<std::array<T, N>> readTuple(const toml::node& n, base::TomlDiagnostics& r,
                                          const std::string& subject, std::string_view field,
                                          const char* shape) {
  std::array<T, N> out{};
  if constexpr (std::is_same_v<T, int>) {
    if (!r.integers(n, fieldOf(subject, field), N, shape)) return std::nullopt;
    const toml::array& a = *n.as_array();
    bool ok = true;
    for (size_t i = 0; i < N; ++i) {
      const std::optional<int> e = readInt(a[i], r, subject, field);
      ok = ok && e.has_value();
      out[i] = e.value_or(0);
    }
    if (!ok) return std::nullopt;
  } else {
    const auto v = r.numbers(n, fieldOf(subject, field), N, shape);
    if (!v) return std::nullopt;
    std::copy(v->begin(), v->end(), out.begin());
  }
  return out;
}

std::optional<std::string> readString(const toml::node& n, base::TomlDiagnostics& r,
                                      const std::string& subject, std::string_view field) {
  return r.string(n, fieldOf(subject, field));
}

std::optional<bool> readBool(const toml::node& n, base::TomlDiagnostics& r,
                             const std::string& subject, std::string_view field) {
  return r.boolean(n, fieldOf(subject, field));
}

// One [[display]] table. Returns whether it set `process`.
bool readDisplay(const toml::table& t, int index, Display& d, base::TomlDiagnostics& r) {
  mark(d, &Display::Places::table, t);
  std::string subject = "display #" + std::to_string(index + 1);
  if (const toml::node* n = t.get("name")) {
    mark(d, &Display::Places::name, *n);
    if (auto s = readString(*n, r, subject, "name")) {
      d.name = *s;
      subject = "display '" + d.name + "'";
    }
  } else {
    r.add(t, fieldOf(subject, "name"), "missing; every [[display]] needs a name");
  }
  r.unknownKeys(t, subject, kDisplayKeys);

  if (const toml::node* n = t.get("origin")) {
    mark(d, &Display::Places::origin, *n);
    if (auto v = readTuple<int, 2>(*n, r, subject, "origin", "[x, y]"))
      d.rect.x0 = (*v)[0], d.rect.y0 = (*v)[1];
  } else {
    r.add(t, fieldOf(subject, "origin"), "missing; give the top-left corner as [x, y]");
  }
  int w = 0, h = 0;
  const toml::node* size = t.get("size");
  if (size) {
    mark(d, &Display::Places::size, *size);
    if (auto v = readTuple<int, 2>(*size, r, subject, "size", "[w, h]")) w = (*v)[0], h = (*v)[1];
  } else {
    r.add(t, fieldOf(subject, "size"), "missing; give the size in pixels as [w, h]");
  }
  // Computed in 64 bits: a huge origin plus size must not wrap into a plausible rectangle.
  const int64_t x1 = int64_t{d.rect.x0} + w, y1 = int64_t{d.rect.y0} + h;
  if (x1 > std::numeric_limits<int>::max() || y1 > std::numeric_limits<int>::max()) {
    r.add(*size, fieldOf(subject, "size"), "origin + size is out of range");
    w = h = 0;
  }
  d.rect.x1 = d.rect.x0 + w;
  d.rect.y1 = d.rect.y0 + h;

  bool setProcess = false;
  if (const toml::node* n = t.get("process")) {
    mark(d, &Display::Places::process, *n);
    setProcess = true;
    if (auto v = readInt(*n, r, subject, "process")) d.process = *v;
  }
  if (const toml::node* n = t.get("host")) d.host = readString(*n, r, subject, "host").value_or("");
  if (const toml::node* n = t.get("monitor")) {
    d.monitor = readInt(*n, r, subject, "monitor").value_or(0);
    if (d.monitor < 0) r.add(*n, fieldOf(subject, "monitor"), "must be 0 or more");
  }
  if (const toml::node* n = t.get("fullscreen"))
    d.fullscreen = readBool(*n, r, subject, "fullscreen").value_or(false);
  detail::readDisplayScreen(t, subject, d, r);
  return setProcess;
}

// `trusted[i]`: display i was read without a problem, so semantic checks may look at it.
void readDisplays(const toml::node& node, Layout& layout, std::vector<bool>& trusted,
                  base::TomlDiagnostics& r) {
  const toml::array* a = node.as_array();
  if (!a || !a->is_array_of_tables()) {
    r.add(node, "display",
          "expected [[display]] tables (an array of tables), got " + base::tomlTypeName(node));
    return;
  }
  if (a->size() > static_cast<size_t>(kMaxDisplays)) {
    r.add(node, "display",
          std::to_string(a->size()) + " [[display]] tables: at most " +
              std::to_string(kMaxDisplays) + " displays in a layout");
    return;
  }
  std::vector<bool> setsProcess;
  for (size_t i = 0; i < a->size(); ++i) {
    Display d;
    const size_t before = r.count();
    setsProcess.push_back(readDisplay(*(*a)[i].as_table(), static_cast<int>(i), d, r));
    trusted.push_back(r.count() == before);
    layout.displays.push_back(std::move(d));
  }
  // Either every display names its process or none does (then display i is process i); a mix
  // would make the defaults collide with the explicit indices in ways nobody means.
  const auto firstSet = std::find(setsProcess.begin(), setsProcess.end(), true);
  for (size_t i = 0; i < layout.displays.size(); ++i) {
    Display& d = layout.displays[i];
    if (firstSet == setsProcess.end()) {
      d.process = static_cast<int>(i);
    } else if (!setsProcess[i]) {
      const Display& other = layout.displays[static_cast<size_t>(firstSet - setsProcess.begin())];
      trusted[i] = false;
      r.add(d.lines.table, d.columns.table, "display '" + d.name + "'.process",
            "missing; display '" + other.name + "' (line " + std::to_string(other.lines.process) +
                ") sets 'process', so every display must");
    }
  }
}

// [grid]: columns x rows panels of one size, r<row>c<col>, process = row-major index (or the
// column, or the row, with process_per). A panel's
// left edge is its column times (width + left bezel + right bezel): the pixels that would sit
// behind the bezels belong to the canvas but to no display, so the picture continues.
void readGrid(const toml::table& t, Layout& layout, base::TomlDiagnostics& r) {
  const std::string subject = "grid";
  r.unknownKeys(t, subject, kGridKeys);
  bool ok = true;
  auto positive = [&](const char* field) -> int {
    const toml::node* n = t.get(field);
    if (!n) {
      r.add(t, fieldOf(subject, field), "missing");
      ok = false;
      return 0;
    }
    auto v = readInt(*n, r, subject, field);
    if (v && *v <= 0)
      r.add(*n, fieldOf(subject, field), "must be positive, got " + std::to_string(*v));
    if (!v || *v <= 0) ok = false;
    return v.value_or(0);
  };
  const int columns = positive("columns");
  const int rows = positive("rows");

  int w = 0, h = 0;
  const toml::node* size = t.get("display_size");
  const toml::node& sizeAt = size ? *size : t;  // where the panels' size is given
  if (size) {
    if (auto v = readTuple<int, 2>(*size, r, subject, "display_size", "[w, h]")) {
      w = (*v)[0], h = (*v)[1];
      if (w <= 0)
        r.add(*size, "grid.display_size", "width must be positive, got " + std::to_string(w));
      if (h <= 0)
        r.add(*size, "grid.display_size", "height must be positive, got " + std::to_string(h));
      ok = ok && w > 0 && h > 0;
    } else {
      ok = false;
    }
  } else {
    r.add(t, "grid.display_size", "missing; give each panel's size in pixels as [w, h]");
    ok = false;
  }

  std::array<int, 4> bezel{};  // left, right, top, bottom
  const toml::node* px = t.get("bezel_px");
  const toml::node* mm = t.get("bezel_mm");
  const toml::node* pitch = t.get("pixel_pitch_mm");
  if (px && mm) {
    r.add(*mm, "grid.bezel_mm", "give either bezel_px or bezel_mm, not both");
    ok = false;
  } else if (px) {
    if (auto v = readTuple<int, 4>(*px, r, subject, "bezel_px", "[left, right, top, bottom]")) {
      bezel = *v;
    } else {
      ok = false;
    }
  } else if (mm) {
    auto v = readTuple<double, 4>(*mm, r, subject, "bezel_mm", "[left, right, top, bottom]");
    std::optional<double> p;
    if (!pitch) {
      r.add(*mm, "grid.pixel_pitch_mm",
            "missing; bezel_mm needs the pixel pitch to turn millimetres into pixels");
    } else if ((p = readNumber(*pitch, r, subject, "pixel_pitch_mm")) && !(*p > 0.0)) {
      r.add(*pitch, "grid.pixel_pitch_mm", "must be positive");
      p.reset();
    }
    if (v && p) {
      for (size_t i = 0; i < 4; ++i) {
        const double pixels = std::round((*v)[i] / *p);
        if ((*v)[i] < 0) {
          bezel[i] = -1;               // reported below, with the bezel_px case
        } else if (!(pixels < 1e6)) {  // also NaN
          r.add(*mm, "grid.bezel_mm",
                "a bezel of " + std::to_string((*v)[i]) + " mm is out of range");
          ok = false;
        } else {
          bezel[i] = static_cast<int>(pixels);
        }
      }
    } else {
      ok = false;
    }
  }
  if (pitch && !mm) {
    r.add(*pitch, "grid.pixel_pitch_mm", "only used with bezel_mm; remove it or add bezel_mm");
    ok = false;
  }
  const char* sides[] = {"left", "right", "top", "bottom"};
  for (size_t i = 0; i < 4; ++i) {
    if (bezel[i] < 0) {
      r.add(px ? *px : *mm, px ? "grid.bezel_px" : "grid.bezel_mm",
            std::string(sides[i]) + " bezel must be 0 or more");
      ok = false;
    }
  }
  bool fullscreen = false;
  int monitor = 0;
  if (const toml::node* n = t.get("fullscreen"))
    fullscreen = readBool(*n, r, subject, "fullscreen").value_or(false);
  if (const toml::node* n = t.get("monitor")) {
    monitor = readInt(*n, r, subject, "monitor").value_or(0);
    if (monitor < 0) r.add(*n, "grid.monitor", "must be 0 or more");
  }
  // Which panels one wall process drives: one each, or a whole column or row (one host with
  // several monitors per column of a wall is a common way to cable one).
  std::string processPer = "display";
  if (const toml::node* n = t.get("process_per")) {
    processPer = readString(*n, r, subject, "process_per").value_or("display");
    if (processPer != "display" && processPer != "column" && processPer != "row") {
      r.add(*n, "grid.process_per",
            "must be \"display\", \"column\" or \"row\", got \"" + processPer + "\"");
      ok = false;
    }
  }
  if (!ok) return;

  if (int64_t{columns} * rows > kMaxDisplays) {
    r.add(*t.get("columns"), "grid.columns",
          std::to_string(columns) + " x " + std::to_string(rows) + " panels: at most " +
              std::to_string(kMaxDisplays) + " displays in a layout");
    return;
  }
  const int64_t pitchX = int64_t{w} + bezel[0] + bezel[1],
                pitchY = int64_t{h} + bezel[2] + bezel[3];
  if (pitchX * columns > std::numeric_limits<int>::max() ||
      pitchY * rows > std::numeric_limits<int>::max()) {
    r.add(sizeAt, "grid.display_size", "the grid is too large");
    return;
  }
  for (int row = 0; row < rows; ++row) {
    for (int col = 0; col < columns; ++col) {
      Display d;
      // Built piecewise: GCC 12 -O3 warns falsely (-Wrestrict) on "r" + to_string(...).
      d.name = 'r';
      d.name += std::to_string(row);
      d.name += 'c';
      d.name += std::to_string(col);
      d.rect.x0 = static_cast<int>(col * pitchX);
      d.rect.y0 = static_cast<int>(row * pitchY);
      d.rect.x1 = d.rect.x0 + w;
      d.rect.y1 = d.rect.y0 + h;
      d.fullscreen = fullscreen;
      if (processPer == "column") {  // the panels of a column are that host's monitors, top first
        d.process = col;
        d.monitor = monitor + row;
      } else if (processPer == "row") {
        d.process = row;
        d.monitor = monitor + col;
      } else {
        d.process = row * columns + col;
        d.monitor = monitor;
      }
      for (int Display::Places::*field : {&Display::Places::table, &Display::Places::name,
                                          &Display::Places::origin, &Display::Places::process})
        mark(d, field, t);
      mark(d, &Display::Places::size, sizeAt);
      layout.displays.push_back(std::move(d));
    }
  }
  if (const toml::node* room = t.get("room"))
    detail::placeGrid(*room, columns, rows, layout.displays, r);
}

void readRoot(const toml::table& root, Layout& layout, std::vector<bool>& trusted,
              base::TomlDiagnostics& r) {
  r.unknownKeys(root, "", kTopKeys);
  if (const toml::node* n = root.get("description")) readString(*n, r, "", "description");
  const toml::node* displays = root.get("display");
  const toml::node* grid = root.get("grid");
  if (displays && grid) {
    r.add(*grid, "grid", "use either [grid] or [[display]] tables, not both");
    return;
  }
  if (grid) {
    if (const toml::table* t = grid->as_table())
      readGrid(*t, layout, r);  // expands only when the grid itself is sound
    else
      r.add(*grid, "grid", "expected a [grid] table, got " + base::tomlTypeName(*grid));
    trusted.assign(layout.displays.size(), true);
  } else if (displays) {
    readDisplays(*displays, layout, trusted, r);
  } else {
    r.add(1, 1, "", "no displays: describe them with [[display]] tables or a [grid] table");
  }
  detail::readRoom(root.get("viewer"), layout, r);
}

}  // namespace

LayoutResult readLayoutText(std::string_view text, const std::string& fileName) {
  LayoutResult result;
  result.layout.file = fileName;
  base::TomlDiagnostics diagnostics(fileName, std::string(text));
  if (const std::optional<toml::table> root = diagnostics.parse()) {
    std::vector<bool> trusted;
    readRoot(*root, result.layout, trusted, diagnostics);
    // Semantic checks look only at displays read cleanly, so a typo in one display does not
    // hide an overlap elsewhere, nor does it produce follow-on noise about itself.
    detail::validateDisplays(result.layout, trusted, diagnostics);
  }
  result.problems = diagnostics.texts();
  if (result.problems.empty()) computeCanvas(result.layout);
  return result;
}

}  // namespace wall
