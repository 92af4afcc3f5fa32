#include "wall/PieceMessage.h"

#include <cstring>
#include <string>

#include "wall/Error.h"

namespace wall {

dfb::Bytes packPiece(std::uint32_t frameId, int display, const dfb::Region& local,
                     const std::uint32_t* source, int sourceWidth, int sourceX, int sourceY,
                     bool planeDelta) {
  const PieceHeader header{kPieceMagic, frameId,  display,  local.x0,
                           local.y0,    local.x1, local.y1, planeDelta ? 1u : 0u};
  const size_t rowBytes = static_cast<size_t>(local.width()) * 4;
  dfb::Bytes pixels(rowBytes * static_cast<size_t>(local.height()));
  for (int y = 0; y < local.height(); ++y)
    std::memcpy(pixels.data() + static_cast<size_t>(y) * rowBytes,
                source + static_cast<size_t>(sourceY + y) * static_cast<size_t>(sourceWidth) +
                    static_cast<size_t>(sourceX),
                rowBytes);
  dfb::Bytes out(sizeof header);
  std::memcpy(out.data(), &header, sizeof header);
  if (planeDelta) {
    dfb::Bytes filtered;
    dfb::planeDeltaEncode(pixels, 4, filtered);
    out.insert(out.end(), filtered.begin(), filtered.end());
  } else {
    out.insert(out.end(), pixels.begin(), pixels.end());
  }
  return out;
}

PieceHeader unpackPiece(const dfb::Bytes& bytes, std::vector<std::uint32_t>& pixels) {
  PieceHeader header;
  if (bytes.size() < sizeof header) throw Error("piece message shorter than its header");
  std::memcpy(&header, bytes.data(), sizeof header);
  const dfb::Region local{header.x0, header.y0, header.x1, header.y1};
  if (header.magic != kPieceMagic || local.empty())
    throw Error("malformed piece message (bad magic or empty rectangle)");
  const size_t count = static_cast<size_t>(local.pixelCount());
  if (bytes.size() != sizeof header + 4 * count)
    throw Error("piece message for display " + std::to_string(header.display) + " has " +
                std::to_string(bytes.size() - sizeof header) +
                " pixel bytes, its rectangle needs " + std::to_string(4 * count));
  const std::span<const std::byte> body(bytes.data() + sizeof header, 4 * count);
  pixels.resize(count);
  if (header.planeDelta) {
    dfb::Bytes decoded;
    dfb::planeDeltaDecode(body, 4, decoded);
    std::memcpy(pixels.data(), decoded.data(), decoded.size());
  } else {
    std::memcpy(pixels.data(), body.data(), body.size());
  }
  return header;
}

}  // namespace wall
