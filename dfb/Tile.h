#pragma once
// A tile: a rectangle of the image with its pixels, and where it sits in a tile operation's
// dependency tree (paper, listing 1). Sizes are dynamic: tiles at the image edge are partial.
#include <cstdint>
#include <vector>

namespace dfb {

// Half-open pixel rectangle [x0, x1) x [y0, y1) in image coordinates, y down.
struct Region {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  int width() const { return x1 - x0; }
  int height() const { return y1 - y0; }
  int pixelCount() const { return width() * height(); }
  bool empty() const { return x1 <= x0 || y1 <= y0; }
  bool operator==(const Region&) const = default;
};

Region intersect(const Region& a, const Region& b);

// Whether a region read from the wire is non-empty with sides of at most `maxSide` pixels,
// computed in 64 bits: width() and pixelCount() of an unchecked header can overflow an int.
bool isSaneRegion(const Region& r, int maxSide);

struct Tile {
  Region region;
  // Dependency tree (paper 3.1.1): this tile belongs to `generation` and announces `children`
  // tiles in generation + 1. A plain image-parallel tile is generation 0 with no children.
  int generation = 0;
  int children = 0;
  // Sample pass within the current accumulation epoch; the owner rejects a mismatch.
  std::uint32_t accumulationId = 0;
  // Redundant inputs of one tile are combined in ascending `sequence` order, each weighted by
  // `weight` (the samples per pixel behind it), so the result does not depend on arrival order.
  std::uint32_t sequence = 0;
  std::uint32_t weight = 1;
  // Fragments per pixel of a tile in a sort-last tree: a brick's samples of one frame travel
  // apart (color and depth hold `samples` blocks of the region's pixels, sample 0's first) and
  // are composited sample by sample, then averaged: a composite of per-brick means is not the
  // mean of the composites (it was 0.13 off along brick seams at 2 spp). 1: a plain tile.
  std::uint32_t samples = 1;

  std::vector<float> color;   // RGBA per pixel, row-major over the region; RGB linear radiance
  std::vector<float> depth;   // one per pixel; empty means "at infinity"
  std::vector<float> normal;  // optional, 3 per pixel
  std::vector<float> albedo;  // optional, 3 per pixel
  // Optional display pixels (sRGB RGBA8, R in the low byte) from a renderer that makes them
  // directly (the pattern): with them, color may be empty and the owner skips tone mapping.
  // Only the write operation takes such tiles; the pixels must be what tone mapping color with
  // the DFB's settings would give (dfb::toneMapPixel), so every path agrees bit for bit.
  std::vector<std::uint32_t> rgba8;

  // Sets the region and sizes color (and depth when `withDepth`) for it, zero-filled.
  void reset(const Region& r, bool withDepth = false);
  int pixelCount() const { return region.pixelCount(); }
};

// The most samples a tile may carry apart (Tile::samples): 16 RGBA-and-depth blocks of a 64²
// tile are 1.3 MB.
constexpr std::uint32_t kMaxTileSamples = 16;

// Which tiles an image of a given size has, at a given tile size.
class TileGrid {
 public:
  TileGrid(int width, int height, int tileSize);
  int width() const { return width_; }
  int height() const { return height_; }
  int tileSize() const { return tileSize_; }
  int tilesX() const { return tilesX_; }
  int tilesY() const { return tilesY_; }
  int tileCount() const { return tilesX_ * tilesY_; }
  Region region(int tileIndex) const;
  // The tile whose region starts at (x0, y0); -1 when that is no tile's origin.
  int indexOfOrigin(int x0, int y0) const;

 private:
  int width_, height_, tileSize_, tilesX_, tilesY_;
};

}  // namespace dfb
