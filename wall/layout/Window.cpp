#include "wall/layout/Window.h"

#include <cstdlib>
#include <limits>

#include "base/Error.h"

namespace wall {
namespace {

std::string regionText(const dfb::Region& r) {
  return std::to_string(r.x0) + "," + std::to_string(r.y0) + "," + std::to_string(r.width()) + "," +
         std::to_string(r.height());
}

}  // namespace

WindowRequest parseWindowRequest(const std::string& text) {
  WindowRequest request;
  if (text.empty() || text == "full") return request;
  if (text.find(',') == std::string::npos) {
    for (char c : text)
      if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
            c == '-' || c == '_'))
        throw base::Error("--window '" + text +
                          "': expected full, X,Y,W,H or a display's name (letters, digits, '-' "
                          "and '_')");
    request.kind = WindowRequest::Kind::Display;
    request.display = text;
    return request;
  }
  long long v[4] = {};
  const char* at = text.c_str();
  for (int i = 0; i < 4; ++i) {
    char* end = nullptr;
    v[i] = std::strtoll(at, &end, 10);
    const char want = i < 3 ? ',' : '\0';
    if (end == at || *end != want || v[i] < 0 || v[i] > kMaxCanvasSide)
      throw base::Error("--window '" + text + "': expected X,Y,W,H, whole numbers from 0 to " +
                        std::to_string(kMaxCanvasSide));
    at = end + (i < 3 ? 1 : 0);
  }
  if (v[2] == 0 || v[3] == 0)
    throw base::Error("--window '" + text + "': the window is empty (W and H must be positive)");
  request.kind = WindowRequest::Kind::Rect;
  request.rect = {static_cast<int>(v[0]), static_cast<int>(v[1]), static_cast<int>(v[0] + v[2]),
                  static_cast<int>(v[1] + v[3])};
  return request;
}

std::string windowText(const WindowRequest& request) {
  switch (request.kind) {
    case WindowRequest::Kind::Rect:
      return regionText(request.rect);
    case WindowRequest::Kind::Display:
      return request.display;
    default:
      return "full";
  }
}

dfb::Region resolveWindow(const Layout& wall, const WindowRequest& request) {
  const dfb::Region canvas{0, 0, wall.canvasWidth, wall.canvasHeight};
  switch (request.kind) {
    case WindowRequest::Kind::Full:
      return canvas;
    case WindowRequest::Kind::Display: {
      const int d = wall.findDisplay(request.display);
      if (d >= 0) return wall.displays[static_cast<size_t>(d)].rect;
      std::string names;
      for (const Display& display : wall.displays)
        names += (names.empty() ? "" : ", ") + display.name;
      throw base::Error("window '" + request.display + "': the wall has no display of that name (" +
                        names + ")");
    }
    case WindowRequest::Kind::Rect:
      break;
  }
  const dfb::Region& r = request.rect;
  // 64 bits: the fields come from the wire.
  if (r.x0 < 0 || r.y0 < 0 || std::int64_t{r.x1} <= r.x0 || std::int64_t{r.y1} <= r.y0)
    throw base::Error("window " + std::to_string(r.x0) + "," + std::to_string(r.y0) +
                      " is empty or negative");
  if (r.x1 > canvas.x1 || r.y1 > canvas.y1)
    throw base::Error("window " + regionText(r) + " is not inside the wall's canvas (" +
                      std::to_string(canvas.x1) + "x" + std::to_string(canvas.y1) + ")");
  bool touches = false;
  for (const Display& d : wall.displays) touches = touches || !dfb::intersect(d.rect, r).empty();
  if (!touches) throw base::Error("window " + regionText(r) + " touches no display (only bezels)");
  return r;
}

Layout windowLayout(const Layout& wall, const dfb::Region& window) {
  Layout out;
  out.file = wall.file;
  out.canvasWidth = window.width();
  out.canvasHeight = window.height();
  out.processCount = wall.processCount;
  for (const Display& d : wall.displays) {
    const dfb::Region part = dfb::intersect(d.rect, window);
    if (part.empty()) continue;
    Display clipped = d;
    clipped.rect = {part.x0 - window.x0, part.y0 - window.y0, part.x1 - window.x0,
                    part.y1 - window.y0};
    out.displays.push_back(std::move(clipped));
  }
  return out;
}

}  // namespace wall
