#include "wall/service/protocol/ServiceCommands.h"

#include <algorithm>
#include <cstring>

#include "base/Error.h"
#include "wall/service/protocol/Protocol.h"

namespace wall::service {

messaging::Bytes packCommand(const ServiceCommand& command) {
  CommandHeader h = command.header;
  h.textBytes = static_cast<std::uint32_t>(std::min(command.text.size(), kMaxStringBytes));
  messaging::Bytes out(sizeof h + h.textBytes);
  std::memcpy(out.data(), &h, sizeof h);
  std::memcpy(out.data() + sizeof h, command.text.data(), h.textBytes);
  return out;
}

ServiceCommand parseCommand(const messaging::Bytes& body) {
  ServiceCommand c;
  if (body.size() < sizeof c.header) throw base::Error("malformed service command");
  std::memcpy(&c.header, body.data(), sizeof c.header);
  if (body.size() != sizeof c.header + c.header.textBytes || c.header.textBytes > kMaxStringBytes)
    throw base::Error("malformed service command");
  const auto kind = static_cast<std::uint32_t>(c.header.kind);
  if (kind < static_cast<std::uint32_t>(Command::Start) ||
      kind > static_cast<std::uint32_t>(Command::Thumbnails))
    throw base::Error("unknown service command " + std::to_string(kind));
  c.text.assign(reinterpret_cast<const char*>(body.data() + sizeof c.header), c.header.textBytes);
  return c;
}

std::string startProblem(const ServiceCommand& start) {
  const CommandHeader& h = start.header;
  if (h.session == 0) return "session 0";
  if (h.a < 0 || h.a > std::int64_t{0xffffffff})
    return "first frame " + std::to_string(h.a) + " (expected 0..4294967295)";
  return jobFieldsProblem({h.renderRanks, h.tileSize, h.codec, h.framesInFlight, h.captureEvery});
}

}  // namespace wall::service
