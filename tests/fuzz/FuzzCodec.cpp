// libFuzzer target: a piece's pixel bytes as they arrive at a remote wall process, decoded with
// each codec of wall/service/protocol/Codec.h as a 64x64 rectangle into a buffer of exactly that
// size. Anything but a clean decode or a base::Error (a crash, a sanitizer report, another
// exception) is a finding. What decodes is decoded again into rows 72 pixels apart, the strided
// path. After each input a valid piece of each codec must still decode: one hostile piece must not
// break the thread's decoders (libjpeg-turbo 2.1's tjDecompressHeader3 did, see Codec.cpp). Seeds
// (tests/fuzz/corpus/codec/): encodePixels output for 64x64 pieces, one file per codec (raw, Snappy
// compressed and stored, JPEG at 4:2:0, 4:2:2 and 4:4:4).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "base/Error.h"
#include "wall/service/protocol/Codec.h"

namespace {

using wall::service::Codec;
constexpr int kSide = 64, kStride = 72;
constexpr Codec kCodecs[] = {Codec::Raw, Codec::Snappy, Codec::Jpeg};

// A valid piece of each codec, to decode after every input.
const std::vector<messaging::Bytes>& validPieces() {
  static const std::vector<messaging::Bytes> pieces = [] {
    std::vector<std::uint32_t> pixels(kSide * kSide);
    for (int i = 0; i < kSide * kSide; ++i)
      pixels[static_cast<std::size_t>(i)] =
          0xFF000000u | static_cast<std::uint32_t>(i * 2654435761u);
    std::vector<messaging::Bytes> out;
    for (const Codec codec : kCodecs) {
      out.emplace_back();
      wall::service::encodePixels(wall::service::CodecSpec{codec}, pixels.data(), kSide, kSide,
                                  kSide, out.back());
    }
    return out;
  }();
  return pieces;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // Exactly as large as the rectangle needs, so a write past it is a heap overflow ASan sees.
  static std::vector<std::uint32_t> packed(kSide * kSide);
  static std::vector<std::uint32_t> strided((kSide - 1) * kStride + kSide);
  const auto* bytes = reinterpret_cast<const std::byte*>(data);
  for (std::size_t c = 0; c < std::size(kCodecs); ++c) {
    try {
      wall::service::decodePixels(kCodecs[c], bytes, size, kSide, kSide, packed.data(), kSide);
      wall::service::decodePixels(kCodecs[c], bytes, size, kSide, kSide, strided.data(), kStride);
    } catch (const base::Error&) {
    }
    const messaging::Bytes& valid = validPieces()[c];
    try {
      wall::service::decodePixels(kCodecs[c], valid.data(), valid.size(), kSide, kSide,
                                  packed.data(), kSide);
    } catch (const base::Error&) {
      std::abort();  // the input left this thread unable to decode a valid piece
    }
  }
  return 0;
}
