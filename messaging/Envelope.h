#pragma once
// The messenger's envelope: which object a message is for, its size before compression and
// whether it is compressed. It travels as a 16-byte trailer after the payload, not a header
// before it: the payload vector becomes the wire buffer by appending 16 bytes (free when the
// producer reserved them, see Messenger::kSpareCapacity) and becomes the payload again by
// dropping them, so neither side copies the body. Kept apart from the messenger so the parser
// of bytes from other ranks can be unit-tested and fuzzed on its own.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "base/ObjectIds.h"
#include "messaging/Compression.h"

namespace messaging {

using base::ObjectId;

// The largest payload any message may carry: the wire buffer (payload and envelope; a compressed
// body is only used when smaller) must fit MPI's int count.
inline constexpr std::size_t kEnvelopeBytes = 16;
inline constexpr std::size_t kLargestPayload = 0x7FFF'FFFF - kEnvelopeBytes;

// The one size cap, applied by the sender before a message is sealed and by the receiver before
// it allocates: throws base::Error naming `what` (e.g. "message to object id 5") when
// `payloadBytes` is above `maxPayloadBytes` or kLargestPayload.
void checkPayloadSize(std::size_t payloadBytes, std::size_t maxPayloadBytes,
                      const std::string& what);

struct Envelope {
  ObjectId object = 0;
  std::uint32_t rawBytes = 0;  // the payload's size before compression
  std::uint32_t flags = 0;
};

// Turns `payload` into a wire buffer for object `object`: Snappy-compressed when `compress`
// and that makes it smaller (then `*compressed` is set). Payloads above kLargestPayload are
// refused.
Bytes sealEnvelope(Bytes payload, ObjectId object, bool compress, bool* compressed = nullptr);
// The envelope of a wire buffer without opening it; throws base::Error when it is too short.
Envelope peekEnvelope(const Bytes& wire);
// Checks the envelope of `wire` (size limit `maxPayloadBytes`, flags, sizes) and returns it with
// the payload moved into `payload` (decompressed when needed). Throws base::Error naming what
// is wrong; never allocates more than `maxPayloadBytes` for a hostile size.
Envelope openEnvelope(Bytes&& wire, std::size_t maxPayloadBytes, Bytes& payload);

}  // namespace messaging
