#include "wall/PieceMessage.h"

#include <cstring>
#include <string>

#include "wall/Error.h"
#include "wall/Layout.h"

namespace wall {

dfb::Bytes packPiece(std::uint32_t frameId, int display, const dfb::Region& local,
                     const std::uint32_t* source, int sourceWidth, int sourceX, int sourceY,
                     bool planeDelta) {
  const PieceHeader header{kPieceMagic, frameId,  display,  local.x0,
                           local.y0,    local.x1, local.y1, planeDelta ? 1u : 0u};
  const size_t rowBytes = static_cast<size_t>(local.width()) * 4;
  const size_t pixelBytes = rowBytes * static_cast<size_t>(local.height());
  dfb::Bytes out;
  out.reserve(sizeof header + pixelBytes + dfb::Messenger::kSpareCapacity);
  out.resize(sizeof header + pixelBytes);
  std::memcpy(out.data(), &header, sizeof header);
  std::byte* pixels = out.data() + sizeof header;
  for (int y = 0; y < local.height(); ++y)
    std::memcpy(pixels + static_cast<size_t>(y) * rowBytes,
                source + static_cast<size_t>(sourceY + y) * static_cast<size_t>(sourceWidth) +
                    static_cast<size_t>(sourceX),
                rowBytes);
  if (planeDelta) {  // only where Snappy follows: it makes smooth 8-bit pixels compressible
    dfb::Bytes filtered;
    dfb::planeDeltaEncode(std::span<const std::byte>(pixels, pixelBytes), 4, filtered);
    std::memcpy(pixels, filtered.data(), pixelBytes);
  }
  return out;
}

PieceHeader readPieceHeader(const dfb::Bytes& bytes) {
  PieceHeader header;
  if (bytes.size() < sizeof header) throw Error("piece message shorter than its header");
  std::memcpy(&header, bytes.data(), sizeof header);
  const dfb::Region local{header.x0, header.y0, header.x1, header.y1};
  // Checked in 64 bits before width() or pixelCount() is used: the fuzzer found rectangles
  // whose int product overflowed (and could then match the message size).
  if (header.magic != kPieceMagic || !dfb::isSaneRegion(local, kMaxCanvasSide))
    throw Error("malformed piece message (bad magic, or an empty or oversized rectangle)");
  // Sides of up to 2^20 make a product past an int: the count is taken in 64 bits.
  const size_t count = static_cast<size_t>(local.width()) * static_cast<size_t>(local.height());
  if (bytes.size() != sizeof header + 4 * count)
    throw Error("piece message for display " + std::to_string(header.display) + " has " +
                std::to_string(bytes.size() - sizeof header) +
                " pixel bytes, its rectangle needs " + std::to_string(4 * count));
  return header;
}

void copyPiece(const dfb::Bytes& bytes, const PieceHeader& header, Image& display) {
  const dfb::Region local{header.x0, header.y0, header.x1, header.y1};
  if (local.x0 < 0 || local.y0 < 0 || local.x1 > display.width || local.y1 > display.height)
    throw Error("piece [" + std::to_string(local.x0) + ", " + std::to_string(local.x1) + ") x [" +
                std::to_string(local.y0) + ", " + std::to_string(local.y1) +
                ") lies outside its display of " + std::to_string(display.width) + "x" +
                std::to_string(display.height));
  const std::span<const std::byte> body(bytes.data() + sizeof header,
                                        4 * static_cast<size_t>(local.pixelCount()));
  dfb::Bytes decoded;
  const std::byte* pixels = body.data();
  if (header.planeDelta) {
    dfb::planeDeltaDecode(body, 4, decoded);
    pixels = decoded.data();
  }
  const size_t rowBytes = 4 * static_cast<size_t>(local.width());
  for (int y = 0; y < local.height(); ++y)
    std::memcpy(&display.at(local.x0, local.y0 + y), pixels + static_cast<size_t>(y) * rowBytes,
                rowBytes);
}

}  // namespace wall
