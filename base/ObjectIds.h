#pragma once
// Every distributed object a job's messenger addresses, in one list: each takes the id after the
// one before, so no two can share an id, whichever binaries they end up in together.
#include <cstdint>

namespace base {

using ObjectId = std::uint64_t;

enum class MessageObject : ObjectId {
  kFrameBuffer = 0xDFB0,  // the DFB's default id (DistributedFrameBuffer::Options::objectId)
  kRunControl,
  kSteering,
  kWallControl,
  kWallNode,
  kFrameCredits,
  kPreview,
  kMessengerProbeRequest,
  kMessengerProbeAnswer,
  kMessengerLeave,
};

constexpr ObjectId objectId(MessageObject object) { return static_cast<ObjectId>(object); }

}  // namespace base
