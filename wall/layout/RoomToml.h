#pragma once
// Inside wall/layout/: the TOML of screens placed in a room (docs/rooms.md): a display's corners
// and eye, the [grid.room] generators (a plane, a cylinder) and the [viewer]. LayoutToml.cpp
// calls these while it reads a layout.
#include <toml++/toml.h>

#include <string>
#include <vector>

#include "base/TomlDiagnostics.h"
#include "wall/layout/Layout.h"

namespace wall::detail {

// A [[display]]'s bottom_left, bottom_right, top_left and eye (all optional here).
void readDisplayScreen(const toml::table& t, const std::string& subject, Display& d,
                       base::TomlDiagnostics& r);

// [grid.room]: places the grid's panels (`displays`, r<row>c<col> in row-major order) in the
// room, as a plane or a cylinder section.
void placeGrid(const toml::node& node, int columns, int rows, std::vector<Display>& displays,
               base::TomlDiagnostics& r);

// [viewer] (null: none written), then the checks that tie the room together: every display
// placed or none, corners that span a rectangle, an eye only on a placed display, a viewer only
// with placed displays. Sets layout.viewer when the displays are placed.
void readRoom(const toml::node* viewer, Layout& layout, base::TomlDiagnostics& r);

}  // namespace wall::detail
