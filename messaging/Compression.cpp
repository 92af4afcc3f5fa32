#include "messaging/Compression.h"

#include <snappy.h>

#include "base/Error.h"

namespace messaging {

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
    throw base::Error("corrupt compressed message: header says " + std::to_string(length) +
                      " bytes, expected " + std::to_string(rawSize));
  // No Snappy element yields more than 64 bytes from 3 (a 2-byte-offset copy), so a stream
  // announcing more than that ratio is corrupt and refused before its size is allocated. This
  // bound replaces Snappy's validator, a second walk over the stream that cost as much as the
  // decoding; the decoder itself checks every element against the buffers and fails cleanly.
  constexpr std::size_t kMaxRatio = 22;
  if (length > kMaxRatio * compressed.size())
    throw base::Error("corrupt compressed message: " + std::to_string(compressed.size()) +
                      " bytes cannot decode to the " + std::to_string(length) + " bytes announced");
  out.resize(rawSize);
  if (!snappy::RawUncompress(in, compressed.size(), reinterpret_cast<char*>(out.data())))
    throw base::Error("corrupt compressed message: Snappy could not decode it");
}

}  // namespace messaging
