// libFuzzer target: a tile input as it arrives from another rank.
#include <cstddef>
#include <cstdint>

#include "base/Error.h"
#include "dfb/TileMessage.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto* bytes = reinterpret_cast<const std::byte*>(data);
  const messaging::Bytes message(bytes, bytes + size);
  dfb::TileMessageHeader header;
  try {
    (void)dfb::unpackTile(message, header);
  } catch (const base::Error&) {
  }
  return 0;
}
