#pragma once
// Test access to a session's messaging (tests/api; not installed): puts on the wire what a faulty
// peer could, which no public call can, since the session duplicates the program's communicator.
#include <cstdint>

#include "api/DataDistributed.h"

namespace dfbwall {

class TestedSession : public Session {
 public:
  using Session::Session;
  // An empty message from this rank to object id `object` on rank `toRank` of the session's
  // communicator, through the session's messenger.
  void send(int toRank, std::uint64_t object);
  // Collective over the session's communicator: returns once every message sent before any rank
  // entered it has been handled (messaging::Messenger::quiesce).
  void quiesce();
};

}  // namespace dfbwall
