// Semantic checks on a layout, the canvas, and the small Layout helpers.
#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <map>
#include <set>

#include "base/Error.h"
#include "base/TomlDiagnostics.h"
#include "wall/layout/Layout.h"
#include "wall/layout/LayoutChecks.h"

namespace wall {
namespace {

std::string subjectOf(const Display& d, size_t index) {
  return d.name.empty() ? "display #" + std::to_string(index + 1) : "display '" + d.name + "'";
}

bool validName(const std::string& name) {
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' ||
           c == '_';
  });
}

std::string rectText(const dfb::Region& r) {
  // Appended, not "[" + string: GCC 12 at -O3 warns falsely (-Wrestrict) about the latter.
  std::string out = "[";
  out += std::to_string(r.x0) + ", " + std::to_string(r.y0) + "] to [";
  out += std::to_string(r.x1) + ", " + std::to_string(r.y1) + ")";
  return out;
}

}  // namespace

namespace detail {

void validateDisplays(const Layout& layout, const std::vector<bool>& trusted,
                      base::TomlDiagnostics& report, bool processGaps) {
  const size_t before = report.count();
  // At the field's place, or the display's when the field was not written.
  auto add = [&](int Display::Places::*place, const Display& d, size_t i, const char* field,
                 const std::string& what) {
    const bool written = d.lines.*place > 0;
    report.add(written ? d.lines.*place : d.lines.table,
               written ? d.columns.*place : d.columns.table,
               subjectOf(d, i) + "." + std::string(field), what);
  };
  const size_t n = layout.displays.size();
  auto isTrusted = [&](size_t i) { return trusted.empty() || trusted[i]; };
  const bool allTrusted = std::all_of(trusted.begin(), trusted.end(), [](bool b) { return b; });

  std::map<std::string, size_t> firstWithName;
  for (size_t i = 0; i < n; ++i) {
    if (!isTrusted(i)) continue;
    const Display& d = layout.displays[i];
    if (d.rect.width() <= 0)
      add(&Display::Places::size, d, i, "size",
          "width must be positive, got " + std::to_string(d.rect.width()));
    if (d.rect.height() <= 0)
      add(&Display::Places::size, d, i, "size",
          "height must be positive, got " + std::to_string(d.rect.height()));
    if (d.name.empty()) {
      add(&Display::Places::name, d, i, "name", "must not be empty");
    } else if (!validName(d.name)) {
      add(&Display::Places::name, d, i, "name",
          "'" + d.name +
              "' may contain only letters, digits, '-' and '_' (it names a capture "
              "folder and a window)");
    } else if (auto [it, fresh] = firstWithName.emplace(d.name, i); !fresh) {
      const Display& first = layout.displays[it->second];
      add(&Display::Places::name, d, i, "name",
          "duplicate name '" + d.name + "'; the display at line " +
              std::to_string(first.lines.table) + " has it already");
    }
    if (d.process < 0 || d.process >= kMaxDisplays)
      add(&Display::Places::process, d, i, "process",
          "must be from 0 to " + std::to_string(kMaxDisplays - 1) +
              " (one wall process drives "
              "at least one display), got " +
              std::to_string(d.process));
  }

  // Overlaps: reported once per pair, on the later display, where the reader will look.
  for (size_t j = 0; j < n; ++j) {
    const Display& b = layout.displays[j];
    if (!isTrusted(j) || b.rect.empty()) continue;
    for (size_t i = 0; i < j; ++i) {
      const Display& a = layout.displays[i];
      if (!isTrusted(i) || a.rect.empty()) continue;
      const dfb::Region o = dfb::intersect(a.rect, b.rect);
      if (o.empty()) continue;
      add(&Display::Places::origin, b, j, "origin",
          "overlaps " + subjectOf(a, i) + " (line " + std::to_string(a.lines.table) + ") in the " +
              std::to_string(o.width()) + "x" + std::to_string(o.height()) + " pixels " +
              rectText(o));
    }
  }

  // Process indices 0..W-1 without gaps: a gap would be a wall rank with nothing to show, which
  // is always a typo. Only judged when every display's index is known.
  if (allTrusted && !processGaps) {
    std::set<int> used;
    for (const Display& d : layout.displays)
      if (d.process >= 0) used.insert(d.process);
    std::int64_t expected = 0;  // 64 bits: a process index may be INT_MAX
    for (int p : used) {
      if (expected < p && p < kMaxDisplays) {
        // One message per gap, on the first display (in file order) whose index lies past it.
        size_t at = 0;
        while (layout.displays[at].process != p) ++at;
        const Display& d = layout.displays[at];
        const std::string missing = p - expected == 1
                                        ? std::to_string(expected)
                                        : std::to_string(expected) + " to " + std::to_string(p - 1);
        add(&Display::Places::process, d, at, "process",
            "process indices must run from 0 without gaps, but no display has process " + missing +
                " (the highest is " + std::to_string(*used.rbegin()) + ")");
      }
      expected = std::int64_t{p} + 1;
    }
  }

  if (report.count() == before && n > 0 && allTrusted) {
    int64_t x0 = std::numeric_limits<int>::max(), y0 = x0, x1 = std::numeric_limits<int>::min(),
            y1 = x1;
    size_t farthest = 0;  // the display reaching farthest from (0, 0): named in the message
    int64_t reach = -1;
    for (size_t i = 0; i < n; ++i) {
      const Display& d = layout.displays[i];
      x0 = std::min<int64_t>(x0, d.rect.x0), y0 = std::min<int64_t>(y0, d.rect.y0);
      x1 = std::max<int64_t>(x1, d.rect.x1), y1 = std::max<int64_t>(y1, d.rect.y1);
      for (int64_t v :
           {int64_t{d.rect.x0}, int64_t{d.rect.y0}, int64_t{d.rect.x1}, int64_t{d.rect.y1}})
        if (std::abs(v) > reach) reach = std::abs(v), farthest = i;
    }
    // Region::pixelCount is an int: the whole canvas must fit one. Each side is checked first,
    // so the product cannot overflow even 64 bits (origins near -2^31 and +2^31).
    if (x1 - x0 > kMaxCanvasSide || y1 - y0 > kMaxCanvasSide ||
        (x1 - x0) * (y1 - y0) > kMaxCanvasPixels)
      add(&Display::Places::origin, layout.displays[farthest], farthest, "origin",
          "the canvas, " + std::to_string(x1 - x0) + "x" + std::to_string(y1 - y0) +
              " pixels, is too large (at most " + std::to_string(kMaxCanvasSide) +
              " pixels a side and 2^31-1 in all); this display lies farthest out");
  }
}

}  // namespace detail

