// libFuzzer target: a piece of a display as it arrives on a wall rank.
#include <cstddef>
#include <cstdint>

#include "base/Error.h"
#include "wall/image/Image.h"
#include "wall/route/PieceMessage.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto* bytes = reinterpret_cast<const std::byte*>(data);
  const messaging::Bytes message(bytes, bytes + size);
  static wall::Image display(96, 64);
  try {
    const wall::PieceHeader header = wall::readPieceHeader(message);
    wall::copyPiece(message, header, display);
  } catch (const base::Error&) {
  }
  return 0;
}
