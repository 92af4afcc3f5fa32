// TOML → screens in a room: corners per display, the [grid.room] generators and the [viewer].
#include "wall/layout/RoomToml.h"

#include <array>
#include <cmath>
#include <optional>
#include <string_view>

namespace wall::detail {
namespace {

constexpr std::array<std::string_view, 4> kViewerKeys = {"head", "orientation", "eye_separation",
                                                         "description"};
constexpr std::array<std::string_view, 10> kRoomKeys = {
    "shape",       "origin",           "right", "up", "tile_size", "bezel", "radius",
    "first_angle", "angle_per_column", "bottom"};
// A room bigger than this (metres, any coordinate) is a typo, and float rays lose the screen.
constexpr double kMaxMetres = 1e5;

std::string fieldOf(const std::string& subject, std::string_view field) {
  return subject + "." + std::string(field);
}

std::optional<Point3> readPoint(const toml::node& n, base::TomlDiagnostics& r,
                                const std::string& field) {
  const auto v = r.numbers(n, field, 3, "[x, y, z]");
  if (!v) return std::nullopt;
  for (double c : *v)
    if (std::abs(c) > kMaxMetres) {
      r.add(n, field,
            "coordinates beyond " + std::to_string(static_cast<int>(kMaxMetres)) +
                " m are out of range");
      return std::nullopt;
    }
  return Point3{(*v)[0], (*v)[1], (*v)[2]};
}

Point3 minus(Point3 a, Point3 b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Point3 plus(Point3 a, Point3 b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Point3 times(Point3 a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
double dot(Point3 a, Point3 b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm(Point3 a) { return std::sqrt(dot(a, a)); }

// The screen of a panel whose picture's bottom-left corner is `at`, spanning `across` and `up`.
Screen panel(Point3 at, Point3 across, Point3 up) { return {at, plus(at, across), plus(at, up)}; }

}  // namespace

void readDisplayScreen(const toml::table& t, const std::string& subject, Display& d,
                       base::TomlDiagnostics& r) {
  const toml::node* corners[3] = {t.get("bottom_left"), t.get("bottom_right"), t.get("top_left")};
  const char* names[3] = {"bottom_left", "bottom_right", "top_left"};
  const bool any = corners[0] || corners[1] || corners[2];
  if (any) {
    Screen s;
    Point3* into[3] = {&s.bottomLeft, &s.bottomRight, &s.topLeft};
    bool ok = true;
    for (int i = 0; i < 3; ++i) {
      if (!corners[i]) {
        r.add(t, fieldOf(subject, names[i]),
              "missing; a screen in the room needs bottom_left, bottom_right and top_left");
        ok = false;
      } else if (auto p = readPoint(*corners[i], r, fieldOf(subject, names[i]))) {
        *into[i] = *p;
      } else {
        ok = false;
      }
    }
    const toml::node& first = corners[0] ? *corners[0] : corners[1] ? *corners[1] : *corners[2];
    d.lines.screen = static_cast<int>(first.source().begin.line);
    d.columns.screen = static_cast<int>(first.source().begin.column);
    if (ok) d.screen = s;
  }
  if (const toml::node* n = t.get("eye")) {
    d.lines.eye = static_cast<int>(n->source().begin.line);
    d.columns.eye = static_cast<int>(n->source().begin.column);
    if (auto e = r.string(*n, fieldOf(subject, "eye"))) {
      if (*e == "left") {
        d.eye = Eye::Left;
      } else if (*e == "right") {
        d.eye = Eye::Right;
      } else {
        r.add(*n, fieldOf(subject, "eye"), "must be \"left\" or \"right\", got \"" + *e + "\"");
      }
    }
  }
}

void placeGrid(const toml::node& node, int columns, int rows, std::vector<Display>& displays,
               base::TomlDiagnostics& r) {
  const toml::table* t = r.table(node, "grid.room");
  if (!t) return;
  r.unknownKeys(*t, "grid.room", kRoomKeys);
  const std::string shape = [&] {
    const toml::node* n = t->get("shape");
    return n ? r.string(*n, "grid.room.shape").value_or("") : std::string("plane");
  }();
  if (shape != "plane" && shape != "cylinder") {
    if (!shape.empty())
      r.add(*t->get("shape"), "grid.room.shape",
            "must be \"plane\" or \"cylinder\", got \"" + shape + "\"");
    return;
  }
  const auto need = [&](const char* key) -> const toml::node* {
    const toml::node* n = t->get(key);
    if (!n) r.add(*t, std::string("grid.room.") + key, "missing (a " + shape + " needs it)");
    return n;
  };
  const auto numberOf = [&](const char* key) -> std::optional<double> {
    const toml::node* n = need(key);
    return n ? r.number(*n, std::string("grid.room.") + key) : std::nullopt;
  };
  const auto forbid = [&](const char* key) {
    if (const toml::node* n = t->get(key))
      r.add(*n, std::string("grid.room.") + key, "is not a field of a " + shape);
  };
  std::optional<std::vector<double>> size, bezel;
  if (const toml::node* n = need("tile_size")) {
    size = r.numbers(*n, "grid.room.tile_size", 2, "[width, height]");
    if (size &&
        !((*size)[0] > 0 && (*size)[1] > 0 && (*size)[0] < kMaxMetres && (*size)[1] < kMaxMetres)) {
      r.add(*n, "grid.room.tile_size", "each side must be positive (metres)");
      size.reset();
    }
  }
  bezel = std::vector<double>(4, 0.0);
  if (const toml::node* n = t->get("bezel")) {
    bezel = r.numbers(*n, "grid.room.bezel", 4, "[left, right, top, bottom]");
    if (bezel)
      for (double b : *bezel)
        if (!(b >= 0 && b < kMaxMetres)) {
          r.add(*n, "grid.room.bezel", "each bezel must be 0 or more (metres)");
          bezel.reset();
          break;
        }
  }
  const auto panelAt = [&](int row, int col) -> Display& {
    return displays[static_cast<std::size_t>(row * columns + col)];
  };
  if (shape == "plane") {
    for (const char* key : {"radius", "first_angle", "angle_per_column", "bottom"}) forbid(key);
    std::optional<Point3> origin, right, up;
    if (const toml::node* n = need("origin")) origin = readPoint(*n, r, "grid.room.origin");
    if (const toml::node* n = need("right")) right = readPoint(*n, r, "grid.room.right");
    if (const toml::node* n = need("up")) up = readPoint(*n, r, "grid.room.up");
    if (right && !(norm(*right) > 0)) {
      r.add(*t->get("right"), "grid.room.right", "must be a non-zero direction");
      right.reset();
    }
    if (up && !(norm(*up) > 0)) {
      r.add(*t->get("up"), "grid.room.up", "must be a non-zero direction");
      up.reset();
    }
    if (!origin || !right || !up || !size || !bezel) return;
    const Point3 x = times(*right, 1.0 / norm(*right)), y = times(*up, 1.0 / norm(*up));
    if (std::abs(dot(x, y)) > 1e-6) {
      r.add(*t->get("up"), "grid.room.up", "must be at right angles to grid.room.right");
      return;
    }
    const double w = (*size)[0], h = (*size)[1];
    const double pitchX = w + (*bezel)[0] + (*bezel)[1], pitchY = h + (*bezel)[2] + (*bezel)[3];
    // origin is the bottom-left corner of the bottom-left panel's picture; row 0 is the top.
    for (int row = 0; row < rows; ++row)
      for (int col = 0; col < columns; ++col) {
        const Point3 at =
            plus(*origin, plus(times(x, col * pitchX), times(y, (rows - 1 - row) * pitchY)));
        panelAt(row, col).screen = panel(at, times(x, w), times(y, h));
      }
    return;
  }
  for (const char* key : {"origin", "right", "up"}) forbid(key);
  const std::optional<double> radius = numberOf("radius"), first = numberOf("first_angle"),
                              step = numberOf("angle_per_column");
  std::optional<double> bottom = 0.0;
  if (const toml::node* n = t->get("bottom")) bottom = r.number(*n, "grid.room.bottom");
  if (radius && !(*radius > 0 && *radius < kMaxMetres)) {
    r.add(*t->get("radius"), "grid.room.radius", "must be positive (metres)");
    return;
  }
  if (step && !(std::abs(*step) > 0 && std::abs(*step) * columns <= 360.0)) {
    r.add(*t->get("angle_per_column"), "grid.room.angle_per_column",
          "must be non-zero, the columns spanning at most 360 degrees");
    return;
  }
  if (!radius || !first || !step || !bottom || !size || !bezel) return;
  constexpr double kDegrees = 3.14159265358979323846 / 180.0;
  const double w = (*size)[0], h = (*size)[1], pitchY = h + (*bezel)[2] + (*bezel)[3];
  // Column c's panel faces the axis at angle first + c * step (0: straight ahead, -z; positive
  // to the right), its centre at the radius, its picture moved by (left - right) / 2 bezels.
  for (int col = 0; col < columns; ++col) {
    const double a = (*first + col * *step) * kDegrees;
    const Point3 centre{*radius * std::sin(a), 0.0, -*radius * std::cos(a)};
    const Point3 across{std::cos(a), 0.0, std::sin(a)};
    const double left = 0.5 * ((*bezel)[0] - (*bezel)[1]) - 0.5 * w;
    for (int row = 0; row < rows; ++row) {
      const Point3 at = plus(plus(centre, times(across, left)),
                             Point3{0.0, *bottom + (rows - 1 - row) * pitchY, 0.0});
      panelAt(row, col).screen = panel(at, times(across, w), Point3{0.0, h, 0.0});
    }
  }
}

void readRoom(const toml::node* viewerNode, Layout& layout, base::TomlDiagnostics& r) {
  Viewer viewer;
  if (viewerNode) {
    if (const toml::table* t = r.table(*viewerNode, "viewer")) {
      r.unknownKeys(*t, "viewer", kViewerKeys);
      if (const toml::node* n = t->get("head"))
        viewer.head = readPoint(*n, r, "viewer.head").value_or(viewer.head);
      if (const toml::node* n = t->get("orientation")) {
        if (auto v = r.numbers(*n, "viewer.orientation", 3, "[yaw, pitch, roll]"))
          viewer.orientation = {(*v)[0], (*v)[1], (*v)[2]};
      }
      if (const toml::node* n = t->get("eye_separation")) {
        const std::optional<double> e = r.number(*n, "viewer.eye_separation");
        if (e && !(*e >= 0 && *e < 1.0))
          r.add(*n, "viewer.eye_separation", "must be 0 or more and under 1 m");
        else if (e)
          viewer.eyeSeparation = *e;
      }
      if (const toml::node* n = t->get("description")) r.string(*n, "viewer.description");
    }
  }
  const Display* placed = nullptr;
  const Display* unplaced = nullptr;
  for (const Display& d : layout.displays) {
    (d.screen || d.lines.screen ? placed : unplaced) = &d;
    if (d.lines.eye && !d.lines.screen && !d.screen)
      r.add(d.lines.eye, d.columns.eye, "display '" + d.name + "'.eye",
            "only a display placed in the room (bottom_left, bottom_right, top_left) has an eye");
    if (!d.screen) continue;
    const Screen& s = *d.screen;
    const Point3 across = minus(s.bottomRight, s.bottomLeft), up = minus(s.topLeft, s.bottomLeft);
    const int line = d.lines.screen ? d.lines.screen : d.lines.table;
    const int column = d.lines.screen ? d.columns.screen : d.columns.table;
    if (!(norm(across) > 1e-6) || !(norm(up) > 1e-6)) {
      r.add(line, column, "display '" + d.name + "'.bottom_right",
            "the corners must span a screen: bottom_left, bottom_right and top_left differ");
    } else if (std::abs(dot(across, up)) > 1e-3 * norm(across) * norm(up)) {
      r.add(line, column, "display '" + d.name + "'.top_left",
            "the screen must be a rectangle: top_left - bottom_left at right angles to "
            "bottom_right - bottom_left");
    }
  }
  if (placed && unplaced) {
    r.add(unplaced->lines.table, unplaced->columns.table, "display '" + unplaced->name + "'",
          "not placed in the room, while display '" + placed->name +
              "' is: place every display (bottom_left, bottom_right, top_left) or none");
    return;
  }
  if (viewerNode && !placed) {
    r.add(*viewerNode, "viewer",
          "a viewer needs displays placed in the room (bottom_left, bottom_right, top_left, or "
          "[grid.room])");
    return;
  }
  if (placed) layout.viewer = viewer;
}

}  // namespace wall::detail
