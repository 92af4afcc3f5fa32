#pragma once
// What a relay (`dfbwall relay`, wall/service/relay/Relay.h) decides about the messages it
// forwards, apart from its sockets, so a test can check it message by message.
//
// Wall -> job: a Directory or Roster names the wall processes' piece endpoints; a job behind the
// relay cannot reach those, so it gets the relay's own endpoint for each process instead (every
// other field, the live flags included, as the wall said). The relay keeps what the wall said, to
// forward the pieces there.
//
// Job -> wall pieces: a message is forwarded only when it is a Batch whose session the wall gave
// a job through this relay (in a Directory). The relay never decodes the batch beyond its header:
// the wall checks the rest, as it does for a job connected straight to it.
#include <cstdint>
#include <functional>
#include <set>
#include <string>
#include <vector>

#include "wall/service/protocol/Protocol.h"

namespace wall::service {

// The relay's endpoint ("tcp://HOST:PORT") for wall process `process`.
using RelayEndpointOf = std::function<std::string(int process)>;

// `directory` as a job behind the relay must see it: process p's endpoint is relayEndpoint(p).
messaging::Bytes relayDirectory(const Directory& directory, const RelayEndpointOf& relayEndpoint);
// The same for a Roster; a process without an endpoint (lost, never joined) keeps none.
messaging::Bytes relayRoster(const Roster& roster, const RelayEndpointOf& relayEndpoint);
// The same for a Reshape's directory (a moved window; its piece session is forwarded too).
messaging::Bytes relayReshape(const Reshape& reshape, const RelayEndpointOf& relayEndpoint);

// The kinds a job says on the directory link (Hello, Keepalive, Capture, Bye) and the kinds the
// wall answers a job with (Directory, Refused, Queued, Keepalive, Presented, Ended, Roster,
// Reshape): the
// relay forwards these only, so a connection to the relay never reaches the wall's own link
// (Join, Beat, Command, ...) on the head's directory socket, nor a job the wall's.
bool jobKind(Kind kind);
bool wallToJobKind(Kind kind);

// The sessions the wall gave jobs through the relay, and the verdict on each piece message.
class RelaySessions {
 public:
  void add(std::uint64_t session) { sessions_.insert(session); }
  void remove(std::uint64_t session) { sessions_.erase(session); }
  bool has(std::uint64_t session) const { return sessions_.count(session) != 0; }
  std::size_t size() const { return sessions_.size(); }

  struct Verdict {
    bool forward = false;
    std::uint64_t session = 0;  // the header's (0 when there is no valid header)
    std::string why;            // when not forwarded: one line for the log
  };
  // A message that arrived on one of the relay's piece sockets.
  Verdict admit(const std::byte* data, std::size_t size) const;

 private:
  std::set<std::uint64_t> sessions_;
};

}  // namespace wall::service
