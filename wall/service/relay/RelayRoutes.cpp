#include "wall/service/relay/RelayRoutes.h"

#include <exception>

namespace wall::service {

messaging::Bytes relayDirectory(const Directory& directory, const RelayEndpointOf& relayEndpoint) {
  Directory relayed = directory;
  for (size_t p = 0; p < relayed.processes.size(); ++p)
    relayed.processes[p].endpoint = relayEndpoint(static_cast<int>(p));
  return packDirectory(relayed);
}

messaging::Bytes relayRoster(const Roster& roster, const RelayEndpointOf& relayEndpoint) {
  Roster relayed = roster;
  for (size_t p = 0; p < relayed.processes.size(); ++p)
    if (!relayed.processes[p].endpoint.empty())
      relayed.processes[p].endpoint = relayEndpoint(static_cast<int>(p));
  return packRoster(relayed);
}

messaging::Bytes relayReshape(const Reshape& reshape, const RelayEndpointOf& relayEndpoint) {
  Reshape relayed = reshape;
  for (size_t p = 0; p < relayed.directory.processes.size(); ++p)
    relayed.directory.processes[p].endpoint = relayEndpoint(static_cast<int>(p));
  return packReshape(relayed);
}

bool jobKind(Kind kind) {
  return kind == Kind::Hello || kind == Kind::Keepalive || kind == Kind::Capture ||
         kind == Kind::Bye;
}

bool wallToJobKind(Kind kind) {
  return kind == Kind::Directory || kind == Kind::Refused || kind == Kind::Queued ||
         kind == Kind::Keepalive || kind == Kind::Presented || kind == Kind::Ended ||
         kind == Kind::Roster || kind == Kind::Reshape || kind == Kind::Input;
}

RelaySessions::Verdict RelaySessions::admit(const std::byte* data, std::size_t size) const {
  Verdict v;
  try {
    const MessageHeader h = parseHeader(data, size);
    v.session = h.session;
    if (h.kind != static_cast<std::uint16_t>(Kind::Batch)) {
      v.why = "message kind " + std::to_string(h.kind) + " is not a piece batch";
      return v;
    }
  } catch (const std::exception& e) {
    v.why = e.what();
    return v;
  }
  if (!has(v.session)) {
    v.why = "not the session of a job the wall accepted through this relay";
    return v;
  }
  v.forward = true;
  return v;
}

}  // namespace wall::service
