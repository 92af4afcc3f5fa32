// libFuzzer target: a compressed message body and the size its envelope announces (the first 4
// bytes): corrupt input is a base::Error, and nothing is allocated for a size the stream cannot
// produce.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

#include "base/Error.h"
#include "messaging/Compression.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 4) return 0;
  std::uint32_t rawSize = 0;
  std::memcpy(&rawSize, data, 4);
  messaging::Bytes out;
  try {
    messaging::decompress(std::span(reinterpret_cast<const std::byte*>(data) + 4, size - 4),
                          rawSize, out);
    messaging::Bytes back;
    if (!out.empty()) messaging::planeDeltaDecode(out, 4, back);
  } catch (const base::Error&) {
  }
  return 0;
}
