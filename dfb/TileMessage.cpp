#include "dfb/TileMessage.h"

#include <cstring>
#include <string>

#include "base/Error.h"
#include "messaging/Messenger.h"

namespace dfb {
namespace {

void append(messaging::Bytes& out, size_t& at, const std::vector<float>& channel) {
  std::memcpy(out.data() + at, channel.data(), channel.size() * sizeof(float));
  at += channel.size() * sizeof(float);
}

void take(const messaging::Bytes& in, size_t& at, std::vector<float>& channel, size_t count) {
  channel.resize(count);
  std::memcpy(channel.data(), in.data() + at, count * sizeof(float));
  at += count * sizeof(float);
}

}  // namespace

messaging::Bytes packTile(const Tile& tile, int tileIndex, std::uint32_t frameId,
                          std::uint32_t epoch) {
  const size_t n = static_cast<size_t>(tile.pixelCount());
  const bool rgba8 = !tile.rgba8.empty();
  if (rgba8 && tile.rgba8.size() != n)
    throw base::Error("tile " + std::to_string(tileIndex) + " has " +
                      std::to_string(tile.rgba8.size()) + " RGBA8 pixels for " + std::to_string(n) +
                      " pixels");
  const size_t samples = tile.samples;
  if (samples < 1 || samples > kMaxTileSamples || (samples > 1 && rgba8))
    throw base::Error("tile " + std::to_string(tileIndex) + " carries " + std::to_string(samples) +
                      " samples apart (1 to " + std::to_string(kMaxTileSamples) +
                      ", and 1 with RGBA8 pixels)");
  if (tile.color.size() != 4 * n * samples && !(rgba8 && tile.color.empty()))
    throw base::Error("tile " + std::to_string(tileIndex) + " has " +
                      std::to_string(tile.color.size()) + " color floats for " + std::to_string(n) +
                      " pixels");
  TileMessageHeader header{};
  header.magic = kTileMagic;
  header.frameId = frameId;
  header.epoch = epoch;
  header.accumulationId = tile.accumulationId;
  header.tileIndex = tileIndex;
  header.x0 = tile.region.x0;
  header.y0 = tile.region.y0;
  header.x1 = tile.region.x1;
  header.y1 = tile.region.y1;
  header.generation = tile.generation;
  header.children = tile.children;
  header.sequence = tile.sequence;
  header.weight = tile.weight;
  header.samples = tile.samples;
  size_t floats = tile.color.empty() ? 0 : 4 * n * samples;
  if (tile.color.empty()) header.channels |= kNoColor;
  if (tile.depth.size() == n * samples) header.channels |= kHasDepth, floats += n * samples;
  if (tile.normal.size() == 3 * n) header.channels |= kHasNormal, floats += 3 * n;
  if (tile.albedo.size() == 3 * n) header.channels |= kHasAlbedo, floats += 3 * n;
  if (rgba8) header.channels |= kHasRgba8;
  header.payloadBytes =
      static_cast<std::uint32_t>(floats * sizeof(float) + (rgba8 ? n * sizeof(std::uint32_t) : 0));

  messaging::Bytes out;
  out.reserve(sizeof header + header.payloadBytes + messaging::Messenger::kSpareCapacity);
  out.resize(sizeof header + header.payloadBytes);
  std::memcpy(out.data(), &header, sizeof header);
  size_t at = sizeof header;
  if (!tile.color.empty()) append(out, at, tile.color);  // memcpy from null is undefined
  if (header.channels & kHasDepth) append(out, at, tile.depth);
  if (header.channels & kHasNormal) append(out, at, tile.normal);
  if (header.channels & kHasAlbedo) append(out, at, tile.albedo);
  if (rgba8) std::memcpy(out.data() + at, tile.rgba8.data(), n * sizeof(std::uint32_t));
  return out;
}

Tile unpackTile(const messaging::Bytes& bytes, TileMessageHeader& header) {
  if (bytes.size() < sizeof header)
    throw base::Error("tile message of " + std::to_string(bytes.size()) +
                      " bytes is shorter than its header");
  std::memcpy(&header, bytes.data(), sizeof header);
  if (header.magic != kTileMagic) throw base::Error("message is not a tile (bad magic)");
  Tile tile;
  tile.region = Region{header.x0, header.y0, header.x1, header.y1};
  tile.generation = header.generation;
  tile.children = header.children;
  tile.accumulationId = header.accumulationId;
  tile.sequence = header.sequence;
  tile.weight = header.weight;
  // Tiles are at most 1024 pixels a side (the --tile-size cap); the fuzzer found headers whose
  // width times height overflowed an int before this check.
  constexpr int kMaxTileSide = 4096;
  if (!isSaneRegion(tile.region, kMaxTileSide))
    throw base::Error("tile message for tile " + std::to_string(header.tileIndex) +
                      " has an empty or oversized region");
  const size_t n = static_cast<size_t>(tile.region.pixelCount());
  const bool noColor = header.channels & kNoColor, rgba8 = header.channels & kHasRgba8;
  if (noColor && !rgba8)
    throw base::Error("tile message for tile " + std::to_string(header.tileIndex) +
                      " has neither color nor RGBA8 pixels");
  const size_t samples = header.samples;
  if (samples < 1 || samples > kMaxTileSamples ||
      (samples > 1 && (rgba8 || (header.channels & (kHasNormal | kHasAlbedo)))))
    throw base::Error("tile message for tile " + std::to_string(header.tileIndex) + " carries " +
                      std::to_string(samples) + " samples apart (1 to " +
                      std::to_string(kMaxTileSamples) + ", and 1 with normals, albedo or RGBA8)");
  tile.samples = header.samples;
  size_t floats = noColor ? 0 : 4 * n * samples;
  if (header.channels & kHasDepth) floats += n * samples;
  if (header.channels & kHasNormal) floats += 3 * n;
  if (header.channels & kHasAlbedo) floats += 3 * n;
  const size_t payload = floats * sizeof(float) + (rgba8 ? n * sizeof(std::uint32_t) : 0);
  if (header.payloadBytes != payload || bytes.size() != sizeof header + header.payloadBytes)
    throw base::Error("tile message for tile " + std::to_string(header.tileIndex) + " has " +
                      std::to_string(bytes.size() - sizeof header) +
                      " payload bytes, its header implies " + std::to_string(payload));
  size_t at = sizeof header;
  if (!noColor) take(bytes, at, tile.color, 4 * n * samples);
  if (header.channels & kHasDepth) take(bytes, at, tile.depth, n * samples);
  if (header.channels & kHasNormal) take(bytes, at, tile.normal, 3 * n);
  if (header.channels & kHasAlbedo) take(bytes, at, tile.albedo, 3 * n);
  if (rgba8) {
    tile.rgba8.resize(n);
    std::memcpy(tile.rgba8.data(), bytes.data() + at, n * sizeof(std::uint32_t));
  }
  return tile;
}

}  // namespace dfb
