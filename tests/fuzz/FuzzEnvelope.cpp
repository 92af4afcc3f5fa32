// libFuzzer target: a whole wire buffer as another rank could send it (body + envelope trailer).
// Opening it either yields a payload of exactly the announced size or throws base::Error; a
// hostile size never allocates more than the limit; sealing the payload again and reopening it
// gives the same payload back.
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "base/Error.h"
#include "messaging/Envelope.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  constexpr std::size_t kLimit = std::size_t{1} << 20;
  const auto* bytes = reinterpret_cast<const std::byte*>(data);
  messaging::Bytes payload;
  messaging::Envelope envelope;
  try {
    envelope = messaging::openEnvelope(messaging::Bytes(bytes, bytes + size), kLimit, payload);
  } catch (const base::Error&) {
    return 0;
  }
  if (payload.size() != envelope.rawBytes || payload.size() > kLimit) std::abort();
  for (const bool compress : {false, true}) {
    messaging::Bytes again;
    const messaging::Envelope reopened = messaging::openEnvelope(
        messaging::sealEnvelope(payload, envelope.object, compress), kLimit, again);
    if (again != payload || reopened.object != envelope.object) std::abort();
  }
  return 0;
}
