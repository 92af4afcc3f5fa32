#include "dfb/TileDoor.h"

#include <string>

#include "base/Error.h"

namespace dfb {
namespace {

std::string describe(const Region& r) {
  return "[" + std::to_string(r.x0) + ", " + std::to_string(r.x1) + ") x [" + std::to_string(r.y0) +
         ", " + std::to_string(r.y1) + ")";
}

// An optional channel: absent, or `perPixel` values for each of `pixels`.
void checkOptional(const char* name, size_t size, size_t perPixel, size_t pixels) {
  if (size != 0 && size != perPixel * pixels)
    throw base::Error(std::string(name) + " has " + std::to_string(size) +
                      " values, the tile needs " + std::to_string(perPixel * pixels) + " (" +
                      std::to_string(perPixel) + " per pixel) or none");
}

}  // namespace

Admission admitInput(const Tile& input, const FrameInfo& label, const TileState& tile) {
  // The frame first: a surplus input of a frame this tile has left is no error of the input.
  if (label.frameId < tile.frame.frameId) return Admission::Stale;
  if (label.frameId > tile.frame.frameId)
    throw base::Error("input for frame " + std::to_string(label.frameId) +
                      ", but the tile is in frame " + std::to_string(tile.frame.frameId));
  if (label.epoch != tile.frame.epoch)
    throw base::Error("input of accumulation epoch " + std::to_string(label.epoch) +
                      ", but frame " + std::to_string(tile.frame.frameId) + " is epoch " +
                      std::to_string(tile.frame.epoch));
  if (!tile.active) throw base::Error("input though the tile expects none this frame");
  if (tile.complete) throw base::Error("input after the tile was complete");

  if (input.region != tile.region)
    throw base::Error("input region " + describe(input.region) + " is not the tile's " +
                      describe(tile.region));
  if (input.samples < 1 || input.samples > kMaxTileSamples)
    throw base::Error("input carries " + std::to_string(input.samples) + " samples apart (1 to " +
                      std::to_string(kMaxTileSamples) + ")");
  if (input.samples > 1 && !tile.needs.tree)
    throw base::Error("input carries " + std::to_string(input.samples) +
                      " samples apart, but this tile operation composites no tree (1 only)");
  if (input.samples > 1 && (!input.normal.empty() || !input.albedo.empty() || !input.rgba8.empty()))
    throw base::Error(
        "input carries " + std::to_string(input.samples) +
        " samples apart with normals, albedo or display pixels (color and depth only)");
  const size_t samples = input.samples;
  const size_t n = static_cast<size_t>(tile.region.pixelCount());
  const bool pixelsForColor =
      tile.needs.displayPixelsForColor && input.color.empty() && input.rgba8.size() == n;
  if (input.color.size() != 4 * n * samples && !pixelsForColor)
    throw base::Error(
        "color has " + std::to_string(input.color.size()) + " floats, the tile needs " +
        std::to_string(4 * n * samples) + " (4 per pixel and sample)" +
        (tile.needs.displayPixelsForColor ? " or display pixels instead (" + std::to_string(n) + ")"
                                          : std::string()));
  checkOptional("depth", input.depth.size(), samples, n);
  checkOptional("normal", input.normal.size(), 3, n);
  checkOptional("albedo", input.albedo.size(), 3, n);
  checkOptional("display pixels", input.rgba8.size(), 1, n);

  if (tile.needs.tree) {
    if (input.generation < 0 || input.generation > kMaxGeneration)
      throw base::Error("generation " + std::to_string(input.generation) + " is outside [0, " +
                        std::to_string(kMaxGeneration) + "]");
    if (input.children < 0 || input.children > kMaxChildren)
      throw base::Error("children count " + std::to_string(input.children) + " is outside [0, " +
                        std::to_string(kMaxChildren) + "]");
  } else if (input.generation != 0 || input.children != 0) {
    throw base::Error(
        "generation " + std::to_string(input.generation) + " with " +
        std::to_string(input.children) +
        " children, but this tile operation takes no dependency tree (both must be 0)");
  }
  if (tile.needs.accumulation) {
    if (input.accumulationId != tile.accumulationId)
      throw base::Error("input for accumulation pass " + std::to_string(input.accumulationId) +
                        ", but this frame is pass " + std::to_string(tile.accumulationId));
    if (input.weight == 0) throw base::Error("input with weight 0");
  }
  return Admission::Apply;
}

}  // namespace dfb
