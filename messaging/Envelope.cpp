#include "messaging/Envelope.h"

#include <cstring>
#include <limits>
#include <span>
#include <string>

#include "messaging/Compression.h"
#include "messaging/Error.h"

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

Bytes sealEnvelope(Bytes payload, ObjectId object, bool compress, bool* compressed) {
  if (payload.size() > std::numeric_limits<std::uint32_t>::max())
    throw Error("message of " + std::to_string(payload.size()) + " bytes to object id " +
                std::to_string(object) + ": more than a message can carry (4 GiB)");
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
    throw Error("truncated message of " + std::to_string(wire.size()) + " bytes");
  std::memcpy(&trailer, wire.data() + wire.size() - sizeof trailer, sizeof trailer);
  return Envelope{trailer.object, trailer.rawBytes, trailer.flags};
}

Envelope openEnvelope(Bytes&& wire, std::size_t maxPayloadBytes, Bytes& payload) {
  const Envelope envelope = peekEnvelope(wire);
  const std::string what = "message to object id " + std::to_string(envelope.object);
  if (envelope.flags & ~kKnownFlags)
    throw Error(what + " has unknown flags " + std::to_string(envelope.flags));
  if (envelope.rawBytes > maxPayloadBytes)
    throw Error(what + " of " + std::to_string(envelope.rawBytes) +
                " bytes, more than the limit of " + std::to_string(maxPayloadBytes));
  const size_t bodyBytes = wire.size() - kEnvelopeBytes;
  if (envelope.flags & kCompressed) {
    decompress(std::span<const std::byte>(wire.data(), bodyBytes), envelope.rawBytes, payload);
  } else {
    if (bodyBytes != envelope.rawBytes)
      throw Error(what + " says " + std::to_string(envelope.rawBytes) + " bytes but carries " +
                  std::to_string(bodyBytes));
    payload = std::move(wire);
    payload.resize(bodyBytes);
  }
  return envelope;
}

}  // namespace messaging
