#include "dfb/Compression.h"

#include <snappy.h>

#include "dfb/Error.h"

namespace dfb {

bool compressIfSmaller(std::span<const std::byte> raw, Bytes& out) {
  out.resize(snappy::MaxCompressedLength(raw.size()));
  size_t written = 0;
  snappy::RawCompress(reinterpret_cast<const char*>(raw.data()), raw.size(),
                      reinterpret_cast<char*>(out.data()), &written);
  if (written >= raw.size()) {
    out.clear();
    return false;
  }
  out.resize(written);
  return true;
}

void decompress(std::span<const std::byte> compressed, std::size_t rawSize, Bytes& out) {
  const char* in = reinterpret_cast<const char*>(compressed.data());
  size_t length = 0;
  if (!snappy::GetUncompressedLength(in, compressed.size(), &length) || length != rawSize)
    throw Error("corrupt compressed message: header says " + std::to_string(length) +
                " bytes, expected " + std::to_string(rawSize));
  // Snappy's validator walks the whole stream without writing: a stream that cannot produce
  // `length` bytes is refused before that much memory is allocated for it.
  if (!snappy::IsValidCompressedBuffer(in, compressed.size()))
    throw Error("corrupt compressed message: Snappy's validator rejects it");
  out.resize(rawSize);
  if (!snappy::RawUncompress(in, compressed.size(), reinterpret_cast<char*>(out.data())))
    throw Error("corrupt compressed message: Snappy could not decode it");
}

void planeDeltaEncode(std::span<const std::byte> pixels, int channels, Bytes& out) {
  const size_t count = pixels.size() / static_cast<size_t>(channels);
  out.resize(pixels.size());
  for (int c = 0; c < channels; ++c) {
    unsigned char previous = 0;
    std::byte* plane = out.data() + static_cast<size_t>(c) * count;
    for (size_t i = 0; i < count; ++i) {
      const auto value = static_cast<unsigned char>(
          pixels[i * static_cast<size_t>(channels) + static_cast<size_t>(c)]);
      plane[i] = static_cast<std::byte>(static_cast<unsigned char>(value - previous));
      previous = value;
    }
  }
}

void planeDeltaDecode(std::span<const std::byte> encoded, int channels, Bytes& out) {
  const size_t count = encoded.size() / static_cast<size_t>(channels);
  out.resize(encoded.size());
  for (int c = 0; c < channels; ++c) {
    unsigned char previous = 0;
    const std::byte* plane = encoded.data() + static_cast<size_t>(c) * count;
    for (size_t i = 0; i < count; ++i) {
      previous = static_cast<unsigned char>(previous + static_cast<unsigned char>(plane[i]));
      out[i * static_cast<size_t>(channels) + static_cast<size_t>(c)] =
          static_cast<std::byte>(previous);
    }
  }
}

}  // namespace dfb
