#include "wall/route/PieceMessage.h"

#include <cstdint>
#include <cstring>
#include <string>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "base/Error.h"
#include "wall/layout/Layout.h"

namespace wall {
namespace {

// A display image is megabytes that the next draw reads from memory anyway: rows go there with
// non-temporal stores, which skip reading each destination line into the cache first (a third
// of a cached copy's memory traffic). Unaligned rows take memcpy.
void copyRowStreaming(void* to, const std::byte* from, size_t bytes) {
#if defined(__SSE2__)
  if (reinterpret_cast<std::uintptr_t>(to) % 16 == 0 && bytes % 16 == 0) {
    auto* out = static_cast<__m128i*>(to);
    for (size_t i = 0; i < bytes / 16; ++i)
      _mm_stream_si128(out + i, _mm_loadu_si128(reinterpret_cast<const __m128i*>(from) + i));
    return;
  }
#endif
  std::memcpy(to, from, bytes);
}

}  // namespace

messaging::Bytes packPiece(std::uint32_t frameId, int display, const dfb::Region& local,
                           const std::uint32_t* source, int sourceWidth, int sourceX, int sourceY,
                           bool planeDelta) {
  const PieceHeader header{kPieceMagic, frameId,  display,  local.x0,
                           local.y0,    local.x1, local.y1, planeDelta ? 1u : 0u};
  const size_t rowBytes = static_cast<size_t>(local.width()) * 4;
  const size_t pixelBytes = rowBytes * static_cast<size_t>(local.height());
  messaging::Bytes out;
  out.reserve(sizeof header + pixelBytes + messaging::Messenger::kSpareCapacity);
  out.resize(sizeof header + pixelBytes);
  std::memcpy(out.data(), &header, sizeof header);
  std::byte* pixels = out.data() + sizeof header;
  const auto row = [&](int y) {
    return reinterpret_cast<const std::byte*>(
        source + static_cast<size_t>(sourceY + y) * static_cast<size_t>(sourceWidth) +
        static_cast<size_t>(sourceX));
  };
  if (!planeDelta) {
    for (int y = 0; y < local.height(); ++y)
      std::memcpy(pixels + static_cast<size_t>(y) * rowBytes, row(y), rowBytes);
    return out;
  }
  // The filter (only where Snappy follows: it makes smooth 8-bit pixels compressible) reads the
  // piece's pixels in one run: the tile's own rows when the piece is as wide as the tile (most
  // are), else the rows gathered into this thread's scratch buffer first.
  const std::byte* run = row(0);
  if (local.width() != sourceWidth) {
    thread_local messaging::Bytes scratch;
    scratch.resize(pixelBytes);
    for (int y = 0; y < local.height(); ++y)
      std::memcpy(scratch.data() + static_cast<size_t>(y) * rowBytes, row(y), rowBytes);
    run = scratch.data();
  }
  messaging::planeDeltaEncode(std::span<const std::byte>(run, pixelBytes), 4, pixels);
  return out;
}

PieceHeader readPieceHeader(const messaging::Bytes& bytes) {
  PieceHeader header;
  if (bytes.size() < sizeof header) throw base::Error("piece message shorter than its header");
  std::memcpy(&header, bytes.data(), sizeof header);
  const dfb::Region local{header.x0, header.y0, header.x1, header.y1};
  // Checked in 64 bits before width() or pixelCount() is used: the fuzzer found rectangles
  // whose int product overflowed (and could then match the message size).
  if (header.magic != kPieceMagic || !dfb::isSaneRegion(local, kMaxCanvasSide))
    throw base::Error("malformed piece message (bad magic, or an empty or oversized rectangle)");
  // Sides of up to 2^20 make a product past an int: the count is taken in 64 bits.
  const size_t count = static_cast<size_t>(local.width()) * static_cast<size_t>(local.height());
  if (bytes.size() != sizeof header + 4 * count)
    throw base::Error("piece message for display " + std::to_string(header.display) + " has " +
                      std::to_string(bytes.size() - sizeof header) +
                      " pixel bytes, its rectangle needs " + std::to_string(4 * count));
  return header;
}

void copyPiece(const messaging::Bytes& bytes, const PieceHeader& header, Image& display) {
  const dfb::Region local{header.x0, header.y0, header.x1, header.y1};
  if (local.x0 < 0 || local.y0 < 0 || local.x1 > display.width || local.y1 > display.height)
    throw base::Error("piece [" + std::to_string(local.x0) + ", " + std::to_string(local.x1) +
                      ") x [" + std::to_string(local.y0) + ", " + std::to_string(local.y1) +
                      ") lies outside its display of " + std::to_string(display.width) + "x" +
                      std::to_string(display.height));
  const std::span<const std::byte> body(bytes.data() + sizeof header,
                                        4 * static_cast<size_t>(local.pixelCount()));
  const std::byte* pixels = body.data();
  if (header.planeDelta) {  // into this thread's scratch buffer, then row by row as unfiltered
    thread_local messaging::Bytes decoded;
    decoded.resize(body.size());
    messaging::planeDeltaDecode(body, 4, decoded.data());
    pixels = decoded.data();
  }
  const size_t rowBytes = 4 * static_cast<size_t>(local.width());
  for (int y = 0; y < local.height(); ++y)
    copyRowStreaming(&display.at(local.x0, local.y0 + y),
                     pixels + static_cast<size_t>(y) * rowBytes, rowBytes);
#if defined(__SSE2__)
  _mm_sfence();  // the streamed rows are visible before the piece is counted (under a lock)
#endif
}

}  // namespace wall
