#pragma once
// Cutting canvas tiles at display borders: which display shows which part of a tile. The
// display-routing pixel op sends each piece to the wall rank of its display; a wall rank uses
// the same cut to know how many pieces of a frame to expect. Pure functions of the layout, so
// every rank computes the same answer without talking.
#include <vector>

#include "dfb/Tile.h"
#include "wall/layout/Layout.h"

namespace wall {

struct Piece {
  int display = -1;    // index into layout.displays
  dfb::Region canvas;  // the pixels, in canvas coordinates (inside the tile and the display)
  dfb::Region local;   // the same pixels in the display's coordinates, (0, 0) its top-left
  bool operator==(const Piece&) const = default;
};

// The pieces of canvas region `tile` that displays show, in display order. Pixels that fall on
// no display (behind bezels, outside every display) belong to no piece. Any region works, not
// only tile-grid ones.
std::vector<Piece> piecesOf(const Layout& layout, const dfb::Region& tile);

// The canvas's tiles at `tileSize`: the DFB's own grid (index = ty * tilesX + tx, edge tiles
// partial), so wall ranks and tile owners number tiles alike.
dfb::TileGrid canvasTiles(const Layout& layout, int tileSize);

struct DisplayTile {
  int tileIndex = 0;
  dfb::Region tile;  // the whole tile on the canvas
  Piece piece;       // the part of it this display shows
};

// Every canvas tile that touches display `display`, in tile order, with the piece it shows.
// The wall rank expects exactly these pieces for the display each frame.
std::vector<DisplayTile> tilesOfDisplay(const Layout& layout, int display, int tileSize);

// For each canvas tile: does any display show a pixel of it? Tiles nobody sees need not be
// rendered.
std::vector<bool> tilesShownByAnyDisplay(const Layout& layout, int tileSize);

}  // namespace wall
