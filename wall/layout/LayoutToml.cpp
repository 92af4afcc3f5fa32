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
#include "wall/layout/Layout.h"
#include "wall/layout/LayoutChecks.h"

namespace wall {
namespace {

constexpr std::array<std::string_view, 2> kTopKeys = {"display", "grid"};
constexpr std::array<std::string_view, 1> kTopScalarKeys = {"description"};
constexpr std::array<std::string_view, 7> kDisplayKeys = {"name", "origin",  "size",      "process",
                                                          "host", "monitor", "fullscreen"};
constexpr std::array<std::string_view, 9> kGridKeys = {"columns",    "rows",     "display_size",
                                                       "bezel_px",   "bezel_mm", "pixel_pitch_mm",
                                                       "fullscreen", "monitor",  "process_per"};

int lineOf(const toml::node& n) { return static_cast<int>(n.source().begin.line); }

std::string typeName(const toml::node& n) {
  switch (n.type()) {
    case toml::node_type::table:
      return "a table";
    case toml::node_type::array:
      return "an array";
    case toml::node_type::string:
      return "a string";
    case toml::node_type::integer:
      return "an integer";
    case toml::node_type::floating_point:
      return "a floating-point number";
    case toml::node_type::boolean:
      return "a boolean";
    case toml::node_type::date:
      return "a date";
    case toml::node_type::time:
      return "a time";
    case toml::node_type::date_time:
      return "a date-time";
    default:
      return "nothing";
  }
}

// Levenshtein distance, to turn "orign" into "did you mean 'origin'?".
size_t editDistance(std::string_view a, std::string_view b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diag = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

// Collects problems with the file name and a subject ("display 'a'", "grid") in front.
class Reporter {
 public:
  Reporter(const std::string& file, Problems& out) : file_(file), out_(out) {}

  void add(int line, const std::string& subject, std::string_view field, const std::string& what) {
    std::string m = file_ + ":" + std::to_string(line) + ": ";
    if (!subject.empty()) m += subject + ": ";
    if (!field.empty()) m += "field '" + std::string(field) + "': ";
    out_.push_back(m + what);
  }
  size_t count() const { return out_.size(); }

  template <size_t N>
  void unknownKeys(const toml::table& t, const std::string& subject,
                   const std::array<std::string_view, N>& known) {
    for (auto&& [k, v] : t) {
      if (std::find(known.begin(), known.end(), k.str()) != known.end()) continue;
      std::string what = "unknown field '" + std::string(k.str()) + "'";
      std::string_view best;
      size_t bestDistance = 3;  // suggest only close matches
      for (std::string_view candidate : known) {
        const size_t d = editDistance(k.str(), candidate);
        if (d < bestDistance) bestDistance = d, best = candidate;
      }
      what += best.empty() ? "" : " (did you mean '" + std::string(best) + "'?)";
      what += "; known fields: ";
      for (size_t i = 0; i < N; ++i) what += (i ? ", " : "") + std::string(known[i]);
      add(static_cast<int>(k.source().begin.line), subject, "", what);
    }
  }

 private:
  const std::string& file_;
  Problems& out_;
};

std::optional<int> readInt(const toml::node& n, Reporter& r, const std::string& subject,
                           std::string_view field) {
  if (!n.is_integer()) {
    r.add(lineOf(n), subject, field, "expected an integer, got " + typeName(n));
    return std::nullopt;
  }
  const int64_t v = n.as_integer()->get();
  if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max()) {
    r.add(lineOf(n), subject, field, std::to_string(v) + " is out of range");
    return std::nullopt;
  }
  return static_cast<int>(v);
}

std::optional<double> readNumber(const toml::node& n, Reporter& r, const std::string& subject,
                                 std::string_view field) {
  if (n.is_integer()) return static_cast<double>(n.as_integer()->get());
  if (n.is_floating_point()) {
    const double v = n.as_floating_point()->get();
    if (std::isfinite(v)) return v;
    r.add(lineOf(n), subject, field, "expected a finite number, got " + std::to_string(v));
    return std::nullopt;
  }
  r.add(lineOf(n), subject, field, "expected a number, got " + typeName(n));
  return std::nullopt;
}

// An array of exactly N integers (N = names.size()), e.g. origin = [x, y].
template <typename T, size_t N>
std::optional<std::array<T, N>> readTuple(const toml::node& n, Reporter& r,
                                          const std::string& subject, std::string_view field,
                                          const char* shape) {
  const toml::array* a = n.as_array();
  const char* kind = std::is_same_v<T, int> ? "integers" : "numbers";
  if (!a) {
    r.add(lineOf(n), subject, field,
          std::string("expected ") + shape + " (" + std::to_string(N) + " " + kind + "), got " +
              typeName(n));
    return std::nullopt;
  }
  if (a->size() != N) {
    r.add(lineOf(n), subject, field,
          std::string("expected ") + shape + " (" + std::to_string(N) + " " + kind + "), got " +
              std::to_string(a->size()) + " element" + (a->size() == 1 ? "" : "s"));
    return std::nullopt;
  }
  std::array<T, N> out{};
  bool ok = true;
  for (size_t i = 0; i < N; ++i) {
    std::optional<T> v;
    if constexpr (std::is_same_v<T, int>)
      v = readInt((*a)[i], r, subject, field);
    else
      v = readNumber((*a)[i], r, subject, field);
    if (v)
      out[i] = *v;
    else
      ok = false;
  }
  if (!ok) return std::nullopt;
  return out;
}

std::optional<std::string> readString(const toml::node& n, Reporter& r, const std::string& subject,
                                      std::string_view field) {
  if (const auto* s = n.as_string()) return s->get();
  r.add(lineOf(n), subject, field, "expected a string, got " + typeName(n));
  return std::nullopt;
}

std::optional<bool> readBool(const toml::node& n, Reporter& r, const std::string& subject,
                             std::string_view field) {
  if (const auto* b = n.as_boolean()) return b->get();
  r.add(lineOf(n), subject, field, "expected true or false, got " + typeName(n));
  return std::nullopt;
}

// One [[display]] table. Returns whether it set `process`.
bool readDisplay(const toml::table& t, int index, Display& d, Reporter& r) {
  d.lines.table = lineOf(t);
  std::string subject = "display #" + std::to_string(index + 1);
  if (const toml::node* n = t.get("name")) {
    d.lines.name = lineOf(*n);
    if (auto s = readString(*n, r, subject, "name")) {
      d.name = *s;
      subject = "display '" + d.name + "'";
    }
  } else {
    r.add(d.lines.table, subject, "name", "missing; every [[display]] needs a name");
  }
  r.unknownKeys(t, subject, kDisplayKeys);

  if (const toml::node* n = t.get("origin")) {
    d.lines.origin = lineOf(*n);
    if (auto v = readTuple<int, 2>(*n, r, subject, "origin", "[x, y]"))
      d.rect.x0 = (*v)[0], d.rect.y0 = (*v)[1];
  } else {
    r.add(d.lines.table, subject, "origin", "missing; give the top-left corner as [x, y]");
  }
  int w = 0, h = 0;
  if (const toml::node* n = t.get("size")) {
    d.lines.size = lineOf(*n);
    if (auto v = readTuple<int, 2>(*n, r, subject, "size", "[w, h]")) w = (*v)[0], h = (*v)[1];
  } else {
    r.add(d.lines.table, subject, "size", "missing; give the size in pixels as [w, h]");
  }
  // Computed in 64 bits: a huge origin plus size must not wrap into a plausible rectangle.
  const int64_t x1 = int64_t{d.rect.x0} + w, y1 = int64_t{d.rect.y0} + h;
  if (x1 > std::numeric_limits<int>::max() || y1 > std::numeric_limits<int>::max()) {
    r.add(d.lines.size, subject, "size", "origin + size is out of range");
    w = h = 0;
  }
  d.rect.x1 = d.rect.x0 + w;
  d.rect.y1 = d.rect.y0 + h;

  bool setProcess = false;
  if (const toml::node* n = t.get("process")) {
    d.lines.process = lineOf(*n);
    setProcess = true;
    if (auto v = readInt(*n, r, subject, "process")) d.process = *v;
  }
  if (const toml::node* n = t.get("host")) d.host = readString(*n, r, subject, "host").value_or("");
  if (const toml::node* n = t.get("monitor")) {
    d.monitor = readInt(*n, r, subject, "monitor").value_or(0);
    if (d.monitor < 0) r.add(lineOf(*n), subject, "monitor", "must be 0 or more");
  }
  if (const toml::node* n = t.get("fullscreen"))
    d.fullscreen = readBool(*n, r, subject, "fullscreen").value_or(false);
  return setProcess;
}

// `trusted[i]`: display i was read without a problem, so semantic checks may look at it.
void readDisplays(const toml::node& node, Layout& layout, std::vector<bool>& trusted, Reporter& r) {
  const toml::array* a = node.as_array();
  if (!a || !a->is_array_of_tables()) {
    r.add(lineOf(node), "", "display",
          "expected [[display]] tables (an array of tables), got " + typeName(node));
    return;
  }
  if (a->size() > static_cast<size_t>(kMaxDisplays)) {
    r.add(lineOf(node), "", "display",
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
      r.add(d.lines.table, "display '" + d.name + "'", "process",
            "missing; display '" + other.name + "' (line " + std::to_string(other.lines.process) +
                ") sets 'process', so every display must");
    }
  }
}

// [grid]: columns x rows panels of one size, r<row>c<col>, process = row-major index (or the
// column, or the row, with process_per). A panel's
// left edge is its column times (width + left bezel + right bezel): the pixels that would sit
// behind the bezels belong to the canvas but to no display, so the picture continues.
void readGrid(const toml::table& t, Layout& layout, Reporter& r) {
  const std::string subject = "grid";
  const int line = lineOf(t);
  r.unknownKeys(t, subject, kGridKeys);
  bool ok = true;
  auto positive = [&](const char* field) -> int {
    const toml::node* n = t.get(field);
    if (!n) {
      r.add(line, subject, field, "missing");
      ok = false;
      return 0;
    }
    auto v = readInt(*n, r, subject, field);
    if (v && *v <= 0)
      r.add(lineOf(*n), subject, field, "must be positive, got " + std::to_string(*v));
    if (!v || *v <= 0) ok = false;
    return v.value_or(0);
  };
  const int columns = positive("columns");
  const int rows = positive("rows");

  int w = 0, h = 0, sizeLine = line;
  if (const toml::node* n = t.get("display_size")) {
    sizeLine = lineOf(*n);
    if (auto v = readTuple<int, 2>(*n, r, subject, "display_size", "[w, h]")) {
      w = (*v)[0], h = (*v)[1];
      if (w <= 0)
        r.add(sizeLine, subject, "display_size",
              "width must be positive, got " + std::to_string(w));
      if (h <= 0)
        r.add(sizeLine, subject, "display_size",
              "height must be positive, got " + std::to_string(h));
      ok = ok && w > 0 && h > 0;
    } else {
      ok = false;
    }
  } else {
    r.add(line, subject, "display_size", "missing; give each panel's size in pixels as [w, h]");
    ok = false;
  }

  std::array<int, 4> bezel{};  // left, right, top, bottom
  const toml::node* px = t.get("bezel_px");
  const toml::node* mm = t.get("bezel_mm");
  const toml::node* pitch = t.get("pixel_pitch_mm");
  if (px && mm) {
    r.add(lineOf(*mm), subject, "bezel_mm", "give either bezel_px or bezel_mm, not both");
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
      r.add(lineOf(*mm), subject, "pixel_pitch_mm",
            "missing; bezel_mm needs the pixel pitch to turn millimetres into pixels");
    } else if ((p = readNumber(*pitch, r, subject, "pixel_pitch_mm")) && !(*p > 0.0)) {
      r.add(lineOf(*pitch), subject, "pixel_pitch_mm", "must be positive");
      p.reset();
    }
    if (v && p) {
      for (size_t i = 0; i < 4; ++i) {
        const double pixels = std::round((*v)[i] / *p);
        if ((*v)[i] < 0) {
          bezel[i] = -1;               // reported below, with the bezel_px case
        } else if (!(pixels < 1e6)) {  // also NaN
          r.add(lineOf(*mm), subject, "bezel_mm",
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
    r.add(lineOf(*pitch), subject, "pixel_pitch_mm",
          "only used with bezel_mm; remove it or add bezel_mm");
    ok = false;
  }
  const char* sides[] = {"left", "right", "top", "bottom"};
  for (size_t i = 0; i < 4; ++i) {
    if (bezel[i] < 0) {
      r.add(lineOf(px ? *px : *mm), subject, px ? "bezel_px" : "bezel_mm",
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
    if (monitor < 0) r.add(lineOf(*n), subject, "monitor", "must be 0 or more");
  }
  // Which panels one wall process drives: one each, or a whole column or row (one host with
  // several monitors per column of a wall is a common way to cable one).
  std::string processPer = "display";
  if (const toml::node* n = t.get("process_per")) {
    processPer = readString(*n, r, subject, "process_per").value_or("display");
    if (processPer != "display" && processPer != "column" && processPer != "row") {
      r.add(lineOf(*n), subject, "process_per",
            "must be \"display\", \"column\" or \"row\", got \"" + processPer + "\"");
      ok = false;
    }
  }
  if (!ok) return;

  if (int64_t{columns} * rows > kMaxDisplays) {
    r.add(line, subject, "columns",
          std::to_string(columns) + " x " + std::to_string(rows) + " panels: at most " +
              std::to_string(kMaxDisplays) + " displays in a layout");
    return;
  }
  const int64_t pitchX = int64_t{w} + bezel[0] + bezel[1],
                pitchY = int64_t{h} + bezel[2] + bezel[3];
  if (pitchX * columns > std::numeric_limits<int>::max() ||
      pitchY * rows > std::numeric_limits<int>::max()) {
    r.add(sizeLine, subject, "display_size", "the grid is too large");
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
      d.lines = {line, line, line, sizeLine, line};
      layout.displays.push_back(std::move(d));
    }
  }
}

void readRoot(const toml::table& root, Layout& layout, std::vector<bool>& trusted, Reporter& r) {
  for (auto&& [k, v] : root) {
    const bool known =
        std::find(kTopKeys.begin(), kTopKeys.end(), k.str()) != kTopKeys.end() ||
        std::find(kTopScalarKeys.begin(), kTopScalarKeys.end(), k.str()) != kTopScalarKeys.end();
    if (known) continue;
    std::string what = "unknown table or key '" + std::string(k.str()) + "'";
    for (std::string_view c : {"display", "grid", "description"})
      if (editDistance(k.str(), c) <= 2) what += " (did you mean '" + std::string(c) + "'?)";
    r.add(static_cast<int>(k.source().begin.line), "", "",
          what + "; a layout has [[display]] tables or one [grid], and an optional description");
  }
  if (const toml::node* n = root.get("description")) readString(*n, r, "", "description");
  const toml::node* displays = root.get("display");
  const toml::node* grid = root.get("grid");
  if (displays && grid) {
    r.add(lineOf(*grid), "", "grid", "use either [grid] or [[display]] tables, not both");
    return;
  }
  if (grid) {
    if (const toml::table* t = grid->as_table())
      readGrid(*t, layout, r);  // expands only when the grid itself is sound
    else
      r.add(lineOf(*grid), "", "grid", "expected a [grid] table, got " + typeName(*grid));
    trusted.assign(layout.displays.size(), true);
  } else if (displays) {
    readDisplays(*displays, layout, trusted, r);
  } else {
    r.add(1, "", "", "no displays: describe them with [[display]] tables or a [grid] table");
  }
}

}  // namespace

LayoutResult readLayoutText(std::string_view text, const std::string& fileName) {
  LayoutResult result;
  result.layout.file = fileName;
  Reporter reporter(fileName, result.problems);
  toml::table root;
  try {
    root = toml::parse(text, fileName);
  } catch (const toml::parse_error& e) {
    const toml::source_position& p = e.source().begin;
    result.problems.push_back(fileName + ":" + std::to_string(p.line) + ":" +
                              std::to_string(p.column) +
                              ": TOML syntax error: " + std::string(e.description()));
    return result;
  }
  std::vector<bool> trusted;
  readRoot(root, result.layout, trusted, reporter);
  // Semantic checks look only at displays read cleanly, so a typo in one display does not hide
  // an overlap elsewhere, nor does it produce follow-on noise about itself.
  Problems semantic = detail::validateDisplays(result.layout, trusted);
  result.problems.insert(result.problems.end(), semantic.begin(), semantic.end());
  if (result.problems.empty()) computeCanvas(result.layout);
  return result;
}

}  // namespace wall
