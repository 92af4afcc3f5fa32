// libFuzzer target: a piece batch as it arrives on a wall process's piece socket
// (wall/service/protocol/Protocol.h, wall/service/protocol/Codec.h). The batch is parsed, then
// every piece of at most 256x256 pixels is decoded into a buffer of exactly its size, as the piece
// receiver does into a display image. Any bytes are accepted or refused with a base::Error
// (anything else escapes and is a crash); nothing is read or written out of bounds; a lossless
// piece that decoded encodes and decodes back to the same pixels.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <vector>

#include "base/Error.h"
#include "wall/service/protocol/Codec.h"
#include "wall/service/protocol/Protocol.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* raw, std::size_t size) {
  using namespace wall::service;
  constexpr int kMaxDecodedSide = 256;
  const auto* data = reinterpret_cast<const std::byte*>(raw);
  try {
    parseHeader(data, size);
  } catch (const base::Error&) {
  }
  std::vector<BatchPiece> pieces;
  BatchHeader header;
  try {
    header = parseBatch(data, size, pieces);
  } catch (const base::Error&) {
    return 0;
  }
  if (pieces.size() != header.pieceCount) std::abort();
  for (const BatchPiece& piece : pieces) {
    if (!dfb::isSaneRegion(piece.local, 4096) || piece.local.x0 < 0 || piece.local.y0 < 0 ||
        piece.data < data || piece.size > size || piece.data + piece.size > data + size)
      std::abort();  // a piece past the parser's promises
    const int width = piece.local.width(), height = piece.local.height();
    if (width > kMaxDecodedSide || height > kMaxDecodedSide) continue;
    const std::size_t pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    // Exactly the piece's size, so ASan sees a write past it.
    const std::unique_ptr<std::uint32_t[]> dest(new std::uint32_t[pixels]);
    try {
      decodePixels(header.codec, piece.data, piece.size, width, height, dest.get(), width);
    } catch (const base::Error&) {
      continue;
    }
    if (header.codec == Codec::Jpeg) continue;
    messaging::Bytes again;
    encodePixels(CodecSpec{header.codec}, dest.get(), width, height, width, again);
    const std::unique_ptr<std::uint32_t[]> back(new std::uint32_t[pixels]);
    decodePixels(header.codec, again.data(), again.size(), width, height, back.get(), width);
    for (std::size_t i = 0; i < pixels; ++i)
      if (back[i] != dest[i]) std::abort();  // a lossless codec that is not
  }
  return 0;
}
