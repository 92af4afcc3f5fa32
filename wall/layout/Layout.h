#pragma once
// A display wall's layout: which displays there are, where each sits on the canvas, and which
// wall process drives it. Read from TOML (configs/walls/*.toml); the format is described in
// configs/walls/README.md.
//
// Coordinates are canvas pixels, x right, y down. The canvas is the bounding box of all
// displays, moved so that it starts at (0, 0): whatever origins the file uses, the top-left-most
// display edge lands on x = 0 and y = 0, so canvas tiles start where the picture starts.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "dfb/Tile.h"
#include "wall/layout/Room.h"

namespace wall {

struct Display {
  std::string name;  // letters, digits, '-' and '_'; grid displays are r<row>c<col>
  dfb::Region rect;  // on the canvas, after normalisation (see above)
  int process = 0;   // index of the wall process that drives it, 0 .. processCount-1
  std::string host;  // expected MPI processor name; empty = any (mismatch is a warning)
  int monitor = 0;   // GLFW monitor index for window mode (0 = primary)
  bool fullscreen = false;
  // Where its picture is in the room (metres), and which eye it shows; no screen: a flat canvas.
  std::optional<Screen> screen;
  Eye eye = Eye::Centre;
  // Where each field was written (line and column, from 1), for messages; 0 when the field was
  // not written (defaults; grid-expanded displays use the [grid]'s places).
  struct Places {
    int table = 0, name = 0, origin = 0, size = 0, process = 0, screen = 0, eye = 0;
  };
  Places lines, columns;
};

// Caps that keep every size computation small and exact (64-bit where it adds up): a layout past
// them is refused with a message, never a crash or a hang.
constexpr int kMaxDisplays = 1024;       // displays, hence also wall processes
constexpr int kMaxCanvasSide = 1 << 20;  // canvas width and height, in pixels
constexpr long long kMaxCanvasPixels = (1LL << 31) - 1;

struct Layout {
  std::string file;  // path as given to the loader, used in every message
  int canvasWidth = 0;
  int canvasHeight = 0;
  int processCount = 0;  // wall processes W: the last W ranks of the job
  std::vector<Display> displays;
  // [viewer]: set exactly when the displays are placed in a room (the default viewer if the
  // file has no [viewer]). Every display then has a screen.
  std::optional<Viewer> viewer;
  bool inRoom() const { return viewer.has_value(); }

  // Display indices driven by wall process `process`, in file order.
  std::vector<int> displaysOfProcess(int process) const;
  // Index of the display called `name`, or -1.
  int findDisplay(std::string_view name) const;
};

// Every problem with a layout file, one each: "FILE:LINE:COLUMN: display 'NAME'.FIELD: what",
// then the line echoed with a caret under the column (base/TomlDiagnostics.h). Empty when the
// layout is usable.
using Problems = std::vector<std::string>;

struct LayoutResult {
  Layout layout;      // filled as far as the file allowed; trust it only when problems is empty
  Problems problems;  // syntax, types, unknown keys, then validateLayout's findings
  bool ok() const { return problems.empty(); }
};

// Reads and validates a layout file. Never throws for a bad file; reports every problem.
LayoutResult readLayoutFile(const std::string& path);
// The same for TOML text already in memory; `fileName` is only used in messages.
LayoutResult readLayoutText(std::string_view toml, const std::string& fileName);

// Semantic checks on a layout that parsed: positive sizes, valid and unique names, no two
// displays overlapping, process indices 0..W-1 without gaps (`processGaps`: gaps allowed, as in a
// window's layout, wall/layout/Window.h). Returns every problem.
Problems validateLayout(const Layout& layout, bool processGaps = false);

// Reads and validates a layout file; throws base::Error carrying every problem otherwise.
Layout loadLayout(const std::string& path);

// Moves the displays so the canvas starts at (0, 0), then sets the canvas size and processCount
// (highest process index + 1). The loader calls it; call it on a layout built in code.
void computeCanvas(Layout& layout);

// Joins problems into one message, one problem per line (for an exception or stderr).
std::string joinProblems(const Problems& problems);

}  // namespace wall
