#pragma once
// The wire format of a tile input travelling to its owner: a fixed header that names the frame,
// the accumulation epoch and pass, the tile and its place in the dependency tree, followed by
// the channels the header's flags announce (color always; depth, normal, albedo optional).
#include <cstdint>

#include "dfb/Tile.h"
#include "messaging/Compression.h"

namespace dfb {

struct TileMessageHeader {
  std::uint32_t magic;
  std::uint32_t frameId;
  std::uint32_t epoch;
  std::uint32_t accumulationId;
  std::int32_t tileIndex;
  std::int32_t x0, y0, x1, y1;
  std::int32_t generation, children;
  std::uint32_t sequence, weight;
  std::uint32_t channels;  // kHasDepth | kHasNormal | kHasAlbedo | kHasRgba8 | kNoColor
  std::uint32_t payloadBytes;
  std::uint32_t samples;  // Tile::samples: color and depth hold that many blocks
};
static_assert(sizeof(TileMessageHeader) == 64, "the tile header is part of the protocol");

constexpr std::uint32_t kTileMagic = 0x54494C45;  // "TILE"
constexpr std::uint32_t kHasDepth = 1, kHasNormal = 2, kHasAlbedo = 4;
// Display pixels after the float channels; with kNoColor, no color floats (RGBA8 only).
constexpr std::uint32_t kHasRgba8 = 8, kNoColor = 16;

messaging::Bytes packTile(const Tile& tile, int tileIndex, std::uint32_t frameId,
                          std::uint32_t epoch);
// Throws base::Error when the bytes are not a well-formed tile message.
Tile unpackTile(const messaging::Bytes& bytes, TileMessageHeader& header);

}  // namespace dfb