Problems validateLayout(const Layout& layout, bool processGaps) {
  base::TomlDiagnostics report(layout.file);
  // (The TOML reader reports a file without displays itself, with its own wording.)
  if (layout.displays.empty())
    report.add(0, 0, "", "the layout has no displays");
  else
    detail::validateDisplays(layout, {}, report, processGaps);
  return report.texts();
}

void computeCanvas(Layout& layout) {
  if (layout.displays.empty()) {
    layout.canvasWidth = layout.canvasHeight = layout.processCount = 0;
    return;
  }
  int x0 = std::numeric_limits<int>::max(), y0 = x0;
  int x1 = std::numeric_limits<int>::min(), y1 = x1, maxProcess = -1;
  for (const Display& d : layout.displays) {
    x0 = std::min(x0, d.rect.x0), y0 = std::min(y0, d.rect.y0);
    x1 = std::max(x1, d.rect.x1), y1 = std::max(y1, d.rect.y1);
    maxProcess = std::max(maxProcess, d.process);
  }
  for (Display& d : layout.displays) {
    d.rect.x0 -= x0, d.rect.x1 -= x0;
    d.rect.y0 -= y0, d.rect.y1 -= y0;
  }
  layout.canvasWidth = x1 - x0;
  layout.canvasHeight = y1 - y0;
  layout.processCount = maxProcess + 1;
}

LayoutResult readLayoutFile(const std::string& path) {
  base::TomlDiagnostics file(path);
  if (file.readFile("layout file")) return readLayoutText(file.text(), path);
  LayoutResult result;
  result.layout.file = path;
  result.problems = file.texts();
  return result;
}

Layout loadLayout(const std::string& path) {
  LayoutResult result = readLayoutFile(path);
  if (!result.ok()) throw base::Error(joinProblems(result.problems));
  return std::move(result.layout);
}

std::string joinProblems(const Problems& problems) {
  std::string out;
  for (const std::string& p : problems) out += (out.empty() ? "" : "\n") + p;
  return out;
}

std::vector<int> Layout::displaysOfProcess(int process) const {
  std::vector<int> out;
  for (size_t i = 0; i < displays.size(); ++i)
    if (displays[i].process == process) out.push_back(static_cast<int>(i));
  return out;
}

int Layout::findDisplay(std::string_view name) const {
  for (size_t i = 0; i < displays.size(); ++i)
    if (displays[i].name == name) return static_cast<int>(i);
  return -1;
}

}  // namespace wall
