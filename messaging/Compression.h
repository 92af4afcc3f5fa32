#pragma once
// Payload compression for the wire: Snappy, skipped under a minimum size or when it would not
// shrink the data, plus a byte-plane + delta pre-filter that makes 8-bit pixels compressible
// (Snappy alone measured 1.00x on RGBA8 tiles, the filter first ~10x on smooth ones).
#include <cstddef>
#include <span>
#include <vector>

namespace messaging {

using Bytes = std::vector<std::byte>;

// Snappy-compresses `raw` into `out`; returns false (and leaves `out` empty) when the result
// would not be smaller than `raw`.
bool compressIfSmaller(std::span<const std::byte> raw, Bytes& out);
// Inverse of compressIfSmaller; throws base::Error on corrupt input or a size mismatch.
void decompress(std::span<const std::byte> compressed, std::size_t rawSize, Bytes& out);

// Reorders interleaved `channels`-byte pixels into planes (all R, all G, ...) and replaces each
// byte by its difference from the previous one in its plane. Lossless; size unchanged.
// (messaging/PlaneDelta.cpp; SSSE3 for 4 channels where the CPU has it, same bytes.)
void planeDeltaEncode(std::span<const std::byte> pixels, int channels, Bytes& out);
void planeDeltaDecode(std::span<const std::byte> encoded, int channels, Bytes& out);
// The same into `out`, which holds as many bytes as the input (no allocation; not overlapping).
void planeDeltaEncode(std::span<const std::byte> pixels, int channels, std::byte* out);
void planeDeltaDecode(std::span<const std::byte> encoded, int channels, std::byte* out);

}  // namespace messaging
