#include "messaging/Envelope.h"

#include <algorithm>
#include <cstring>
#include <span>
#include <string>

#include "base/Error.h"
#include "messaging/Compression.h"

namespace messaging {
namespace {

constexpr std::uint32_t kCompressed = 1;
constexpr std::uint32_t kKnownFlags = kCompressed;

struct WireTrailer {
  std::uint64_t object;
  std::uint32_t rawBytes;
  std::uint32_t flags;
};
static_assert(sizeof(WireTrailer) == kEnvelopeBytes, "the envelope is part of the protocol");

}  // namespace

void checkPayloadSize(std::size_t payloadBytes, std::size_t maxPayloadBytes,
                      const std::string& what) {
  const std::size_t limit = std::min(maxPayloadBytes, kLargestPayload);
  if (payloadBytes > limit)
    throw base::Error(what + " of " + std::to_string(payloadBytes) +
                      " bytes, more than the limit of " + std::to_string(limit));
}

Bytes sealEnvelope(Bytes payload, ObjectId object, bool compress, bool* compressed) {
  checkPayloadSize(payload.size(), kLargestPayload,
                   "message to object id " + std::to_string(object));
  WireTrailer trailer{object, static_cast<std::uint32_t>(payload.size()), 0};
  Bytes wire;
  if (compress && compressIfSmaller(payload, wire))
    trailer.flags |= kCompressed;
  else
    wire = std::move(payload);
  if (compressed) *compressed = trailer.flags & kCompressed;
  const size_t bodyBytes = wire.size();
  wire.resize(bodyBytes + sizeof trailer);
  std::memcpy(wire.data() + bodyBytes, &trailer, sizeof trailer);
  return wire;
}

Envelope peekEnvelope(const Bytes& wire) {
  WireTrailer trailer;
  if (wire.size() < sizeof trailer)
    throw base::Error("truncated message of " + std::to_string(wire.size()) + " bytes");
  std::memcpy(&trailer, wire.data() + wire.size() - sizeof trailer, sizeof trailer);
  return Envelope{trailer.object, trailer.rawBytes, trailer.flags};
}

Envelope openEnvelope(Bytes&& wire, std::size_t maxPayloadBytes, Bytes& payload) {
  const Envelope envelope = peekEnvelope(wire);
  const std::string what = "message to object id " + std::to_string(envelope.object);
  if (envelope.flags & ~kKnownFlags)
    throw base::Error(what + " has unknown flags " + std::to_string(envelope.flags));
  checkPayloadSize(envelope.rawBytes, maxPayloadBytes, what);
  const size_t bodyBytes = wire.size() - kEnvelopeBytes;
  if (envelope.flags & kCompressed) {
    decompress(std::span<const std::byte>(wire.data(), bodyBytes), envelope.rawBytes, payload);
  } else {
    if (bodyBytes != envelope.rawBytes)
      throw base::Error(what + " says " + std::to_string(envelope.rawBytes) +
                        " bytes but carries " + std::to_string(bodyBytes));
    payload = std::move(wire);
    payload.resize(bodyBytes);
  }
  return envelope;
}

}  // namespace messaging
