// libFuzzer target: tile messages past the parser, through the DFB's door (dfb/TileDoor.h) into
// each tile operation, as a tile owner takes them. The input picks the operation and how many
// inputs each tile expects, then carries records (a 16-bit length and a tile message); an empty
// record begins the next frame (the next accumulation pass of the same epoch). A message that
// unpacks goes to its tile's state exactly as the DFB holds it; what the door admits, the
// operation takes. Whatever the bytes, a completed tile has the colour its readers (tone
// mapping, the float gather) read, or the display pixels that stand in for it.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <vector>

#include "base/Error.h"
#include "dfb/PixelOp.h"
#include "dfb/TileDoor.h"
#include "dfb/TileMessage.h"
#include "dfb/TileOperation.h"

namespace {

// A small image, so messages are small: tiles of 8x8, 4x8, 8x2 and 4x2 pixels.
constexpr int kWidth = 12, kHeight = 10, kTileSize = 8;
constexpr std::uint32_t kFirstFrame = 5, kEpoch = 2;

struct OwnedTile {
  std::unique_ptr<dfb::TileOperation> operation;
  dfb::TileState state;
};

// What the DFB does with a completed tile: tone map it (reads color unless display pixels came)
// and, for the float gather, read its color.
void finish(OwnedTile& tile, bool floatGather) {
  const dfb::Tile& done = tile.operation->finished();
  const size_t n = static_cast<size_t>(tile.state.region.pixelCount());
  const bool pixels = done.rgba8.size() == n;
  if (done.color.size() != 4 * n && !pixels) std::abort();  // a reader would overrun
  if (floatGather && done.color.size() != 4 * n) std::abort();
  dfb::FinishedTile finished;
  finished.region = tile.state.region;
  finished.linear = &done;
  std::vector<std::uint32_t> rgba8;
  finished.rgba8 = &rgba8;
  if (!pixels) dfb::ToneMapOp().process(finished);
  volatile float sink = tile.operation->error();
  (void)sink;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  const dfb::TileOperationFactory factories[] = {
      dfb::accumulateOperation(), dfb::alphaBlendOperation(), dfb::compositeAccumulateOperation(),
      dfb::writeOperation()};
  const int which = data[0] % 4;
  const bool floatGather = data[0] & 4;
  const int expected = data[1] % 5;  // 0: tiles nobody renders
  const dfb::TileGrid grid(kWidth, kHeight, kTileSize);
  std::vector<OwnedTile> tiles(static_cast<size_t>(grid.tileCount()));

  std::uint32_t frame = kFirstFrame, pass = 0;
  auto begin = [&] {
    for (int t = 0; t < grid.tileCount(); ++t) {
      OwnedTile& tile = tiles[static_cast<size_t>(t)];
      dfb::TileState& s = tile.state;
      s.frame = {frame, kEpoch};
      s.accumulationId = pass;
      s.active = expected > 0;
      s.complete = !s.active;
      if (!s.active) continue;
      if (!tile.operation) {
        s.region = grid.region(t);
        tile.operation = factories[which](s.region);
        s.needs = tile.operation->needs();
        if (floatGather) s.needs.displayPixelsForColor = false;
      }
      tile.operation->newFrame(s.frame, pass, expected);
    }
  };
  begin();

  size_t at = 2;
  while (at + 2 <= size) {
    std::uint16_t length;
    std::memcpy(&length, data + at, sizeof length);
    at += sizeof length;
    if (length == 0) {
      ++frame, ++pass;
      begin();
      continue;
    }
    if (length > size - at) break;
    const auto* bytes = reinterpret_cast<const std::byte*>(data + at);
    const messaging::Bytes message(bytes, bytes + length);
    at += length;
    dfb::TileMessageHeader header;
    dfb::Tile input;
    try {
      input = dfb::unpackTile(message, header);
    } catch (const base::Error&) {
      continue;
    }
    if (header.tileIndex < 0 || header.tileIndex >= grid.tileCount()) continue;  // not owned
    OwnedTile& tile = tiles[static_cast<size_t>(header.tileIndex)];
    try {
      if (dfb::admitInput(input, {header.frameId, header.epoch}, tile.state) ==
          dfb::Admission::Stale)
        continue;
      if (tile.operation->process(std::move(input))) {
        tile.state.complete = true;
        finish(tile, floatGather);
      }
    } catch (const base::Error&) {
    }
  }
  return 0;
}
