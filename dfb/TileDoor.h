#pragma once
// The one check every tile input passes before its tile operation sees it (docs/design.md,
// "Hostile input"). The DFB calls admitInput under the tile's lock, the lock that then applies
// the input, for an input rendered on this rank and one from another rank alike: an operation
// never sees an input that does not fit its tile, its frame or its needs (InputNeeds).
#include "dfb/Tile.h"
#include "dfb/TileOperation.h"

namespace dfb {

// A tile as its owner holds it this frame.
struct TileState {
  Region region;
  InputNeeds needs;
  FrameInfo frame;  // the frame the tile was last begun in
  std::uint32_t accumulationId = 0;
  bool active = false;  // expects inputs this frame
  bool complete = false;
};

enum class Admission {
  Apply,  // the input fits: hand it to the operation
  Stale,  // it belongs to a frame this tile has left (a surplus input): drop it and count it
};

// Throws base::Error saying what is wrong with any input that is neither (a region that is not
// the tile's, a channel missing or of the wrong size, another epoch, a generation or children
// count out of bounds, another accumulation pass, weight 0, a tile that expects no more inputs).
// `label`: the frame the input says it belongs to (its message's header, or this rank's frame
// for setTile()).
Admission admitInput(const Tile& input, const FrameInfo& label, const TileState& tile);

}  // namespace dfb
